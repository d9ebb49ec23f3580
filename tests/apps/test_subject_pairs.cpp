// Fields between two subjects of one template (phantasm pair, evaluation/subject_pairs.cpp): the
// composition through the template on analytic fields, the pairs chosen, and on a population of
// three solved subjects: the composed field against the direct composition of the two solved
// meshes, i -> j after j -> i against the identity, the landmarks, transformix carrying i's labels
// onto j's, and bad input refused with nothing written.

#include "anatomy/phantom.hpp"
#include "batch/sweep.hpp"
#include "core/error.hpp"
#include "evaluation/subject_pairs.hpp"
#include "geometry/ras_lps.hpp"
#include "geometry/tet_location.hpp"
#include "io/dataset_layout.hpp"
#include "io/mesh_file.hpp"
#include "io/nifti_file.hpp"
#include "scene/scene.hpp"
#include "sim/deform_phantom.hpp"
#include "tests/apps/cli_fixtures.hpp"
#include "tests/apps/transformix_parameters.hpp"
#include "tests/support/error_message.hpp"
#include "tests/support/shared_output.hpp"
#include "tests/support/subprocess.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

using namespace phantasm;
using namespace phantasm::testing;
namespace fs = std::filesystem;

namespace {

const fs::path k_population = k_source_dir / "tests" / "data" / "sweeps" / "population-balls.yaml";

ImageGrid small_grid() {
  ImageGrid grid;
  grid.dims = Eigen::Vector3i(16, 14, 12);
  grid.spacing_mm = Eigen::Vector3d::Constant(2.0);
  grid.world_from_voxel.topLeftCorner<3, 3>() = 2.0 * Eigen::Matrix3d::Identity();
  grid.world_from_voxel.topRightCorner<3, 1>() = Eigen::Vector3d(-15, -13, -11);
  return grid;
}

/// The field of the point map x -> map(x) sampled at the voxels of `grid`.
template <typename Map>
DisplacementField sampled_field(const ImageGrid& grid, const Map& map) {
  DisplacementField field{grid, std::vector<Eigen::Vector3d>(static_cast<std::size_t>(grid.voxel_count()))};
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i) {
        const Eigen::Vector3d x = grid.world_from_index(Eigen::Vector3d(i, j, k));
        field.lps_mm[voxel_index(grid.dims, i, j, k)] = lps_from_ras(map(x) - x);
      }
  return field;
}

/// The field of the affine point map x -> a x + b on `grid` (trilinear interpolation is exact on it).
DisplacementField affine_field(const ImageGrid& grid, const Eigen::Matrix3d& a, const Eigen::Vector3d& b) {
  return sampled_field(grid, [&](const Eigen::Vector3d& x) { return Eigen::Vector3d(a * x + b); });
}

/// A batch of the three-subject population and its pairs (all), which the tests of this file read
/// (made once per build of the program: tests/support/shared_output.hpp), and a fresh folder
/// `root` of the test's own for what it writes.
struct Population {
  fs::path root, dataset, pairs;
};

Population make_population(const std::string& name) {
  const std::vector<fs::path> inputs = {k_population,
                                        k_source_dir / "tests/data/scenes/population-balls.yaml"};
  const fs::path shared = shared_output("population-balls-pairs", inputs, [](const fs::path& folder) {
    const CommandResult batch = run_command({k_phantasm, "batch", k_population.string(), "-o",
                                             (folder / "dataset").string(), "--jobs", "2", "--quiet"});
    EXPECT_EQ(batch.exit_code, 0) << batch.err;
    if (batch.exit_code != 0) return false;
    const CommandResult pair = run_command(
        {k_phantasm, "pair", (folder / "dataset").string(), "-o", (folder / "pairs").string(), "-q"});
    EXPECT_EQ(pair.exit_code, 0) << pair.err;
    return pair.exit_code == 0;
  });
  return {fresh_folder(name), shared / "dataset", shared / "pairs"};
}

fs::path pair_file(const Population& p, const std::string& i, const std::string& j,
                   const std::string& suffix) {
  const std::string name = "from-" + i + "_to-" + j;
  return p.pairs / name / (name + suffix);
}

std::vector<std::int32_t> labels_of(const fs::path& path, ImageGrid* grid = nullptr) {
  ImageGrid ignored;
  return read_nifti_labels(path, grid ? grid : &ignored);
}

/// Voxels whose 26 neighbours all carry their label: away from every boundary.
std::vector<bool> interior(const std::vector<std::int32_t>& labels, const ImageGrid& grid) {
  std::vector<bool> inside(labels.size(), false);
  for (int k = 1; k + 1 < grid.dims.z(); ++k)
    for (int j = 1; j + 1 < grid.dims.y(); ++j)
      for (int i = 1; i + 1 < grid.dims.x(); ++i) {
        const std::int32_t own = labels[voxel_index(grid.dims, i, j, k)];
        bool same = true;
        for (int dk = -1; dk <= 1 && same; ++dk)
          for (int dj = -1; dj <= 1 && same; ++dj)
            for (int di = -1; di <= 1 && same; ++di)
              same = labels[voxel_index(grid.dims, i + di, j + dj, k + dk)] == own;
        inside[voxel_index(grid.dims, i, j, k)] = same;
      }
  return inside;
}

/// The smallest Dice over the labels of `fixed` (but 0) within `region`.
double smallest_dice(const std::vector<std::int32_t>& fixed, const std::vector<std::int32_t>& warped,
                     const std::vector<bool>& region) {
  std::map<std::int32_t, std::array<double, 3>> counts; // both, fixed, warped
  for (std::size_t v = 0; v < fixed.size(); ++v) {
    if (!region[v]) continue;
    counts[fixed[v]][1] += 1;
    counts[warped[v]][2] += 1;
    if (fixed[v] == warped[v]) counts[fixed[v]][0] += 1;
  }
  double smallest = 1.0;
  for (const auto& [label, c] : counts)
    if (label != 0 && c[1] > 0) smallest = std::min(smallest, 2.0 * c[0] / (c[1] + c[2]));
  return smallest;
}

} // namespace

// Two affine maps composed through a template: trilinear interpolation is exact on affine fields,
// so the composed field is the composed map wherever the template point lies on the grid; a
// voxel not exact in the fixed subject's mask, or a template cell touching one not exact in the
// moving subject's, is not exact in the result.
TEST(SubjectPairs, CompositionThroughTheTemplateIsTheComposedMapAndItsMaskTheIntersection) {
  const ImageGrid grid = small_grid();
  Eigen::Matrix3d a_moving, a_fixed;
  a_moving << 1.05, 0.02, 0.0, -0.01, 0.97, 0.03, 0.0, 0.01, 1.02;
  a_fixed << 0.96, 0.0, 0.02, 0.01, 1.03, 0.0, -0.02, 0.0, 0.99;
  const Eigen::Vector3d b_moving(0.4, -0.3, 0.2), b_fixed(-0.2, 0.1, 0.3);
  const DisplacementField moving = affine_field(grid, a_moving, b_moving);
  const DisplacementField fixed = affine_field(grid, a_fixed, b_fixed);
  const std::size_t n = static_cast<std::size_t>(grid.voxel_count());
  std::vector<std::uint8_t> moving_exact(n, 1), fixed_exact(n, 1);
  fixed_exact[voxel_index(grid.dims, 8, 7, 6)] = 0;
  moving_exact[voxel_index(grid.dims, 4, 4, 4)] = 0;
  const ComposedField composed = compose_through_template(moving, moving_exact, fixed, fixed_exact);
  std::size_t checked = 0;
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i) {
        const std::size_t v = voxel_index(grid.dims, i, j, k);
        const Eigen::Vector3d x = grid.world_from_index(Eigen::Vector3d(i, j, k));
        const Eigen::Vector3d in_template = a_fixed * x + b_fixed;
        const Eigen::Vector3d index = grid.index_from_world(in_template);
        const bool on_grid =
            (index.array() >= 0.0).all() && (index.array() <= (grid.dims.cast<double>().array() - 1.0)).all();
        if (!on_grid) {
          EXPECT_EQ(composed.exact[v], 0) << "a template point off the grid is no exact composition";
          continue;
        }
        const Eigen::Vector3d expected = a_moving * in_template + b_moving - x;
        EXPECT_LT((ras_from_lps(composed.field.lps_mm[v]) - expected).norm(), 1e-9)
            << i << " " << j << " " << k;
        const bool touches = (index - Eigen::Vector3d(4, 4, 4)).cwiseAbs().maxCoeff() < 1.0;
        EXPECT_EQ(composed.exact[v], (i == 8 && j == 7 && k == 6) || touches ? 0 : 1)
            << i << " " << j << " " << k;
        ++checked;
      }
  EXPECT_GT(checked, n / 2);
}

// A body whose map kinks inside a grid cell: a box of 12 tets (x from -8 to 8 mm, two cubes) whose
// middle plane the moving subject's solve took 4 mm along x, the rest of space still. Through
// the body's tets the composed field is the map itself at every template point in the body (the
// trilinear field misses it by more than 0.1 voxel at the kink); exact are the voxels whose
// template cell lies wholly in the body, without a voxel of still tissue, or wholly outside it,
// and, where the body's map and the still space's agree within 0.01 voxel, those across.
TEST(SubjectPairs, ABodysMapIsComposedThroughItsTetsAndCellsAcrossItsBoundaryOnlyWhereTheMapsAgree) {
  const ImageGrid grid = small_grid(); // voxel centres at odd x: the kink at x = 0 is mid-cell
  SolvedBodies bodies;
  Eigen::MatrixX3d rest(12, 3);
  for (int n = 0; n < 12; ++n)
    rest.row(n) = Eigen::RowVector3d(-8.0 + 8.0 * (n % 3), (n / 3) % 2 ? 8.0 : -8.0, n / 6 ? 8.0 : -8.0);
  const auto corner = [](int xi, int yi, int zi) { return xi + 3 * yi + 6 * zi; };
  Eigen::MatrixX4i tets(12, 4);
  int row = 0;
  for (int cube = 0; cube < 2; ++cube) {
    // The six tets of a cube around its diagonal (0,0,0)-(1,1,1), each path through the axes once.
    const int order[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    for (const auto& axes : order) {
      int at[3] = {0, 0, 0};
      tets(row, 0) = corner(cube + at[0], at[1], at[2]);
      for (int step = 0; step < 3; ++step) {
        at[axes[step]] = 1;
        tets(row, step + 1) = corner(cube + at[0], at[1], at[2]);
      }
      ++row;
    }
  }
  Eigen::MatrixX3d solved = rest;
  for (int n = 0; n < 12; ++n)
    if (n % 3 == 1) solved(n, 0) += 4.0;
  bodies.tets = {tets};
  bodies.rest_mm = {rest};
  bodies.deformed_mm = {solved};
  // The map: x moved by 4 (1 - |x| / 8) along x inside the box.
  const auto inside = [](const Eigen::Vector3d& p) { return (p.array().abs() <= 8.0).all(); };
  const auto map = [&](const Eigen::Vector3d& p) {
    return inside(p) ? Eigen::Vector3d(p.x() + 4.0 * (1.0 - std::abs(p.x()) / 8.0), p.y(), p.z()) : p;
  };
  // The moving subject's field samples the map; one voxel in the body holds still tissue.
  const std::size_t n = static_cast<std::size_t>(grid.voxel_count());
  DisplacementField moving = sampled_field(grid, map);
  const Eigen::Vector3i still(9, 6, 5); // x = 3, y = -1, z = -1 mm
  moving.lps_mm[voxel_index(grid.dims, still.x(), still.y(), still.z())] = Eigen::Vector3d::Zero();
  // The fixed subject: the template shifted off the grid's voxels.
  const Eigen::Vector3d shift(0.5, 0.3, 0.2);
  const DisplacementField fixed = affine_field(grid, Eigen::Matrix3d::Identity(), shift);
  const std::vector<std::uint8_t> all(n, 1);
  const ComposedField through_tets = compose_through_template(moving, all, fixed, all, &bodies);
  const ComposedField trilinear = compose_through_template(moving, all, fixed, all);
  double trilinear_miss = 0.0;
  std::size_t exact_inside = 0, exact_outside = 0;
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i) {
        const std::size_t v = voxel_index(grid.dims, i, j, k);
        const Eigen::Vector3d x = grid.world_from_index(Eigen::Vector3d(i, j, k));
        const Eigen::Vector3d in_template = x + shift;
        const Eigen::Vector3d index = grid.index_from_world(in_template);
        if ((index.array() < 0.0).any() || (index.array() > grid.dims.cast<double>().array() - 1.0).any()) {
          EXPECT_EQ(through_tets.exact[v], 0);
          continue;
        }
        // The cell's voxels: all in the body (none the still one), or all outside it.
        int in_body = 0;
        bool touches_still = false;
        const Eigen::Vector3i low = index.array().floor().cast<int>();
        for (int c = 0; c < 8; ++c) {
          const Eigen::Vector3i at = low + Eigen::Vector3i(c & 1, (c >> 1) & 1, (c >> 2) & 1);
          in_body += inside(grid.world_from_index(at.cast<double>())) ? 1 : 0;
          touches_still = touches_still || at == still;
        }
        const bool expected_exact = inside(in_template) ? in_body == 8 && !touches_still : in_body == 0;
        EXPECT_EQ(through_tets.exact[v], expected_exact ? 1 : 0) << i << " " << j << " " << k;
        (inside(in_template) ? exact_inside : exact_outside) += expected_exact ? 1 : 0;
        if (!inside(in_template)) continue;
        const Eigen::Vector3d expected = map(in_template) - x;
        EXPECT_LT((ras_from_lps(through_tets.field.lps_mm[v]) - expected).norm(), 1e-9)
            << i << " " << j << " " << k;
        if (expected_exact)
          trilinear_miss =
              std::max(trilinear_miss, (ras_from_lps(trilinear.field.lps_mm[v]) - expected).norm());
      }
  EXPECT_GT(exact_inside, 100u);
  EXPECT_GT(exact_outside, 100u);
  EXPECT_GT(trilinear_miss, 0.1 * grid.spacing_mm.minCoeff())
      << "the kink must be one the trilinear field misses";

  // The middle plane moved 0.01 mm instead: the body's map and the still space around it differ
  // by at most that, below a hundredth of a voxel (0.02 mm), so a cell across the boundary or
  // touching the still voxel is exact too (every template point on the grid), the body's map
  // inside and the still space's outside.
  bodies.deformed_mm[0] = rest;
  for (int vertex = 0; vertex < 12; ++vertex)
    if (vertex % 3 == 1) bodies.deformed_mm[0](vertex, 0) += 0.01;
  const auto small_map = [&](const Eigen::Vector3d& p) {
    return inside(p) ? Eigen::Vector3d(p.x() + 0.01 * (1.0 - std::abs(p.x()) / 8.0), p.y(), p.z()) : p;
  };
  moving = sampled_field(grid, small_map);
  moving.lps_mm[voxel_index(grid.dims, still.x(), still.y(), still.z())] = Eigen::Vector3d::Zero();
  const ComposedField slight = compose_through_template(moving, all, fixed, all, &bodies);
  std::size_t mixed_exact = 0;
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i) {
        const std::size_t v = voxel_index(grid.dims, i, j, k);
        const Eigen::Vector3d x = grid.world_from_index(Eigen::Vector3d(i, j, k));
        const Eigen::Vector3d index = grid.index_from_world(x + shift);
        if ((index.array() > grid.dims.cast<double>().array() - 1.0).any()) continue;
        EXPECT_EQ(slight.exact[v], 1) << i << " " << j << " " << k;
        EXPECT_LT((ras_from_lps(slight.field.lps_mm[v]) - (small_map(x + shift) - x)).norm(), 1e-9)
            << i << " " << j << " " << k;
        mixed_exact += through_tets.exact[v] ? 0 : 1;
      }
  EXPECT_GT(mixed_exact, 100u) << "cells across the boundary, not exact with the 4 mm move";
}

// A pair's round trip: a voxel of the forward field's exact mask whose point the backward field
// (trilinear) does not bring back within 0.1 voxel leaves the mask; every other voxel stays.
TEST(SubjectPairs, TheRoundTripNarrowsTheMaskToWhereTheTwoFieldsInvertEachOther) {
  const ImageGrid grid = small_grid();
  const std::size_t n = static_cast<std::size_t>(grid.voxel_count());
  const Eigen::Vector3d step(0.6, 0.0, 0.0); // 0.3 voxel along x
  ComposedField forward{affine_field(grid, Eigen::Matrix3d::Identity(), step),
                        std::vector<std::uint8_t>(n, 1)};
  DisplacementField backward = affine_field(grid, Eigen::Matrix3d::Identity(), -step);
  backward.lps_mm[voxel_index(grid.dims, 8, 7, 6)] += lps_from_ras(Eigen::Vector3d(1.0, 0.0, 0.0));
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      forward.exact[voxel_index(grid.dims, grid.dims.x() - 1, j, k)] = 0; // its point leaves the grid
  // The voxels (7, 7, 6) and (8, 7, 6) read the bent voxel with weights 0.3 and 0.7: misses of
  // 0.3 and 0.7 mm, over 0.1 voxel (0.2 mm).
  EXPECT_EQ(narrow_to_round_trip(forward, backward), 2u);
  std::size_t kept = 0;
  for (std::size_t v = 0; v < n; ++v)
    kept += forward.exact[v];
  EXPECT_EQ(kept, n - static_cast<std::size_t>(grid.dims.y() * grid.dims.z()) - 2);
  EXPECT_EQ(forward.exact[voxel_index(grid.dims, 7, 7, 6)], 0);
  EXPECT_EQ(forward.exact[voxel_index(grid.dims, 8, 7, 6)], 0);
}

// All pairs are every unordered pair; random pairs are distinct, the same for the same seed;
// listed pairs name subjects of the dataset, or the message names the one that is not.
TEST(SubjectPairs, PairsAreAllListedOrDrawnWithTheSeed) {
  const std::vector<std::string> subjects = {"01", "02", "03", "04", "05", "06"};
  PairRequest request;
  request.dataset = "data";
  EXPECT_EQ(choose_pairs(subjects, request).size(), 15u);
  request.random_count = 5;
  request.seed = 3;
  const std::vector<SubjectPair> drawn = choose_pairs(subjects, request);
  EXPECT_EQ(drawn.size(), 5u);
  EXPECT_EQ(std::set<SubjectPair>(drawn.begin(), drawn.end()).size(), 5u);
  EXPECT_EQ(choose_pairs(subjects, request), drawn);
  bool another = false;
  for (std::uint64_t seed = 4; seed < 8; ++seed) {
    request.seed = seed;
    another = another || choose_pairs(subjects, request) != drawn;
  }
  EXPECT_TRUE(another) << "the seed chooses the pairs";
  request.random_count = 16;
  EXPECT_NE(input_error_message([&] {
              choose_pairs(subjects, request);
            }).find("--random: expected at most 15 pairs"),
            std::string::npos);
  request.random_count = 0;
  request.listed = parse_pair_list("03:01,02:05");
  EXPECT_EQ(choose_pairs(subjects, request), (std::vector<SubjectPair>{{"01", "03"}, {"02", "05"}}));
  request.listed = parse_pair_list("01:09");
  EXPECT_NE(input_error_message([&] {
              choose_pairs(subjects, request);
            }).find("--pairs: expected subjects of data (01, 02, 03, 04, 05, 06), found '09'"),
            std::string::npos);
  EXPECT_NE(input_error_message([&] { parse_pair_list("01-02"); }).find("found '01-02'"), std::string::npos);
}

// Three subjects solved from one template, paired: in the exact mask, each composed field is
// within 0.1 voxel of the direct composition (the point of j located in j's solved mesh, carried
// by the same barycentric weights to i's) and i -> j composed with j -> i (trilinear, as a tool
// composes the files) is the identity within 0.1 voxel, at every voxel, and i's landmarks are where the field
// takes j's (within 0.2 voxel, as a single subject's fields carry its landmarks: docs/volumes-and-images.md).
// Then bad input: a subject the dataset does not hold, and a subject of another template, each exit 2 with
// nothing written.
TEST(SubjectPairs, PopulationPairsMatchTheDirectCompositionAndInvertEachOther) {
  const Population p = make_population("pairs");
  const Sweep sweep = load_sweep(k_population);
  Reporter quiet = Reporter::silent();
  const SceneLoadResult first = parse_scene(sweep.subjects[0].scene_text, sweep.base_scene);
  ASSERT_TRUE(first.scene);
  const Phantom phantom = build_phantom(first.scene->anatomy, {}, quiet);
  std::map<std::string, DeformedBody> bodies;
  for (const SweepSubject& subject : sweep.subjects) {
    const SceneLoadResult loaded = parse_scene(subject.scene_text, sweep.base_scene);
    ASSERT_TRUE(loaded.scene);
    StageReport report;
    bodies[subject.id] =
        deform_phantom(loaded.scene->deformation, loaded.scene->organs, phantom, report, quiet).bodies.at(0);
  }
  const ImageGrid grid = first.scene->grid.grid();
  const double voxel = grid.spacing_mm.minCoeff();
  double largest_move = 0.0;
  for (const auto& [i, j] : std::vector<SubjectPair>{{"01", "02"}, {"02", "03"}, {"03", "01"}}) {
    const DisplacementField forward = read_displacement_field(pair_file(p, i, j, "_mode-image_xfm.nii.gz"));
    const DisplacementField backward = read_displacement_field(pair_file(p, j, i, "_mode-image_xfm.nii.gz"));
    const std::vector<std::int32_t> exact = labels_of(pair_file(p, i, j, "_desc-exact_mask.nii.gz"));
    const DeformedBody& moving = bodies.at(i);
    const DeformedBody& fixed = bodies.at(j);
    const TetMeshLocator locator(fixed.deformed_mm, fixed.tets);
    std::vector<double> direct_errors, identity_errors;
    for (int k = 0; k < grid.dims.z(); ++k)
      for (int jj = 0; jj < grid.dims.y(); ++jj)
        for (int ii = 0; ii < grid.dims.x(); ++ii) {
          const std::size_t v = voxel_index(grid.dims, ii, jj, k);
          if (!exact[v]) continue;
          const Eigen::Vector3d x = grid.world_from_index(Eigen::Vector3d(ii, jj, k));
          const Eigen::Vector3d in_moving = forward.moved(x);
          largest_move = std::max(largest_move, (in_moving - x).norm());
          identity_errors.push_back((backward.moved(in_moving) - x).norm());
          const std::optional<TetLocation> at = locator.find(x, 1e-9, 1e-6);
          if (!at) continue; // outside the solved body: the still box, where both stay
          Eigen::Vector3d direct = Eigen::Vector3d::Zero();
          for (int c = 0; c < 4; ++c)
            direct += at->weights[c] * moving.deformed_mm.row(fixed.tets(at->tet, c)).transpose();
          direct_errors.push_back((in_moving - direct).norm());
        }
    const Summary direct = summarize(direct_errors), identity = summarize(identity_errors);
    const auto over = [&](const std::vector<double>& errors) {
      return 100.0 *
             static_cast<double>(
                 std::count_if(errors.begin(), errors.end(), [&](double e) { return e > 0.1 * voxel; })) /
             static_cast<double>(errors.size());
    };
    EXPECT_GT(direct.count, 100000u);
    EXPECT_LE(direct.max, 0.1 * voxel) << i << " -> " << j;
    EXPECT_LE(identity.max, 0.1 * voxel) << i << " -> " << j << " -> " << i;
    std::printf(
        "[pairs] %s -> %s: against the direct composition mean %.4f, p95 %.4f, max %.4f mm, %.4f %% over "
        "0.1 voxel (%zu voxels); round trip mean %.4f, p95 %.4f, max %.4f mm, %.4f %% over 0.1 voxel\n",
        i.c_str(), j.c_str(), direct.mean, direct.p95, direct.max, over(direct_errors), direct.count,
        identity.mean, identity.p95, identity.max, over(identity_errors));

    // Landmarks: the field takes j's landmark to i's.
    std::ifstream table(p.pairs / ("from-" + i + "_to-" + j) / "landmarks.csv");
    std::string line;
    std::getline(table, line);
    int rows = 0;
    while (std::getline(table, line)) {
      std::stringstream cells(line);
      std::string cell;
      std::vector<double> numbers;
      for (int c = 0; std::getline(cells, cell, ','); ++c)
        if (c >= 2) numbers.push_back(std::stod(cell));
      ASSERT_EQ(numbers.size(), 6u) << line;
      const Eigen::Vector3d in_i(numbers[0], numbers[1], numbers[2]),
          in_j(numbers[3], numbers[4], numbers[5]);
      EXPECT_LT((forward.moved(in_j) - in_i).norm(), 0.2 * voxel) << line;
      ++rows;
    }
    EXPECT_GT(rows, 3);
  }
  EXPECT_GT(largest_move, voxel) << "subjects must differ by more than a voxel for the test to tell";

  // Without -q, each field's line gives its exact fraction and what the round trip left out, as
  // pairs.tsv holds the fraction.
  const CommandResult printed = run_command(
      {k_phantasm, "pair", p.dataset.string(), "-o", (p.root / "printed").string(), "--pairs", "01:02"});
  EXPECT_EQ(printed.exit_code, 0) << printed.err;
  EXPECT_NE(printed.out.find("sub-01 -> sub-02  from-01_to-02  (exact in "), std::string::npos) << printed.out;
  EXPECT_NE(printed.out.find("voxels left out by the round trip)"), std::string::npos) << printed.out;

  // Bad input: exit 2, the message names the subject, nothing written.
  const CommandResult unknown = run_command(
      {k_phantasm, "pair", p.dataset.string(), "-o", (p.root / "bad1").string(), "--pairs", "01:07"});
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_NE(unknown.err.find("found '07', which it does not hold"), std::string::npos) << unknown.err;
  EXPECT_FALSE(fs::exists(p.root / "bad1"));
  // A subject of another template: its reference labels differ (one voxel changed).
  const fs::path mixed = p.root / "mixed";
  fs::copy(p.dataset, mixed, fs::copy_options::recursive);
  const DatasetLayout third(mixed, "03");
  ImageGrid labels_grid;
  std::vector<std::int32_t> labels = labels_of(third.dseg(PhantomState::reference), &labels_grid);
  labels[labels.size() / 2] += 1;
  write_nifti_labels(third.dseg(PhantomState::reference), labels_grid, labels);
  const CommandResult other =
      run_command({k_phantasm, "pair", mixed.string(), "-o", (p.root / "bad2").string()});
  EXPECT_EQ(other.exit_code, 2);
  EXPECT_NE(other.err.find("sub-03 and sub-01 cannot be paired through one template"), std::string::npos)
      << other.err;
  EXPECT_FALSE(fs::exists(p.root / "bad2"));
  // A subject without its solved tet mesh, and one whose rest tet mesh is not the template's.
  const fs::path meshless = p.root / "meshless";
  fs::copy(p.dataset, meshless, fs::copy_options::recursive);
  const fs::path solved_mesh = DatasetLayout(meshless, "02").tet_mesh(PhantomState::deformed, "layer");
  ASSERT_TRUE(fs::remove(solved_mesh));
  const CommandResult missing =
      run_command({k_phantasm, "pair", meshless.string(), "-o", (p.root / "bad3").string()});
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.err.find(solved_mesh.string() + ": expected sub-02's file"), std::string::npos)
      << missing.err;
  EXPECT_FALSE(fs::exists(p.root / "bad3"));
  const fs::path moved = p.root / "moved";
  fs::copy(p.dataset, moved, fs::copy_options::recursive);
  const fs::path rest_mesh = DatasetLayout(moved, "03").tet_mesh(PhantomState::reference, "layer");
  TetMesh rest = read_vtu(rest_mesh);
  rest.vertices(0, 0) += 0.01;
  write_vtu(rest_mesh, rest);
  const CommandResult moved_rest =
      run_command({k_phantasm, "pair", moved.string(), "-o", (p.root / "bad4").string(), "--pairs", "01:03"});
  EXPECT_EQ(moved_rest.exit_code, 2);
  EXPECT_NE(moved_rest.err.find("expected the rest tet mesh of sub-01"), std::string::npos) << moved_rest.err;
  EXPECT_FALSE(fs::exists(p.root / "bad4"));
}

// transformix, given the pair field from-i_to-j as docs/subject-pairs.md says, carries i's labels
// (ses-def) onto j's grid: Dice >= 0.98 for every label away from j's boundaries, where i's labels
// unwarped score lower (the subjects differ there).
TEST(SubjectPairs, TransformixCarriesOneSubjectsLabelsOntoTheOthers) {
  const Population p = make_population("pairs-transformix");
  for (const auto& [i, j] : std::vector<SubjectPair>{{"01", "02"}, {"03", "01"}}) {
    ImageGrid grid;
    const std::vector<std::int32_t> target =
        labels_of(DatasetLayout(p.dataset, j).dseg(PhantomState::deformed), &grid);
    const fs::path moving = DatasetLayout(p.dataset, i).dseg(PhantomState::deformed);
    const fs::path folder = p.root / ("transformix-" + i + "-" + j);
    fs::create_directories(folder);
    write_text_file(folder / "parameters.txt",
                    deformation_field_parameters(pair_file(p, i, j, "_mode-image_xfm.nii.gz"), grid));
    const CommandResult result = run_command({"/usr/bin/transformix", "-in", moving.string(), "-out",
                                              folder.string(), "-tp", (folder / "parameters.txt").string()});
    ASSERT_EQ(result.exit_code, 0) << result.out << result.err;
    const std::vector<std::int32_t> warped = labels_of(folder / "result.nii.gz");
    const std::vector<bool> away = interior(target, grid);
    const double dice = smallest_dice(target, warped, away);
    const double unwarped = smallest_dice(target, labels_of(moving), away);
    std::printf("[pairs] transformix %s -> %s: smallest Dice away from boundaries %.4f (unwarped %.4f)\n",
                i.c_str(), j.c_str(), dice, unwarped);
    EXPECT_GE(dice, 0.98);
    EXPECT_LT(unwarped, dice);
  }
}
