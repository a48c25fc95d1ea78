// The list of every parameter-file key: its type, default, allowed range and meaning.
#pragma once
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace fountain {

enum class ParamKind { Real, Integer, Boolean, Text, RealList };

struct ParamSpec {
  std::string key;                        // dotted path, e.g. "hydro.gamma"
  ParamKind kind = ParamKind::Real;
  std::optional<std::string> default_value;  // empty: the key is required
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_exclusive = false;
  std::string doc;
  std::vector<std::string> choices;       // for Text keys with a fixed set of values
  bool or_number = false;                 // Text: one of `choices`, or a number in [min, max]
  // A required key (no default) that this boolean key, when true, makes unnecessary; it then
  // takes `default_unless`. (A comoving run ends at its last scale factor, not at run.t_end.)
  std::string required_unless;
  std::string default_unless;
};

// All keys Fountain knows; the one place a new key is declared.
const std::vector<ParamSpec>& parameter_schema();

// The parameter reference (docs/parameters.md) generated from the schema.
std::string parameter_reference_markdown();

}  // namespace fountain
