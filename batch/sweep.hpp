// Sweep files: a base scene and what varies (grids of values, seeded random ranges), expanded
// into subjects with their BIDS labels and scenes, and split into shards.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace phantasm {

/// One subject of a sweep: its BIDS label, the values it was given, and its scene.
struct SweepSubject {
  std::string id;                                          ///< zero-padded index, e.g. "007"
  std::vector<std::pair<std::string, std::string>> values; ///< varied key -> value (YAML flow text)
  std::string scene_text;                                  ///< the base scene with the values set
};

/// A sweep file (docs/batch.md): a base scene and what varies, expanded into subjects.
/// Lists form a grid (every combination, the last key fastest), each combination `repeats`
/// times; random ranges ({uniform: [a, b]}, {log_uniform: [a, b]}, {random_integer: [a, b]})
/// are drawn per subject from the sweep's seed, the subject's index and the key, so a subject
/// is the same whichever shard or job makes it.
struct Sweep {
  std::filesystem::path file;
  std::filesystem::path base_scene; ///< anchors the subjects' relative paths
  std::string name;
  std::vector<std::string> varied_keys;
  std::size_t subject_count = 0; ///< every subject of the sweep, also when `subjects` holds a sample
  std::vector<SweepSubject> subjects;
};

/// How much of a sweep load_sweep makes.
enum class SweepDepth {
  full,   ///< every subject with its scene, each checked (batch)
  labels, ///< every subject's label only, no scene made (batch --list): seconds for 10^6 subjects
  sample, ///< every subject up to 1000; beyond, a sample: the first 1000, the last, and each value
          ///< of each list at least once, each checked (validate)
};

/// True when the text is a sweep's (a line starting "phantasm_sweep:").
bool is_sweep_text(const std::string& text);

/// True when a YAML file is a sweep (its text has a top-level `phantasm_sweep:` key).
bool is_sweep_file(const std::filesystem::path& file);

/// Reads a sweep and, as `depth` asks, makes and checks its subjects' scenes (as `phantasm
/// validate` would). The subject count is bounded (10^6) before any subject is made.
/// @throws InputError naming the sweep file, line and key, or the subject and its scene problem
Sweep load_sweep(const std::filesystem::path& file, SweepDepth depth = SweepDepth::full);

/// load_sweep of a sweep file's text, read by the caller; `file` names it in messages and
/// anchors its relative paths.
Sweep parse_sweep(const std::string& text, const std::filesystem::path& file,
                  SweepDepth depth = SweepDepth::full);

/// The i-th of N disjoint slices of a sweep ("2/3"): subjects whose index modulo N is i - 1.
struct Shard {
  int index = 1;
  int count = 1;
  bool holds(std::size_t subject_index) const {
    return static_cast<int>(subject_index % static_cast<std::size_t>(count)) == index - 1;
  }
};

/// Parses "i/N" with 1 <= i <= N. @throws InputError otherwise
Shard parse_shard(const std::string& text);

/// A scene's text with one key path set to a value given as YAML text, exactly as a sweep sets
/// it (docs/batch.md: dotted keys, [index], deformation.scale, sequences).
/// @throws InputError naming the key when the path does not fit the scene
std::string scene_text_with_value(const std::string& scene_text, const std::string& key,
                                  const std::string& value_yaml);

/// participants.tsv of a sweep: one row per subject with its varied values.
std::string participants_tsv(const Sweep& sweep);

} // namespace phantasm
