// The keys of a scene section read as their settings declare them (scene/settings_declarations.hpp):
// type, bounds and whether required come from the declaration, the messages from the checked
// YAML mapping. Internal to the scene target.
#pragma once

#include "scene/settings_declarations.hpp"
#include "scene/yaml_checker.hpp"

#include <algorithm>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace phantasm::scene_detail {

/// A SettingReader over the keys of a checked mapping.
class CheckedMapReader final : public SettingReader {
public:
  explicit CheckedMapReader(CheckedMap& map) : m_map(map) {}
  bool number(const std::string& key, double& out, const NumberRule& rule, bool required) override {
    return m_map.number(key, out, rule, required);
  }
  bool integer(const std::string& key, int& out, const NumberRule& rule, bool required) override {
    return m_map.integer(key, out, static_cast<int>(rule.min), static_cast<int>(rule.max), required);
  }
  bool boolean(const std::string& key, bool& out, bool required) override {
    return m_map.boolean(key, out, required);
  }
  bool text(const std::string& key, std::string& out, bool required) override {
    return m_map.string(key, out, required);
  }
  bool texts(const std::string& key, std::vector<std::string>& out, bool required) override {
    return m_map.string_list(key, out, required);
  }
  bool vec3(const std::string& key, Eigen::Vector3d& out, const NumberRule& rule, bool required,
            bool scalar_allowed) override {
    return m_map.vec3(key, out, rule, required, scalar_allowed);
  }
  bool choice(const std::string& key, std::string& out, const std::vector<std::string>& choices,
              bool required) override {
    return m_map.choice(key, out, choices, required);
  }

private:
  CheckedMap& m_map;
};

/// Whether a declared field is a plain key of its section's mapping: read by its declaration,
/// written in its section, not derived, not a field of a list or of a nested mapping.
template <typename S>
bool is_plain_key(const SettingField<S>& f) {
  return f.read && f.in_section && !f.derived && f.name.find_first_of(".[") == std::string::npos;
}

/// The declared field named `name` of S; a name that is not declared is a programming error.
template <typename S>
const SettingField<S>& declared_field(const std::string& name) {
  const std::vector<SettingField<S>>& fields = declared_settings<S>();
  const auto f =
      std::find_if(fields.begin(), fields.end(), [&](const SettingField<S>& d) { return d.name == name; });
  if (f == fields.end()) throw std::logic_error("no declared setting " + name);
  return *f;
}

/// The declared rule of the numeric setting `name` of S (its key read by hand).
template <typename S>
NumberRule declared_rule(const std::string& name) {
  const SettingField<S>& f = declared_field<S>(name);
  if (!f.rule) throw std::logic_error("no declared bounds of " + name);
  return *f.rule;
}

/// Reads the keys `keys` of the mapping into `s`, in that order, as S's declaration says.
/// @return the keys read (present and accepted)
template <typename S>
std::set<std::string> read_declared_keys(CheckedMap& map, S& s, const std::vector<std::string>& keys) {
  CheckedMapReader reader(map);
  std::set<std::string> read;
  for (const std::string& key : keys) {
    const SettingField<S>& f = declared_field<S>(key);
    if (!f.read) throw std::logic_error("declared setting " + key + " has no plain key");
    if (read_field(reader, f, s)) read.insert(key);
  }
  return read;
}

/// Reads the declared key `key` into `s`, required as the caller says: for a key that one variant
/// of a family needs and another does not (a sequence type's parameter), its type and choices
/// still the declaration's.
/// @return whether the key was present and accepted
template <typename S>
bool read_declared_key(CheckedMap& map, S& s, const std::string& key, bool required) {
  SettingField<S> f = declared_field<S>(key);
  if (!f.read) throw std::logic_error("declared setting " + key + " has no plain key");
  f.required = required;
  CheckedMapReader reader(map);
  return read_field(reader, f, s);
}

/// Reads every plain key of S's declaration but those of `except`, in declaration order.
/// @return the keys read (present and accepted)
template <typename S>
std::set<std::string> read_declared(CheckedMap& map, S& s, const std::vector<std::string>& except = {}) {
  CheckedMapReader reader(map);
  std::set<std::string> read;
  for (const SettingField<S>& f : declared_settings<S>()) {
    if (!is_plain_key(f) || std::find(except.begin(), except.end(), f.name) != except.end()) continue;
    if (read_field(reader, f, s)) read.insert(f.name);
  }
  return read;
}

} // namespace phantasm::scene_detail
