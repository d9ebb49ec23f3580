// A change of the whole head's size and shape after the solve (deformation.head_scale): the
// subject's map is the head's growth after the solved one, x -> c + A (phi(x) - c), on every
// deformed position (the bodies' tets and every organ, fixed ones too), in both fields, their
// masks and Jacobians; bad values are clear errors; a population sweep draws it per subject.

#include "anatomy/phantom.hpp"
#include "batch/sweep.hpp"
#include "core/error.hpp"
#include "pipeline/run_pipeline.hpp"
#include "scene/scene.hpp"
#include "sim/deform_phantom.hpp"
#include "tests/support/deformed_bodies.hpp"
#include "tests/support/error_message.hpp"
#include "voxelize/motion_fields.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iostream>
#include <map>
#include <set>
#include <sstream>

using namespace phantasm;

namespace {

std::string repository_text(const std::string& path) {
  std::ifstream file(std::string(PHANTASM_SOURCE_DIR) + "/" + path);
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

/// The growth-balls scene (two balls grown in a compliant layer held by a box) with `head_scale`
/// set as YAML flow text under deformation, parsed.
SceneLoadResult balls_with(const std::string& head_scale, const std::string& mode = "quasi_static") {
  std::string text = repository_text("tests/data/scenes/growth-balls.yaml");
  const std::string key = "deformation:\n  mode: quasi_static\n";
  const std::size_t at = text.find(key);
  EXPECT_NE(at, std::string::npos);
  text.replace(at, key.size(),
               "deformation:\n  mode: " + mode + "\n" +
                   (head_scale.empty() ? "" : "  head_scale: " + head_scale + "\n"));
  if (mode == "none") {
    // No loads without a deformation.
    text = text.substr(0, text.find("  fixed: [box]")) + text.substr(text.find("sequences:"));
  }
  return parse_scene(text, std::string(PHANTASM_SOURCE_DIR) + "/tests/data/scenes/growth-balls.yaml");
}

double body_volume(const DeformedBody& body, bool deformed) {
  double total = 0.0;
  for (Eigen::Index t = 0; t < body.tets.rows(); ++t)
    total += phantasm::testing::body_tet_volume(deformed ? body.deformed_mm : body.rest_mm, body.tets, t);
  return total;
}

Eigen::Vector3d field_at(const std::vector<float>& u, std::size_t count, std::size_t v) {
  return {u[v], u[count + v], u[2 * count + v]};
}

} // namespace

// The solved body and every organ, the fixed box included, are the regional solve grown about the
// head's centre: the deformed body's volume is s^3 times the regionally grown one, each vertex is
// c + s (x - c) of its regional place within round-off, and the growth's own volume change is
// what the stage reports.
TEST(HeadScale, TheSolvedStateIsTheRegionalOneGrownAboutTheHeadsCentre) {
  const SceneLoadResult plain = balls_with("");
  const SceneLoadResult grown = balls_with("{scale: 1.08}");
  ASSERT_TRUE(plain.scene) << format_diagnostics(plain.problems);
  ASSERT_TRUE(grown.scene) << format_diagnostics(grown.problems);
  Reporter quiet = Reporter::silent();
  const Phantom phantom = build_phantom(plain.scene->anatomy, {}, quiet);
  StageReport plain_report, grown_report;
  const PhantomDeformation d0 =
      deform_phantom(plain.scene->deformation, plain.scene->organs, phantom, plain_report, quiet);
  const PhantomDeformation d1 =
      deform_phantom(grown.scene->deformation, grown.scene->organs, phantom, grown_report, quiet);
  ASSERT_EQ(d0.bodies.size(), 1u);
  ASSERT_EQ(d1.bodies.size(), 1u);
  EXPECT_TRUE(d0.head.identity());
  ASSERT_FALSE(d1.head.identity());
  const double s = 1.08;
  // The centre of the box of the organs at rest: the box, centred at the origin.
  EXPECT_LT(d1.head.center.norm(), 1.0);
  EXPECT_NEAR(d1.head.determinant(), s * s * s, 1e-12);
  EXPECT_NEAR(grown_report.accuracy.at("head scale volume factor"), s * s * s, 1e-12);
  // The body: s^3 its regionally grown volume, and its tets' det F s^3 theirs.
  EXPECT_NEAR(body_volume(d1.bodies[0], true) / body_volume(d0.bodies[0], true), s * s * s, 1e-9);
  ASSERT_EQ(d1.bodies[0].det_F.size(), d0.bodies[0].det_F.size());
  for (std::size_t t = 0; t < d0.bodies[0].det_F.size(); ++t)
    ASSERT_NEAR(d1.bodies[0].det_F[t], s * s * s * d0.bodies[0].det_F[t], 1e-9) << "tet " << t;
  const Eigen::Vector3d c = d1.head.center;
  double worst = 0.0;
  for (Eigen::Index v = 0; v < d0.bodies[0].deformed_mm.rows(); ++v) {
    const Eigen::Vector3d x = d0.bodies[0].deformed_mm.row(v).transpose();
    worst = std::max(worst, (d1.bodies[0].deformed_mm.row(v).transpose() - (c + s * (x - c))).norm());
  }
  EXPECT_LT(worst, 1e-9) << "the body's vertices are its regional solve grown";
  // Every organ follows, the fixed box too (the whole head grows), and the balls keep their
  // regional volume changes on top of the growth.
  ASSERT_EQ(d1.organs.size(), phantom.organs.size());
  for (std::size_t o = 0; o < phantom.organs.size(); ++o) {
    SCOPED_TRACE(phantom.organs[o].name);
    const Eigen::MatrixX3d& x0 = d0.organs[o].surface_mm;
    const Eigen::MatrixX3d& x1 = d1.organs[o].surface_mm;
    ASSERT_EQ(x0.rows(), x1.rows());
    ASSERT_GT(x0.rows(), 0);
    double miss = 0.0;
    for (Eigen::Index v = 0; v < x0.rows(); ++v)
      miss = std::max(miss, (x1.row(v).transpose() - (c + s * (x0.row(v).transpose() - c))).norm());
    EXPECT_LT(miss, 1e-9);
  }
  const std::size_t box = 0;
  ASSERT_EQ(phantom.organs[box].name, "box");
  EXPECT_EQ(d1.organs[box].moved_by, "fixed");
  EXPECT_GT(
      (d1.organs[box].surface_mm - phantom.organs[box].surface->rest_positions()).rowwise().norm().minCoeff(),
      0.08 * 30.0)
      << "the fixed box grows with the head";
  const std::map<std::string, double> change0 =
      phantasm::testing::organ_volume_changes(d0, plain.scene->organs);
  const std::map<std::string, double> change1 =
      phantasm::testing::organ_volume_changes(d1, grown.scene->organs);
  for (const char* ball : {"left", "right"})
    EXPECT_NEAR(1.0 + change1.at(ball), s * s * s * (1.0 + change0.at(ball)), 1e-9) << ball;
}

// A shape change: per-axis factors about a given centre move each axis by its own factor.
TEST(HeadScale, EachAxisGrowsByItsOwnFactorAboutTheGivenCentre) {
  const SceneLoadResult grown = balls_with("{scale: 1.02, axes: [1.03, 0.97, 1.0], center_mm: [1, -2, 3]}");
  ASSERT_TRUE(grown.scene) << format_diagnostics(grown.problems);
  Reporter quiet = Reporter::silent();
  const Phantom phantom = build_phantom(grown.scene->anatomy, {}, quiet);
  StageReport report;
  const PhantomDeformation d =
      deform_phantom(grown.scene->deformation, grown.scene->organs, phantom, report, quiet);
  const Eigen::Vector3d factors(1.02 * 1.03, 1.02 * 0.97, 1.02);
  EXPECT_LT((d.head.factors - factors).norm(), 1e-15);
  EXPECT_EQ(d.head.center, Eigen::Vector3d(1, -2, 3));
  // The fixed box does not move in the solve: its grown positions are its rest ones grown.
  const Eigen::MatrixX3d& rest = phantom.organs[0].surface->rest_positions();
  const Eigen::MatrixX3d& moved = d.organs[0].surface_mm;
  for (Eigen::Index v = 0; v < rest.rows(); ++v) {
    const Eigen::Vector3d expected =
        Eigen::Vector3d(1, -2, 3) + factors.cwiseProduct(rest.row(v).transpose() - Eigen::Vector3d(1, -2, 3));
    ASSERT_LT((moved.row(v).transpose() - expected).norm(), 1e-9) << "vertex " << v;
  }
  EXPECT_NEAR(d.head.determinant(), factors.prod(), 1e-15);
}

// Scene level, through the voxelization: the forward field carries each template point to its
// regional place grown (within the fields' float round-off), the inverse field carries each
// subject point back to the regional map's inverse of its ungrown place, still tissue moves by
// the growth alone, and the Jacobians are s^3 times the regional ones.
TEST(HeadScale, TheFieldsBothWaysAndTheirJacobiansFollowTheGrowth) {
  const SceneLoadResult plain = balls_with("");
  const SceneLoadResult grown = balls_with("{scale: 0.94}");
  ASSERT_TRUE(plain.scene && grown.scene);
  Reporter quiet = Reporter::silent();
  const Simulation r0 = simulate(*plain.scene, quiet, SimulationStage::voxelization);
  const Simulation r1 = simulate(*grown.scene, quiet, SimulationStage::voxelization);
  ASSERT_TRUE(r0.volumes.motion && r1.volumes.motion);
  ASSERT_TRUE(r0.deformation && r1.deformation);
  const HeadAffine& head = r1.deformation->head;
  const double s = 0.94, s3 = s * s * s;
  ASSERT_NEAR(head.determinant(), s3, 1e-12);
  const ImageGrid& grid = r1.volumes.grid;
  const auto count = static_cast<std::size_t>(grid.voxel_count());
  const MotionFields& f0 = *r0.volumes.motion;
  const MotionFields& f1 = *r1.volumes.motion;
  // The regional map, to compare the subject's inverse with.
  const DeformationMap regional(r0.deformation->bodies, 2.0 * grid.spacing_mm.maxCoeff());
  const std::vector<std::uint8_t> still = still_organ_labels(*r1.deformation);
  const std::vector<std::int32_t>& labels1 = r1.volumes.deformed->labels;
  long forward_checked = 0, backward_checked = 0, still_checked = 0, exact0 = 0, exact1 = 0;
  double forward_miss = 0.0, backward_miss = 0.0, still_miss = 0.0;
  double jacobian_sum0 = 0.0, jacobian_sum1 = 0.0;
  long jacobian_count = 0, still_jacobians = 0;
  for (std::size_t v = 0; v < count; ++v) {
    const auto row = static_cast<std::int64_t>(v) / grid.dims.x();
    const Eigen::Vector3d x = grid.world_from_index(
        Eigen::Vector3d(static_cast<double>(static_cast<std::int64_t>(v) % grid.dims.x()),
                        static_cast<double>(row % grid.dims.y()), static_cast<double>(row / grid.dims.y())));
    exact0 += f0.ref_to_def_exact[v];
    exact1 += f1.ref_to_def_exact[v];
    if (f0.ref_to_def_exact[v] && f1.ref_to_def_exact[v]) {
      const Eigen::Vector3d regional_place = x + field_at(f0.ref_to_def, count, v);
      forward_miss =
          std::max(forward_miss, (x + field_at(f1.ref_to_def, count, v) - head.apply(regional_place)).norm());
      ++forward_checked;
      jacobian_sum0 += f0.jacobian[v];
      jacobian_sum1 += f1.jacobian[v];
      ++jacobian_count;
    }
    const auto label = static_cast<std::size_t>(labels1[v]);
    const bool still_voxel = label < still.size() && still[label];
    if (f1.def_to_ref_exact[v] && still_voxel) {
      still_miss = std::max(still_miss, (x + field_at(f1.def_to_ref, count, v) - head.unapply(x)).norm());
      ++still_checked;
      if (f1.def_to_ref_jacobian[v] == static_cast<float>(1.0 / s3)) ++still_jacobians;
    } else if (f1.def_to_ref_exact[v]) {
      bool exact = false;
      const Eigen::Vector3d back = regional.inverse(head.unapply(x), &exact);
      if (!exact) continue;
      backward_miss = std::max(backward_miss, (x + field_at(f1.def_to_ref, count, v) - back).norm());
      ++backward_checked;
    }
  }
  std::cout << "s = " << s << ": forward field on " << forward_checked << " voxels, largest miss "
            << forward_miss << " mm; inverse field on " << backward_checked << " moving voxels, largest miss "
            << backward_miss << " mm, on " << still_checked << " still voxels " << still_miss
            << " mm; Jacobian mean ratio " << jacobian_sum1 / jacobian_sum0 << " (s^3 " << s3 << ") over "
            << jacobian_count << " voxels exact in both; exact voxels " << exact0 << " -> " << exact1 << "\n";
  // Float fields of a few mm: round-off of 1e-6 mm, far below a voxel.
  EXPECT_GT(forward_checked, static_cast<long>(count / 2));
  EXPECT_LT(forward_miss, 1e-4);
  EXPECT_GT(backward_checked, 1000);
  EXPECT_LT(backward_miss, 1e-4);
  EXPECT_GT(still_checked, 1000) << "the box and the space around it move by the growth alone";
  EXPECT_LT(still_miss, 1e-4);
  EXPECT_EQ(still_jacobians, still_checked);
  // The growth leaves the exact masks about as they were (a tenth of a voxel of composition).
  EXPECT_NEAR(static_cast<double>(exact1) / static_cast<double>(exact0), 1.0, 0.02);
  // The Jacobian over the voxels exact in both: s^3 times the regional one.
  ASSERT_GT(jacobian_count, 0);
  EXPECT_NEAR(jacobian_sum1 / jacobian_sum0, s3, 1e-4 * s3);
  // The tissue inside the box: s^3 its template volume (the balls' changes stay inside it).
  auto inside_volume = [&](const TissueVolumes& volumes) {
    long voxels = 0;
    for (const std::int32_t l : volumes.labels)
      voxels += l >= 2 ? 1 : 0; // every label but the background and the box
    return static_cast<double>(voxels);
  };
  const double inside_ratio = inside_volume(*r1.volumes.deformed) / inside_volume(r1.volumes.reference);
  std::cout << "volume inside the box, subject over template: " << inside_ratio << " (s^3 " << s3 << ")\n";
  EXPECT_NEAR(inside_ratio, s3, 0.02);
}

// Values that would invert or absurdly shrink the head are refused at their key, with the range;
// so is a growth in a scene that deforms nothing.
TEST(HeadScale, BadValuesAreClearErrorsAtTheirKey) {
  {
    const SceneLoadResult r = balls_with("{scale: 1.5}");
    EXPECT_FALSE(r.scene);
    const std::string text = format_diagnostics(r.problems);
    EXPECT_NE(text.find("deformation.head_scale.scale"), std::string::npos) << text;
    EXPECT_NE(text.find("0.7"), std::string::npos) << text;
    EXPECT_NE(text.find("1.3"), std::string::npos) << text;
  }
  {
    const SceneLoadResult r = balls_with("{scale: 0}");
    EXPECT_FALSE(r.scene);
    EXPECT_NE(format_diagnostics(r.problems).find("deformation.head_scale.scale"), std::string::npos);
  }
  {
    const SceneLoadResult r = balls_with("{scale: 1.2, axes: [1.2, 1, 1]}");
    EXPECT_FALSE(r.scene);
    const std::string text = format_diagnostics(r.problems);
    EXPECT_NE(text.find("deformation.head_scale.axes"), std::string::npos) << text;
    EXPECT_NE(text.find("1.44"), std::string::npos) << text;
  }
  {
    const SceneLoadResult r = balls_with("{scale: 1.0, axes: [1, -1, 1]}");
    EXPECT_FALSE(r.scene);
    EXPECT_NE(format_diagnostics(r.problems).find("deformation.head_scale.axes"), std::string::npos);
  }
  {
    const SceneLoadResult r = balls_with("{scale: 1.05, size: 2}");
    EXPECT_FALSE(r.scene);
    EXPECT_NE(format_diagnostics(r.problems).find("size"), std::string::npos);
  }
  {
    const SceneLoadResult r = balls_with("{scale: 1.05}", "none");
    EXPECT_FALSE(r.scene);
    const std::string text = format_diagnostics(r.problems);
    EXPECT_NE(text.find("deformation.head_scale"), std::string::npos) << text;
    EXPECT_NE(text.find("mode none"), std::string::npos) << text;
  }
  {
    const SceneLoadResult r = balls_with("{scale: 0.7, axes: [1, 1, 1]}");
    EXPECT_TRUE(r.scene) << format_diagnostics(r.problems);
  }
}

// The shipped population sweep draws each subject's head scale and shape: different per subject,
// the same on every reading (seeded by the sweep's seed, the subject and the key), within their
// truncation, and every subject's scene valid.
TEST(HeadScale, ThePopulationSweepDrawsEachSubjectsHeadReproducibly) {
  const std::filesystem::path file =
      std::string(PHANTASM_SOURCE_DIR) + "/data-synthetic/colin-population.yaml";
  const Sweep first = load_sweep(file, SweepDepth::full);
  const Sweep again = load_sweep(file, SweepDepth::full);
  ASSERT_EQ(first.subjects.size(), 20u);
  ASSERT_EQ(again.subjects.size(), 20u);
  std::set<std::string> scales;
  std::vector<double> values;
  for (std::size_t i = 0; i < first.subjects.size(); ++i) {
    EXPECT_EQ(first.subjects[i].values, again.subjects[i].values);
    EXPECT_EQ(first.subjects[i].scene_text, again.subjects[i].scene_text);
    std::map<std::string, std::string> drawn(first.subjects[i].values.begin(),
                                             first.subjects[i].values.end());
    ASSERT_EQ(drawn.count("deformation.head_scale.scale"), 1u);
    const double scale = std::stod(drawn.at("deformation.head_scale.scale"));
    EXPECT_GE(scale, 0.92);
    EXPECT_LE(scale, 1.08);
    scales.insert(drawn.at("deformation.head_scale.scale"));
    values.push_back(scale);
    for (int a = 0; a < 3; ++a) {
      const std::string key = "deformation.head_scale.axes[" + std::to_string(a) + "]";
      ASSERT_EQ(drawn.count(key), 1u) << key;
      const double factor = std::stod(drawn.at(key));
      EXPECT_GE(factor, 0.97);
      EXPECT_LE(factor, 1.03);
    }
    const SceneLoadResult scene = parse_scene(first.subjects[i].scene_text, first.base_scene);
    ASSERT_TRUE(scene.scene) << format_diagnostics(scene.problems);
    EXPECT_NEAR(scene.scene->deformation.head_scale.scale, scale, 1e-12);
  }
  EXPECT_EQ(scales.size(), first.subjects.size()) << "each subject draws its own";
  // A spread of the order drawn (sd 0.033): not all within a hundredth of 1.
  double mean = 0.0;
  for (const double v : values)
    mean += v / static_cast<double>(values.size());
  double variance = 0.0;
  for (const double v : values)
    variance += (v - mean) * (v - mean) / static_cast<double>(values.size() - 1);
  EXPECT_GT(std::sqrt(variance), 0.015);
  EXPECT_LT(std::sqrt(variance), 0.05);
}
