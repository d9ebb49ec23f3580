#include "batch/sweep.hpp"

#include "core/error.hpp"
#include "scene/scene.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <random>
#include <regex>
#include <sstream>

namespace phantasm {
namespace {

/// A key path element: a mapping key and the list indices after it ("loads[1]").
struct Segment {
  std::string key;
  std::vector<std::size_t> indices;
};

/// One varied key: its path and either a list of values or a random range.
struct Variation {
  std::string key;
  YAML::Mark mark;
  std::vector<YAML::Node> values; ///< a list: the grid
  std::string random_kind;        ///< or a range: uniform, log_uniform, random_integer
  double low = 0.0, high = 0.0;
};

class SweepReader {
public:
  explicit SweepReader(std::filesystem::path file) : m_file(std::move(file)) {}

  [[noreturn]] void fail(const YAML::Mark& mark, const std::string& key, const std::string& message) const {
    std::string where = m_file.string();
    if (mark.line >= 0) where += ":" + std::to_string(mark.line + 1) + ":" + std::to_string(mark.column + 1);
    throw InputError(where + ": " + key + ": " + message);
  }

  std::string flow(const YAML::Node& node) const {
    YAML::Emitter out;
    out.SetSeqFormat(YAML::Flow);
    out.SetMapFormat(YAML::Flow);
    out << node;
    return out.c_str();
  }

  std::vector<Segment> parse_path(const Variation& v) const {
    static const std::regex segment(R"(([A-Za-z_][A-Za-z0-9_]*)((\[[0-9]+\])*))");
    std::vector<Segment> path;
    std::stringstream parts(v.key);
    std::string part;
    while (std::getline(parts, part, '.')) {
      std::smatch match;
      if (!std::regex_match(part, match, segment)) {
        fail(v.mark, "vary." + v.key,
             "expected a scene key path such as acquisition.noise_percent or "
             "deformation.loads[1].displacement_mm, "
             "found '" +
                 part + "' in it");
      }
      Segment s{match[1].str(), {}};
      static const std::regex index(R"(\[([0-9]+)\])");
      const std::string indices = match[2].str();
      for (std::sregex_iterator it(indices.begin(), indices.end(), index), end; it != end; ++it)
        s.indices.push_back(std::stoul((*it)[1].str()));
      path.push_back(s);
    }
    return path;
  }

  Variation read_variation(const std::string& key, const YAML::Node& value) const {
    Variation v;
    v.key = key;
    v.mark = value.Mark();
    if (value.IsSequence()) {
      if (value.size() == 0) fail(v.mark, "vary." + key, "expected a non-empty list of values, found []");
      for (const auto& item : value)
        v.values.push_back(item);
      return v;
    }
    if (value.IsMap() && value.size() == 1) {
      v.random_kind = value.begin()->first.as<std::string>();
      const YAML::Node range = value.begin()->second;
      if (v.random_kind != "uniform" && v.random_kind != "log_uniform" && v.random_kind != "random_integer") {
        fail(v.mark, "vary." + key,
             "expected a list of values or one of {uniform: [a, b]}, {log_uniform: [a, b]}, {random_integer: "
             "[a, "
             "b]}, found '" +
                 v.random_kind + "'");
      }
      try {
        if (!range.IsSequence() || range.size() != 2) throw YAML::Exception(range.Mark(), "range");
        v.low = range[0].as<double>();
        v.high = range[1].as<double>();
      } catch (const YAML::Exception&) {
        fail(v.mark, "vary." + key + "." + v.random_kind,
             "expected [low, high] (two numbers), found " + flow(range));
      }
      if (!(v.low <= v.high) || (v.random_kind == "log_uniform" && v.low <= 0.0) ||
          (v.random_kind == "random_integer" &&
           (v.low != std::floor(v.low) || v.high != std::floor(v.high)))) {
        fail(v.mark, "vary." + key + "." + v.random_kind,
             "expected low <= high" + std::string(v.random_kind == "log_uniform" ? ", both > 0" : "") +
                 std::string(v.random_kind == "random_integer" ? ", whole numbers" : "") + ", found " +
                 flow(range));
      }
      return v;
    }
    fail(v.mark, "vary." + key,
         "expected a list of values or a random range such as {uniform: [a, b]}, found " + flow(value));
  }

  /// Sets a value at a key path of a scene tree, creating missing mapping keys.
  void assign(YAML::Node root, const Variation& v, const YAML::Node& value) const {
    if (v.key == "deformation.scale") return scale_displacements(root, v, value);
    if (v.key == "sequences") return keep_sequences(root, v, value);
    const std::vector<Segment> path = parse_path(v);
    YAML::Node node = root;
    for (std::size_t s = 0; s < path.size(); ++s) {
      const Segment& segment = path[s];
      const bool last = s + 1 == path.size();
      if (!node.IsMap() && node.IsDefined() && !node.IsNull()) {
        fail(v.mark, "vary." + v.key,
             "expected a mapping at '" + segment.key + "' in the base scene, found " + flow(node));
      }
      if (last && segment.indices.empty()) {
        node[segment.key] = YAML::Clone(value);
        return;
      }
      YAML::Node child = node[segment.key];
      for (std::size_t i = 0; i < segment.indices.size(); ++i) {
        const std::size_t index = segment.indices[i];
        if (!child.IsSequence() || index >= child.size()) {
          fail(
              v.mark, "vary." + v.key,
              "expected list element [" + std::to_string(index) + "] of '" + segment.key +
                  "' in the base scene, found " +
                  (child.IsSequence() ? std::to_string(child.size()) + " elements" : std::string("no list")));
        }
        if (last && i + 1 == segment.indices.size()) {
          child[index] = YAML::Clone(value);
          return;
        }
        YAML::Node element = child[index];
        child.reset(element);
      }
      node.reset(child);
    }
  }

  void scale_displacements(YAML::Node root, const Variation& v, const YAML::Node& value) const {
    double scale = 0.0;
    try {
      scale = value.as<double>();
    } catch (const YAML::Exception&) {
      fail(v.mark, "vary.deformation.scale",
           "expected numbers (factors of the displacement loads), found " + flow(value));
    }
    bool found = false;
    YAML::Node loads = root["deformation"]["loads"];
    if (loads.IsSequence()) {
      for (std::size_t i = 0; i < loads.size(); ++i) {
        YAML::Node load = loads[i];
        if (!load.IsMap() || !load["type"] || load["type"].as<std::string>() != "displacement") continue;
        YAML::Node vector = load["displacement_mm"];
        if (!vector.IsSequence()) continue;
        for (std::size_t c = 0; c < vector.size(); ++c)
          vector[c] = vector[c].as<double>() * scale;
        found = true;
      }
    }
    if (!found) {
      fail(v.mark, "vary.deformation.scale",
           "expected a base scene with a displacement load to scale, found none in deformation.loads");
    }
  }

  void keep_sequences(YAML::Node root, const Variation& v, const YAML::Node& names) const {
    const YAML::Node sequences = root["sequences"];
    if (!names.IsSequence() || !sequences.IsSequence()) {
      fail(v.mark, "vary.sequences",
           "expected lists of sequence names of the base scene, found " + flow(names));
    }
    YAML::Node kept(YAML::NodeType::Sequence);
    for (const auto& name : names) {
      bool known = false;
      for (const auto& sequence : sequences) {
        if (sequence["name"] && sequence["name"].as<std::string>() == name.as<std::string>()) {
          kept.push_back(YAML::Clone(sequence));
          known = true;
        }
      }
      if (!known) {
        fail(v.mark, "vary.sequences",
             "expected names of the base scene's sequences, found '" + name.as<std::string>() + "'");
      }
    }
    root["sequences"] = kept;
  }

  Sweep read() {
    YAML::Node top;
    try {
      top = YAML::LoadFile(m_file.string());
    } catch (const YAML::BadFile&) {
      throw InputError(m_file.string() + ": expected a sweep file, found no readable file");
    } catch (const YAML::Exception& error) {
      fail(error.mark, "sweep", "expected valid YAML, found " + error.msg);
    }
    if (!top.IsMap()) fail(top.Mark(), "sweep", "expected a mapping, found " + flow(top));
    for (const auto& entry : top) {
      const std::string key = entry.first.as<std::string>();
      if (key != "phantasm_sweep" && key != "name" && key != "base_scene" && key != "seed" &&
          key != "repeats" && key != "vary") {
        fail(entry.first.Mark(), key,
             "expected one of phantasm_sweep, name, base_scene, seed, repeats, vary; found an unknown key");
      }
    }
    if (!top["phantasm_sweep"] || top["phantasm_sweep"].as<std::string>() != "1") {
      fail(top.Mark(), "phantasm_sweep", "expected 'phantasm_sweep: 1' (the sweep format version)");
    }
    Sweep sweep;
    sweep.file = m_file;
    if (!top["base_scene"]) fail(top.Mark(), "base_scene", "expected the path of the base scene, found none");
    sweep.base_scene = m_file.parent_path() / top["base_scene"].as<std::string>();
    std::ifstream base_file(sweep.base_scene);
    if (!base_file) {
      fail(top["base_scene"].Mark(), "base_scene",
           "expected a scene file, found no such file: " + sweep.base_scene.string());
    }
    const std::string base_text((std::istreambuf_iterator<char>(base_file)),
                                std::istreambuf_iterator<char>());
    sweep.name = top["name"] ? top["name"].as<std::string>() : m_file.stem().string();
    std::uint64_t seed = 0;
    int repeats = 1;
    try {
      if (top["seed"]) seed = top["seed"].as<std::uint64_t>();
      if (top["repeats"]) repeats = top["repeats"].as<int>();
    } catch (const YAML::Exception& error) {
      fail(error.mark, top["seed"] && !top["seed"].IsScalar() ? "seed" : "seed or repeats",
           "expected a whole number");
    }
    if (repeats < 1 || repeats > 100000) fail(top["repeats"].Mark(), "repeats", "expected 1 to 100000");

    std::vector<Variation> variations;
    if (top["vary"]) {
      if (!top["vary"].IsMap()) fail(top["vary"].Mark(), "vary", "expected a mapping of key paths to values");
      for (const auto& entry : top["vary"])
        variations.push_back(read_variation(entry.first.as<std::string>(), entry.second));
    }
    std::size_t combinations = 1;
    for (const auto& v : variations) {
      sweep.varied_keys.push_back(v.key);
      if (!v.values.empty()) combinations *= v.values.size();
    }
    const std::size_t count = combinations * static_cast<std::size_t>(repeats);
    if (count > 1000000)
      fail(top.Mark(), "vary", "expected at most 10^6 subjects, found " + std::to_string(count));
    const int width = std::max<int>(2, static_cast<int>(std::to_string(count).size()));

    for (std::size_t s = 0; s < count; ++s) {
      SweepSubject subject;
      subject.id = std::to_string(s + 1);
      subject.id.insert(0, static_cast<std::size_t>(width) - subject.id.size(), '0');
      YAML::Node scene = YAML::Load(base_text);
      std::size_t combination = s / static_cast<std::size_t>(repeats);
      // The grid index of each list, the last list fastest.
      std::vector<std::size_t> choice(variations.size(), 0);
      for (std::size_t k = variations.size(); k-- > 0;) {
        if (variations[k].values.empty()) continue;
        choice[k] = combination % variations[k].values.size();
        combination /= variations[k].values.size();
      }
      for (std::size_t k = 0; k < variations.size(); ++k) {
        const Variation& v = variations[k];
        YAML::Node value;
        if (!v.values.empty()) {
          value = v.values[choice[k]];
        } else {
          std::seed_seq mix{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32),
                            static_cast<std::uint32_t>(s), static_cast<std::uint32_t>(k)};
          std::mt19937_64 random(mix);
          std::ostringstream text;
          text.precision(6);
          if (v.random_kind == "random_integer") {
            std::uniform_int_distribution<long long> draw(static_cast<long long>(v.low),
                                                          static_cast<long long>(v.high));
            text << draw(random);
          } else if (v.random_kind == "uniform") {
            text << std::uniform_real_distribution<double>(v.low, v.high)(random);
          } else {
            text << std::exp(
                std::uniform_real_distribution<double>(std::log(v.low), std::log(v.high))(random));
          }
          value = YAML::Load(text.str());
        }
        assign(scene, v, value);
        subject.values.emplace_back(v.key, flow(value));
      }
      scene["outputs"]["subject"] = subject.id;
      YAML::Emitter out;
      out << scene;
      subject.scene_text = std::string(out.c_str()) + "\n";
      const SceneLoadResult checked = parse_scene(subject.scene_text, sweep.base_scene);
      if (!checked.scene) {
        std::string values;
        for (const auto& [key, text] : subject.values)
          values += (values.empty() ? "" : ", ") + key + " = " + text;
        throw InputError(m_file.string() + ": subject " + subject.id + " (" + values +
                         ") gives a scene that does not validate:\n" + format_diagnostics(checked.problems));
      }
      sweep.subjects.push_back(std::move(subject));
    }
    return sweep;
  }

private:
  std::filesystem::path m_file;
};

} // namespace

bool is_sweep_file(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("phantasm_sweep:", 0) == 0) return true;
  return false;
}

Sweep load_sweep(const std::filesystem::path& file) {
  return SweepReader(file).read();
}

std::string scene_text_with_value(const std::string& scene_text, const std::string& key,
                                  const std::string& value_yaml) {
  const SweepReader reader("scene value");
  Variation v;
  v.key = key;
  v.mark = YAML::Mark::null_mark();
  YAML::Node scene, value;
  try {
    scene = YAML::Load(scene_text);
    value = YAML::Load(value_yaml);
  } catch (const YAML::Exception& error) {
    throw InputError(key + ": expected a YAML value, found '" + value_yaml + "' (" + error.msg + ")");
  }
  reader.assign(scene, v, value);
  YAML::Emitter out;
  out << scene;
  return std::string(out.c_str()) + "\n";
}

Shard parse_shard(const std::string& text) {
  static const std::regex pattern(R"(([0-9]{1,6})/([0-9]{1,6}))");
  std::smatch match;
  if (std::regex_match(text, match, pattern)) {
    const Shard shard{std::stoi(match[1].str()), std::stoi(match[2].str())};
    if (shard.count >= 1 && shard.index >= 1 && shard.index <= shard.count) return shard;
  }
  throw InputError("--shard: expected i/N with 1 <= i <= N (e.g. 2/3), found '" + text + "'");
}

std::string participants_tsv(const Sweep& sweep) {
  std::string text = "participant_id";
  for (const auto& key : sweep.varied_keys)
    text += "\t" + key;
  text += "\n";
  for (const auto& subject : sweep.subjects) {
    text += "sub-" + subject.id;
    for (const auto& [key, value] : subject.values)
      text += "\t" + value;
    text += "\n";
  }
  return text;
}

} // namespace phantasm
