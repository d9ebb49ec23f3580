// The scene's loads on the model: gravity, displacement springs on the organs' surface points,
// the held boundary released near them, and obstacles placed at rest or moved.
#include "sim/loads.hpp"

#include "core/error.hpp"
#include "core/format.hpp"
#include "sim/growth.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace phantasm::sim_detail {

Eigen::Vector3d loaded_position_m(const LoadSettings& load, const Eigen::Vector3d& rest_m, double amount) {
  const Eigen::Vector3d centre_m = k_mm * load.rotation_center_mm;
  const Eigen::AngleAxisd turn(amount * load.rotation_deg * M_PI / 180.0, load.rotation_axis);
  return centre_m + turn * (rest_m - centre_m) + amount * k_mm * load.displacement_mm;
}

Loads add_loads(const std::vector<LoadSettings>& load_settings, const OrganTable& organs,
                const Phantom& phantom, const BodyAssignment& assignment, BodyModel& built,
                double nominal_stiffness, StageReport& report) {
  const std::size_t n = organs.size();
  const std::vector<int>& body_of = assignment.body_of;
  const std::vector<Body>& bodies = built.bodies;
  ElasticModel& model = built.model;
  Loads loads;
  Eigen::MatrixX3d& acceleration = loads.acceleration;
  std::vector<PushedPoints>& pushes = loads.pushes;
  acceleration = Eigen::MatrixX3d::Zero(model.vertex_count(), 3);
  for (std::size_t k = 0; k < load_settings.size(); ++k) {
    const LoadSettings& load = load_settings[k];
    if (load.kind == LoadKind::gravity) {
      for (const Body& body : bodies) {
        bool acts = load.organs.empty();
        for (std::size_t i = 0; i < n; ++i)
          if (body_of[i] == body.organ &&
              std::find(load.organs.begin(), load.organs.end(), organs[i].name) != load.organs.end())
            acts = true;
        if (!acts) continue;
        acceleration.middleRows(body.first_vertex, body.vertex_count).rowwise() =
            load.acceleration_m_s2.transpose();
      }
      report.modelled.push_back("gravity " + format_vector(load.acceleration_m_s2) +
                                " m/s^2 on the bodies' lumped masses");
      continue;
    }
    if (load.kind == LoadKind::growth && !load.regions.empty()) {
      loads.growth_moved_m = std::max(loads.growth_moved_m, built.region_growth_moved_m);
      continue;
    }
    const int organ = organs.index_of(load.organ);
    if (organ < 0) {
      throw SettingError("deformation.loads[" + std::to_string(k) + "].organ",
                         "expected an organ of the phantom, found '" + load.organ + "'");
    }
    const std::size_t i = static_cast<std::size_t>(organ);
    if (load.kind == LoadKind::growth) {
      const Organ& grown = phantom.organs[i];
      loads.growth_moved_m = std::max(
          loads.growth_moved_m, growth_displacement_m(load, grown.surface ? grown.surface->rest_positions()
                                                            : grown.solid ? grown.solid->vertices
                                                                          : Eigen::MatrixX3d()));
      continue;
    }
    if (body_of[i] < 0 || (!phantom.organs[i].surface && !phantom.organs[i].sheet)) {
      report.skipped.push_back("displacement of " + load.organ +
                               ": the organ is not part of a simulated body");
      continue;
    }
    PushedPoints push;
    push.load = &load;
    const Eigen::MatrixX3d& rest = phantom.organs[i].surface ? phantom.organs[i].surface->rest_positions()
                                                             : phantom.organs[i].sheet->vertices;
    const double stiffness = 1e4 * nominal_stiffness;
    for (Eigen::Index v = 0; v < rest.rows(); ++v) {
      const Eigen::Vector3d x = rest.row(v).transpose();
      if ((x - load.region_center_mm).norm() > load.region_radius_mm) continue;
      const Embedding e = embed(phantom, assignment, bodies, i, v, x);
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
      report.skipped.push_back("displacement of " + load.organ + ": no surface point lies within " +
                               format_number(load.region_radius_mm) + " mm of " +
                               format_vector(load.region_center_mm));
      continue;
    }
    report.modelled.push_back(
        "displacement " + format_vector(load.displacement_mm) + " mm" +
        (load.rotation_deg != 0.0 ? " and turn of " + format_number(load.rotation_deg) + " degrees about " +
                                        format_vector(load.rotation_axis) + " through " +
                                        format_vector(load.rotation_center_mm) + " mm"
                                  : std::string()) +
        " of " + std::to_string(push.constraints.size()) + " surface points of " + load.organ +
        ", by springs of " + format_number(stiffness) + " N/m (10^4 x the mean elastic stiffness)");
    pushes.push_back(std::move(push));
  }
  return loads;
}

void hold_boundaries(const std::vector<PushedPoints>& pushes, BodyModel& built, StageReport& report) {
  ElasticModel& model = built.model;
  // The container holds a body's boundary, except where a load pushes (a retractor through an
  // opening of the skull, a paddle on the skin): boundary vertices within 1.5 region radii of a
  // displacement load's centre are released [choice], so the pushed surface is not pinned to a
  // held layer next to it.
  std::size_t released = 0;
  for (int v : built.held) {
    const Eigen::Vector3d x_mm = model.rest_positions_m.row(v).transpose() / k_mm;
    bool in_opening = false;
    for (const PushedPoints& push : pushes)
      in_opening |= (x_mm - push.load->region_center_mm).norm() <= 1.5 * push.load->region_radius_mm;
    if (in_opening) {
      ++released;
    } else {
      model.fixed[static_cast<std::size_t>(v)] = 1;
    }
  }
  if (released > 0) {
    report.modelled.push_back(
        std::to_string(released) +
        " held boundary vertices released within 1.5 region radii of a displacement load");
  }
}

void add_obstacles(const std::vector<ObstacleSettings>& obstacles, const std::vector<Body>& bodies,
                   double nominal_stiffness, ElasticModel& model, StageReport& report) {
  // Obstacles act on every free vertex of every body, by a penalty as stiff as the displacement
  // loads' springs.
  if (!obstacles.empty() && !bodies.empty()) {
    model.contact_stiffness_N_m = 1e4 * nominal_stiffness;
    place_obstacles(
        obstacles, [](const ObstacleSettings&) { return 0.0; }, model);
    for (const ObstacleSettings& o : obstacles) {
      report.modelled.push_back(
          std::string(to_string(o.shape)) + " obstacle " +
          (o.shape == ObstacleShape::sphere
               ? "centred at " + format_vector(o.point_mm) + " mm, radius " + format_number(o.radius_mm) +
                     " mm"
               : "through " + format_vector(o.point_mm) + " mm, normal " + format_vector(o.normal)) +
          ", moved by " + format_vector(o.displacement_mm) + " mm; contacts by a penalty of " +
          format_number(model.contact_stiffness_N_m) + " N/m (10^4 x the mean elastic stiffness)");
    }
  } else if (!obstacles.empty()) {
    report.skipped.push_back("obstacles: no organ is simulated, nothing can touch them");
  }
}

void place_obstacles(const std::vector<ObstacleSettings>& obstacles,
                     const std::function<double(const ObstacleSettings&)>& amount_of, ElasticModel& model) {
  model.obstacles.clear();
  for (const ObstacleSettings& obstacle : obstacles) {
    Obstacle o;
    o.shape = obstacle.shape == ObstacleShape::sphere ? Obstacle::Shape::sphere : Obstacle::Shape::half_space;
    o.point_m = k_mm * (obstacle.point_mm + amount_of(obstacle) * obstacle.displacement_mm);
    o.normal = obstacle.normal;
    o.radius_m = k_mm * obstacle.radius_mm;
    model.obstacles.push_back(o);
  }
}

} // namespace phantasm::sim_detail
