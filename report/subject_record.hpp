// What a subject's report shows, read back from the dataset a run wrote: provenance, log,
// scene, label table, landmarks, and pictures of its volumes (images, labels, fields).
#pragma once

#include "core/stage_report.hpp"
#include "report/slice_pictures.hpp"

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace phantasm {

/// One image of both states, as pictures of its middle slices (PNG bytes).
struct ImagePictures {
  std::string name; ///< the file suffix: "T1w", ..., or "dseg" when the run made no images
  std::string reference_png, deformed_png;
};

/// A landmark in both states (RAS mm).
struct LandmarkMove {
  std::string name, organ;
  Eigen::Vector3d reference_mm = Eigen::Vector3d::Zero(), deformed_mm = Eigen::Vector3d::Zero();
};

/// A label of dseg.tsv and its voxels in each state.
struct LabelVolume {
  std::string name, tissue;
  std::array<std::int64_t, 2> voxels{0, 0}; ///< reference, deformed
};

/// A colour overlay on the reference grid with its scale.
struct Overlay {
  std::string png;
  ColourScale scale;
};

/// Everything a subject's report shows, read from its files.
struct SubjectRecord {
  std::string subject;
  nlohmann::json provenance;
  std::string scene_text;             ///< the scene file as run (scene.yaml beside provenance.json)
  std::vector<std::string> log_lines; ///< log.txt
  Eigen::Vector3i dims = Eigen::Vector3i::Zero();
  Eigen::Vector3d spacing_mm = Eigen::Vector3d::Zero();
  std::vector<ImagePictures> images;
  /// the run wrote the reference state only (nothing deforms): each picture's deformed side is the
  /// reference's, and there are no landmark moves
  bool reference_only = false;
  std::string reference_contours_png, deformed_contours_png; ///< empty without labels
  std::optional<Overlay> displacement;                       ///< |u| of from-def_to-ref, mm
  std::optional<Overlay> jacobian;                           ///< det(I + grad u) of from-def_to-ref
  double largest_displacement_mm = 0.0;
  double smallest_jacobian = 0.0;
  std::int64_t nonpositive_jacobian_voxels = 0;
  std::map<std::int32_t, LabelVolume> labels; ///< by dseg index (background left out)
  std::vector<LandmarkMove> landmarks;
  std::vector<StageTiming> timings; ///< empty when the run's times were not recorded
};

/// Where the run's stage times are kept: derivatives/phantasm/sub-<id>/timing.json (the one file
/// of a subject, with its report, that differs from run to run).
std::filesystem::path timing_path(const std::filesystem::path& dataset, const std::string& subject);

/// Writes the stage times (timing_path), atomically.
void write_timings(const std::filesystem::path& dataset, const std::string& subject,
                   const std::vector<StageTiming>& timings);

/// A text file of the dataset, whole.
/// @param what what the file should hold, named in the message
/// @throws InputError naming the file when it cannot be read
std::string read_dataset_text(const std::filesystem::path& file, const char* what);

/// The stage times of a subject's run (timing_path); empty when they were not recorded.
/// @throws InputError naming the file when it is damaged
std::vector<StageTiming> read_stage_timings(const std::filesystem::path& dataset, const std::string& subject);

/// Reads a complete subject (provenance.json present) and makes its pictures.
/// @throws InputError naming the file that is missing or damaged (a file provenance.json lists,
///         a table that does not parse, volumes on different grids)
SubjectRecord read_subject_record(const std::filesystem::path& dataset, const std::string& subject);

} // namespace phantasm
