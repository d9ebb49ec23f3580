#include "scene/yaml_checker.hpp"

#include "core/edit_distance.hpp"
#include "core/format.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>

namespace phantasm::scene_detail {
namespace {

bool is_quoted(const YAML::Node& node) {
  return node.Tag() == "!";
}

std::string join(const std::vector<std::string>& items) {
  std::string text;
  for (std::size_t i = 0; i < items.size(); ++i)
    text += (i ? ", " : "") + items[i];
  return text;
}

/// The accepted key closest to a misspelt one, if it is close enough to be a typo.
std::string closest_key(const std::string& key, const std::vector<std::string>& accepted) {
  std::string best;
  std::size_t best_distance = std::max<std::size_t>(2, key.size() / 4) + 1;
  for (const auto& candidate : accepted) {
    const std::size_t d = edit_distance(key, candidate);
    if (d < best_distance) {
      best_distance = d;
      best = candidate;
    }
  }
  return best;
}

} // namespace

YamlContext::YamlContext(std::string file, std::vector<Diagnostic>& problems,
                         std::map<std::string, SourceLocation>& locations)
    : m_file(std::move(file)), m_problems(problems), m_locations(locations) {}

SourceLocation YamlContext::location(const YAML::Node& node) const {
  SourceLocation where{m_file, 0, 0};
  if (node.IsDefined()) {
    const YAML::Mark mark = node.Mark();
    if (mark.line >= 0) {
      where.line = mark.line + 1;
      where.column = mark.column + 1;
    }
  }
  return where;
}

void YamlContext::problem(const YAML::Node& at, const std::string& key_path, const std::string& message) {
  problem(location(at), key_path, message);
}

void YamlContext::problem(const SourceLocation& at, const std::string& key_path, const std::string& message) {
  m_problems.push_back(Diagnostic{at, key_path, message});
}

void YamlContext::remember(const YAML::Node& node, const std::string& key_path) {
  m_locations[key_path] = location(node);
}

std::string describe(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "nothing";
  if (node.IsSequence()) return "a list of " + std::to_string(node.size()) + " items";
  if (node.IsMap()) return "a mapping";
  return "'" + node.Scalar() + "'";
}

bool read_number(YamlContext& context, const YAML::Node& node, const std::string& path,
                 const NumberRule& rule, double& out) {
  if (node.IsScalar() && !is_quoted(node)) {
    const std::string& text = node.Scalar();
    char* end = nullptr;
    errno = 0;
    const double value = std::strtod(text.c_str(), &end);
    if (!text.empty() && end != text.c_str() && *end == '\0' && errno == 0 && std::isfinite(value)) {
      if (!rule.accepts(value)) {
        context.problem(node, path, "expected " + rule.describe() + ", found " + describe(node));
        return false;
      }
      out = value;
      return true;
    }
  }
  context.problem(node, path, "expected " + rule.describe() + ", found " + describe(node));
  return false;
}

bool read_integer(YamlContext& context, const YAML::Node& node, const std::string& path, long long min,
                  long long max, long long& out) {
  const std::string expected =
      "expected an integer in [" + std::to_string(min) + ", " + std::to_string(max) + "]";
  if (node.IsScalar() && !is_quoted(node)) {
    const std::string& text = node.Scalar();
    char* end = nullptr;
    errno = 0;
    const long long value = std::strtoll(text.c_str(), &end, 10);
    if (!text.empty() && end != text.c_str() && *end == '\0' && errno == 0 && value >= min && value <= max) {
      out = value;
      return true;
    }
  }
  context.problem(node, path, expected + ", found " + describe(node));
  return false;
}

bool read_string(YamlContext& context, const YAML::Node& node, const std::string& path, std::string& out) {
  if (node.IsScalar() && !node.Scalar().empty()) {
    out = node.Scalar();
    return true;
  }
  context.problem(node, path, "expected a non-empty text, found " + describe(node));
  return false;
}

CheckedMap::CheckedMap(YamlContext& context, const YAML::Node& node, std::string path)
    : m_context(context), m_node(node), m_path(std::move(path)) {
  if (node.IsMap()) {
    m_valid = true;
  } else {
    m_context.problem(node, m_path, "expected a mapping (key: value lines), found " + describe(node));
  }
}

CheckedMap::~CheckedMap() {
  if (!m_valid) return;
  std::vector<std::string> accepted(m_known.begin(), m_known.end());
  std::set<std::string> seen;
  for (const auto& pair : m_node) {
    const YAML::Node key = pair.first;
    const std::string name = key.IsScalar() ? key.Scalar() : describe(key);
    const std::string where = child_path(name);
    if (!seen.insert(name).second) {
      m_context.problem(key, where, "expected each key once, found '" + name + "' again");
    } else if (m_known.count(name) == 0 && !m_accept_all) {
      const std::string suggestion = closest_key(name, accepted);
      m_context.problem(key, where,
                        "expected one of the keys " + join(accepted) + ", found unknown key '" + name + "'" +
                            (suggestion.empty() ? "" : " (did you mean '" + suggestion + "'?)"));
    }
  }
}

std::string CheckedMap::child_path(const std::string& key) const {
  return m_path.empty() ? key : m_path + "." + key;
}

YAML::Node CheckedMap::get(const std::string& key) {
  m_known.insert(key);
  if (!m_valid) return YAML::Node(YAML::NodeType::Undefined);
  // Look the key up by iteration: operator[] on a const node would not tell a missing key
  // from a null value, and non-const operator[] inserts.
  for (const auto& pair : m_node) {
    if (pair.first.IsScalar() && pair.first.Scalar() == key) {
      m_context.remember(pair.second.IsNull() ? pair.first : pair.second, child_path(key));
      return pair.second;
    }
  }
  return YAML::Node(YAML::NodeType::Undefined);
}

bool CheckedMap::has(const std::string& key) {
  return get(key).IsDefined();
}

void CheckedMap::missing(const std::string& key, const std::string& expected) {
  m_context.problem(m_node, child_path(key), "expected " + expected + ", found no such key");
}

bool CheckedMap::number(const std::string& key, double& out, const NumberRule& rule, bool required) {
  const YAML::Node node = get(key);
  if (!node.IsDefined()) {
    if (required && m_valid) missing(key, rule.describe());
    return false;
  }
  return read_number(m_context, node, child_path(key), rule, out);
}

bool CheckedMap::integer(const std::string& key, int& out, int min, int max, bool required) {
  const YAML::Node node = get(key);
  if (!node.IsDefined()) {
    if (required && m_valid) {
      missing(key, "an integer in [" + std::to_string(min) + ", " + std::to_string(max) + "]");
    }
    return false;
  }
  long long value = 0;
  if (!read_integer(m_context, node, child_path(key), min, max, value)) return false;
  out = static_cast<int>(value);
  return true;
}

bool CheckedMap::unsigned_integer(const std::string& key, std::uint64_t& out, bool required) {
  const YAML::Node node = get(key);
  const std::string expected = "an integer in [0, 9223372036854775807]";
  if (!node.IsDefined()) {
    if (required && m_valid) missing(key, expected);
    return false;
  }
  long long value = 0;
  if (!read_integer(m_context, node, child_path(key), 0, std::numeric_limits<long long>::max(), value)) {
    return false;
  }
  out = static_cast<std::uint64_t>(value);
  return true;
}

bool CheckedMap::boolean(const std::string& key, bool& out, bool required) {
  const YAML::Node node = get(key);
  if (!node.IsDefined()) {
    if (required && m_valid) missing(key, "true or false");
    return false;
  }
  if (node.IsScalar() && !is_quoted(node) && (node.Scalar() == "true" || node.Scalar() == "false")) {
    out = node.Scalar() == "true";
    return true;
  }
  m_context.problem(node, child_path(key), "expected true or false, found " + describe(node));
  return false;
}

bool CheckedMap::string(const std::string& key, std::string& out, bool required) {
  const YAML::Node node = get(key);
  if (!node.IsDefined()) {
    if (required && m_valid) missing(key, "a non-empty text");
    return false;
  }
  return read_string(m_context, node, child_path(key), out);
}

bool CheckedMap::choice(const std::string& key, std::string& out, const std::vector<std::string>& choices,
                        bool required) {
  const YAML::Node node = get(key);
  const std::string expected = "one of " + join(choices);
  if (!node.IsDefined()) {
    if (required && m_valid) missing(key, expected);
    return false;
  }
  if (node.IsScalar()) {
    for (const auto& c : choices) {
      if (node.Scalar() == c) {
        out = c;
        return true;
      }
    }
  }
  m_context.problem(node, child_path(key), "expected " + expected + ", found " + describe(node));
  return false;
}

bool CheckedMap::vec3(const std::string& key, Eigen::Vector3d& out, const NumberRule& rule, bool required,
                      bool allow_scalar) {
  const YAML::Node node = get(key);
  const std::string path = child_path(key);
  const std::string expected =
      std::string(allow_scalar ? "one number or " : "") + "a list of 3 numbers, each " + rule.describe();
  if (!node.IsDefined()) {
    if (required && m_valid) missing(key, expected);
    return false;
  }
  if (allow_scalar && node.IsScalar()) {
    double value = 0.0;
    if (!read_number(m_context, node, path, rule, value)) return false;
    out.setConstant(value);
    return true;
  }
  if (!node.IsSequence() || node.size() != 3) {
    m_context.problem(node, path, "expected " + expected + ", found " + describe(node));
    return false;
  }
  Eigen::Vector3d value;
  bool ok = true;
  for (std::size_t i = 0; i < 3; ++i) {
    ok = read_number(m_context, node[i], path + "[" + std::to_string(i) + "]", rule,
                     value[static_cast<int>(i)]) &&
         ok;
  }
  if (ok) out = value;
  return ok;
}

bool CheckedMap::string_list(const std::string& key, std::vector<std::string>& out, bool required) {
  const YAML::Node node = get(key);
  const std::string path = child_path(key);
  if (!node.IsDefined()) {
    if (required && m_valid) missing(key, "a list of names");
    return false;
  }
  if (!node.IsSequence()) {
    m_context.problem(node, path, "expected a list of names, found " + describe(node));
    return false;
  }
  std::vector<std::string> values;
  bool ok = true;
  for (std::size_t i = 0; i < node.size(); ++i) {
    std::string value;
    const std::string item_path = path + "[" + std::to_string(i) + "]";
    if (read_string(m_context, node[i], item_path, value)) {
      m_context.remember(node[i], item_path);
      values.push_back(value);
    } else {
      ok = false;
    }
  }
  if (ok) out = values;
  return ok;
}

} // namespace phantasm::scene_detail
