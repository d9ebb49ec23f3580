#include "anatomy/anatomy_plan.hpp"
#include "anatomy/shape_build.hpp"
#include "anatomy/shape_source.hpp"

#include <gtest/gtest.h>

#include <set>

using namespace phantasm;

TEST(AnalyticShapeBounds, EllipsoidBoundsFollowItsRotation) {
  ShapeSettings shape;
  shape.center_mm = {1, 2, 3};
  shape.radii_mm = {10, 20, 30};
  auto box = analytic_shape_bounds(shape);
  ASSERT_TRUE(box);
  EXPECT_TRUE(box->max_mm.isApprox(Eigen::Vector3d(11, 22, 33)));
  shape.rotation_deg = {0, 0, 90}; // x and y radii swap
  box = analytic_shape_bounds(shape);
  EXPECT_TRUE((box->max_mm - shape.center_mm).isApprox(Eigen::Vector3d(20, 10, 30), 1e-12));
  // At 45 degrees about z the x extent is sqrt((10^2 + 20^2) / 2), tighter than the box bound.
  shape.rotation_deg = {0, 0, 45};
  box = analytic_shape_bounds(shape);
  EXPECT_NEAR(box->max_mm.x() - 1.0, std::sqrt(250.0), 1e-12);
}

TEST(AnalyticShapeBounds, FileShapesHaveNoBoundsUntilRead) {
  ShapeSettings shape;
  shape.kind = ShapeKind::mesh;
  EXPECT_FALSE(analytic_shape_bounds(shape));
}

TEST(OrganTable, ResolvesParentsAndCountsContainingOrgans) {
  AnatomySettings anatomy;
  anatomy.organs = {{"scalp", "skin", "", "", true, 0, {}, 1.0, {}},
                    {"skull", "bone_cortical", "", "scalp", true, 0, {}, 1.0, {}},
                    {"brain", "white_matter", "", "skull", true, 0, {}, 1.0, {}}};
  const OrganTable organs = organ_table(anatomy);
  EXPECT_EQ(organs[0].depth, 0);
  EXPECT_EQ(organs[0].parent, -1);
  EXPECT_EQ(organs[2].depth, 2);
  EXPECT_EQ(organs[2].parent, 1);
  EXPECT_EQ(organs.index_of("skull"), 1);
  EXPECT_EQ(organs.index_of("liver"), -1);
  const StageReport report = plan_anatomy(anatomy, organs);
  ASSERT_EQ(report.modelled.size(), 3u);
  EXPECT_NE(report.modelled[2].find("inside skull (depth 2)"), std::string::npos) << report.modelled[2];
}

TEST(AnatomyPlan, StatesEachOrgansOwnBaseSizeAndItsTetSize) {
  AnatomySettings anatomy; // the scene's base size: 320
  OrganSettings ball, pea;
  ball.name = "ball", pea.name = "pea";
  ball.tissue = pea.tissue = "muscle_skeletal";
  ball.base_mesh_triangles = 100000; // its own
  pea.solid = false;
  anatomy.organs = {ball, pea};
  anatomy.organs[0].shape.radii_mm = {50, 45, 40};
  const StageReport report = plan_anatomy(anatomy, organ_table(anatomy));
  ASSERT_EQ(report.modelled.size(), 2u);
  // What the run builds: the organ's own 100000, not the scene's 320.
  EXPECT_NE(report.modelled[0].find("surface of 100000 base triangles (its own base_mesh_triangles)"),
            std::string::npos)
      << report.modelled[0];
  // Area 25400 mm^2 over 100000 triangles: edges of 1.35 x 0.77 = 1.03 mm.
  EXPECT_NE(report.modelled[0].find("tets of about 1."), std::string::npos) << report.modelled[0];
  EXPECT_NE(report.modelled[1].find("surface of 320 base triangles with"), std::string::npos)
      << report.modelled[1];
}

// The registry of organ shape sources (anatomy/shape_source.hpp, anatomy/shape_build.hpp): what
// every member must supply, and properties of what it supplies.

namespace {

/// A shape of `kind` with every analytic key set away from its default, rotated about each axis.
ShapeSettings sample_shape(ShapeKind kind) {
  ShapeSettings shape;
  shape.kind = kind;
  shape.center_mm = {3, -2, 5};
  shape.radii_mm = {10, 14, 8};
  shape.rotation_deg = {20, 30, 40};
  shape.exponent_1 = 0.7;
  shape.exponent_2 = 1.3;
  shape.size_mm = {16, 22, kind == ShapeKind::sheet ? 0.0 : 12.0};
  shape.cells = {2, 3, kind == ShapeKind::sheet ? 1 : 2};
  return shape;
}

} // namespace

TEST(ShapeSources, EveryMemberHasItsOwnNameAndKindAndABuildOfTheSameKind) {
  const auto& sources = shape_sources();
  const auto& builds = shape_builds();
  ASSERT_EQ(sources.size(), builds.size());
  std::set<std::string> names;
  std::set<int> kinds;
  for (std::size_t i = 0; i < sources.size(); ++i) {
    const ShapeSource& source = *sources[i];
    EXPECT_TRUE(names.insert(source.name).second) << source.name;
    EXPECT_TRUE(kinds.insert(static_cast<int>(source.kind)).second) << source.name;
    EXPECT_EQ(builds[i]->kind, source.kind) << source.name;
    EXPECT_EQ(&shape_source(source.kind), &source);
    EXPECT_EQ(find_shape_source(source.name), &source);
    EXPECT_STREQ(to_string(source.kind), source.name);
    EXPECT_NE(builds[i]->target, nullptr) << source.name;
  }
  EXPECT_EQ(shape_source_names().size(), sources.size());
  EXPECT_EQ(find_shape_source("cylinder"), nullptr);
}

TEST(ShapeSources, EveryMemberHasHelpAndWellFormedKeys) {
  for (const ShapeSource* source : shape_sources()) {
    EXPECT_GT(std::string(source->description).size(), 10u) << source->name;
    std::set<std::string> keys;
    for (const ShapeParameter& p : source->parameters) {
      const std::string where = std::string(source->name) + "." + p.key;
      EXPECT_FALSE(std::string(p.key).empty()) << source->name;
      EXPECT_TRUE(keys.insert(p.key).second) << where << " twice";
      EXPECT_NE(std::string(p.key), "type") << where;
      switch (p.kind) {
      case ShapeParameter::Kind::vector3:
      case ShapeParameter::Kind::extent2:
        EXPECT_NE(p.vector, nullptr) << where;
        EXPECT_LT(p.min, p.max) << where;
        break;
      case ShapeParameter::Kind::number:
        EXPECT_NE(p.number, nullptr) << where;
        EXPECT_LT(p.min, p.max) << where;
        break;
      case ShapeParameter::Kind::cells: EXPECT_TRUE(p.axes == 2 || p.axes == 3) << where; break;
      case ShapeParameter::Kind::file:
        for (const std::string& extension : p.extensions)
          EXPECT_EQ(extension.front(), '.') << where;
        break;
      case ShapeParameter::Kind::labels: break;
      }
    }
  }
}

TEST(ShapeSources, AShapeGivenBySettingsHasBoundsAndCostTermsAndOneReadFromFilesHasNeither) {
  for (const ShapeSource* source : shape_sources()) {
    const bool from_settings = source->input == ShapeInput::none;
    EXPECT_EQ(source->bounds != nullptr, from_settings) << source->name;
    EXPECT_EQ(source->area_volume != nullptr, from_settings) << source->name;
    if (source->nesting == NestingCheck::by_bounds) {
      EXPECT_NE(source->bounds, nullptr) << source->name;
    }
    if (source->plan_tet_size) {
      EXPECT_NE(source->area_volume, nullptr) << source->name;
    }
    if (source->structured) {
      const StructuredCounts solid = source->structured(sample_shape(source->kind), true);
      EXPECT_GT(solid.patches, 0.0) << source->name;
      EXPECT_EQ(solid.tets > 0.0, source->has_interior) << source->name;
      EXPECT_EQ(source->structured(sample_shape(source->kind), false).tets, 0.0) << source->name;
    }
  }
}

TEST(ShapeSources, EachTargetLiesWithinItsBoundsAndEnclosesItsEstimatedVolume) {
  for (const ShapeSource* source : shape_sources()) {
    if (source->bounds == nullptr) continue;
    const ShapeSettings shape = sample_shape(source->kind);
    const WorldBox bounds = source->bounds(shape);
    const std::unique_ptr<ImplicitShape> target = shape_build(source->kind).target(shape, nullptr, "organ");
    const double volume = source->area_volume(shape).second;
    if (!source->has_interior) {
      EXPECT_EQ(target, nullptr) << source->name;
      EXPECT_EQ(volume, 0.0) << source->name;
      continue;
    }
    ASSERT_NE(target, nullptr) << source->name;
    // Sample a box 20 % wider than the bounds: every inside point lies within them and, where the
    // bounds are the extent (NestingCheck::by_bounds), the inside points reach each face.
    const Eigen::Vector3d margin = 0.2 * (bounds.max_mm - bounds.min_mm);
    const Eigen::Vector3d low = bounds.min_mm - margin,
                          step = (bounds.max_mm - bounds.min_mm + 2 * margin) / 80;
    Eigen::Vector3d reached_min = Eigen::Vector3d::Constant(1e300), reached_max = -reached_min;
    for (int i = 0; i <= 80; ++i)
      for (int j = 0; j <= 80; ++j)
        for (int k = 0; k <= 80; ++k) {
          const Eigen::Vector3d x = low + step.cwiseProduct(Eigen::Vector3d(i, j, k));
          if (target->value(x) <= 0.0) continue;
          reached_min = reached_min.cwiseMin(x);
          reached_max = reached_max.cwiseMax(x);
        }
    EXPECT_TRUE((reached_min.array() >= bounds.min_mm.array()).all()) << source->name;
    EXPECT_TRUE((reached_max.array() <= bounds.max_mm.array()).all()) << source->name;
    if (source->nesting == NestingCheck::by_bounds) {
      EXPECT_LT((reached_min - bounds.min_mm).maxCoeff(), 1.01 * step.maxCoeff()) << source->name;
      EXPECT_LT((bounds.max_mm - reached_max).maxCoeff(), 1.01 * step.maxCoeff()) << source->name;
    }
    // The cost estimate's volume: exact where the plan sizes tets from its area, else within 30 %.
    const double tolerance = source->plan_tet_size ? 1e-9 : 0.3;
    EXPECT_NEAR(volume / target->volume(), 1.0, tolerance) << source->name;
  }
}
