// Small helpers the evaluation's reports share: summaries and numbers as JSON, and a whole file
// read with a message naming it.
#pragma once

#include "core/error.hpp"
#include "core/path_kind.hpp"
#include "evaluation/registration_metrics.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace phantasm {

inline nlohmann::json summary_json(const Summary& s) {
  // An empty set has no statistics: null, not the zeros of an empty Summary (a task pair without
  // keypoints would otherwise score a TRE of 0).
  if (s.count == 0)
    return {{"count", 0}, {"mean", nullptr}, {"sd", nullptr}, {"p95", nullptr}, {"max", nullptr}};
  return {{"count", s.count}, {"mean", s.mean}, {"sd", s.sd}, {"p95", s.p95}, {"max", s.max}};
}

/// A finite number, or null (JSON has no NaN or infinity).
inline nlohmann::json number_or_null(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json();
}

/// The bytes of a file.
/// @param what what the file should be, for the message ("the task's dataset JSON")
/// @throws InputError naming the file when it is not a readable regular file
inline std::string whole_file(const std::filesystem::path& path, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  if (!in || path_kind(path) != "a regular file")
    throw InputError(path.string() + ": expected " + what + ", found " + path_kind(path));
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

} // namespace phantasm
