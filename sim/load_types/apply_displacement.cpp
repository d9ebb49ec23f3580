// How a displacement load acts on the model: the organ's surface points in its region, embedded
// in their body, held by stiff springs to their displaced (and turned) places.
#include "core/format.hpp"
#include "sim/body_embedding.hpp"
#include "sim/loads.hpp"

namespace phantasm::sim_detail {
namespace {

void add_displacement(const LoadSettings& load, std::size_t index, LoadTarget& t) {
  const Phantom& phantom = t.phantom;
  ElasticModel& model = t.built.model;
  const std::size_t i = loaded_organ(load, index, t.organs);
  if (t.assignment.body_of[i] < 0 || (!phantom.organs[i].surface && !phantom.organs[i].sheet)) {
    t.report.skipped.push_back("displacement of " + load.organ +
                               ": the organ is not part of a simulated body");
    return;
  }
  PushedPoints push;
  push.load = &load;
  const Eigen::MatrixX3d& rest = phantom.organs[i].surface ? phantom.organs[i].surface->rest_positions()
                                                           : phantom.organs[i].sheet->vertices;
  const double stiffness = 1e4 * t.nominal_stiffness;
  for (Eigen::Index v = 0; v < rest.rows(); ++v) {
    const Eigen::Vector3d x = rest.row(v).transpose();
    if ((x - load.region_center_mm).norm() > load.region_radius_mm) continue;
    const Embedding e = embed(phantom, t.assignment, t.built.bodies, i, v, x);
    PointConstraint c;
    c.vertices = e.vertices;
    c.coefficients = e.coefficients;
    c.count = e.coefficients.tail<3>().isZero() ? 1 : 4;
    c.stiffness_N_m = stiffness;
    push.rest_m.push_back(interpolate(e, model.rest_positions_m));
    c.target_m = loaded_position_m(load, push.rest_m.back(), 1.0);
    push.constraints.push_back(model.points.size());
    model.points.push_back(c);
  }
  if (push.constraints.empty()) {
    t.report.skipped.push_back("displacement of " + load.organ + ": no surface point lies within " +
                               format_number(load.region_radius_mm) + " mm of " +
                               format_vector(load.region_center_mm));
    return;
  }
  t.report.modelled.push_back(
      "displacement " + format_vector(load.displacement_mm) + " mm" +
      (load.rotation_deg != 0.0 ? " and turn of " + format_number(load.rotation_deg) + " degrees about " +
                                      format_vector(load.rotation_axis) + " through " +
                                      format_vector(load.rotation_center_mm) + " mm"
                                : std::string()) +
      " of " + std::to_string(push.constraints.size()) + " surface points of " + load.organ +
      ", by springs of " + format_number(stiffness) + " N/m (10^4 x the mean elastic stiffness)");
  t.loads.pushes.push_back(std::move(push));
}

} // namespace

const LoadEntry& displacement_load_entry() {
  static const LoadEntry entry{LoadKind::displacement, add_displacement};
  return entry;
}

} // namespace phantasm::sim_detail
