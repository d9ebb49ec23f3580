#include "sim/vertex_star_volumes.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace phantasm {

namespace {

/// The union of `tets` (indices into model.tets) as an EnclosedVolume of its boundary triangles
/// (faces shared by two of its tets cancel) with bulk modulus K, range model.volume_range.
EnclosedVolume union_volume(const ElasticModel& model, const std::vector<int>& tets, double bulk_modulus_Pa) {
  // A positively oriented tet (a, b, c, d)'s outward faces.
  static constexpr int faces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  // Each face with its orientation, keyed by its sorted vertices; a face shared by two of the
  // tets appears twice (opposite orientations) and cancels.
  std::map<std::array<int, 3>, std::array<int, 3>> boundary;
  for (int t : tets) {
    const TetElement& e = model.tets[static_cast<std::size_t>(t)];
    for (const auto& f : faces) {
      const std::array<int, 3> face = {e.vertices[static_cast<std::size_t>(f[0])],
                                       e.vertices[static_cast<std::size_t>(f[1])],
                                       e.vertices[static_cast<std::size_t>(f[2])]};
      std::array<int, 3> key = face;
      std::sort(key.begin(), key.end());
      const auto [it, inserted] = boundary.emplace(key, face);
      if (!inserted) boundary.erase(it);
    }
  }
  std::vector<int> vertices;
  std::map<int, int> local;
  std::vector<std::array<int, 3>> triangles;
  for (const auto& [key, face] : boundary) {
    std::array<int, 3> triangle{};
    for (int k = 0; k < 3; ++k) {
      const int u = face[static_cast<std::size_t>(k)];
      const auto [it, inserted] = local.emplace(u, static_cast<int>(vertices.size()));
      if (inserted) vertices.push_back(u);
      triangle[static_cast<std::size_t>(k)] = it->second;
    }
    triangles.push_back(triangle);
  }
  EnclosedVolume volume =
      enclosed_volume_constraint(std::move(vertices), std::move(triangles), {}, model.rest_positions_m,
                                 bulk_modulus_Pa, model.volume_range);
  // Few vertices: Newton takes the rank-one Gauss-Newton block (sim/newton.cpp), as for stars.
  volume.vertex_star = true;
  return volume;
}

} // namespace

int move_bulk_to_vertex_stars(ElasticModel& model) {
  const auto n = static_cast<std::size_t>(model.vertex_count());
  // Per vertex: its tets, and sum_t lambda_t V_t (volume weight 3 lambda V).
  std::vector<std::vector<int>> tets_of(n);
  std::vector<double> lambda_volume(n, 0.0);
  for (std::size_t t = 0; t < model.tets.size(); ++t) {
    const TetElement& e = model.tets[t];
    if (!(e.volume_weight > 0.0)) continue;
    for (int v : e.vertices) {
      tets_of[static_cast<std::size_t>(v)].push_back(static_cast<int>(t));
      lambda_volume[static_cast<std::size_t>(v)] += e.volume_weight / 3.0;
    }
  }
  int added = 0;
  for (std::size_t v = 0; v < n; ++v) {
    if (tets_of[v].empty()) continue;
    double star_volume = 0.0;
    for (int t : tets_of[v])
      star_volume += model.tets[static_cast<std::size_t>(t)].rest_volume_m3;
    model.volumes.push_back(union_volume(model, tets_of[v], lambda_volume[v] / (4.0 * star_volume)));
    ++added;
  }
  for (TetElement& e : model.tets)
    e.volume_weight = 0.0;
  return added;
}

int move_bulk_to_tet_groups(ElasticModel& model, const std::vector<std::vector<int>>& groups,
                            double kept_per_tet) {
  if (!(kept_per_tet >= 0.0 && std::isfinite(kept_per_tet)))
    throw std::invalid_argument(
        "move_bulk_to_tet_groups: the bulk weight kept per tet over its strain weight "
        "must be finite and >= 0, found " +
        std::to_string(kept_per_tet));
  // What a tet keeps of its bulk weight: at most kept_per_tet times its strain weight.
  auto kept = [&](const TetElement& e) { return std::min(e.volume_weight, kept_per_tet * e.strain_weight); };
  std::vector<char> grouped(model.tets.size(), 0);
  for (const std::vector<int>& group : groups) {
    for (int t : group) {
      if (t < 0 || static_cast<std::size_t>(t) >= model.tets.size() || grouped[static_cast<std::size_t>(t)])
        throw std::invalid_argument("move_bulk_to_tet_groups: tet " + std::to_string(t) +
                                    " is out of range or in two groups");
      grouped[static_cast<std::size_t>(t)] = 1;
    }
  }
  int added = 0;
  for (const std::vector<int>& group : groups) {
    TetGroup g;
    std::vector<int> bulk;
    for (int t : group) {
      const TetElement& e = model.tets[static_cast<std::size_t>(t)];
      if (!(e.volume_weight > 0.0)) continue;
      bulk.push_back(t);
      g.rest_volume_m3 += e.rest_volume_m3;
      g.weight += e.volume_weight - kept(e);
    }
    if (!(g.weight > 0.0)) continue; // no tet of the group gives any of its bulk weight
    // The group's vertices in order of first use, and G = sum_t V_t S_t Q_t / V_g.
    std::map<int, int> local;
    for (int t : bulk)
      for (int v : model.tets[static_cast<std::size_t>(t)].vertices)
        if (local.emplace(v, static_cast<int>(g.vertices.size())).second) g.vertices.push_back(v);
    g.G = Eigen::Matrix<double, Eigen::Dynamic, 3>::Zero(static_cast<Eigen::Index>(g.vertices.size()), 3);
    for (int t : bulk) {
      const TetElement& e = model.tets[static_cast<std::size_t>(t)];
      for (int k = 0; k < 4; ++k)
        g.G.row(local.at(e.vertices[static_cast<std::size_t>(k)])) +=
            (e.rest_volume_m3 / g.rest_volume_m3) * e.Q.row(k);
    }
    g.tets = bulk;
    model.tet_groups.push_back(std::move(g));
    for (int t : bulk)
      model.tets[static_cast<std::size_t>(t)].volume_weight = kept(model.tets[static_cast<std::size_t>(t)]);
    ++added;
  }
  return added;
}

Eigen::MatrixXd tet_group_hessian(const ElasticModel& model, const TetGroup& g, const Eigen::MatrixX3d& p,
                                  bool clamp_negative) {
  const auto n = static_cast<Eigen::Index>(g.vertices.size());
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  const SignedSvd svd = signed_svd(group_deformation_gradient(g, p), rotation);
  const SingularValueEnergy volume =
      singular_value_energy(TetConstraintKind::volume, model.volume_range, g.weight, svd.sigma);
  if (volume.value == 0.0 && volume.hessian.isZero()) return Eigen::MatrixXd::Zero(3 * n, 3 * n);
  const Eigen::Matrix<double, 9, 9> H_F = projected_hessian(svd, volume, clamp_negative);
  // vec(F) = (G^T (x) I3) vec(X): column c of F is sum_k G(k, c) x_k.
  Eigen::MatrixXd dF = Eigen::MatrixXd::Zero(3 * n, 9);
  for (Eigen::Index k = 0; k < n; ++k)
    for (int c = 0; c < 3; ++c)
      dF.block<3, 3>(3 * k, 3 * c) = g.G(k, c) * Eigen::Matrix3d::Identity();
  return dF * H_F * dF.transpose();
}

int apply_volume_formulation(ElasticModel& model, VolumeFormulation formulation, const TetMesh& mesh,
                             std::size_t first_tet, const std::vector<int>& labels) {
  switch (formulation) {
  case VolumeFormulation::tet: return 0;
  case VolumeFormulation::vertex_star: return move_bulk_to_vertex_stars(model);
  case VolumeFormulation::tet_group:
  case VolumeFormulation::tet_group_and_tet: {
    std::vector<std::vector<int>> groups = group_tets(mesh, tets_per_group, labels);
    for (std::vector<int>& group : groups)
      for (int& t : group)
        t += static_cast<int>(first_tet);
    return move_bulk_to_tet_groups(
        model, groups, formulation == VolumeFormulation::tet_group_and_tet ? tet_bulk_ratio : 0.0);
  }
  }
  return 0;
}

} // namespace phantasm
