// How gravity acts on the model: its acceleration on the lumped masses of the bodies it acts on.
#include "core/format.hpp"
#include "sim/loads.hpp"

#include <algorithm>

namespace phantasm::sim_detail {
namespace {

void add_gravity(const LoadSettings& load, std::size_t, LoadTarget& t) {
  const std::vector<int>& body_of = t.assignment.body_of;
  const std::vector<std::string>& named = load.organs;
  for (const Body& body : t.built.bodies) {
    bool acts = named.empty();
    for (std::size_t i = 0; i < t.organs.size(); ++i)
      if (body_of[i] == body.organ && std::find(named.begin(), named.end(), t.organs[i].name) != named.end())
        acts = true;
    if (!acts) continue;
    t.loads.acceleration.middleRows(body.first_vertex, body.vertex_count).rowwise() =
        load.acceleration_m_s2.transpose();
  }
  t.report.modelled.push_back("gravity " + format_vector(load.acceleration_m_s2) +
                              " m/s^2 on the bodies' lumped masses");
}

} // namespace

const LoadEntry& gravity_load_entry() {
  static const LoadEntry entry{LoadKind::gravity, add_gravity};
  return entry;
}

} // namespace phantasm::sim_detail
