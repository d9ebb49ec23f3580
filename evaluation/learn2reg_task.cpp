#include "evaluation/learn2reg_task.hpp"

#include "core/error.hpp"
#include "core/path_kind.hpp"
#include "core/sha256.hpp"
#include "evaluation/evaluation_json.hpp"
#include "evaluation/field_conventions.hpp"
#include "io/atomic_file.hpp"
#include "io/dataset_layout.hpp"
#include "io/dataset_tables.hpp"
#include "io/json_file.hpp"
#include "io/nifti_file.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>

namespace phantasm {
namespace {

std::string four_digits(int value) {
  char text[16];
  std::snprintf(text, sizeof text, "%04d", value);
  return text;
}

/// The contrasts (BIDS suffixes: T1w, T2w, FLAIR, ...) a subject's reference session holds.
std::vector<std::string> contrasts(const DatasetLayout& layout) {
  const std::filesystem::path example = layout.anat_image(PhantomState::reference, "X");
  const std::string prefix = example.filename().string().substr(0, example.filename().string().size() - 8);
  std::vector<std::string> found;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(example.parent_path(), error)) {
    const std::string name = entry.path().filename().string();
    if (name.size() > prefix.size() + 7 && name.rfind(prefix, 0) == 0 &&
        name.compare(name.size() - 7, 7, ".nii.gz") == 0)
      found.push_back(name.substr(prefix.size(), name.size() - prefix.size() - 7));
  }
  std::sort(found.begin(), found.end());
  return found;
}

std::string choose_contrast(const std::string& requested, const std::vector<std::string>& available,
                            const std::string& option, const std::filesystem::path& where) {
  std::string list;
  for (const auto& c : available)
    list += (list.empty() ? "" : ", ") + c;
  if (available.empty())
    throw InputError(where.string() + ": expected the subject's images (sub-<id>_ses-ref_<contrast>.nii.gz), "
                                      "found none");
  if (requested.empty())
    return std::find(available.begin(), available.end(), "T1w") != available.end() ? "T1w"
                                                                                   : available.front();
  if (std::find(available.begin(), available.end(), requested) == available.end())
    throw InputError(option + ": expected a contrast of the dataset (" + list + "), found '" + requested +
                     "'");
  return requested;
}

void require_grid(const ImageGrid& expected, const ImageGrid& found, const std::filesystem::path& path,
                  const std::filesystem::path& expected_path) {
  const double mismatch = (expected.world_from_voxel - found.world_from_voxel).cwiseAbs().maxCoeff();
  if (expected.dims != found.dims || mismatch > 1e-3) {
    throw InputError(path.string() + ": expected the grid of " + expected_path.string() +
                     " (a Learn2Reg pair shares one grid), found another size or affine");
  }
}

std::string keypoint_row(const Eigen::Vector3d& ijk) {
  char text[96];
  std::snprintf(text, sizeof text, "%.6f,%.6f,%.6f", ijk.x(), ijk.y(), ijk.z());
  return text;
}

/// Points of both states matched by name, in the fixed file's order (those of one state only are
/// left out), in voxel coordinates of each grid.
struct CorrespondingPoints {
  std::vector<std::string> names, organs;
  std::vector<Eigen::Vector3d> fixed, moving;
};

CorrespondingPoints corresponding_points(const std::filesystem::path& fixed_file,
                                         const std::filesystem::path& moving_file,
                                         const ImageGrid& fixed_grid, const ImageGrid& moving_grid) {
  CorrespondingPoints out;
  std::map<std::string, Eigen::Vector3d> moving_by_name;
  for (const auto& row : read_landmarks(moving_file))
    moving_by_name[row.name] = row.ras_mm;
  for (const auto& row : read_landmarks(fixed_file)) {
    const auto found = moving_by_name.find(row.name);
    if (found == moving_by_name.end()) continue;
    out.names.push_back(row.name);
    out.organs.push_back(row.organ);
    out.fixed.push_back(fixed_grid.index_from_world(row.ras_mm));
    out.moving.push_back(moving_grid.index_from_world(found->second));
  }
  return out;
}

/// Everything one pair needs, read and checked before anything is written.
struct PairInputs {
  PairInputs(TaskPair p, DatasetLayout l) : pair(std::move(p)), layout(std::move(l)) {}
  TaskPair pair;
  DatasetLayout layout;
  ImageGrid grid;
  std::vector<std::int32_t> fixed_labels, moving_labels;
  std::filesystem::path fixed_image, moving_image;
  CorrespondingPoints landmarks;
  std::optional<CorrespondingPoints> dense; ///< the dense landmarks, when the dataset has them
  DisplacementField truth;
  std::filesystem::path truth_mask;
};

PairInputs read_pair(const std::filesystem::path& dataset, const std::string& subject, int case_index,
                     const std::string& fixed_contrast, const std::string& moving_contrast) {
  PairInputs in{{case_index, subject, four_digits(case_index) + "_0000", four_digits(case_index) + "_0001"},
                DatasetLayout(dataset, subject)};
  const DatasetLayout& layout = in.layout;
  in.fixed_image = layout.anat_image(PhantomState::reference, fixed_contrast);
  in.moving_image = layout.anat_image(PhantomState::deformed, moving_contrast);
  for (const auto& image : {in.fixed_image, in.moving_image})
    if (path_kind(image) != "a regular file")
      throw InputError(image.string() + ": expected the image of the pair, found " + path_kind(image));
  in.fixed_labels = read_nifti_labels(layout.dseg(PhantomState::reference), &in.grid);
  ImageGrid moving_grid;
  in.moving_labels = read_nifti_labels(layout.dseg(PhantomState::deformed), &moving_grid);
  require_grid(in.grid, moving_grid, layout.dseg(PhantomState::deformed),
               layout.dseg(PhantomState::reference));
  for (const auto& image : {in.fixed_image, in.moving_image})
    require_grid(in.grid, read_nifti(image).grid, image, layout.dseg(PhantomState::reference));

  in.landmarks = corresponding_points(layout.landmarks(PhantomState::reference),
                                      layout.landmarks(PhantomState::deformed), in.grid, moving_grid);
  // A dataset written without dense landmarks (outputs.dense_landmarks: 0, or before they existed)
  // has no such files: its task has none.
  std::error_code error;
  if (std::filesystem::exists(layout.dense_landmarks(PhantomState::reference), error))
    in.dense = corresponding_points(layout.dense_landmarks(PhantomState::reference),
                                    layout.dense_landmarks(PhantomState::deformed), in.grid, moving_grid);

  // The truth on the fixed (reference) grid: the field that brings the moving (deformed) image there.
  const std::filesystem::path field_path = layout.transform(PhantomState::deformed, PhantomState::reference);
  in.truth = read_field(field_path, FieldConvention::itk, in.grid);
  require_grid(in.grid, in.truth.grid, field_path, layout.dseg(PhantomState::reference));
  in.truth_mask = layout.transform_mask(PhantomState::deformed, PhantomState::reference);
  require_grid(in.grid, read_nifti(in.truth_mask).grid, in.truth_mask, layout.dseg(PhantomState::reference));
  return in;
}

/// A sweep's varied values per subject, from the participants.tsv a batch writes (participant_id
/// and a column per variation); none for a dataset without it.
std::map<std::string, nlohmann::json> sweep_factors(const std::filesystem::path& path) {
  std::map<std::string, nlohmann::json> factors;
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) return factors;
  std::istringstream in(whole_file(path, "the sweep's participants table"));
  auto cells = [](const std::string& line) {
    std::vector<std::string> fields;
    std::istringstream text(line);
    for (std::string cell; std::getline(text, cell, '\t');)
      fields.push_back(cell.empty() || cell.back() != '\r' ? cell : cell.substr(0, cell.size() - 1));
    return fields;
  };
  std::string line;
  if (!std::getline(in, line)) return factors;
  const std::vector<std::string> header = cells(line);
  while (std::getline(in, line)) {
    const std::vector<std::string> row = cells(line);
    if (row.empty() || row.front().rfind("sub-", 0) != 0) continue;
    nlohmann::json values = nlohmann::json::object();
    for (std::size_t c = 1; c < row.size() && c < header.size(); ++c)
      values[header[c]] = row[c];
    factors[row.front().substr(4)] = values;
  }
  return factors;
}

void require_new_or_empty(const std::filesystem::path& folder, const std::string& option) {
  std::error_code error;
  if (!std::filesystem::exists(folder, error)) return;
  if (!std::filesystem::is_directory(folder, error))
    throw InputError(option + ": expected a new or empty folder, found " + path_kind(folder) + " at " +
                     folder.string());
  if (!std::filesystem::is_empty(folder, error))
    throw InputError(option + ": expected a new or empty folder, found " + folder.string() +
                     " holding files (remove it, or choose another)");
}

void require_task_name(const std::string& name) {
  if (name.empty() || name.size() > 32 || std::any_of(name.begin(), name.end(), [](char c) {
        return !std::isalnum(static_cast<unsigned char>(c));
      })) {
    throw InputError(
        "--name: expected 1 to 32 ASCII letters and digits (Learn2Reg splits file names at '_'), "
        "found '" +
        name + "'");
  }
}

/// The dataset's complete subjects, one case each (four-digit case numbers).
std::vector<std::string> task_subjects(const std::filesystem::path& dataset) {
  const std::vector<std::string> subjects = complete_subjects(dataset);
  if (subjects.empty()) {
    throw InputError(dataset.string() + ": expected a phantasm dataset with a complete subject "
                                        "(derivatives/phantasm/sub-<id>/provenance.json), found none");
  }
  if (subjects.size() > 9999)
    throw InputError(dataset.string() +
                     ": expected at most 9999 subjects (four-digit case numbers), "
                     "found " +
                     std::to_string(subjects.size()));
  return subjects;
}

/// Refuses a truth folder inside the task folder or the other way round (a method must not see
/// the truth).
void require_truth_apart(const TaskRequest& request) {
  // Compared by path components ("out/" and "out" are one folder; "out2" is not inside "out").
  auto components = [](const std::filesystem::path& p) {
    std::vector<std::filesystem::path> parts;
    for (const std::filesystem::path& part : std::filesystem::absolute(p).lexically_normal())
      if (!part.empty()) parts.push_back(part);
    return parts;
  };
  const std::vector<std::filesystem::path> task_parts = components(request.task),
                                           truth_parts = components(request.truth);
  const std::size_t common = std::min(task_parts.size(), truth_parts.size());
  if (std::equal(task_parts.begin(), task_parts.begin() + static_cast<std::ptrdiff_t>(common),
                 truth_parts.begin())) {
    throw InputError(
        "--truth: expected a folder apart from the task (a method must not see the truth), found " +
        request.truth.string() + " and " + request.task.string());
  }
}

/// A file of the task, relative to its folder: ./<folder>/<name>_<id><extension>.
std::string task_file(const char* folder, const std::string& name, const std::string& id,
                      const char* extension) {
  return std::string("./") + folder + "/" + name + "_" + id + extension;
}

/// Writes a pair's image, labels, mask and keypoints of both states into the task, adding them to
/// `training` and the pair to `paired`.
void write_task_pair(const std::filesystem::path& task, const std::string& name, const PairInputs& p,
                     nlohmann::json* training, nlohmann::json* paired) {
  const std::pair<std::string, PhantomState> states[2] = {{p.pair.fixed_id, PhantomState::reference},
                                                          {p.pair.moving_id, PhantomState::deformed}};
  for (const auto& [id, state] : states) {
    const bool fixed = state == PhantomState::reference;
    write_file_atomically(task / task_file("imagesTr", name, id, ".nii.gz"),
                          whole_file(fixed ? p.fixed_image : p.moving_image, "a file of the dataset"));
    write_file_atomically(task / task_file("labelsTr", name, id, ".nii.gz"),
                          whole_file(p.layout.dseg(state), "a file of the dataset"));
    const std::vector<std::int32_t>& labels = fixed ? p.fixed_labels : p.moving_labels;
    std::vector<std::int32_t> mask(labels.size());
    for (std::size_t v = 0; v < labels.size(); ++v)
      mask[v] = labels[v] > 0 ? 1 : 0;
    write_nifti_labels(task / task_file("masksTr", name, id, ".nii.gz"), p.grid, mask);
    std::string csv;
    for (const auto& point : fixed ? p.landmarks.fixed : p.landmarks.moving)
      csv += keypoint_row(point) + "\n";
    write_file_atomically(task / task_file("keypointsTr", name, id, ".csv"), csv);
    training->push_back({{"image", task_file("imagesTr", name, id, ".nii.gz")},
                         {"label", task_file("labelsTr", name, id, ".nii.gz")},
                         {"mask", task_file("masksTr", name, id, ".nii.gz")},
                         {"keypoints", task_file("keypointsTr", name, id, ".csv")}});
  }
  paired->push_back({{"fixed", task_file("imagesTr", name, p.pair.fixed_id, ".nii.gz")},
                     {"moving", task_file("imagesTr", name, p.pair.moving_id, ".nii.gz")}});
}

/// Writes a pair's true field, mask and keypoints into the truth folder; returns its entry of truth.json.
nlohmann::json write_truth_pair(const std::filesystem::path& truth, const std::string& name,
                                const PairInputs& p, const std::map<std::string, nlohmann::json>& factors) {
  const std::string stem = p.pair.fixed_id + "_" + p.pair.moving_id;
  write_field(truth / learn2reg_result_name(p.pair), p.truth, FieldConvention::learn2reg);
  write_file_atomically(truth / ("mask_" + stem + ".nii.gz"),
                        whole_file(p.truth_mask, "a file of the dataset"));
  std::string csv = "name,fixed_i,fixed_j,fixed_k,moving_i,moving_j,moving_k\n";
  const CorrespondingPoints& l = p.landmarks;
  for (std::size_t r = 0; r < l.names.size(); ++r)
    csv += l.names[r] + "," + keypoint_row(l.fixed[r]) + "," + keypoint_row(l.moving[r]) + "\n";
  write_file_atomically(truth / ("keypoints_" + stem + ".csv"), csv);
  nlohmann::json entry = {
      {"case", p.pair.case_index},
      {"subject", p.pair.subject},
      {"fixed", task_file("imagesTr", name, p.pair.fixed_id, ".nii.gz")},
      {"moving", task_file("imagesTr", name, p.pair.moving_id, ".nii.gz")},
      {"fixed_id", p.pair.fixed_id},
      {"moving_id", p.pair.moving_id},
      {"result", learn2reg_result_name(p.pair)},
      {"displacement", learn2reg_result_name(p.pair)},
      {"mask", "mask_" + stem + ".nii.gz"},
      {"keypoints", "keypoints_" + stem + ".csv"},
      {"factors", factors.count(p.pair.subject) ? factors.at(p.pair.subject) : nlohmann::json::object()}};
  if (p.dense) {
    std::string dense = "name,organ,fixed_i,fixed_j,fixed_k,moving_i,moving_j,moving_k\n";
    for (std::size_t r = 0; r < p.dense->names.size(); ++r)
      dense += p.dense->names[r] + "," + p.dense->organs[r] + "," + keypoint_row(p.dense->fixed[r]) + "," +
               keypoint_row(p.dense->moving[r]) + "\n";
    write_file_atomically(truth / ("dense_keypoints_" + stem + ".csv"), dense);
    entry["dense_keypoints"] = "dense_keypoints_" + stem + ".csv";
  }
  return entry;
}

/// The task's <name>_dataset.json (Learn2Reg's description of a task).
nlohmann::json task_dataset_json(const std::string& name, const std::string& fixed_contrast,
                                 const std::string& moving_contrast, const nlohmann::json& labels,
                                 const std::vector<int>& dims, const nlohmann::json& training,
                                 const nlohmann::json& paired) {
  return {
      {"name", name},
      {"release", "1.0"},
      {"description", "Registration pairs of a phantasm dataset: each subject's reference state (fixed, " +
                          fixed_contrast + ") and deformed state (moving, " + moving_contrast + ")"},
      {"licence", "as the source dataset"},
      {"reference", "phantasm"},
      {"pairings", "paired"},
      {"provided_data",
       {{"0", {"image", "label", "mask", "keypoints"}}, {"1", {"image", "label", "mask", "keypoints"}}}},
      {"registration_direction", {{"fixed", 0}, {"moving", 1}}},
      {"modality", {{"0", "MR " + fixed_contrast}, {"1", "MR " + moving_contrast}}},
      {"img_shift", {{"fixed", "0000"}, {"moving", "0001"}}},
      {"labels", {{"0", labels}, {"1", labels}}},
      {"tensorImageSize", {{"0", "3D"}, {"1", "3D"}}},
      {"tensorImageShape", {{"0", dims}, {"1", dims}}},
      {"numTraining", training.size()},
      {"numTest", 0},
      {"training", training},
      {"test", nlohmann::json::array()},
      {"numPairedTraining", paired.size()},
      {"training_paired_images", paired},
      {"numRegistration_val", paired.size()},
      {"registration_val", paired},
      {"numRegistration_test", 0},
      {"registration_test", nlohmann::json::array()}};
}

} // namespace

std::string learn2reg_result_name(const TaskPair& pair) {
  return "disp_" + pair.fixed_id + "_" + pair.moving_id + ".nii.gz";
}

nlohmann::json make_learn2reg_task(const TaskRequest& request) {
  const std::string& name = request.name;
  require_task_name(name);
  const std::vector<std::string> subjects = task_subjects(request.dataset);
  const std::filesystem::path task = std::filesystem::absolute(request.task).lexically_normal();
  const std::filesystem::path truth = std::filesystem::absolute(request.truth).lexically_normal();
  require_truth_apart(request);
  require_new_or_empty(request.task, "-o");
  require_new_or_empty(request.truth, "--truth");

  const DatasetLayout first(request.dataset, subjects.front());
  const std::vector<std::string> available = contrasts(first);
  const std::filesystem::path anat = first.anat_image(PhantomState::reference, "X").parent_path();
  const std::string fixed_contrast =
      choose_contrast(request.fixed_contrast, available, "--fixed-contrast", anat);
  const std::string moving_contrast =
      choose_contrast(request.moving_contrast.empty() ? fixed_contrast : request.moving_contrast, available,
                      "--moving-contrast", anat);
  const std::map<std::int32_t, std::string> label_names = read_label_names(first.dseg_table());

  std::vector<PairInputs> pairs;
  for (std::size_t s = 0; s < subjects.size(); ++s)
    pairs.push_back(
        read_pair(request.dataset, subjects[s], static_cast<int>(s) + 1, fixed_contrast, moving_contrast));
  const Eigen::Vector3i shape = pairs.front().grid.dims;
  for (const auto& p : pairs)
    if (p.grid.dims != shape)
      throw InputError(
          p.layout.dseg(PhantomState::reference).string() +
          ": expected the grid size of every other subject (a Learn2Reg task has one tensor shape)");

  const std::map<std::string, nlohmann::json> factors = sweep_factors(request.dataset / "participants.tsv");

  // Everything read: write.
  for (const char* folder : {"imagesTr", "labelsTr", "masksTr", "keypointsTr"})
    std::filesystem::create_directories(task / folder);
  std::filesystem::create_directories(truth);
  nlohmann::json training = nlohmann::json::array(), paired = nlohmann::json::array();
  nlohmann::json truth_pairs = nlohmann::json::array();
  for (const PairInputs& p : pairs) {
    write_task_pair(task, name, p, &training, &paired);
    truth_pairs.push_back(write_truth_pair(truth, name, p, factors));
  }

  nlohmann::json labels = nlohmann::json::object();
  labels["0"] = "background";
  for (const auto& [index, label_name] : label_names)
    labels[std::to_string(index)] = label_name;
  const std::vector<int> dims = {shape.x(), shape.y(), shape.z()};
  const std::filesystem::path dataset_json_path = task / (name + "_dataset.json");
  write_json_file(dataset_json_path,
                  task_dataset_json(name, fixed_contrast, moving_contrast, labels, dims, training, paired));

  const nlohmann::json truth_json = {
      {"task", name},
      {"dataset", std::filesystem::absolute(request.dataset).lexically_normal().string()},
      {"dataset_json", dataset_json_path.filename().string()},
      {"dataset_json_sha256", sha256_hex(whole_file(dataset_json_path, "a file of the dataset"))},
      {"fixed_contrast", fixed_contrast},
      {"moving_contrast", moving_contrast},
      {"tensorImageShape", dims},
      {"labels", labels},
      {"pairs", truth_pairs},
      {"conventions",
       {{"displacement", "Learn2Reg: (X, Y, Z, 3) float32 on the fixed grid, voxels along i, j, k; the fixed "
                         "voxel x is carried to x + u(x) in the moving image"},
        {"mask", "voxels where the displacement is exact (inside the organs in both states)"},
        {"keypoints",
         "corresponding landmarks, voxel coordinates (i, j, k) of the fixed and the moving image"},
        {"dense_keypoints",
         "the dataset's dense landmarks (seeded material points of each organ, with the organ), "
         "voxel coordinates of both images; pairs of a dataset without them have none"}}}};
  write_json_file(truth / "truth.json", truth_json);
  return {{"task", task.string()}, {"truth", truth.string()}, {"pairs", truth_pairs}};
}

} // namespace phantasm
