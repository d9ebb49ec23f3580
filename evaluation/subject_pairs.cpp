#include "evaluation/subject_pairs.hpp"

#include "core/error.hpp"
#include "core/path_kind.hpp"
#include "evaluation/field_conventions.hpp"
#include "geometry/ras_lps.hpp"
#include "geometry/tet_location.hpp"
#include "io/atomic_file.hpp"
#include "io/dataset_layout.hpp"
#include "io/dataset_tables.hpp"
#include "io/json_file.hpp"
#include "io/mesh_file.hpp"
#include "io/nifti_file.hpp"

#include <Eigen/QR>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <regex>
#include <set>
#include <sstream>

namespace phantasm {
namespace {

/// True when X (voxel coordinates) lies on the grid and `holds` every voxel of its trilinear cell.
template <typename Holds>
bool whole_cell(const ImageGrid& grid, const Eigen::Vector3d& index, const Holds& holds) {
  int low[3];
  for (int a = 0; a < 3; ++a) {
    if (!(index[a] >= 0.0 && index[a] <= grid.dims[a] - 1)) return false;
    low[a] = std::min(static_cast<int>(std::floor(index[a])), std::max(grid.dims[a] - 2, 0));
  }
  for (int corner = 0; corner < 8; ++corner) {
    int c[3];
    for (int a = 0; a < 3; ++a)
      c[a] = std::min(low[a] + ((corner >> a) & 1), grid.dims[a] - 1);
    if (!holds(voxel_index(grid.dims, c[0], c[1], c[2]))) return false;
  }
  return true;
}

/// How far a voxel's field may be from a body's map there and still be that map (the field is
/// stored in single precision: a few micrometres at most; still tissue inside a body's tets keeps
/// the head's growth instead).
constexpr double k_body_map_tolerance_mm = 1e-3;

/// The template tet of a body holding X and X carried by the subject's solved vertices.
std::optional<Eigen::Vector3d> through_bodies(const SolvedBodies& bodies,
                                              const std::vector<TetMeshLocator>& locators,
                                              const Eigen::Vector3d& x) {
  for (std::size_t b = 0; b < locators.size(); ++b) {
    if (const std::optional<TetLocation> at = locators[b].find(x)) {
      Eigen::Vector3d y = Eigen::Vector3d::Zero();
      for (int c = 0; c < 4; ++c)
        y += at->weights[c] * bodies.deformed_mm[b].row(bodies.tets[b](at->tet, c)).transpose();
      return y;
    }
  }
  return std::nullopt;
}

/// Per voxel of the field's grid: 1 where the field is exact and is a body's map (the voxel lies
/// in a body's rest tets and the field there is within k_body_map_tolerance_mm of the solved
/// vertices at its weights).
std::vector<std::uint8_t> body_map_voxels(const DisplacementField& field,
                                          const std::vector<std::uint8_t>& exact, const SolvedBodies& bodies,
                                          const std::vector<TetMeshLocator>& locators) {
  const ImageGrid& grid = field.grid;
  std::vector<std::uint8_t> marks(exact.size(), 0);
  for (const TetMeshLocator& locator : locators) {
    // The voxels of the body's box: its corners' indices (any affine of the grid).
    Eigen::Vector3d low = Eigen::Vector3d::Constant(1e300), high = -low;
    for (int corner = 0; corner < 8; ++corner) {
      Eigen::Vector3d p;
      for (int a = 0; a < 3; ++a)
        p[a] = ((corner >> a) & 1) ? locator.high()[a] : locator.low()[a];
      const Eigen::Vector3d index = grid.index_from_world(p);
      low = low.cwiseMin(index);
      high = high.cwiseMax(index);
    }
    int lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::max(0, static_cast<int>(std::floor(low[a])));
      hi[a] = std::min(grid.dims[a] - 1, static_cast<int>(std::ceil(high[a])));
    }
#pragma omp parallel for schedule(dynamic, 1)
    for (int k = lo[2]; k <= hi[2]; ++k)
      for (int j = lo[1]; j <= hi[1]; ++j)
        for (int i = lo[0]; i <= hi[0]; ++i) {
          const std::size_t v = voxel_index(grid.dims, i, j, k);
          if (!exact[v] || marks[v]) continue;
          const Eigen::Vector3d x = grid.world_from_index(Eigen::Vector3d(i, j, k));
          const std::optional<Eigen::Vector3d> y = through_bodies(bodies, locators, x);
          if (y && (*y - x - ras_from_lps(field.lps_mm[v])).norm() <= k_body_map_tolerance_mm) marks[v] = 1;
        }
  }
  return marks;
}

std::vector<std::uint8_t> read_mask(const std::filesystem::path& path, ImageGrid* grid) {
  const std::vector<std::int32_t> labels = read_nifti_labels(path, grid);
  std::vector<std::uint8_t> mask(labels.size());
  for (std::size_t v = 0; v < labels.size(); ++v)
    mask[v] = labels[v] != 0 ? 1 : 0;
  return mask;
}

bool same_grid(const ImageGrid& a, const ImageGrid& b) {
  return a.dims == b.dims && (a.world_from_voxel - b.world_from_voxel).cwiseAbs().maxCoeff() <= 1e-6;
}

std::string coordinates(const Eigen::Vector3d& ras) {
  char text[96];
  std::snprintf(text, sizeof text, "%.6f,%.6f,%.6f", ras.x(), ras.y(), ras.z());
  return text;
}

/// The files a subject's pairs read.
struct SubjectFiles {
  std::filesystem::path from_template, from_template_mask; ///< from-def_to-ref: template grid -> def
  std::filesystem::path to_template, to_template_mask;     ///< from-ref_to-def: def grid -> template
  std::filesystem::path landmarks, reference_labels;
  /// Each solved body's tet mesh in the reference and the deformed state.
  std::vector<std::pair<std::filesystem::path, std::filesystem::path>> bodies;
};

SubjectFiles subject_files(const std::filesystem::path& dataset, const std::string& subject) {
  const DatasetLayout layout(dataset, subject);
  SubjectFiles files{layout.transform(PhantomState::deformed, PhantomState::reference),
                     layout.transform_mask(PhantomState::deformed, PhantomState::reference),
                     layout.transform(PhantomState::reference, PhantomState::deformed),
                     layout.transform_mask(PhantomState::reference, PhantomState::deformed),
                     layout.landmarks(PhantomState::deformed),
                     layout.dseg(PhantomState::reference),
                     {}};
  // The solved bodies, as provenance.json lists them.
  const nlohmann::json provenance =
      read_json_file(layout.provenance(), "the JSON phantasm writes in provenance.json");
  if (provenance.contains("bodies") && provenance["bodies"].is_array()) {
    for (const nlohmann::json& body : provenance["bodies"]) {
      if (!body.contains("organ") || !body["organ"].is_string())
        throw InputError(layout.provenance().string() +
                         ": expected each of bodies to name its organ (a string), found " + body.dump());
      const std::string organ = body["organ"].get<std::string>();
      files.bodies.emplace_back(layout.tet_mesh(PhantomState::reference, organ),
                                layout.tet_mesh(PhantomState::deformed, organ));
    }
  }
  std::vector<const std::filesystem::path*> paths = {&files.from_template, &files.from_template_mask,
                                                     &files.to_template,   &files.to_template_mask,
                                                     &files.landmarks,     &files.reference_labels};
  for (const auto& [rest, solved] : files.bodies)
    paths.insert(paths.end(), {&rest, &solved});
  for (const auto* path : paths) {
    if (path_kind(*path) != "a regular file")
      throw InputError(path->string() + ": expected sub-" + subject +
                       "'s file (a dataset of phantasm batch), found " + path_kind(*path));
  }
  return files;
}

/// A subject's solved bodies from its tet meshes, each checked against the template's (the
/// first subject's): the same tets at the same rest positions.
/// @throws InputError naming the file that does not fit
SolvedBodies read_solved_bodies(const SubjectFiles& files, const SolvedBodies* template_bodies,
                                const std::string& subject, const std::string& first) {
  SolvedBodies bodies;
  if (template_bodies && template_bodies->tets.size() != files.bodies.size())
    throw InputError(files.reference_labels.string() + ": expected the " +
                     std::to_string(template_bodies->tets.size()) + " solved bodies of sub-" + first +
                     " (one template), found " + std::to_string(files.bodies.size()) + " in sub-" + subject +
                     "'s provenance.json");
  for (std::size_t b = 0; b < files.bodies.size(); ++b) {
    const TetMesh rest = read_vtu(files.bodies[b].first);
    const TetMesh solved = read_vtu(files.bodies[b].second);
    if (solved.tets != rest.tets || solved.vertices.rows() != rest.vertices.rows())
      throw InputError(files.bodies[b].second.string() + ": expected the tets of " +
                       files.bodies[b].first.string() + " (the same body solved), found others");
    if (template_bodies &&
        (rest.tets != template_bodies->tets[b] || rest.vertices != template_bodies->rest_mm[b]))
      throw InputError(files.bodies[b].first.string() + ": expected the rest tet mesh of sub-" + first +
                       " (subjects of one template), found another: sub-" + subject + " and sub-" + first +
                       " cannot be paired through one template");
    bodies.tets.push_back(rest.tets);
    bodies.rest_mm.push_back(rest.vertices);
    bodies.deformed_mm.push_back(solved.vertices);
  }
  return bodies;
}

/// The pair's landmarks: each name both subjects have, with its place in i and in j.
std::string landmark_table(const std::filesystem::path& moving, const std::filesystem::path& fixed) {
  std::map<std::string, Eigen::Vector3d> in_fixed;
  for (const LandmarkRow& row : read_landmarks(fixed))
    in_fixed[row.name] = row.ras_mm;
  std::string text = "name,organ,moving_x_mm,moving_y_mm,moving_z_mm,fixed_x_mm,fixed_y_mm,fixed_z_mm\n";
  for (const LandmarkRow& row : read_landmarks(moving)) {
    const auto found = in_fixed.find(row.name);
    if (found != in_fixed.end())
      text += row.name + "," + row.organ + "," + coordinates(row.ras_mm) + "," + coordinates(found->second) +
              "\n";
  }
  return text;
}

std::string pair_name(const SubjectPair& pair) {
  return "from-" + pair.first + "_to-" + pair.second;
}

/// How far the body's map and the map outside it may differ at a template point, in voxels, for
/// the point to be exact in a cell that holds voxels of both (a body's boundary against still
/// tissue, whose tets reach a little past the tissue's surface): there the voxels cannot tell
/// which of the two the point follows, and either is then within this of the other.
constexpr double k_material_ambiguity_voxels = 0.01;

/// The affine map the field is outside the bodies' map (the head's growth, or the identity),
/// fitted to the exact voxels that are not the body map (a lattice of about 50 000 of the grid's
/// voxels) and checked on them: nothing when they do not follow one affine map within
/// k_body_map_tolerance_mm.
std::optional<Eigen::Matrix<double, 3, 4>> outside_affine(const DisplacementField& field,
                                                          const std::vector<std::uint8_t>& exact,
                                                          const std::vector<std::uint8_t>& body_map) {
  const ImageGrid& grid = field.grid;
  std::vector<Eigen::Vector3d> from, to;
  const int step = std::max(1, static_cast<int>(std::cbrt(static_cast<double>(grid.voxel_count()) / 5e4)));
  for (int k = 0; k < grid.dims.z(); k += step)
    for (int j = 0; j < grid.dims.y(); j += step)
      for (int i = 0; i < grid.dims.x(); i += step) {
        const std::size_t v = voxel_index(grid.dims, i, j, k);
        if (!exact[v] || body_map[v]) continue;
        from.push_back(grid.world_from_index(Eigen::Vector3d(i, j, k)));
        to.push_back(from.back() + ras_from_lps(field.lps_mm[v]));
      }
  if (from.size() < 16) return std::nullopt;
  // Least squares in coordinates about the points' mean, for conditioning.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : from)
    mean += p / static_cast<double>(from.size());
  Eigen::MatrixXd a(from.size(), 4), b(from.size(), 3);
  for (std::size_t n = 0; n < from.size(); ++n) {
    a.row(static_cast<Eigen::Index>(n)) << (from[n] - mean).transpose(), 1.0;
    b.row(static_cast<Eigen::Index>(n)) = to[n].transpose();
  }
  const Eigen::MatrixXd solution = a.colPivHouseholderQr().solve(b); // 4 x 3
  Eigen::Matrix<double, 3, 4> affine;
  affine.leftCols<3>() = solution.topRows<3>().transpose();
  affine.col(3) = solution.row(3).transpose() - affine.leftCols<3>() * mean;
  for (std::size_t n = 0; n < from.size(); ++n)
    if ((affine.leftCols<3>() * from[n] + affine.col(3) - to[n]).norm() > k_body_map_tolerance_mm)
      return std::nullopt;
  return affine;
}

/// A body's map at x, extrapolated from the tet x is least outside of when no tet holds it
/// (continuous across the faceted boundary); nothing without bodies.
std::optional<Eigen::Vector3d> near_bodies(const SolvedBodies& bodies,
                                           const std::vector<TetMeshLocator>& locators,
                                           const Eigen::Vector3d& x) {
  std::optional<Eigen::Vector3d> best;
  double best_weight = -std::numeric_limits<double>::infinity();
  for (std::size_t b = 0; b < locators.size(); ++b) {
    const TetLocation at = locators[b].nearest(x);
    if (at.tet < 0 || !(at.weights.minCoeff() > best_weight)) continue;
    best_weight = at.weights.minCoeff();
    Eigen::Vector3d y = Eigen::Vector3d::Zero();
    for (int c = 0; c < 4; ++c)
      y += at.weights[c] * bodies.deformed_mm[b].row(bodies.tets[b](at.tet, c)).transpose();
    best = y;
  }
  return best;
}

} // namespace

ComposedField compose_through_template(const DisplacementField& moving_from_template,
                                       const std::vector<std::uint8_t>& moving_exact,
                                       const DisplacementField& template_from_fixed,
                                       const std::vector<std::uint8_t>& fixed_exact,
                                       const SolvedBodies* moving_bodies) {
  if (moving_exact.size() != moving_from_template.lps_mm.size() ||
      fixed_exact.size() != template_from_fixed.lps_mm.size())
    throw InputError("compose_through_template: expected a mask of each field's voxel count, found another");
  const SolvedBodies none;
  const SolvedBodies& bodies = moving_bodies ? *moving_bodies : none;
  std::vector<TetMeshLocator> locators;
  for (std::size_t b = 0; b < bodies.tets.size(); ++b) {
    if (b >= bodies.rest_mm.size() || b >= bodies.deformed_mm.size() ||
        bodies.rest_mm[b].rows() != bodies.deformed_mm[b].rows())
      throw InputError("compose_through_template: expected the rest and solved vertices of each body, found "
                       "other counts");
    locators.emplace_back(bodies.rest_mm[b], bodies.tets[b]);
  }
  const std::vector<std::uint8_t> body_map =
      locators.empty() ? std::vector<std::uint8_t>()
                       : body_map_voxels(moving_from_template, moving_exact, bodies, locators);
  const std::optional<Eigen::Matrix<double, 3, 4>> outside =
      locators.empty() ? std::nullopt : outside_affine(moving_from_template, moving_exact, body_map);
  const ImageGrid& grid = template_from_fixed.grid;
  const ImageGrid& template_grid = moving_from_template.grid;
  const double ambiguity = k_material_ambiguity_voxels * template_grid.spacing_mm.minCoeff();
  ComposedField out{DisplacementField{grid, std::vector<Eigen::Vector3d>(fixed_exact.size())},
                    std::vector<std::uint8_t>(fixed_exact.size(), 0)};
#pragma omp parallel for schedule(dynamic, 1)
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i) {
        const std::size_t v = voxel_index(grid.dims, i, j, k);
        const Eigen::Vector3d x = grid.world_from_index(Eigen::Vector3d(i, j, k));
        const Eigen::Vector3d in_template = x + ras_from_lps(template_from_fixed.lps_mm[v]);
        const Eigen::Vector3d index = template_grid.index_from_world(in_template);
        const std::optional<Eigen::Vector3d> solved = through_bodies(bodies, locators, in_template);
        Eigen::Vector3d in_moving = solved ? *solved : moving_from_template.moved(in_template);
        bool exact = false;
        if (fixed_exact[v]) {
          if (solved)
            exact = whole_cell(template_grid, index, [&](std::size_t c) { return body_map[c] != 0; });
          else
            exact = whole_cell(template_grid, index, [&](std::size_t c) {
              return moving_exact[c] && (body_map.empty() || !body_map[c]);
            });
          // A cell holding voxels of both maps, every one exact: exact where the two maps agree at
          // the point (the body's extrapolated from its nearest tet outside it).
          if (!exact && outside &&
              whole_cell(template_grid, index, [&](std::size_t c) { return moving_exact[c] != 0; })) {
            const Eigen::Vector3d affine = outside->leftCols<3>() * in_template + outside->col(3);
            const std::optional<Eigen::Vector3d> body =
                solved ? solved : near_bodies(bodies, locators, in_template);
            if (body && (*body - affine).norm() <= ambiguity) {
              exact = true;
              if (!solved) in_moving = affine;
            }
          }
        }
        out.field.lps_mm[v] = lps_from_ras(in_moving - x);
        out.exact[v] = exact ? 1 : 0;
      }
  return out;
}

std::size_t narrow_to_round_trip(ComposedField& forward, const DisplacementField& backward) {
  const ImageGrid& grid = forward.field.grid;
  const double tolerance = pair_round_trip_tolerance_voxels * grid.spacing_mm.minCoeff();
  std::size_t dropped = 0;
#pragma omp parallel for schedule(static) reduction(+ : dropped)
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i) {
        const std::size_t v = voxel_index(grid.dims, i, j, k);
        if (!forward.exact[v]) continue;
        const Eigen::Vector3d x = grid.world_from_index(Eigen::Vector3d(i, j, k));
        if ((backward.moved(x + ras_from_lps(forward.field.lps_mm[v])) - x).norm() > tolerance) {
          forward.exact[v] = 0;
          ++dropped;
        }
      }
  return dropped;
}

std::vector<SubjectPair> parse_pair_list(const std::string& text) {
  static const std::regex pair_pattern(R"(([A-Za-z0-9]+):([A-Za-z0-9]+))");
  std::vector<SubjectPair> pairs;
  std::stringstream parts(text);
  std::string part;
  while (std::getline(parts, part, ',')) {
    std::smatch match;
    if (!std::regex_match(part, match, pair_pattern))
      throw InputError("--pairs: expected all or pairs of subject labels such as 01:02,03:05, found '" +
                       part + "' in '" + text + "'");
    pairs.emplace_back(match[1].str(), match[2].str());
  }
  if (pairs.empty()) throw InputError("--pairs: expected all or pairs such as 01:02, found '" + text + "'");
  return pairs;
}

std::vector<SubjectPair> choose_pairs(const std::vector<std::string>& subjects, const PairRequest& request) {
  std::string known;
  for (const std::string& s : subjects)
    known += (known.empty() ? "" : ", ") + s;
  std::set<SubjectPair> chosen;
  if (!request.listed.empty()) {
    for (const SubjectPair& pair : request.listed) {
      for (const std::string& s : {pair.first, pair.second})
        if (std::find(subjects.begin(), subjects.end(), s) == subjects.end())
          throw InputError("--pairs: expected subjects of " + request.dataset.string() + " (" + known +
                           "), found '" + s + "', which it does not hold");
      if (pair.first == pair.second)
        throw InputError("--pairs: expected two different subjects, found " + pair.first + ":" + pair.second);
      chosen.insert(std::minmax(pair.first, pair.second));
    }
    return {chosen.begin(), chosen.end()};
  }
  std::vector<SubjectPair> all;
  for (std::size_t a = 0; a < subjects.size(); ++a)
    for (std::size_t b = a + 1; b < subjects.size(); ++b)
      all.emplace_back(subjects[a], subjects[b]);
  if (request.random_count == 0) return all;
  if (request.random_count > all.size())
    throw InputError("--random: expected at most " + std::to_string(all.size()) + " pairs (the " +
                     std::to_string(subjects.size()) + " subjects of " + request.dataset.string() +
                     " make no more), found " + std::to_string(request.random_count));
  // A partial Fisher-Yates shuffle on 53-bit uniforms: the same pairs for the same seed with any
  // standard library.
  std::seed_seq mix{static_cast<std::uint32_t>(request.seed), static_cast<std::uint32_t>(request.seed >> 32)};
  std::mt19937_64 random(mix);
  for (std::size_t n = 0; n < request.random_count; ++n) {
    const double u = static_cast<double>(random() >> 11) * 0x1.0p-53;
    const std::size_t pick = n + std::min(all.size() - n - 1, static_cast<std::size_t>(u * (all.size() - n)));
    std::swap(all[n], all[pick]);
  }
  all.resize(request.random_count);
  std::sort(all.begin(), all.end());
  return all;
}

nlohmann::json write_subject_pairs(const PairRequest& request) {
  const std::vector<std::string> subjects = complete_subjects(request.dataset);
  if (subjects.size() < 2)
    throw InputError(request.dataset.string() +
                     ": expected a dataset of phantasm batch with at least two complete subjects "
                     "(derivatives/phantasm/sub-<id>/provenance.json), found " +
                     std::to_string(subjects.size()));
  const std::vector<SubjectPair> pairs = choose_pairs(subjects, request);
  std::error_code error;
  if (std::filesystem::exists(request.out, error) &&
      (!std::filesystem::is_directory(request.out, error) || !std::filesystem::is_empty(request.out, error)))
    throw InputError("-o: expected a new or empty folder, found " + path_kind(request.out) + " at " +
                     request.out.string() + " (remove it, or choose another)");

  // Every subject's files and its template checked before anything is written: one grid, and the
  // same reference labels (the template every field goes through).
  std::set<std::string> used;
  for (const SubjectPair& pair : pairs)
    used.insert({pair.first, pair.second});
  std::map<std::string, SubjectFiles> files;
  std::map<std::string, SolvedBodies> bodies;
  ImageGrid grid;
  std::vector<std::int32_t> template_labels;
  std::string first;
  for (const std::string& subject : used) {
    files[subject] = subject_files(request.dataset, subject);
    ImageGrid labels_grid;
    std::vector<std::int32_t> labels = read_nifti_labels(files[subject].reference_labels, &labels_grid);
    if (first.empty()) {
      first = subject;
      grid = labels_grid;
      template_labels = std::move(labels);
    } else if (!same_grid(grid, labels_grid)) {
      throw InputError(files[subject].reference_labels.string() + ": expected the grid of sub-" + first +
                       " (pairs share one grid), found another size or affine");
    } else if (labels != template_labels) {
      throw InputError(files[subject].reference_labels.string() + ": expected the reference labels of sub-" +
                       first +
                       " (subjects of one template: the same anatomy, seed and grid), found others: sub-" +
                       subject + " and sub-" + first + " cannot be paired through one template");
    }
    bodies[subject] =
        read_solved_bodies(files[subject], subject == first ? nullptr : &bodies.at(first), subject, first);
    for (const auto* mask : {&files[subject].from_template_mask, &files[subject].to_template_mask}) {
      ImageGrid mask_grid;
      read_nifti_labels(*mask, &mask_grid);
      if (!same_grid(grid, mask_grid))
        throw InputError(mask->string() + ": expected the grid of sub-" + first +
                         ", found another size or affine");
    }
  }

  std::filesystem::create_directories(request.out);
  nlohmann::json written = nlohmann::json::array();
  std::string table = "moving\tfixed\tfield\tmask\tlandmarks\texact_fraction\n";
  const auto compose = [&](const std::string& moving, const std::string& fixed) {
    ImageGrid ignored;
    return compose_through_template(read_field(files.at(moving).from_template, FieldConvention::itk, grid),
                                    read_mask(files.at(moving).from_template_mask, &ignored),
                                    read_field(files.at(fixed).to_template, FieldConvention::itk, grid),
                                    read_mask(files.at(fixed).to_template_mask, &ignored),
                                    &bodies.at(moving));
  };
  for (const SubjectPair& unordered : pairs) {
    // Both directions, then each mask narrowed to the round trip through the other's field.
    std::array<ComposedField, 2> composed = {compose(unordered.first, unordered.second),
                                             compose(unordered.second, unordered.first)};
    const std::array<std::size_t, 2> dropped = {narrow_to_round_trip(composed[0], composed[1].field),
                                                narrow_to_round_trip(composed[1], composed[0].field)};
    for (int direction = 0; direction < 2; ++direction) {
      const SubjectPair pair = direction == 0 ? unordered : SubjectPair{unordered.second, unordered.first};
      const ComposedField& field = composed[static_cast<std::size_t>(direction)];
      const std::string name = pair_name(pair);
      const std::filesystem::path folder = request.out / name;
      std::filesystem::create_directories(folder);
      write_field(folder / (name + "_mode-image_xfm.nii.gz"), field.field, FieldConvention::itk);
      write_nifti_labels(folder / (name + "_desc-exact_mask.nii.gz"), grid,
                         std::vector<std::int32_t>(field.exact.begin(), field.exact.end()));
      write_file_atomically(folder / "landmarks.csv",
                            landmark_table(files.at(pair.first).landmarks, files.at(pair.second).landmarks));
      std::size_t exact = 0;
      for (const std::uint8_t e : field.exact)
        exact += e;
      const double fraction = static_cast<double>(exact) / static_cast<double>(field.exact.size());
      char cell[32];
      std::snprintf(cell, sizeof cell, "%.6f", fraction);
      table += pair.first + "\t" + pair.second + "\t" + name + "/" + name + "_mode-image_xfm.nii.gz\t" +
               name + "/" + name + "_desc-exact_mask.nii.gz\t" + name + "/landmarks.csv\t" + cell + "\n";
      written.push_back({{"moving", pair.first},
                         {"fixed", pair.second},
                         {"folder", name},
                         {"exact_fraction", fraction},
                         {"left_out_by_round_trip", dropped[static_cast<std::size_t>(direction)]}});
    }
  }
  write_file_atomically(request.out / "pairs.tsv", table);
  return {{"dataset", request.dataset.string()}, {"pairs", written}};
}

} // namespace phantasm
