// A parsed, validated YAML parameter file: every key checked against the schema before use.
#pragma once
#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include "params/ParameterSchema.hpp"

namespace fountain {

class ParameterFile {
 public:
  // Parses `path` and validates it: unknown keys, wrong types, out-of-range values and
  // missing required keys throw InputError naming the key and the file.
  static ParameterFile load(const std::string& path);
  // Same, from text (for tests and for restart files); `origin` names it in messages.
  static ParameterFile parse(const std::string& yaml_text, const std::string& origin);
  // Checks one value of `key` as a file's value is checked (type and range), for a value that
  // comes from elsewhere (a command-line option); `where` names that place in the message.
  static std::string check(const std::string& key, const std::string& value, const std::string& where);

  double real(const std::string& key) const;
  long long integer(const std::string& key) const;
  bool flag(const std::string& key) const;
  std::vector<double> reals(const std::string& key) const;  // a list key's values, in the file's order
  const std::string& text(const std::string& key) const;
  bool was_given(const std::string& key) const { return given_.count(key) != 0; }
  // "FILE:LINE: key 'KEY'" for a key the file gives, "FILE: key 'KEY' (default)" otherwise:
  // the prefix of a message about a value that passed its own range but not a rule with others.
  std::string where(const std::string& key) const;

  // A parameter file is a few kB; a larger one is refused before it is read whole.
  static constexpr std::size_t kMaxFileBytes = std::size_t{16} << 20;

  // Every key with the value in force (given or default), as YAML text.
  std::string used_as_yaml() const;
  const std::map<std::string, std::string>& values() const { return values_; }
  const std::string& origin() const { return origin_; }

 private:
  const ParamSpec& spec(const std::string& key) const;
  std::string origin_;
  std::map<std::string, std::string> values_;  // canonical text of each value in force
  std::map<std::string, int> given_;  // the line of each key the file gives
};

}  // namespace fountain
