#include "params/ParameterFile.hpp"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "core/Error.hpp"

namespace fountain {

namespace {

const ParamSpec* find_spec(const std::string& key) {
  for (const auto& p : parameter_schema())
    if (p.key == key) return &p;
  return nullptr;
}

bool parse_real(const std::string& s, double& out) {
  if (s.empty()) return false;
  errno = 0;
  char* end = nullptr;
  out = std::strtod(s.c_str(), &end);
  return errno == 0 && end == s.c_str() + s.size() && std::isfinite(out);
}

bool parse_integer(const std::string& s, long long& out) {
  if (s.empty()) return false;
  errno = 0;
  char* end = nullptr;
  out = std::strtoll(s.c_str(), &end, 10);
  if (errno == 0 && end == s.c_str() + s.size()) return true;
  double d = 0;  // accept 1e6-style integers
  if (parse_real(s, d) && d == std::floor(d) && std::fabs(d) < 9e15) {
    out = static_cast<long long>(d);
    return true;
  }
  return false;
}

bool parse_bool(const std::string& s, bool& out) {
  if (s == "true" || s == "True" || s == "yes" || s == "on") return out = true, true;
  if (s == "false" || s == "False" || s == "no" || s == "off") return out = false, true;
  return false;
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t") + 1 - b);
}

// Checks one value against its spec and returns its canonical text.
std::string check_value(const ParamSpec& spec, const std::string& value, const std::string& where) {
  auto out_of_range = [&](double v) {
    const bool lo_bad = spec.min_exclusive ? !(v > spec.min) : !(v >= spec.min);
    return lo_bad || !(v <= spec.max);
  };
  auto range_text = [&] {
    return fmt::format("{}{:g}, {:g}]", spec.min_exclusive ? "(" : "[", spec.min, spec.max);
  };
  switch (spec.kind) {
    case ParamKind::Real: {
      double v = 0;
      if (!parse_real(value, v))
        throw InputError(fmt::format("{}: key '{}' must be a finite number, got '{}'", where, spec.key, value));
      if (out_of_range(v))
        throw InputError(fmt::format("{}: key '{}' = {} is out of range {}", where, spec.key, value, range_text()));
      return fmt::format("{}", v);
    }
    case ParamKind::Integer: {
      long long v = 0;
      if (!parse_integer(value, v))
        throw InputError(fmt::format("{}: key '{}' must be an integer, got '{}'", where, spec.key, value));
      if (out_of_range(static_cast<double>(v)))
        throw InputError(fmt::format("{}: key '{}' = {} is out of range {}", where, spec.key, value, range_text()));
      return fmt::format("{}", v);
    }
    case ParamKind::Boolean: {
      bool b = false;
      if (!parse_bool(value, b))
        throw InputError(fmt::format("{}: key '{}' must be true or false, got '{}'", where, spec.key, value));
      return b ? "true" : "false";
    }
    case ParamKind::RealList: {
      // "0.1, 0.5, 1" (a YAML sequence arrives joined so); empty: no values.
      std::string body = trim(value);
      if (body.size() >= 2 && body.front() == '[' && body.back() == ']') body = trim(body.substr(1, body.size() - 2));
      std::string canonical;
      std::size_t start = 0;
      while (!body.empty() && start <= body.size()) {
        const std::size_t comma = std::min(body.find(',', start), body.size());
        const std::string item = trim(body.substr(start, comma - start));
        double v = 0;
        if (!parse_real(item, v))
          throw InputError(fmt::format("{}: key '{}' must be a list of finite numbers, got '{}' in '{}'", where,
                                       spec.key, item, value));
        if (out_of_range(v))
          throw InputError(fmt::format("{}: key '{}' holds {}, out of range {}", where, spec.key, item, range_text()));
        canonical += fmt::format("{}{}", canonical.empty() ? "" : ", ", v);
        start = comma + 1;
      }
      return canonical;
    }
    case ParamKind::Text:
      if (!spec.choices.empty()) {
        bool ok = false;
        for (const auto& c : spec.choices) ok = ok || c == value;
        if (ok) return value;
        std::string listed;
        for (const auto& c : spec.choices) listed += (listed.empty() ? "" : ", ") + c;
        double v = 0;
        if (spec.or_number && parse_real(value, v)) {
          if (out_of_range(v))
            throw InputError(fmt::format("{}: key '{}' = {} is out of range {} (or one of: {})", where, spec.key, value,
                                         range_text(), listed));
          return value;
        }
        throw InputError(fmt::format("{}: key '{}' has unknown value '{}' (expected {}{})", where, spec.key, value,
                                     spec.or_number ? "a number in " + range_text() + " or " : "one of: ", listed));
      }
      return value;
  }
  return value;
}

}  // namespace

ParameterFile ParameterFile::load(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw InputError(fmt::format("{}: is a folder, not a parameter file", path));
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(fmt::format("{}: cannot open the parameter file", path));
  // Read at most one byte past the cap: a device or a runaway file must not be read for ever.
  std::string text(kMaxFileBytes + 1, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  if (in.bad()) throw InputError(fmt::format("{}: cannot read the parameter file", path));
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > kMaxFileBytes)
    throw InputError(fmt::format("{}: the parameter file is larger than {} MiB; a parameter file is a few kB of YAML",
                                 path, kMaxFileBytes >> 20));
  return parse(text, path);
}

ParameterFile ParameterFile::parse(const std::string& yaml_text, const std::string& origin) {
  ParameterFile pf;
  pf.origin_ = origin;
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw InputError(fmt::format("{}:{}: malformed YAML: {}", origin, e.mark.line + 1, e.msg));
  }
  if (!root.IsMap())
    throw InputError(fmt::format("{}: the parameter file must be a mapping of sections", origin));
  for (const auto& section : root) {
    const auto sec = section.first.as<std::string>();
    if (!section.second.IsMap())
      throw InputError(fmt::format("{}:{}: section '{}' must be a mapping of keys", origin,
                                   section.second.Mark().line + 1, sec));
    for (const auto& entry : section.second) {
      const std::string key = sec + "." + entry.first.as<std::string>();
      const std::string where = fmt::format("{}:{}", origin, entry.first.Mark().line + 1);
      const ParamSpec* spec = find_spec(key);
      if (!spec) throw InputError(fmt::format("{}: unknown key '{}'", where, key));
      std::string value;
      if (spec->kind == ParamKind::RealList && entry.second.IsSequence()) {
        for (const auto& item : entry.second) {
          if (!item.IsScalar())
            throw InputError(fmt::format("{}: key '{}' must be a list of numbers", where, key));
          value += (value.empty() ? "" : ", ") + item.Scalar();
        }
      } else if (entry.second.IsScalar()) {
        value = entry.second.Scalar();
      } else {
        throw InputError(fmt::format("{}: key '{}' must be a single value{}", where, key,
                                     spec->kind == ParamKind::RealList ? " or a list of numbers" : ""));
      }
      if (pf.given_.count(key)) throw InputError(fmt::format("{}: key '{}' is given twice", where, key));
      pf.values_[key] = check_value(*spec, value, where);
      pf.given_[key] = entry.first.Mark().line + 1;
    }
  }
  for (const auto& spec : parameter_schema()) {
    if (pf.values_.count(spec.key) || !spec.default_value) continue;
    pf.values_[spec.key] = check_value(spec, *spec.default_value, origin + " (default)");
  }
  for (const auto& spec : parameter_schema()) {
    if (pf.values_.count(spec.key)) continue;
    if (spec.required_unless.empty() || pf.values_.at(spec.required_unless) != "true")
      throw InputError(fmt::format("{}: required key '{}' is missing{}", origin, spec.key,
                                   spec.required_unless.empty()
                                       ? ""
                                       : fmt::format(" (it may be left out when {} is true)", spec.required_unless)));
    pf.values_[spec.key] = check_value(spec, spec.default_unless, origin + " (default)");
  }
  return pf;
}

std::string ParameterFile::check(const std::string& key, const std::string& value, const std::string& where) {
  const ParamSpec* s = find_spec(key);
  if (!s) throw std::logic_error("parameter '" + key + "' is not in the schema");
  return check_value(*s, value, where);
}

std::string ParameterFile::where(const std::string& key) const {
  const auto it = given_.find(key);
  return it == given_.end() ? fmt::format("{}: key '{}' (default)", origin_, key)
                            : fmt::format("{}:{}: key '{}'", origin_, it->second, key);
}

const ParamSpec& ParameterFile::spec(const std::string& key) const {
  const ParamSpec* s = find_spec(key);
  if (!s) throw std::logic_error("parameter '" + key + "' is not in the schema");
  return *s;
}

double ParameterFile::real(const std::string& key) const {
  spec(key);
  return std::strtod(values_.at(key).c_str(), nullptr);
}

long long ParameterFile::integer(const std::string& key) const {
  spec(key);
  return std::strtoll(values_.at(key).c_str(), nullptr, 10);
}

bool ParameterFile::flag(const std::string& key) const {
  spec(key);
  return values_.at(key) == "true";
}

std::vector<double> ParameterFile::reals(const std::string& key) const {
  spec(key);
  std::vector<double> out;
  const std::string& text = values_.at(key);
  for (std::size_t start = 0; start < text.size();) {
    const std::size_t comma = std::min(text.find(',', start), text.size());
    out.push_back(std::strtod(text.substr(start, comma - start).c_str(), nullptr));
    start = comma + 1;
  }
  return out;
}

const std::string& ParameterFile::text(const std::string& key) const {
  spec(key);
  return values_.at(key);
}

std::string ParameterFile::used_as_yaml() const {
  YAML::Emitter out;
  out << YAML::BeginMap;
  std::string section;
  for (const auto& [key, value] : values_) {
    const auto dot = key.find('.');
    const std::string sec = key.substr(0, dot);
    if (sec != section) {
      if (!section.empty()) out << YAML::EndMap;
      section = sec;
      out << YAML::Key << sec << YAML::Value << YAML::BeginMap;
    }
    out << YAML::Key << key.substr(dot + 1) << YAML::Value << value;
  }
  if (!section.empty()) out << YAML::EndMap;
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

}  // namespace fountain
