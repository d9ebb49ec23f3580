#include "evaluation/evaluate_registration.hpp"

#include "core/cancellation.hpp"
#include "core/error.hpp"
#include "core/format.hpp"
#include "core/path_kind.hpp"
#include "core/sha256.hpp"
#include "evaluation/evaluation_json.hpp"
#include "evaluation/registration_metrics.hpp"
#include "evaluation/score_task.hpp"
#include "io/dataset_layout.hpp"
#include "io/dataset_tables.hpp"
#include "io/json_file.hpp"
#include "io/nifti_file.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>

namespace phantasm {
namespace {

/// The subject to evaluate: `requested` when the dataset holds it complete, else the only one.
std::string find_subject(const std::filesystem::path& dataset, const std::string& requested) {
  const std::vector<std::string> subjects = complete_subjects(dataset);
  if (!requested.empty()) {
    if (std::find(subjects.begin(), subjects.end(), requested) != subjects.end()) return requested;
    std::string list;
    for (const auto& s : subjects)
      list += (list.empty() ? "" : ", ") + s;
    throw InputError("--subject: expected a complete subject of " + dataset.string() + " (" +
                     (list.empty() ? std::string("it holds none") : list) + "), found " + requested);
  }
  if (subjects.empty()) {
    throw InputError(dataset.string() + ": expected a phantasm dataset with a complete subject "
                                        "(derivatives/phantasm/sub-<id>/provenance.json), found none");
  }
  if (subjects.size() > 1) {
    std::string list;
    for (const auto& s : subjects)
      list += (list.empty() ? "" : ", ") + s;
    throw InputError(dataset.string() + ": expected --subject with a dataset of several subjects, found " +
                     list);
  }
  return subjects.front();
}

void require_same_grid(const ImageGrid& expected, const ImageGrid& found, const std::filesystem::path& path) {
  const double mismatch = (expected.world_from_voxel - found.world_from_voxel).cwiseAbs().maxCoeff();
  if (expected.dims != found.dims || mismatch > 1e-3) {
    std::ostringstream message;
    message << path.string() << ": expected the fixed image's grid (" << expected.dims.x() << " x "
            << expected.dims.y() << " x " << expected.dims.z() << " voxels, the same affine), found "
            << found.dims.x() << " x " << found.dims.y() << " x " << found.dims.z()
            << " voxels with an affine differing by up to " << mismatch << " mm";
    throw InputError(message.str());
  }
}

/// Refuses an exact mask whose values are not those the dataset wrote: the writer records
/// their SHA-256 (one byte per voxel, 1 inside the mask, i fastest) in the mask's sidecar as
/// ValuesSha256. A mask changed after the run would score a registration where the truth is not
/// exact. A dataset written before the record has none: its mask is read as it is.
void require_written_mask(const NiftiVolume& mask, const std::filesystem::path& path) {
  const std::filesystem::path sidecar = sidecar_path(path);
  if (path_kind(sidecar) != "a regular file") return;
  const nlohmann::json record = read_json_file(sidecar, "the JSON sidecar phantasm writes");
  if (!record.is_object() || !record.contains("ValuesSha256")) return;
  if (!record["ValuesSha256"].is_string())
    throw InputError(sidecar.string() + ": ValuesSha256: expected 64 hex digits, found " +
                     record["ValuesSha256"].dump());
  std::string inside(mask.values.size(), '\0');
  for (std::size_t v = 0; v < mask.values.size(); ++v)
    inside[v] = mask.values[v] > 0.5 ? 1 : 0;
  const std::string found = sha256_hex(inside);
  const std::string expected = record["ValuesSha256"].get<std::string>();
  if (found != expected) {
    throw InputError(path.string() + ": expected the exact mask the dataset wrote (SHA-256 of its values " +
                     expected + ", " + sidecar.filename().string() + " ValuesSha256), found other values (" +
                     found + "): the mask was changed after the run");
  }
}

/// Refuses a grid whose affine is not finite (a damaged or hand-made file).
void require_finite_grid(const ImageGrid& grid, const std::filesystem::path& path) {
  if (!grid.world_from_voxel.allFinite())
    throw InputError(path.string() +
                     ": expected a finite voxel-to-world affine, found NaN or infinite entries");
}

/// Refuses a field with a NaN or infinite displacement: scores computed from it would be NaN.
void require_finite_field(const DisplacementField& field, const std::filesystem::path& path) {
  for (std::size_t v = 0; v < field.lps_mm.size(); ++v) {
    if (!field.lps_mm[v].allFinite()) {
      const Eigen::Vector3i& d = field.grid.dims;
      const long long i = static_cast<long long>(v % d.x()), j = static_cast<long long>((v / d.x()) % d.y()),
                      k = static_cast<long long>(v / (static_cast<std::size_t>(d.x()) * d.y()));
      throw InputError(path.string() +
                       ": expected finite displacements (mm), found NaN or infinity at voxel (" +
                       std::to_string(i) + ", " + std::to_string(j) + ", " + std::to_string(k) + ")");
    }
  }
}

/// The registration result to evaluate: its field (none for a warped label map), and the moving
/// labels it carries onto the fixed grid into `warped`; records its kind in `result`.
std::optional<DisplacementField> read_result(const EvaluationRequest& request, const ImageGrid& grid,
                                             const ImageGrid& moving_grid,
                                             const std::vector<std::int32_t>& moving_labels,
                                             nlohmann::json* result, std::vector<std::int32_t>* warped) {
  std::optional<DisplacementField> field;
  if (request.field) {
    field = read_displacement_field(*request.field);
    require_same_grid(grid, field->grid, *request.field);
    require_finite_field(*field, *request.field);
    (*result)["result"] = {{"kind", "field"}, {"path", request.field->string()}};
  } else if (request.identity) {
    field = zero_field(grid);
    (*result)["result"] = {{"kind", "identity"}};
  } else {
    ImageGrid warped_grid;
    *warped = read_nifti_labels(*request.warped_labels, &warped_grid);
    require_same_grid(grid, warped_grid, *request.warped_labels);
    (*result)["result"] = {{"kind", "labels"}, {"path", request.warped_labels->string()}};
  }
  if (field) *warped = warp_labels(moving_labels, moving_grid, *field);
  return field;
}

/// Landmarks: the fixed ones carried by the result against the moving ones (same names), into
/// `result` ("landmarks", "landmark_displacement_mm", "tre_mm").
void score_landmarks(const DatasetLayout& layout, PhantomState fixed, PhantomState moving,
                     const std::optional<DisplacementField>& field, nlohmann::json* result,
                     nlohmann::json* not_available) {
  const std::vector<LandmarkRow> fixed_points = read_landmarks(layout.landmarks(fixed));
  const std::vector<LandmarkRow> moving_points = read_landmarks(layout.landmarks(moving));
  std::map<std::string, Eigen::Vector3d> moving_by_name;
  for (const auto& row : moving_points)
    moving_by_name[row.name] = row.ras_mm;
  std::vector<double> displacement;
  std::vector<double> tre;
  nlohmann::json landmarks = nlohmann::json::array();
  for (const auto& row : fixed_points) {
    const auto found = moving_by_name.find(row.name);
    if (found == moving_by_name.end()) {
      throw InputError(layout.landmarks(moving).string() + ": expected landmark '" + row.name + "' of " +
                       layout.landmarks(fixed).filename().string() + ", found none");
    }
    displacement.push_back((found->second - row.ras_mm).norm());
    nlohmann::json entry = {
        {"name", row.name}, {"organ", row.organ}, {"true_displacement_mm", displacement.back()}};
    if (field) {
      tre.push_back((field->moved(row.ras_mm) - found->second).norm());
      entry["tre_mm"] = tre.back();
    }
    landmarks.push_back(entry);
  }
  (*result)["landmarks"] = landmarks;
  (*result)["landmark_displacement_mm"] = summary_json(summarize(displacement));
  if (field) {
    (*result)["tre_mm"] = summary_json(summarize(tre));
  } else {
    (*result)["tre_mm"] = nullptr;
    not_available->push_back("target registration error: a warped label map does not carry points");
  }
}

/// Dense landmarks, when the dataset has them: each fixed one carried by the result against its
/// moving position, summarized over all and per organ ("dense_landmark_displacement_mm",
/// "dense_tre_mm"; null without them, or without a field).
void score_dense_landmarks(const DatasetLayout& layout, PhantomState fixed, PhantomState moving,
                           const std::optional<DisplacementField>& field, nlohmann::json* result) {
  (*result)["dense_landmark_displacement_mm"] = nullptr;
  (*result)["dense_tre_mm"] = nullptr;
  std::error_code error;
  if (!std::filesystem::exists(layout.dense_landmarks(fixed), error)) return;
  std::map<std::string, Eigen::Vector3d> moving_by_name;
  for (const auto& row : read_landmarks(layout.dense_landmarks(moving)))
    moving_by_name[row.name] = row.ras_mm;
  std::vector<std::string> organs;
  std::vector<double> displacement, tre;
  for (const auto& row : read_landmarks(layout.dense_landmarks(fixed))) {
    const auto found = moving_by_name.find(row.name);
    if (found == moving_by_name.end()) {
      throw InputError(layout.dense_landmarks(moving).string() + ": expected landmark '" + row.name +
                       "' of " + layout.dense_landmarks(fixed).filename().string() + ", found none");
    }
    organs.push_back(row.organ);
    displacement.push_back((found->second - row.ras_mm).norm());
    if (field) tre.push_back((field->moved(row.ras_mm) - found->second).norm());
  }
  (*result)["dense_landmark_displacement_mm"] = dense_tre_json(organs, displacement);
  if (field) (*result)["dense_tre_mm"] = dense_tre_json(organs, tre);
}

/// Label overlap, per label of either map, into `result` ("labels", "mean_dice").
void score_overlaps(const std::vector<std::int32_t>& fixed_labels, const std::vector<std::int32_t>& warped,
                    const ImageGrid& grid, const std::map<std::int32_t, std::string>& names,
                    nlohmann::json* result) {
  nlohmann::json labels = nlohmann::json::array();
  double dice_sum = 0.0;
  std::set<std::int32_t> present(fixed_labels.begin(), fixed_labels.end());
  present.insert(warped.begin(), warped.end());
  for (std::int32_t label : present) {
    throw_if_cancelled();
    if (label == 0) continue;
    // The gap (the space a moved organ left, deformed state only, the last row of dseg.tsv:
    // docs/volumes-and-images.md) has no counterpart in the reference: no overlap to measure.
    const auto gap = names.find(label);
    if (gap != names.end() && gap->second == "gap" && label == names.rbegin()->first) continue;
    const LabelOverlap overlap = label_overlap(fixed_labels, warped, grid, label);
    const auto name = names.find(label);
    labels.push_back({{"label", label},
                      {"name", name != names.end() ? name->second : std::to_string(label)},
                      {"dice", overlap.dice},
                      {"hd95_mm", number_or_null(overlap.hd95_mm)},
                      {"fixed_voxels", overlap.fixed_voxels},
                      {"warped_voxels", overlap.warped_voxels}});
    dice_sum += overlap.dice;
  }
  (*result)["labels"] = labels;
  (*result)["mean_dice"] =
      labels.empty() ? nlohmann::json() : nlohmann::json(dice_sum / static_cast<double>(labels.size()));
}

/// The dense endpoint error where the ground truth is exact, and the result's Jacobian over the
/// fixed foreground, into `result` ("endpoint_error_mm", "jacobian").
void score_field(const DatasetLayout& layout, PhantomState fixed, PhantomState moving, const ImageGrid& grid,
                 const std::vector<std::int32_t>& fixed_labels, const DisplacementField& field,
                 nlohmann::json* result) {
  // The truth on the fixed grid is the field that brings the moving image there (BIDS
  // from-<moving>_to-<fixed>).
  const DisplacementField truth = read_displacement_field(layout.transform(moving, fixed));
  require_same_grid(grid, truth.grid, layout.transform(moving, fixed));
  require_finite_field(truth, layout.transform(moving, fixed));
  const NiftiVolume mask = read_nifti(layout.transform_mask(moving, fixed));
  // Read voxel by voxel with the field's indices: a mask of another grid would be read out of bounds.
  require_same_grid(grid, mask.grid, layout.transform_mask(moving, fixed));
  if (mask.values.size() != truth.lps_mm.size()) {
    throw InputError(layout.transform_mask(moving, fixed).string() + ": expected " +
                     std::to_string(truth.lps_mm.size()) + " voxels (one component), found " +
                     std::to_string(mask.values.size()));
  }
  require_written_mask(mask, layout.transform_mask(moving, fixed));
  std::vector<double> error;
  for (std::size_t v = 0; v < truth.lps_mm.size(); ++v)
    if (mask.values[v] > 0.5) error.push_back((field.lps_mm[v] - truth.lps_mm[v]).norm());
  (*result)["endpoint_error_mm"] = summary_json(summarize(std::move(error)));
  std::vector<bool> foreground(fixed_labels.size());
  for (std::size_t v = 0; v < foreground.size(); ++v)
    foreground[v] = fixed_labels[v] > 0;
  const JacobianStatistics j = jacobian_statistics(field, foreground);
  (*result)["jacobian"] = {{"region", "fixed foreground (label > 0)"},
                           {"voxels", j.voxels},
                           {"folding_voxels", j.folding_voxels},
                           {"folding_fraction", j.folding_fraction},
                           {"log_jacobian_sd", j.log_jacobian_sd},
                           {"min_determinant", number_or_null(j.min_determinant)},
                           {"max_determinant", number_or_null(j.max_determinant)}};
}

} // namespace

nlohmann::json evaluate_registration(const EvaluationRequest& request) {
  if (request.fixed_session != "ref" && request.fixed_session != "def") {
    throw InputError("--fixed: expected ref or def, found '" + request.fixed_session + "'");
  }
  if ((request.field ? 1 : 0) + (request.warped_labels ? 1 : 0) + (request.identity ? 1 : 0) != 1) {
    throw InputError("expected exactly one registration result: --field, --labels or --identity");
  }
  const std::string subject = find_subject(request.dataset, request.subject);
  const DatasetLayout layout(request.dataset, subject);
  const PhantomState fixed =
      request.fixed_session == "ref" ? PhantomState::reference : PhantomState::deformed;
  const PhantomState moving =
      fixed == PhantomState::reference ? PhantomState::deformed : PhantomState::reference;

  ImageGrid grid, moving_grid;
  const std::vector<std::int32_t> fixed_labels = read_nifti_labels(layout.dseg(fixed), &grid);
  const std::vector<std::int32_t> moving_labels = read_nifti_labels(layout.dseg(moving), &moving_grid);
  const std::map<std::int32_t, std::string> names = read_label_names(layout.dseg_table());
  require_finite_grid(grid, layout.dseg(fixed));
  require_finite_grid(moving_grid, layout.dseg(moving));

  nlohmann::json result = {
      {"dataset", request.dataset.string()},
      {"subject", subject},
      {"fixed_session", std::string("ses-") + session_label(fixed)},
      {"moving_session", std::string("ses-") + session_label(moving)},
      {"voxel_size_mm", {grid.spacing_mm.x(), grid.spacing_mm.y(), grid.spacing_mm.z()}}};
  nlohmann::json not_available = nlohmann::json::array();

  std::vector<std::int32_t> warped;
  const std::optional<DisplacementField> field =
      read_result(request, grid, moving_grid, moving_labels, &result, &warped);
  score_landmarks(layout, fixed, moving, field, &result, &not_available);
  score_dense_landmarks(layout, fixed, moving, field, &result);
  score_overlaps(fixed_labels, warped, grid, names, &result);
  if (field) {
    score_field(layout, fixed, moving, grid, fixed_labels, *field, &result);
  } else {
    result["endpoint_error_mm"] = nullptr;
    result["jacobian"] = nullptr;
    not_available.push_back("endpoint error and Jacobian: they need a displacement field");
  }
  result["not_available"] = not_available;
  result["conventions"] = {
      {"field", "ITK/elastix: 5-D NIfTI on the fixed grid, LPS mm, x_moving = x_fixed + u(x_fixed)"},
      {"tre",
       "distance between a fixed landmark carried by the result (trilinear field) and its moving position"},
      {"dense_tre", "the TRE on the dense landmarks (seeded material points of each organ), over all and "
                    "per organ (by_structure); null for a dataset without them"},
      {"hd95", "larger of the two directed 95th percentiles of surface-voxel distances"},
      {"endpoint_error", "|u - u_true| inside the ground truth's exact mask"},
      {"jacobian", "det(I + grad u), central differences; folding counted before clipping to [1e-9, 1e9] for "
                   "the log"}};
  return result;
}

std::string evaluation_table(const nlohmann::json& e) {
  std::ostringstream out;
  auto number = [](const nlohmann::json& value) {
    return value.is_number() ? format_number(value.get<double>()) : std::string("-");
  };
  out << "registration of " << e["moving_session"].get<std::string>() << " onto "
      << e["fixed_session"].get<std::string>() << ", subject " << e["subject"].get<std::string>() << " ("
      << e["result"]["kind"].get<std::string>() << ")\n";
  auto summary_line = [&](const std::string& what, const nlohmann::json& s, const std::string& if_none) {
    out << "  " << what;
    if (s.is_null()) {
      out << "  -\n";
      return;
    }
    if (s["count"].get<std::size_t>() == 0) {
      out << "  none (" << if_none << ")\n";
      return;
    }
    out << "  mean " << number(s["mean"]) << "  sd " << number(s["sd"]) << "  p95 " << number(s["p95"])
        << "  max " << number(s["max"]) << "  (" << s["count"].get<std::size_t>() << ")\n";
  };
  summary_line("landmark motion mm   ", e["landmark_displacement_mm"], "no landmarks in the dataset");
  summary_line("TRE mm               ", e["tre_mm"], "no landmarks in the dataset");
  if (e.value("dense_tre_mm", nlohmann::json()).is_object()) {
    summary_line("dense TRE mm         ", e["dense_tre_mm"], "no dense landmarks in the dataset");
    for (const auto& s : e["dense_tre_mm"]["by_structure"]) {
      std::string name = s["structure"].get<std::string>();
      name.resize(std::max<std::size_t>(name.size(), 19), ' ');
      summary_line("  " + name, s, "");
    }
  }
  summary_line("endpoint error mm    ", e["endpoint_error_mm"], "no voxel in both exact masks");
  if (!e["jacobian"].is_null()) {
    out << "  log-Jacobian sd        " << number(e["jacobian"]["log_jacobian_sd"]) << "\n"
        << "  folding voxels         " << e["jacobian"]["folding_voxels"].get<std::int64_t>() << " ("
        << number(e["jacobian"]["folding_fraction"]) << ")\n";
  }
  out << "  label                  Dice      HD95 mm\n";
  for (const auto& label : e["labels"]) {
    std::string name = label["name"].get<std::string>();
    name.resize(std::max<std::size_t>(name.size(), 22), ' ');
    out << "  " << name << " " << number(label["dice"]) << "  " << number(label["hd95_mm"]) << "\n";
  }
  out << "  mean Dice              " << number(e["mean_dice"]) << "\n";
  return out.str();
}

} // namespace phantasm
