// How growth acts on the model: its tets' rest volume is changed when the bodies are built
// (sim/growth.hpp); here only the scale of the motion it makes is kept.
#include "sim/growth.hpp"
#include "sim/loads.hpp"

#include <algorithm>

namespace phantasm::sim_detail {
namespace {

void add_growth(const LoadSettings& load, std::size_t index, LoadTarget& t) {
  double& moved_m = t.loads.growth_moved_m;
  if (!load.regions.empty()) {
    moved_m = std::max(moved_m, t.built.region_growth_moved_m);
    return;
  }
  const Organ& grown = t.phantom.organs[loaded_organ(load, index, t.organs)];
  moved_m = std::max(moved_m, growth_displacement_m(load, grown.surface ? grown.surface->rest_positions()
                                                          : grown.solid ? grown.solid->vertices
                                                                        : Eigen::MatrixX3d()));
}

} // namespace

const LoadEntry& growth_load_entry() {
  static const LoadEntry entry{LoadKind::growth, add_growth};
  return entry;
}

} // namespace phantasm::sim_detail
