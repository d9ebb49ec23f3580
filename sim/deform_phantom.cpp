#include "sim/deform_phantom.hpp"

#include "sim/body_embedding.hpp"
#include "sim/build_model.hpp"
#include "sim/growth.hpp"
#include "sim/load_schedule.hpp"
#include "sim/load_type.hpp"
#include "sim/loads.hpp"

#include "core/format.hpp"
#include "core/progress.hpp"

#include <algorithm>
#include <limits>

namespace phantasm {
namespace {

/// The loads and obstacles of the scene, named for a warning.
std::string load_names(const DeformationSettings& deformation) {
  std::string names;
  for (const LoadSettings& load : deformation.loads) {
    if (!names.empty()) names += ", ";
    names += load_type(load.kind).summary(load);
  }
  if (!deformation.obstacles.empty())
    names += (names.empty() ? "" : ", ") + std::to_string(deformation.obstacles.size()) + " obstacle(s)";
  return names.empty() ? "no load" : names;
}

/// Physical validity of every body: each tet's det F, the smallest and the inverted tets (det F
/// <= 0) into the body, the stage's accuracy figures and, for inverted tets, a warning naming the organ
/// and the loads (a tet turned inside out has no physical meaning, and the displacement fields
/// of the ground truth are not invertible there).
void check_inversions(const DeformationSettings& deformation, PhantomDeformation& result,
                      StageReport& report) {
  for (DeformedBody& body : result.bodies) {
    body.smallest_det_F = 1.0;
    body.inverted_tets = 0;
    body.det_F.assign(static_cast<std::size_t>(body.tets.rows()), std::numeric_limits<double>::quiet_NaN());
    for (Eigen::Index t = 0; t < body.tets.rows(); ++t) {
      auto edges = [&](const Eigen::MatrixX3d& x) {
        Eigen::Matrix3d D;
        for (int k = 0; k < 3; ++k)
          D.col(k) = (x.row(body.tets(t, k + 1)) - x.row(body.tets(t, 0))).transpose();
        return D;
      };
      const double rest = edges(body.rest_mm).determinant();
      if (rest == 0.0) continue;
      const double det = edges(body.deformed_mm).determinant() / rest;
      body.det_F[static_cast<std::size_t>(t)] = det;
      body.smallest_det_F = std::min(body.smallest_det_F, det);
      if (!(det > 0.0)) ++body.inverted_tets;
    }
    report.accuracy[body.organ + " smallest det F"] = body.smallest_det_F;
    report.accuracy[body.organ + " inverted tets"] = static_cast<double>(body.inverted_tets);
    if (body.inverted_tets > 0) {
      report.warnings.push_back(body.organ + ": " + std::to_string(body.inverted_tets) + " of " +
                                std::to_string(body.tets.rows()) + " tets inverted (det F <= 0, smallest " +
                                format_number(body.smallest_det_F) + ") under " + load_names(deformation) +
                                "; the material is too soft for the load, or the solve did not converge");
    }
  }
}

/// The growth of the whole head that deformation.head_scale asks: about its centre, or about the
/// centre of the box of every organ's positions at rest.
HeadAffine head_affine(const HeadScaleSettings& settings, const Phantom& phantom) {
  HeadAffine head;
  head.factors = settings.factors();
  if (settings.center_mm) {
    head.center = *settings.center_mm;
    return head;
  }
  Eigen::Vector3d low = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), high = -low;
  auto extend = [&](const Eigen::MatrixX3d& points) {
    if (points.rows() == 0) return;
    low = low.cwiseMin(points.colwise().minCoeff().transpose());
    high = high.cwiseMax(points.colwise().maxCoeff().transpose());
  };
  for (const Organ& organ : phantom.organs) {
    if (organ.surface) extend(organ.surface->rest_positions());
    if (organ.sheet) extend(organ.sheet->vertices);
    if (organ.solid) extend(organ.solid->vertices);
  }
  head.center =
      (low.array() <= high.array()).all() ? Eigen::Vector3d(0.5 * (low + high)) : Eigen::Vector3d::Zero();
  return head;
}

/// Grows the whole head by deformation.head_scale after the solve: every organ's deformed
/// positions (fixed and rigid organs too) and the bodies' deformed tets. Stress-free, so the solved
/// state needs no other change: for an isotropic scale A F A^-1 = F (docs/batch.md, Population
/// sweeps).
void grow_head(const DeformationSettings& deformation, const Phantom& phantom, PhantomDeformation& result,
               StageReport& report) {
  if (deformation.head_scale.identity()) return;
  result.head = head_affine(deformation.head_scale, phantom);
  for (OrganDeformation& organ : result.organs) {
    result.head.apply_rows(organ.surface_mm);
    result.head.apply_rows(organ.solid_mm);
  }
  for (DeformedBody& body : result.bodies)
    result.head.apply_rows(body.deformed_mm);
  report.modelled.push_back("the whole head grown after the solve by " + format_vector(result.head.factors) +
                            " (x, y, z) about " + format_vector(result.head.center) +
                            " mm: volumes change by " + format_number(result.head.determinant()) +
                            " (head_scale)");
  report.accuracy["head scale volume factor"] = result.head.determinant();
}

} // namespace

PhantomDeformation deform_phantom(const DeformationSettings& deformation, const OrganTable& organs,
                                  const Phantom& phantom, StageReport& report, Reporter& reporter,
                                  const BodyMeshSource& body_meshes) {
  using namespace sim_detail;
  const BodyAssignment assignment = assign_bodies(deformation, organs, phantom, report);
  // Building a body's conforming tet mesh of its nested organs (CGAL Mesh_3) can take minutes on
  // real anatomy: a bar of its own says what runs and for how long.
  BodyModel built = [&] {
    ProgressBar meshing(reporter, "bodies", 1);
    meshing.set_detail("building the bodies' tet meshes and constraints");
    return build_body_model(deformation, organs, phantom, assignment, report, body_meshes);
  }();
  ElasticModel& model = built.model;
  PhantomDeformation result;
  if (built.bodies.empty()) {
    report.skipped.push_back("the solve: no organ is moved by a load");
  }
  const double stiffness = nominal_stiffness(model);
  Loads loads = add_loads(deformation.loads, organs, phantom, assignment, built, stiffness, report);
  hold_boundaries(loads.pushes, built, report);
  add_obstacles(deformation.obstacles, built.bodies, stiffness, model, report);
  add_collisions(deformation.collisions, organs, phantom, built.bodies, stiffness, model, report);

  Eigen::MatrixX3d p = model.rest_positions_m;
  // Growth prescribes the grown tets' volume in the result: their rest volume is rescaled until
  // the solve meets it (sim/growth.hpp). The solves that only measure how far the rest volumes
  // reach are rough (sim/load_schedule.hpp), each starting about where its result will be and
  // stopping at the residual the first one stopped at; once a rough solve meets the
  // prescription, an exact solve from there decides.
  const bool calibrating = deformation.mode == DeformationMode::quasi_static && !built.bodies.empty() &&
                           std::any_of(built.grown_tets.begin(), built.grown_tets.end(),
                                       [](std::size_t tets) { return tets > 0; });
  bool rough = calibrating;
  if (!built.bodies.empty()) solve_frames(deformation, model, loads, p, result, report, reporter, rough);
  GrowthCalibration calibration;
  if (calibrating && !result.solves.empty() && !result.solves.front().residuals_N.empty())
    calibration.first_residual_N = result.solves.front().residuals_N.front();
  for (int round = 0; calibrating; ++round) {
    const std::vector<double> ratios = built.growth_rest_ratio;
    if (!recalibrate_growth(deformation, built, p, round, rough, report, calibration)) break;
    if (built.growth_rest_ratio == ratios) rough = false; // met roughly: the exact solve
    solve_frames(rough ? rough_solve_settings(deformation, model, p, calibration) : deformation, model, loads,
                 p, result, report, reporter, rough);
  }
  collect_deformations(organs, phantom, assignment, built.bodies, p / k_mm, result);
  grow_head(deformation, phantom, result, report);
  check_inversions(deformation, result, report);
  return result;
}

Phantom deformed_phantom(const Phantom& phantom, const PhantomDeformation& deformation) {
  Phantom moved = phantom;
  for (std::size_t i = 0; i < moved.organs.size(); ++i) {
    Organ& organ = moved.organs[i];
    const OrganDeformation& d = deformation.organs[i];
    if (organ.surface) organ.surface->set_positions(d.surface_mm);
    if (organ.sheet) organ.sheet->vertices = d.surface_mm;
    if (organ.solid) organ.solid->vertices = d.solid_mm;
  }
  return moved;
}

} // namespace phantasm
