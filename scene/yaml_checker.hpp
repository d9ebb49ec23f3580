// Checked reading of YAML: typed values with ranges and units, unknown and missing keys, each
// mistake a diagnostic with its location. Internal to the scene target.
#pragma once

// Reading YAML with a diagnostic for every mistake. Internal to the scene target: yaml-cpp
// types do not appear in the scene's public header.

#include "core/number_rule.hpp"
#include "scene/diagnostic.hpp"

#include <Eigen/Core>
#include <yaml-cpp/yaml.h>

#include <limits>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace phantasm::scene_detail {

/// Collects problems and key locations while a file is read.
class YamlContext {
public:
  YamlContext(std::string file, std::vector<Diagnostic>& problems,
              std::map<std::string, SourceLocation>& locations);

  SourceLocation location(const YAML::Node& node) const;
  void problem(const YAML::Node& at, const std::string& key_path, const std::string& message);
  void problem(const SourceLocation& at, const std::string& key_path, const std::string& message);
  void remember(const YAML::Node& node, const std::string& key_path);
  const std::string& file() const { return m_file; }
  std::size_t problem_count() const { return m_problems.size(); }

private:
  std::string m_file;
  std::vector<Diagnostic>& m_problems;
  std::map<std::string, SourceLocation>& m_locations;
};

/// How a YAML node is described in "found ..." (a quoted scalar, "a list", "a mapping").
std::string describe(const YAML::Node& node);

/// Reads a value node (not a key of a map): each returns false after reporting a problem.
bool read_number(YamlContext& context, const YAML::Node& node, const std::string& path,
                 const NumberRule& rule, double& out);
bool read_integer(YamlContext& context, const YAML::Node& node, const std::string& path, long long min,
                  long long max, long long& out);
bool read_string(YamlContext& context, const YAML::Node& node, const std::string& path, std::string& out);

/// A YAML mapping whose keys are checked: every key a reader asks for is known; the destructor
/// reports every other key as unknown, with the list of keys that would have been accepted.
class CheckedMap {
public:
  CheckedMap(YamlContext& context, const YAML::Node& node, std::string path);
  ~CheckedMap();
  CheckedMap(const CheckedMap&) = delete;
  CheckedMap& operator=(const CheckedMap&) = delete;

  bool valid() const { return m_valid; }
  const std::string& path() const { return m_path; }
  const YAML::Node& node() const { return m_node; }
  YamlContext& context() { return m_context; }
  std::string child_path(const std::string& key) const;

  /// The value of a key (undefined when absent); marks the key as known.
  YAML::Node get(const std::string& key);
  bool has(const std::string& key);
  /// Stops unknown-key reports for this mapping: used when its type key is wrong, so that the
  /// keys of the intended type do not each produce a second message.
  void accept_remaining_keys() { m_accept_all = true; }
  /// Reports a missing required key at the mapping's location.
  void missing(const std::string& key, const std::string& expected);

  bool number(const std::string& key, double& out, const NumberRule& rule, bool required = false);
  bool integer(const std::string& key, int& out, int min, int max, bool required = false);
  bool unsigned_integer(const std::string& key, std::uint64_t& out, bool required = false);
  bool boolean(const std::string& key, bool& out, bool required = false);
  bool string(const std::string& key, std::string& out, bool required = false);
  bool choice(const std::string& key, std::string& out, const std::vector<std::string>& choices,
              bool required = false);
  /// Three numbers [x, y, z]; with allow_scalar a single number stands for all three.
  bool vec3(const std::string& key, Eigen::Vector3d& out, const NumberRule& rule, bool required = false,
            bool allow_scalar = false);
  bool string_list(const std::string& key, std::vector<std::string>& out, bool required = false);

private:
  YamlContext& m_context;
  YAML::Node m_node;
  std::string m_path;
  bool m_valid = false;
  bool m_accept_all = false;
  std::set<std::string> m_known;
};

} // namespace phantasm::scene_detail
