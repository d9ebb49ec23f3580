#include "evaluation/score_task.hpp"

#include "core/cancellation.hpp"
#include "core/error.hpp"
#include "core/format.hpp"
#include "core/path_kind.hpp"
#include "core/sha256.hpp"
#include "evaluation/digital_jacobian.hpp"
#include "evaluation/evaluation_json.hpp"
#include "evaluation/inverse_consistency.hpp"
#include "geometry/ras_lps.hpp"
#include "io/json_file.hpp"
#include "io/nifti_file.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <sstream>

namespace phantasm {
namespace {

const nlohmann::json& member(const nlohmann::json& object, const std::string& key,
                             const std::filesystem::path& path) {
  if (!object.is_object() || !object.contains(key))
    throw InputError(path.string() + ": expected the key '" + key + "' phantasm task writes, found none");
  return object[key];
}

std::string string_member(const nlohmann::json& object, const std::string& key,
                          const std::filesystem::path& path) {
  const nlohmann::json& value = member(object, key, path);
  if (!value.is_string())
    throw InputError(path.string() + ": " + key + ": expected a string, found " + value.dump());
  return value.get<std::string>();
}

/// Fields in voxel units along i, j, k (what the misreadings are stated in).
std::vector<Eigen::Vector3d> voxel_displacements(const DisplacementField& field) {
  const Eigen::Matrix3d index_from_ras = field.grid.world_from_voxel.topLeftCorner<3, 3>().inverse();
  std::vector<Eigen::Vector3d> u(field.lps_mm.size());
  for (std::size_t v = 0; v < u.size(); ++v)
    u[v] = index_from_ras * ras_from_lps(field.lps_mm[v]);
  return u;
}

struct Keypoint {
  std::string name;
  std::string organ;             ///< the dense keypoints' organ; empty for the landmarks
  Eigen::Vector3d fixed, moving; ///< voxel coordinates
};

/// A truth keypoints file: name, fixed i,j,k, moving i,j,k per line (keypoints_...csv), or with
/// the organ after the name when the header says so (dense_keypoints_...csv).
std::vector<Keypoint> read_keypoints(const std::filesystem::path& path) {
  std::istringstream in(whole_file(path, "the pair's keypoints (CSV)"));
  std::string line;
  std::getline(in, line);
  const bool with_organ = line.rfind("name,organ,", 0) == 0;
  std::vector<Keypoint> points;
  int number = 1;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty()) continue;
    std::istringstream fields(line);
    Keypoint p;
    std::getline(fields, p.name, ',');
    if (with_organ && (!std::getline(fields, p.organ, ',') || p.organ.empty()))
      throw InputError(path.string() + ":" + std::to_string(number) +
                       ": expected name, organ and six finite voxel coordinates, found '" + line + "'");
    double values[6];
    for (double& value : values) {
      std::string cell;
      if (!std::getline(fields, cell, ',')) cell.clear();
      char* end = nullptr;
      value = std::strtod(cell.c_str(), &end);
      if (cell.empty() || *end != '\0' || !std::isfinite(value))
        throw InputError(path.string() + ":" + std::to_string(number) +
                         ": expected name and six finite voxel coordinates, found '" + line + "'");
    }
    p.fixed = Eigen::Vector3d(values[0], values[1], values[2]);
    p.moving = Eigen::Vector3d(values[3], values[4], values[5]);
    points.push_back(p);
  }
  return points;
}

/// The value below which a fraction of the values lie (linear between order statistics).
double percentile(std::vector<double> values, double fraction) {
  if (values.empty()) return std::nan("");
  std::sort(values.begin(), values.end());
  const double position = fraction * static_cast<double>(values.size() - 1);
  const auto below = static_cast<std::size_t>(std::floor(position));
  const std::size_t above = std::min(below + 1, values.size() - 1);
  return values[below] + (position - static_cast<double>(below)) * (values[above] - values[below]);
}

/// The pairs' scores grouped by each varied factor of a sweep (participants.tsv): per factor and
/// value, the pairs and their mean Dice, TRE, endpoint error and NDV.
nlohmann::json by_factor(const nlohmann::json& pairs) {
  std::map<std::string, std::map<std::string, std::vector<const nlohmann::json*>>> groups;
  for (const auto& pair : pairs)
    for (const auto& [factor, value] : pair["factors"].items())
      groups[factor][value.is_string() ? value.get<std::string>() : value.dump()].push_back(&pair);
  nlohmann::json result = nlohmann::json::object();
  for (const auto& [factor, values] : groups) {
    for (const auto& [value, members] : values) {
      const std::vector<const nlohmann::json*>& group = members; // a lambda may not capture a binding
      auto mean = [&](const std::function<nlohmann::json(const nlohmann::json&)>& pick) {
        double sum = 0.0;
        int count = 0;
        for (const nlohmann::json* p : group) {
          const nlohmann::json x = pick(*p);
          if (x.is_number()) {
            sum += x.get<double>();
            ++count;
          }
        }
        return count ? nlohmann::json(sum / count) : nlohmann::json();
      };
      result[factor][value] = {
          {"pairs", members.size()},
          {"mean_dice", mean([](const nlohmann::json& p) { return p["mean_dice"]; })},
          {"mean_tre_mm", mean([](const nlohmann::json& p) { return p["tre_mm"]["mean"]; })},
          {"mean_dense_tre_mm", mean([](const nlohmann::json& p) {
             return p["dense_tre_mm"].is_object() ? p["dense_tre_mm"]["mean"] : nlohmann::json();
           })},
          {"mean_endpoint_error_mm",
           mean([](const nlohmann::json& p) { return p["endpoint_error_mm"]["mean"]; })},
          {"mean_ndv_percent", mean([](const nlohmann::json& p) { return p["ndv"]["percent"]; })}};
    }
  }
  return result;
}

/// The result name of a pair's reverse direction (the moving image fixed): disp_<moving>_<fixed>.
std::string reverse_result_name(const nlohmann::json& pair, const std::filesystem::path& truth_path) {
  return "disp_" + string_member(pair, "moving_id", truth_path) + "_" +
         string_member(pair, "fixed_id", truth_path) + ".nii.gz";
}

/// One pair's inputs, read and checked before anything is scored.
struct PairFiles {
  nlohmann::json entry;
  ImageGrid grid;
  std::vector<std::int32_t> fixed_labels, moving_labels;
  DisplacementField result, truth;
  /// The method's field of the reverse direction (moving image fixed), on the moving grid, when
  /// the results hold one: disp_<moving>_<fixed>.nii.gz.
  std::optional<DisplacementField> backward;
  std::vector<bool> mask;
  std::vector<Keypoint> keypoints;
  std::optional<std::vector<Keypoint>> dense_keypoints; ///< when the truth holds them
};

} // namespace

std::vector<Misreading> likely_misreadings(const DisplacementField& result, const DisplacementField& truth,
                                           const std::vector<bool>& mask) {
  const ImageGrid& grid = truth.grid;
  const Eigen::Vector3i& dims = grid.dims;
  const std::vector<Eigen::Vector3d> r = voxel_displacements(result), t = voxel_displacements(truth);
  // Where the truth is exact and moves: a mistake shows there.
  std::vector<std::size_t> region;
  for (std::size_t v = 0; v < t.size(); ++v)
    if (mask[v] && t[v].norm() > 0.25) region.push_back(v);
  if (region.size() < 8) return {};
  using Correction = std::function<Eigen::Vector3d(std::size_t)>;
  auto error_of = [&](const Correction& corrected) {
    double sum = 0.0;
    for (std::size_t v : region)
      sum += (corrected(v) - t[v]).norm();
    return sum / static_cast<double>(region.size());
  };
  const double as_read = error_of([&](std::size_t v) { return r[v]; });
  if (as_read < 0.25) return {};

  struct Candidate {
    std::string mistake;
    Correction corrected;
  };
  std::vector<Candidate> candidates;
  candidates.reserve(32);
  candidates.push_back({"the inverse direction (a field that carries moving points to fixed ones), or fixed "
                        "and moving swapped",
                        [&](std::size_t v) { return Eigen::Vector3d(-r[v]); }});
  const Eigen::Vector3d spacing = grid.spacing_mm;
  if ((spacing.array() - 1.0).abs().maxCoeff() > 0.05) {
    candidates.push_back({"displacements in mm where voxels are expected",
                          [&](std::size_t v) { return Eigen::Vector3d(r[v].cwiseQuotient(spacing)); }});
    candidates.push_back({"displacements in voxels where mm are expected",
                          [&](std::size_t v) { return Eigen::Vector3d(r[v].cwiseProduct(spacing)); }});
  }
  const char* axis = "ijk";
  const int orders[5][3] = {{0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (const auto& o : orders) {
    candidates.push_back(
        {std::string("transposed axes: components stored in the order (") + axis[o[0]] + ", " + axis[o[1]] +
             ", " + axis[o[2]] + ") instead of (i, j, k)",
         [&r, o](std::size_t v) { return Eigen::Vector3d(r[v][o[0]], r[v][o[1]], r[v][o[2]]); }});
  }
  for (int signs = 1; signs < 8; ++signs) {
    std::string which;
    Eigen::Vector3d factor;
    for (int a = 0; a < 3; ++a) {
      factor[a] = (signs >> a) & 1 ? -1.0 : 1.0;
      if ((signs >> a) & 1) which += std::string(which.empty() ? "" : " and ") + axis[a];
    }
    if (signs == 7) continue; // all three reversed: the inverse direction, above
    candidates.push_back(
        {"a flipped axis: component " + which +
             " reversed (an axis read in the opposite direction, e.g. LPS against RAS)",
         [&r, factor](std::size_t v) { return Eigen::Vector3d(r[v].cwiseProduct(factor)); }});
  }
  for (int a = 0; a < 3; ++a) {
    for (bool negate : {false, true}) {
      candidates.push_back({std::string("a flipped axis: the field's array reversed along ") + axis[a] +
                                (negate ? ", with its component" : ""),
                            [&r, &dims, a, negate](std::size_t v) {
                              Eigen::Vector3i ijk(
                                  static_cast<int>(v % dims.x()), static_cast<int>((v / dims.x()) % dims.y()),
                                  static_cast<int>(v / (static_cast<std::size_t>(dims.x()) * dims.y())));
                              ijk[a] = dims[a] - 1 - ijk[a];
                              Eigen::Vector3d u = r[voxel_index(dims, ijk.x(), ijk.y(), ijk.z())];
                              if (negate) u[a] = -u[a];
                              return u;
                            }});
    }
  }
  const Eigen::Matrix3d index_from_ras = grid.world_from_voxel.topLeftCorner<3, 3>().inverse();
  auto position = [&](std::size_t v) {
    const Eigen::Vector3d ijk(static_cast<double>(v % dims.x()),
                              static_cast<double>((v / dims.x()) % dims.y()),
                              static_cast<double>(v / (static_cast<std::size_t>(dims.x()) * dims.y())));
    return Eigen::Vector3d(index_from_ras * grid.world_from_index(ijk));
  };
  candidates.push_back({"positions (a deformation field) where displacements are expected",
                        [&](std::size_t v) { return Eigen::Vector3d(r[v] - position(v)); }});
  candidates.push_back({"displacements where positions (a deformation field) are expected",
                        [&](std::size_t v) { return Eigen::Vector3d(r[v] + position(v)); }});
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  for (std::size_t v : region)
    offset += r[v] - t[v];
  offset /= static_cast<double>(region.size());
  // An index base or an origin at a voxel corner offsets by whole or half voxels.
  // (+ 0.0 turns a rounded -0 into 0 for the message.)
  const Eigen::Vector3d halves = ((2.0 * offset).array().round() / 2.0 + 0.0).matrix();
  if (halves.norm() >= 0.5 && (offset - halves).cwiseAbs().maxCoeff() < 0.1) {
    std::ostringstream name;
    name << "a constant offset of (" << format_number(halves.x()) << ", " << format_number(halves.y()) << ", "
         << format_number(halves.z())
         << ") voxels: an index base (1 against 0) or an origin at a voxel corner against its centre";
    candidates.push_back(
        {name.str(), [&r, offset](std::size_t v) { return Eigen::Vector3d(r[v] - offset); }});
  }

  Misreading best;
  best.error_as_read_voxels = as_read;
  best.error_if_so_voxels = as_read;
  for (const Candidate& c : candidates) {
    const double error = error_of(c.corrected);
    if (error < best.error_if_so_voxels) {
      best.mistake = c.mistake;
      best.error_if_so_voxels = error;
    }
  }
  if (best.mistake.empty() || best.error_if_so_voxels > 0.35 * as_read) return {};
  return {best};
}

namespace {

/// The task's ground truth (truth.json), checked against the task's dataset JSON it was made with.
nlohmann::json read_truth(const TaskScoreRequest& request, const std::filesystem::path& truth_path) {
  const nlohmann::json truth =
      parse_json_text(whole_file(truth_path, "the ground truth phantasm task writes (truth.json)"),
                      truth_path, "the ground truth phantasm task writes");
  const std::filesystem::path dataset_json = request.task / string_member(truth, "dataset_json", truth_path);
  const std::string expected_hash = string_member(truth, "dataset_json_sha256", truth_path);
  if (sha256_hex(whole_file(dataset_json, "the task's dataset JSON")) != expected_hash) {
    throw InputError(dataset_json.string() + ": expected the task the ground truth " + truth_path.string() +
                     " was made with (SHA-256 " + expected_hash +
                     "), found another: a task and truth of different " + "datasets");
  }
  const nlohmann::json& pairs = member(truth, "pairs", truth_path);
  if (!pairs.is_array() || pairs.empty())
    throw InputError(truth_path.string() + ": pairs: expected a list of the task's pairs, found " +
                     pairs.dump());
  return truth;
}

/// The result files of the results folder (disp_*), checked to hold one field per pair, no more,
/// no less (a pair's reverse direction is allowed beside it).
std::set<std::string> result_files(const TaskScoreRequest& request, const nlohmann::json& pairs,
                                   const std::filesystem::path& truth_path) {
  if (path_kind(request.results) != "a folder")
    throw InputError(request.results.string() + ": expected the folder of results (--results), found " +
                     path_kind(request.results));
  std::set<std::string> expected, found, reverses;
  for (const auto& pair : pairs) {
    expected.insert(string_member(pair, "result", truth_path));
    reverses.insert(reverse_result_name(pair, truth_path));
  }
  for (const auto& entry : std::filesystem::directory_iterator(request.results)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("disp_", 0) == 0) found.insert(name);
  }
  std::string missing, extra;
  for (const auto& name : expected)
    if (!found.count(name)) missing += (missing.empty() ? "" : ", ") + name;
  for (const auto& name : found)
    if (!expected.count(name) && !reverses.count(name)) extra += (extra.empty() ? "" : ", ") + name;
  if (!missing.empty() || !extra.empty()) {
    std::string message = request.results.string() + ": expected one result per pair of the task (" +
                          std::to_string(expected.size()) + ")";
    if (!missing.empty()) message += "; missing: " + missing;
    if (!extra.empty()) message += "; not pairs of the task: " + extra;
    throw InputError(message);
  }
  return found;
}

/// One pair's labels, fields, mask and keypoints, read and checked.
PairFiles read_pair(const TaskScoreRequest& request, const nlohmann::json& truth, const nlohmann::json& pair,
                    const std::filesystem::path& truth_path, const std::set<std::string>& found) {
  PairFiles in;
  in.entry = pair;
  const std::string fixed_id = string_member(pair, "fixed_id", truth_path);
  const std::string moving_id = string_member(pair, "moving_id", truth_path);
  const std::string task_name = string_member(truth, "task", truth_path);
  in.fixed_labels =
      read_nifti_labels(request.task / "labelsTr" / (task_name + "_" + fixed_id + ".nii.gz"), &in.grid);
  ImageGrid moving_grid;
  in.moving_labels =
      read_nifti_labels(request.task / "labelsTr" / (task_name + "_" + moving_id + ".nii.gz"), &moving_grid);
  if (moving_grid.dims != in.grid.dims)
    throw InputError((request.task / "labelsTr" / (task_name + "_" + moving_id + ".nii.gz")).string() +
                     ": expected the fixed image's grid size, found another");
  in.truth = read_field(request.truth / string_member(pair, "displacement", truth_path),
                        FieldConvention::learn2reg, in.grid);
  in.result =
      read_field(request.results / string_member(pair, "result", truth_path), request.convention, in.grid);
  const std::filesystem::path reverse = request.results / reverse_result_name(pair, truth_path);
  if (found.count(reverse.filename().string()))
    in.backward = read_field(reverse, request.convention, moving_grid);
  const std::filesystem::path mask_path = request.truth / string_member(pair, "mask", truth_path);
  const NiftiVolume mask = read_nifti(mask_path);
  if (mask.grid.dims != in.grid.dims)
    throw InputError(mask_path.string() + ": expected the fixed image's grid size, found another");
  in.mask.resize(mask.values.size());
  for (std::size_t v = 0; v < mask.values.size(); ++v)
    in.mask[v] = mask.values[v] > 0.5;
  in.keypoints = read_keypoints(request.truth / string_member(pair, "keypoints", truth_path));
  if (pair.contains("dense_keypoints"))
    in.dense_keypoints = read_keypoints(request.truth / string_member(pair, "dense_keypoints", truth_path));
  return in;
}

/// The label names of the task's truth ("labels": index to name), where it has them.
std::map<std::int32_t, std::string> label_names(const nlohmann::json& truth) {
  std::map<std::int32_t, std::string> names;
  if (truth.contains("labels") && truth["labels"].is_object())
    for (const auto& [index, name] : truth["labels"].items())
      if (name.is_string()) names[std::atoi(index.c_str())] = name.get<std::string>();
  return names;
}

/// A pair's scores: its JSON entry and the per-pair values the summary averages.
struct PairScore {
  nlohmann::json out;
  double mean_dice = 0.0, mean_hd95 = 0.0, tre = 0.0, epe = 0.0, ndv = 0.0, sdlogj = 0.0;
  double dense_tre = std::nan(""), dense_tre_p95 = std::nan(""); // pairs with dense keypoints only
  std::optional<double> consistency;                             // pairs with both directions only
};

/// Dice and HD95 per label of the fixed labels against the moving labels carried by the result,
/// into `out` ("labels", "mean_dice", "mean_hd95_mm") and `score`.
void score_overlaps(const PairFiles& in, const std::map<std::int32_t, std::string>& names, PairScore* score) {
  const ImageGrid& grid = in.grid;
  const std::vector<std::int32_t> warped = warp_labels(in.moving_labels, grid, in.result);
  std::set<std::int32_t> present(in.fixed_labels.begin(), in.fixed_labels.end());
  present.insert(warped.begin(), warped.end());
  nlohmann::json labels = nlohmann::json::array();
  double dice_sum = 0.0, hd95_sum = 0.0;
  int hd95_count = 0;
  for (std::int32_t label : present) {
    const auto name = names.find(label);
    // Background, and the gap a moved organ left (deformed state only): nothing to overlap.
    if (label == 0 || (name != names.end() && name->second == "gap")) continue;
    const LabelOverlap overlap = label_overlap(in.fixed_labels, warped, grid, label);
    labels.push_back({{"label", label},
                      {"name", name != names.end() ? name->second : std::to_string(label)},
                      {"dice", overlap.dice},
                      {"hd95_mm", number_or_null(overlap.hd95_mm)}});
    dice_sum += overlap.dice;
    if (std::isfinite(overlap.hd95_mm)) {
      hd95_sum += overlap.hd95_mm;
      ++hd95_count;
    }
  }
  score->out["labels"] = labels;
  score->mean_dice = labels.empty() ? std::nan("") : dice_sum / static_cast<double>(labels.size());
  score->mean_hd95 = hd95_count ? hd95_sum / hd95_count : std::nan("");
  score->out["mean_dice"] = number_or_null(score->mean_dice);
  score->out["mean_hd95_mm"] = number_or_null(score->mean_hd95);
}

/// The warnings of a pair whose result looks like the true field read the wrong way.
nlohmann::json misreading_warnings(const PairFiles& in, const TaskScoreRequest& request,
                                   const std::string& result) {
  nlohmann::json pair_warnings = nlohmann::json::array();
  for (const Misreading& m : likely_misreadings(in.result, in.truth, in.mask)) {
    std::ostringstream text;
    text << (request.results / result).string()
         << ": the result looks like the true field read the wrong way: " << m.mistake << " (endpoint error "
         << format_number(m.error_as_read_voxels) << " voxels as read, "
         << format_number(m.error_if_so_voxels)
         << " if so; convention read: " << to_string(request.convention) << ")";
    pair_warnings.push_back(text.str());
  }
  return pair_warnings;
}

/// TRE per structure on the dense keypoints, where the truth holds them ("dense_tre_mm", null otherwise).
void score_dense_keypoints(const PairFiles& in, PairScore* score) {
  score->out["dense_tre_mm"] = nullptr;
  if (!in.dense_keypoints) return;
  std::vector<std::string> organs;
  std::vector<double> tre;
  for (const Keypoint& p : *in.dense_keypoints) {
    organs.push_back(p.organ);
    tre.push_back(
        (in.result.moved(in.grid.world_from_index(p.fixed)) - in.grid.world_from_index(p.moving)).norm());
  }
  score->out["dense_tre_mm"] = dense_tre_json(organs, tre);
  if (tre.empty()) return;
  const Summary all = summarize(tre);
  score->dense_tre = all.mean;
  score->dense_tre_p95 = all.p95;
}

/// One pair scored: overlaps, TRE, endpoint error, inverse consistency, folding and warnings.
PairScore score_pair(const PairFiles& in, const std::map<std::int32_t, std::string>& names,
                     const TaskScoreRequest& request) {
  const ImageGrid& grid = in.grid;
  PairScore score;
  nlohmann::json& out = score.out;
  out = {{"case", in.entry.value("case", 0)},
         {"subject", in.entry.value("subject", "")},
         {"fixed", in.entry.value("fixed", "")},
         {"moving", in.entry.value("moving", "")},
         {"result", in.entry.value("result", "")}};
  score_overlaps(in, names, &score);

  std::vector<double> tre;
  for (const Keypoint& p : in.keypoints) {
    const Eigen::Vector3d fixed = grid.world_from_index(p.fixed);
    tre.push_back((in.result.moved(fixed) - grid.world_from_index(p.moving)).norm());
  }
  out["tre_mm"] = summary_json(summarize(tre));
  score_dense_keypoints(in, &score);

  std::vector<double> epe;
  for (std::size_t v = 0; v < in.mask.size(); ++v)
    if (in.mask[v]) epe.push_back((in.result.lps_mm[v] - in.truth.lps_mm[v]).norm());
  const Summary epe_summary = summarize(epe);
  out["endpoint_error_mm"] = summary_json(epe_summary);
  out["inverse_consistency_mm"] = nullptr;
  if (in.backward) {
    const Summary consistency = summarize(inverse_consistency_errors(in.result, *in.backward, in.mask));
    out["inverse_consistency_mm"] = summary_json(consistency);
    score.consistency = consistency.mean;
  }

  std::vector<bool> foreground(in.fixed_labels.size());
  for (std::size_t v = 0; v < foreground.size(); ++v)
    foreground[v] = in.fixed_labels[v] > 0;
  const FoldingVolume ndv = non_diffeomorphic_volume(in.result, foreground);
  const JacobianStatistics j = jacobian_statistics(in.result, foreground);
  out["ndv"] = {{"percent", ndv.ndv_percent},
                {"voxels", ndv.ndv_voxels},
                {"folded_cubes", ndv.folded_cubes},
                {"cubes", ndv.cubes}};
  out["jacobian_central_differences"] = {{"folding_fraction", j.folding_fraction},
                                         {"log_jacobian_sd", j.log_jacobian_sd}};
  out["warnings"] = misreading_warnings(in, request, out["result"].get<std::string>());
  out["factors"] = in.entry.value("factors", nlohmann::json::object());
  score.tre = tre.empty() ? std::nan("") : summarize(tre).mean;
  score.epe = epe.empty() ? std::nan("") : epe_summary.mean;
  score.ndv = ndv.ndv_percent;
  score.sdlogj = j.log_jacobian_sd;
  return score;
}

/// The mean of the finite values, null when there are none.
nlohmann::json finite_mean(const std::vector<double>& values) {
  double sum = 0.0;
  int count = 0;
  for (double v : values)
    if (std::isfinite(v)) {
      sum += v;
      ++count;
    }
  return count ? nlohmann::json(sum / count) : nlohmann::json();
}

/// The task's summary: the pairs' scores averaged.
nlohmann::json task_summary(const std::vector<PairScore>& scores) {
  std::vector<double> dice_per_pair, hd95_per_pair, tre_per_pair, epe_per_pair, ndv_per_pair, sdlogj_per_pair;
  std::vector<double> consistency_per_pair; // pairs with both directions only
  std::vector<double> dense_tre_per_pair, dense_p95_per_pair;
  for (const PairScore& s : scores) {
    dense_tre_per_pair.push_back(s.dense_tre);
    dense_p95_per_pair.push_back(s.dense_tre_p95);
    if (s.consistency) consistency_per_pair.push_back(*s.consistency);
    dice_per_pair.push_back(s.mean_dice);
    hd95_per_pair.push_back(s.mean_hd95);
    tre_per_pair.push_back(s.tre);
    epe_per_pair.push_back(s.epe);
    ndv_per_pair.push_back(s.ndv);
    sdlogj_per_pair.push_back(s.sdlogj);
  }
  std::vector<double> finite_dice;
  for (double d : dice_per_pair)
    if (std::isfinite(d)) finite_dice.push_back(d);
  return {{"pairs", scores.size()},
          {"mean_dice", finite_mean(dice_per_pair)},
          {"dice_p30", number_or_null(percentile(finite_dice, 0.3))},
          {"mean_hd95_mm", finite_mean(hd95_per_pair)},
          {"mean_tre_mm", finite_mean(tre_per_pair)},
          {"mean_dense_tre_mm", finite_mean(dense_tre_per_pair)},
          {"mean_dense_tre_p95_mm", finite_mean(dense_p95_per_pair)},
          {"mean_endpoint_error_mm", finite_mean(epe_per_pair)},
          {"mean_ndv_percent", finite_mean(ndv_per_pair)},
          {"mean_log_jacobian_sd", finite_mean(sdlogj_per_pair)},
          {"inverse_consistency_pairs", consistency_per_pair.size()},
          {"mean_inverse_consistency_mm", finite_mean(consistency_per_pair)}};
}

/// What each score of the task's scores means.
nlohmann::json score_conventions() {
  return {
      {"dice_p30", "30th percentile of the pairs' mean Dice (robustness, as LUMIR reports it)"},
      {"tre", "fixed keypoint carried by the result (trilinear) against its moving position, mm"},
      {"dense_tre",
       "TRE on the dense landmarks (a few hundred seeded material points per organ, exact in both "
       "states), over all and per structure; null for a task without them"},
      {"endpoint_error", "|u - u_true| in mm inside the ground truth's exact mask"},
      {"ndv", "non-diffeomorphic volume: negative tetrahedra of each voxel cube of the fixed foreground, "
              "percent of the cubes"},
      {"log_jacobian_sd", "standard deviation of log det(I + grad u), central differences, fixed foreground"},
      {"inverse_consistency",
       "|phi_ba(phi_ab(x)) - x| in mm inside the exact mask, where the results also hold the reverse "
       "direction disp_<moving>_<fixed> (on the moving grid); null otherwise"}};
}

} // namespace

nlohmann::json score_task(const TaskScoreRequest& request) {
  const std::filesystem::path truth_path = request.truth / "truth.json";
  const nlohmann::json truth = read_truth(request, truth_path);
  const nlohmann::json& pairs = truth["pairs"];
  const std::set<std::string> found = result_files(request, pairs, truth_path);
  // Read and check everything before scoring.
  std::vector<PairFiles> inputs;
  for (const auto& pair : pairs)
    inputs.push_back(read_pair(request, truth, pair, truth_path, found));
  const std::map<std::int32_t, std::string> names = label_names(truth);
  nlohmann::json scored = nlohmann::json::array(), warnings = nlohmann::json::array();
  std::vector<PairScore> scores;
  for (PairFiles& in : inputs) {
    throw_if_cancelled();
    PairScore score = score_pair(in, names, request);
    for (const auto& warning : score.out["warnings"])
      warnings.push_back(warning);
    scored.push_back(score.out);
    scores.push_back(std::move(score));
  }
  return {{"task", string_member(truth, "task", truth_path)},
          {"results", request.results.string()},
          {"convention", to_string(request.convention)},
          {"pairs", scored},
          {"summary", task_summary(scores)},
          {"by_factor", by_factor(scored)},
          {"warnings", warnings},
          {"conventions", score_conventions()}};
}

nlohmann::json dense_tre_json(const std::vector<std::string>& organs, const std::vector<double>& tre) {
  nlohmann::json out = summary_json(summarize(tre));
  nlohmann::json by_structure = nlohmann::json::array();
  for (const StructureSummary& s : summarize_by_structure(organs, tre)) {
    nlohmann::json entry = summary_json(s.summary);
    entry["structure"] = s.structure;
    by_structure.push_back(entry);
  }
  out["by_structure"] = by_structure;
  return out;
}

std::string task_scores_csv(const nlohmann::json& scores) {
  std::ostringstream out;
  out << "case,subject,result,mean_dice,mean_hd95_mm,tre_mm_mean,dense_tre_mm_mean,dense_tre_mm_p95,"
         "endpoint_error_mm_mean,endpoint_error_mm_p95,ndv_percent,log_jacobian_sd,folding_fraction_central,"
         "warnings\n";
  auto cell = [](const nlohmann::json& value) {
    return value.is_number() ? format_number(value.get<double>()) : std::string();
  };
  for (const auto& p : scores["pairs"]) {
    const nlohmann::json dense =
        p.value("dense_tre_mm", nlohmann::json()).is_object() ? p["dense_tre_mm"] : nlohmann::json::object();
    out << p["case"].get<int>() << ',' << p["subject"].get<std::string>() << ','
        << p["result"].get<std::string>() << ',' << cell(p["mean_dice"]) << ',' << cell(p["mean_hd95_mm"])
        << ',' << cell(p["tre_mm"]["mean"]) << ',' << cell(dense["mean"]) << ',' << cell(dense["p95"]) << ','
        << cell(p["endpoint_error_mm"]["mean"]) << ',' << cell(p["endpoint_error_mm"]["p95"]) << ','
        << cell(p["ndv"]["percent"]) << ',' << cell(p["jacobian_central_differences"]["log_jacobian_sd"])
        << ',' << cell(p["jacobian_central_differences"]["folding_fraction"]) << ',' << p["warnings"].size()
        << '\n';
  }
  return out.str();
}

std::string task_scores_table(const nlohmann::json& scores) {
  std::ostringstream out;
  auto number = [](const nlohmann::json& value) {
    return value.is_number() ? format_number(value.get<double>()) : std::string("-");
  };
  out << "task " << scores["task"].get<std::string>() << ", " << scores["pairs"].size() << " pairs ("
      << scores["convention"].get<std::string>() << " fields)\n";
  out << "  result                                  Dice   HD95 mm  TRE mm  EPE mm  NDV %   SDlogJ\n";
  for (const auto& p : scores["pairs"]) {
    std::string name = p["result"].get<std::string>();
    name.resize(std::max<std::size_t>(name.size(), 38), ' ');
    out << "  " << name << "  " << number(p["mean_dice"]) << "  " << number(p["mean_hd95_mm"]) << "  "
        << number(p["tre_mm"]["mean"]) << "  " << number(p["endpoint_error_mm"]["mean"]) << "  "
        << number(p["ndv"]["percent"]) << "  " << number(p["jacobian_central_differences"]["log_jacobian_sd"])
        << "\n";
  }
  const nlohmann::json& s = scores["summary"];
  out << "  mean Dice " << number(s["mean_dice"]) << " (30th percentile " << number(s["dice_p30"])
      << "), TRE " << number(s["mean_tre_mm"])
      << " mm (dense landmarks: " << number(s.value("mean_dense_tre_mm", nlohmann::json())) << " mm, p95 "
      << number(s.value("mean_dense_tre_p95_mm", nlohmann::json())) << " mm), endpoint error "
      << number(s["mean_endpoint_error_mm"]) << " mm, NDV " << number(s["mean_ndv_percent"]) << " %\n";
  if (s["inverse_consistency_pairs"].get<std::size_t>() > 0)
    out << "  inverse consistency " << number(s["mean_inverse_consistency_mm"]) << " mm (mean over "
        << s["inverse_consistency_pairs"].get<std::size_t>() << " pairs with both directions)\n";
  for (const auto& w : scores["warnings"])
    out << "  warning: " << w.get<std::string>() << "\n";
  return out.str();
}

} // namespace phantasm
