#include "batch/sweep.hpp"

#include "batch/random_draw.hpp"
#include "core/error.hpp"
#include "core/safe_name.hpp"
#include "scene/scene.hpp"
#include "scene/yaml_documents.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <random>
#include <regex>
#include <set>
#include <sstream>
#include <string_view>

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
  RandomDistribution random;      ///< or a distribution drawn per subject (kind empty for a list)
};

/// The start of the message for a key of vary that names no scene setting.
const std::string k_key_path_expected = "expected a scene key path such as acquisition.noise_percent or "
                                        "deformation.loads[1].displacement_mm, found ";

class SweepReader {
public:
  /// @param text the file's text when the caller read it already (a pipe can be read once)
  explicit SweepReader(std::filesystem::path file, const std::string* text = nullptr)
      : m_file(std::move(file)), m_text(text) {}

  [[noreturn]] void fail(const YAML::Mark& mark, const std::string& key, const std::string& message) const {
    // A value set in a scene (scene_text_with_value) has no sweep file: the key path alone.
    if (m_file.empty()) throw InputError((key.rfind("vary.", 0) == 0 ? key.substr(5) : key) + ": " + message);
    std::string where = m_file.string();
    if (mark.line >= 0) where += ":" + std::to_string(mark.line + 1) + ":" + std::to_string(mark.column + 1);
    throw InputError(where + ": " + key + ": " + message);
  }

  /// A mistake in the base scene found while a value is set in it: named at its place there.
  [[noreturn]] void fail_in_base(const YAML::Mark& mark, const std::string& key,
                                 const std::string& message) const {
    std::string where = m_base_scene.empty() ? std::string("base scene") : m_base_scene.string();
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

  /// A node as a message shows it: a scalar quoted, a list or mapping in flow style.
  std::string shown(const YAML::Node& node) const {
    return node.IsScalar() ? "'" + node.Scalar() + "'" : flow(node);
  }

  std::vector<Segment> parse_path(const Variation& v) const {
    static const std::regex segment(R"(([A-Za-z_][A-Za-z0-9_]*)((\[[0-9]{1,6}\])*))");
    std::vector<Segment> path;
    std::stringstream parts(v.key);
    std::string part;
    while (std::getline(parts, part, '.')) {
      std::smatch match;
      if (!std::regex_match(part, match, segment)) {
        fail(v.mark, "vary." + v.key, k_key_path_expected + ("'" + part + "' in it"));
      }
      Segment s{match[1].str(), {}};
      static const std::regex index(R"(\[([0-9]{1,6})\])");
      const std::string indices = match[2].str();
      for (std::sregex_iterator it(indices.begin(), indices.end(), index), end; it != end; ++it)
        s.indices.push_back(std::stoul((*it)[1].str()));
      path.push_back(s);
    }
    return path;
  }

  /// Two finite numbers [a, b] of a distribution's key.
  std::pair<double, double> number_pair(const Variation& v, const std::string& key,
                                        const YAML::Node& node) const {
    double a = 0.0, b = 0.0;
    try {
      if (!node.IsSequence() || node.size() != 2) throw YAML::Exception(node.Mark(), "range");
      a = node[0].as<double>();
      b = node[1].as<double>();
    } catch (const YAML::Exception&) {
      fail(v.mark, "vary." + v.key + "." + key, "expected [low, high] (two numbers), found " + flow(node));
    }
    // Whole numbers beyond 2^53 are not exact in a double; no scene setting is that large.
    constexpr double k_largest = 9007199254740992.0;
    if (!std::isfinite(a) || !std::isfinite(b) || std::abs(a) > k_largest || std::abs(b) > k_largest) {
      fail(v.mark, "vary." + v.key + "." + key,
           "expected two finite numbers within +-2^53, found " + flow(node));
    }
    return {a, b};
  }

  /// A declared distribution (docs/batch.md, Random draws): its kind with its two parameters,
  /// and for normal and log_normal the optional `add` and `within`.
  void read_distribution(Variation& v, const YAML::Node& value) const {
    RandomDistribution& d = v.random;
    d.kind = value.begin()->first.Scalar();
    static const char* k_kinds = "{uniform: [a, b]}, {log_uniform: [a, b]}, {random_integer: [a, b]}, "
                                 "{normal: [mean, sd]}, {log_normal: [mu, sigma]}";
    if (d.kind != "uniform" && d.kind != "log_uniform" && d.kind != "random_integer" &&
        !takes_shape_options(d.kind))
      fail(v.mark, "vary." + v.key,
           std::string("expected a list of values or one of ") + k_kinds + ", found '" + d.kind + "'");
    const std::string at = "vary." + v.key + "." + d.kind;
    std::tie(d.a, d.b) = number_pair(v, d.kind, value.begin()->second);
    for (auto entry = std::next(value.begin()); entry != value.end(); ++entry) {
      const std::string option = entry->first.IsScalar() ? entry->first.Scalar() : flow(entry->first);
      if (!takes_shape_options(d.kind) || (option != "add" && option != "within")) {
        fail(v.mark, "vary." + v.key,
             takes_shape_options(d.kind)
                 ? "expected add or within beside " + d.kind + ", found '" + option + "'"
                 : "expected only " + d.kind +
                       ": [a, b] (add and within go with normal and log_normal), found '" + option + "'");
      }
      if (option == "within") {
        d.truncated = true;
        std::tie(d.low, d.high) = number_pair(v, "within", entry->second);
        if (!(d.low < d.high))
          fail(v.mark, "vary." + v.key + ".within", "expected low < high, found " + flow(entry->second));
      } else {
        try {
          d.add = entry->second.as<double>();
        } catch (const YAML::Exception&) {
          fail(v.mark, "vary." + v.key + ".add", "expected a number, found " + flow(entry->second));
        }
        if (!std::isfinite(d.add))
          fail(v.mark, "vary." + v.key + ".add", "expected a finite number, found " + flow(entry->second));
      }
    }
    if (takes_shape_options(d.kind)) {
      if (!(d.b >= 0.0))
        fail(v.mark, at, "expected a spread >= 0 as the second number, found " + flow(value.begin()->second));
      // A range the distribution hardly reaches would take endless redraws, and is a mistake.
      if (probability_within(d) < 1e-3) {
        fail(v.mark, "vary." + v.key + ".within",
             "expected a range holding at least 1/1000 of the draws, found one holding " +
                 std::to_string(probability_within(d)));
      }
      return;
    }
    if (!(d.a <= d.b) || (d.kind == "log_uniform" && d.a <= 0.0) ||
        (d.kind == "random_integer" && (d.a != std::floor(d.a) || d.b != std::floor(d.b)))) {
      fail(v.mark, at,
           "expected low <= high" + std::string(d.kind == "log_uniform" ? ", both > 0" : "") +
               std::string(d.kind == "random_integer" ? ", whole numbers" : "") + ", found " +
               flow(value.begin()->second));
    }
  }

  Variation read_variation(const std::string& key, const YAML::Node& value) const {
    Variation v;
    v.key = key;
    v.mark = value.Mark();
    // An empty key path (or one with an empty part) names no setting: it would vary nothing.
    if (key.empty() || key.front() == '.' || key.back() == '.' || key.find("..") != std::string::npos) {
      fail(v.mark, "vary." + key,
           k_key_path_expected +
               (key.empty() ? std::string("an empty key") : "an empty part in '" + key + "'"));
    }
    if (value.IsSequence()) {
      if (value.size() == 0) fail(v.mark, "vary." + key, "expected a non-empty list of values, found []");
      for (const auto& item : value)
        v.values.push_back(item);
      return v;
    }
    if (value.IsMap() && value.size() >= 1 && value.begin()->first.IsScalar()) {
      read_distribution(v, value);
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
    const YAML::Node deformation = root.IsMap() ? root["deformation"] : YAML::Node();
    YAML::Node loads = deformation.IsMap() ? deformation["loads"] : YAML::Node();
    if (loads.IsSequence()) {
      for (std::size_t i = 0; i < loads.size(); ++i) {
        YAML::Node load = loads[i];
        // Loads of another form are the scene check's to report.
        if (!load.IsMap() || !load["type"]) continue;
        if (!load["type"].IsScalar()) {
          fail_in_base(load["type"].Mark(), "deformation.loads[" + std::to_string(i) + "].type",
                       "expected one load type such as displacement, found " + flow(load["type"]));
        }
        if (load["type"].Scalar() != "displacement") continue;
        YAML::Node vector = load["displacement_mm"];
        if (!vector.IsSequence()) continue;
        for (std::size_t c = 0; c < vector.size(); ++c) {
          double component = 0.0;
          try {
            component = vector[c].as<double>();
          } catch (const YAML::Exception&) {
            fail_in_base(
                vector[c].Mark(),
                "deformation.loads[" + std::to_string(i) + "].displacement_mm[" + std::to_string(c) + "]",
                "expected a number in mm (vary.deformation.scale multiplies it), found " + shown(vector[c]));
          }
          vector[c] = component * scale;
        }
        found = true;
      }
    }
    if (!found) {
      fail(v.mark, "vary.deformation.scale",
           "expected a base scene with a displacement load to scale, found none in deformation.loads");
    }
  }

  void keep_sequences(YAML::Node root, const Variation& v, const YAML::Node& names) const {
    const YAML::Node sequences = root.IsMap() ? root["sequences"] : YAML::Node();
    if (!names.IsSequence()) {
      fail(v.mark, "vary.sequences",
           "expected lists of sequence names of the base scene, found " + flow(names));
    }
    if (!sequences.IsSequence()) {
      fail(v.mark, "vary.sequences",
           "expected a base scene with a list of sequences to choose from, found " +
               (!sequences.IsDefined() || sequences.IsNull() ? std::string("none") : flow(sequences)));
    }
    for (std::size_t i = 0; i < sequences.size(); ++i) {
      const YAML::Node sequence = sequences[i];
      if (!sequence.IsMap() || !sequence["name"] || !sequence["name"].IsScalar()) {
        fail_in_base(sequence.Mark(), "sequences[" + std::to_string(i) + "]",
                     "expected a mapping with a name (vary.sequences picks sequences by name), found " +
                         shown(sequence));
      }
    }
    YAML::Node kept(YAML::NodeType::Sequence);
    for (const auto& name : names) {
      if (!name.IsScalar()) {
        fail(v.mark, "vary.sequences",
             "expected lists of sequence names of the base scene, found " + flow(name) + " in " +
                 flow(names));
      }
      bool known = false;
      for (const auto& sequence : sequences) {
        if (sequence["name"].Scalar() == name.Scalar()) {
          kept.push_back(YAML::Clone(sequence));
          known = true;
        }
      }
      if (!known) {
        fail(v.mark, "vary.sequences",
             "expected names of the base scene's sequences, found '" + name.Scalar() + "'");
      }
    }
    root["sequences"] = kept;
  }

  /// Reads the sweep: its header, its variations and, as `depth` asks, its subjects.
  Sweep read(SweepDepth depth) {
    try {
      return read_checked(depth);
    } catch (const YAML::Exception& error) {
      // A value of a kind no reader above checked for: yaml-cpp's own words ("bad conversion",
      // "operator[] call on a scalar") would not tell the user what to write.
      fail(error.mark, "sweep",
           "expected a sweep as docs/batch.md describes it, found a value of another kind here (a list or "
           "mapping where one value belongs, or one value where a list or mapping belongs)");
    }
  }

  Sweep read_checked(SweepDepth depth) {
    const YAML::Node top = read_top();
    Sweep sweep;
    sweep.file = m_file;
    read_base_scene(top, &sweep);
    read_header_values(top, &sweep);
    const std::size_t count = read_variations(top, &sweep);
    m_width = std::max<int>(2, static_cast<int>(std::to_string(count).size()));
    sweep.subject_count = count;
    add_subjects(depth, count, &sweep);
    return sweep;
  }

  /// The sweep file's one YAML document, a mapping of the sweep's keys (phantasm_sweep: 1).
  YAML::Node read_top() {
    std::vector<YAML::Node> documents;
    std::string sweep_text;
    if (m_text)
      sweep_text = *m_text;
    else if (const std::string found = read_scene_text(m_file, sweep_text); !found.empty())
      throw InputError(m_file.string() + ": expected a sweep file, " + found);
    try {
      documents = load_yaml_documents(sweep_text);
    } catch (const YAML::Exception& error) {
      fail(error.mark, "sweep", "expected valid YAML, found " + error.msg);
    }
    if (documents.empty()) fail(YAML::Mark::null_mark(), "sweep", "expected a mapping, found an empty file");
    if (documents.size() > 1) {
      fail(documents[1].Mark(), "sweep",
           "expected one YAML document, found " + std::to_string(documents.size()) + " (a second '---')");
    }
    const YAML::Node top = documents.front();
    if (!top.IsMap()) fail(top.Mark(), "sweep", "expected a mapping, found " + flow(top));
    reject_duplicate_keys(top, "");
    if (!top["phantasm_sweep"] && top["phantasm"]) {
      fail(top["phantasm"].Mark(), "phantasm",
           "expected a sweep (phantasm_sweep: 1, docs/batch.md), found a scene; phantasm run runs a scene");
    }
    for (const auto& entry : top) {
      const std::string key = scalar(entry.first, "sweep");
      if (key != "phantasm_sweep" && key != "name" && key != "base_scene" && key != "seed" &&
          key != "repeats" && key != "vary") {
        fail(entry.first.Mark(), key,
             "expected one of phantasm_sweep, name, base_scene, seed, repeats, vary; found an unknown key");
      }
    }
    if (!top["phantasm_sweep"] || !top["phantasm_sweep"].IsScalar() ||
        top["phantasm_sweep"].Scalar() != "1") {
      fail(top.Mark(), "phantasm_sweep", "expected 'phantasm_sweep: 1' (the sweep format version)");
    }
    return top;
  }

  /// The base scene: its path (relative to the sweep) into `sweep`, its text read and checked to
  /// be one YAML document.
  void read_base_scene(const YAML::Node& top, Sweep* sweep) {
    if (!top["base_scene"]) fail(top.Mark(), "base_scene", "expected the path of the base scene, found none");
    sweep->base_scene = m_file.parent_path() / scalar(top["base_scene"], "base_scene");
    m_base_scene = sweep->base_scene;
    if (const std::string found = read_scene_text(sweep->base_scene, m_base_text); !found.empty()) {
      fail(top["base_scene"].Mark(), "base_scene",
           "expected a scene file, " + found + ": " + sweep->base_scene.string());
    }
    // The base scene's own mistakes are named in the base scene (each subject's scene is made
    // from its first document only, so a second one would be dropped without a word).
    try {
      const std::vector<YAML::Node> base = load_yaml_documents(m_base_text);
      if (base.size() > 1) {
        throw InputError(sweep->base_scene.string() + ":" + std::to_string(base[1].Mark().line + 1) + ":" +
                         std::to_string(base[1].Mark().column + 1) + ": expected one YAML document, found " +
                         std::to_string(base.size()) + " (a second '---')");
      }
    } catch (const YAML::Exception& base_error) {
      throw InputError(sweep->base_scene.string() + ":" + std::to_string(base_error.mark.line + 1) + ":" +
                       std::to_string(base_error.mark.column + 1) + ": expected valid YAML, found " +
                       base_error.msg);
    }
  }

  /// The sweep's name, seed and repeats.
  void read_header_values(const YAML::Node& top, Sweep* sweep) {
    sweep->name = top["name"] ? scalar(top["name"], "name") : m_file.stem().string();
    if (top["name"] && !is_safe_name(sweep->name))
      fail(top["name"].Mark(), "name",
           std::string("expected ") + k_safe_name_rule + ", found " + quote_name(sweep->name));
    try {
      if (top["seed"]) m_seed = top["seed"].as<std::uint64_t>();
    } catch (const YAML::Exception&) {
      fail(top["seed"].Mark(), "seed",
           "expected a whole number from 0 to 2^64 - 1, found " + flow(top["seed"]));
    }
    try {
      if (top["repeats"]) m_repeats = top["repeats"].as<int>();
    } catch (const YAML::Exception&) {
      fail(top["repeats"].Mark(), "repeats",
           "expected a whole number from 1 to 100000, found " + flow(top["repeats"]));
    }
    if (m_repeats < 1 || m_repeats > 100000)
      fail(top["repeats"].Mark(), "repeats", "expected 1 to 100000, found " + std::to_string(m_repeats));
  }

  /// The variations (vary), their keys into `sweep`; returns the number of subjects, bounded
  /// before anything is made (each factor is at most 10^6).
  std::size_t read_variations(const YAML::Node& top, Sweep* sweep) {
    if (top["vary"]) {
      if (!top["vary"].IsMap()) fail(top["vary"].Mark(), "vary", "expected a mapping of key paths to values");
      reject_duplicate_keys(top["vary"], "vary.");
      for (const auto& entry : top["vary"])
        m_variations.push_back(read_variation(scalar(entry.first, "vary"), entry.second));
    }
    std::size_t count = static_cast<std::size_t>(m_repeats);
    for (const auto& v : m_variations) {
      sweep->varied_keys.push_back(v.key);
      if (!v.values.empty()) count *= v.values.size();
      if (count > k_max_subjects)
        fail(top.Mark(), "vary",
             "expected at most 10^6 subjects, found more (" + std::to_string(count) + " so far)");
    }
    return count;
  }

  /// The subjects `depth` asks for: labels alone, a sample, or every subject made and checked.
  void add_subjects(SweepDepth depth, std::size_t count, Sweep* sweep) const {
    if (depth == SweepDepth::labels) {
      sweep->subjects.reserve(count);
      for (std::size_t s = 0; s < count; ++s)
        sweep->subjects.push_back(SweepSubject{label(s), {}, {}});
      return;
    }
    if (depth == SweepDepth::sample && count > k_checked_subjects) {
      // Every value of every list at least once, the first subjects (their random draws) and the
      // last: what `validate` answers in seconds for a sweep of any size.
      std::set<std::size_t> chosen;
      for (std::size_t s = 0; s < k_checked_subjects; ++s)
        chosen.insert(s);
      chosen.insert(count - 1);
      std::size_t stride = static_cast<std::size_t>(m_repeats);
      for (std::size_t k = m_variations.size(); k-- > 0;) {
        const std::size_t n = m_variations[k].values.size();
        if (n == 0) continue;
        for (std::size_t i = 0; i < n; ++i)
          chosen.insert(i * stride);
        stride *= n;
      }
      for (const std::size_t s : chosen)
        sweep->subjects.push_back(make_subject(*sweep, s));
      return;
    }
    for (std::size_t s = 0; s < count; ++s)
      sweep->subjects.push_back(make_subject(*sweep, s));
  }

  std::string label(std::size_t s) const {
    std::string id = std::to_string(s + 1);
    id.insert(0, static_cast<std::size_t>(m_width) - id.size(), '0');
    return id;
  }

  /// Subject s: the base scene with its values set, checked as `phantasm validate` would.
  SweepSubject make_subject(const Sweep& sweep, std::size_t s) const {
    SweepSubject subject;
    subject.id = label(s);
    YAML::Node scene = YAML::Load(m_base_text);
    std::size_t combination = s / static_cast<std::size_t>(m_repeats);
    // The grid index of each list, the last list fastest.
    std::vector<std::size_t> choice(m_variations.size(), 0);
    for (std::size_t k = m_variations.size(); k-- > 0;) {
      if (m_variations[k].values.empty()) continue;
      choice[k] = combination % m_variations[k].values.size();
      combination /= m_variations[k].values.size();
    }
    for (std::size_t k = 0; k < m_variations.size(); ++k) {
      const Variation& v = m_variations[k];
      YAML::Node value;
      if (!v.values.empty()) {
        value = v.values[choice[k]];
      } else {
        std::ostringstream text;
        text.precision(6);
        const double drawn = draw_value(v.random, m_seed, s, k);
        if (v.random.kind == "random_integer")
          text << static_cast<long long>(drawn);
        else
          text << drawn;
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
      std::vector<Diagnostic> problems = checked.problems;
      for (Diagnostic& problem : problems)
        place(problem);
      throw InputError(m_file.string() + ": subject " + subject.id + " (" + values +
                       ") gives a scene that does not validate:\n" + format_diagnostics(problems));
    }
    return subject;
  }

  /// Points a problem of a subject's scene at a line the user wrote: the subject's scene is
  /// emitted anew (its lines are not the base scene's), so a problem at a varied key is placed at
  /// the key in the sweep file, any other at the key (or the nearest enclosing one) in the base
  /// scene.
  void place(Diagnostic& problem) const {
    const std::string& path = problem.key_path;
    const Variation* varied = nullptr;
    for (const Variation& v : m_variations) {
      const bool under =
          path == v.key || (path.size() > v.key.size() && path.compare(0, v.key.size(), v.key) == 0 &&
                            (path[v.key.size()] == '.' || path[v.key.size()] == '['));
      if (under && (!varied || v.key.size() > varied->key.size())) varied = &v;
    }
    if (varied && varied->mark.line >= 0) {
      problem.where = SourceLocation{m_file.string(), varied->mark.line + 1, varied->mark.column + 1};
      return;
    }
    problem.where = SourceLocation{m_base_scene.string(), 0, 0};
    if (path.empty()) return;
    YAML::Node node = YAML::Load(m_base_text);
    YAML::Mark mark = node.Mark();
    static const std::regex element(R"(([^.\[\]]+)|\[([0-9]{1,9})\])");
    for (std::sregex_iterator it(path.begin(), path.end(), element), end; it != end; ++it) {
      YAML::Node child;
      if ((*it)[1].matched && node.IsMap()) {
        child = node[(*it)[1].str()];
      } else if ((*it)[2].matched && node.IsSequence()) {
        const std::size_t index = std::stoul((*it)[2].str()); // at most 9 digits
        if (index < node.size()) child = node[index];
      }
      if (!child.IsDefined()) break;
      node.reset(child);
      mark = node.Mark();
    }
    if (mark.line >= 0) {
      problem.where.line = mark.line + 1;
      problem.where.column = mark.column + 1;
    }
  }

  /// A scalar's text; anything else is named at its line.
  std::string scalar(const YAML::Node& node, const std::string& key) const {
    if (!node.IsScalar())
      fail(node.Mark(), key, "expected a single value (text or number), found " + flow(node));
    return node.Scalar();
  }

  /// yaml-cpp keeps both entries of a key given twice (and lookups see only the first).
  void reject_duplicate_keys(const YAML::Node& map, const std::string& prefix) const {
    std::set<std::string> seen;
    for (const auto& entry : map) {
      const std::string key =
          scalar(entry.first, prefix.empty() ? "sweep" : prefix.substr(0, prefix.size() - 1));
      if (!seen.insert(key).second)
        fail(entry.first.Mark(), prefix + key, "expected each key once, found it a second time");
    }
  }

private:
  static constexpr std::size_t k_max_subjects = 1000000;
  /// Above this many subjects `validate` checks a sample (SweepDepth::sample).
  static constexpr std::size_t k_checked_subjects = 1000;

  std::filesystem::path m_file;
  const std::string* m_text = nullptr;
  std::filesystem::path m_base_scene;
  std::string m_base_text;
  std::vector<Variation> m_variations;
  std::uint64_t m_seed = 0;
  int m_repeats = 1;
  int m_width = 2;
};

} // namespace

bool is_sweep_text(const std::string& text) {
  // A UTF-8 byte-order mark (some editors write one) comes before the first key, not in it.
  const std::string_view bom = "\xef\xbb\xbf";
  std::istringstream in(text.compare(0, bom.size(), bom) == 0 ? text.substr(bom.size()) : text);
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("phantasm_sweep:", 0) == 0) return true;
  return false;
}

bool is_sweep_file(const std::filesystem::path& file) {
  std::string text;
  if (!read_scene_text(file, text).empty()) return false; // load_scene says why
  return is_sweep_text(text);
}

Sweep load_sweep(const std::filesystem::path& file, SweepDepth depth) {
  return SweepReader(file).read(depth);
}

Sweep parse_sweep(const std::string& text, const std::filesystem::path& file, SweepDepth depth) {
  return SweepReader(file, &text).read(depth);
}

std::string scene_text_with_value(const std::string& scene_text, const std::string& key,
                                  const std::string& value_yaml) {
  const SweepReader reader{std::filesystem::path()};
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
