#include "mri/mri_plan.hpp"

#include "core/format.hpp"
#include "mri/sequence_type.hpp"
#include "mri/tissue_parameters.hpp"

#include <cmath>
#include <sstream>
#include <utility>

namespace phantasm {
namespace {

std::string value_text(const std::optional<double>& value) {
  return value ? format_number(*value) : "-";
}

/// FFTW's fast algorithms split a size into the factors it has codelets for (2 to 16, among them
/// the primes up to 13); a larger prime factor goes through slower general algorithms (several
/// times the time per voxel: 197 against 200).
constexpr int k_largest_fast_factor = 13;

/// The note on the k-space line for a grid with a slow size, or nothing.
std::string transform_size_note(const GridSettings& settings) {
  const Eigen::Vector3i dims = settings.grid().dims;
  bool slow = false;
  Eigen::Vector3i faster = dims;
  for (int a = 0; a < 3; ++a) {
    while (largest_prime_factor(faster[a]) > k_largest_fast_factor)
      ++faster[a];
    slow = slow || faster[a] != dims[a];
  }
  if (!slow) return "";
  const auto text = [](const Eigen::Vector3i& d) {
    return std::to_string(d.x()) + " x " + std::to_string(d.y()) + " x " + std::to_string(d.z());
  };
  return "; the grid's " + text(dims) +
         " voxels have prime factors above 13, which FFTW transforms several times slower per voxel: " +
         text(faster) + " would not (grid.field_of_view_mm; docs/volumes-and-images.md)";
}

} // namespace

StageReport plan_mri(const MriSettings& settings, const OrganTable& organs, const GridSettings& grid) {
  StageReport report;
  report.stage = "mri";
  if (!settings.images || settings.sequences.empty()) {
    report.status = "skipped";
    report.skipped.push_back(settings.sequences.empty() ? "MR images (the scene lists no sequences)"
                                                        : "MR images (outputs.images is false)");
    return report;
  }
  for (const auto& s : settings.sequences) {
    std::ostringstream line;
    line << s.name << ": " << to_string(s.kind) << ", TR " << s.TR_ms << " ms, TE " << s.TE_ms << " ms"
         << sequence_type(s.kind).plan(s) << "; reference and deformed";
    report.modelled.push_back(line.str());
  }
  for (const auto& s : settings.sequences) {
    // A gradient-echo excitation of 0 or 180 degrees leaves no transverse magnetisation: the image
    // is zero, and noise relative to the reference tissue's signal is zero as well.
    if (sequence_type(s.kind).gradient_echo && std::abs(std::sin(s.flip_deg * M_PI / 180.0)) < 1e-6) {
      report.warnings.push_back("sequence " + s.name + ": a flip angle of " + format_number(s.flip_deg) +
                                " deg makes no signal (sin(flip) = 0): the image is zero");
    }
  }
  for (const auto& [name, p] : resolve_tissue_parameters(settings, organs)) {
    // No tissue relaxes over more than 1000 s (water's T1 is about 4 s): longer times make the
    // signal equations 0/0 or 0 for every sequence.
    constexpr double k_longest_ms = 1e6;
    for (const auto& [label, value] :
         {std::pair{"T1", p.T1_ms}, std::pair{"T2", p.T2_ms}, std::pair{"T2*", p.T2star_ms}}) {
      if (value && *value > k_longest_ms) {
        report.warnings.push_back(
            "tissue " + name + ": " + label + " of " + format_number(*value) +
            " ms is beyond any tissue's (at most 1e6 ms): its signal may be zero or undefined");
      }
    }
  }
  for (const auto& [name, p] : resolve_tissue_parameters(settings, organs)) {
    report.modelled.push_back("tissue " + name + " at " + value_text(settings.field_strength_T) + " T: T1 " +
                              value_text(p.T1_ms) + " ms, T2 " + value_text(p.T2_ms) + " ms, T2* " +
                              value_text(p.T2star_ms) + " ms, PD " + value_text(p.PD));
  }
  const AcquisitionSettings& a = settings.acquisition;
  if (a.kspace) {
    const std::string acquired =
        a.acquired_voxel_mm ? "acquired voxel " + format_number((*a.acquired_voxel_mm).x()) + " x " +
                                  format_number((*a.acquired_voxel_mm).y()) + " x " +
                                  format_number((*a.acquired_voxel_mm).z()) + " mm"
                            : std::to_string(a.kspace_oversampling) + " grid voxels per acquired sample";
    report.modelled.push_back("k-space truncation (" + acquired + "), zero-filled onto the grid" +
                              (a.slice_thickness_mm > 0.0
                                   ? ", slice profile " + format_number(a.slice_thickness_mm) + " mm"
                                   : std::string()) +
                              transform_size_note(grid));
  } else {
    report.skipped.push_back("k-space simulation (acquisition.kspace is false): images are sampled directly");
  }
  if (a.bias_percent > 0.0) {
    report.modelled.push_back("bias field of " + value_text(a.bias_percent) + " %");
  } else {
    report.skipped.push_back("bias field (acquisition.bias_percent is 0)");
  }
  if (a.coils > 1) report.modelled.push_back(std::to_string(a.coils) + " coils, sum of squares");
  if (settings.parameter_maps) {
    report.modelled.push_back("parameter maps PD, T1, T2, T2* of each state");
  } else {
    report.skipped.push_back("parameter maps (outputs.parameter_maps is false)");
  }
  if (a.noise_percent > 0.0) {
    report.modelled.push_back("Rician noise, " + value_text(a.noise_percent) + " % of " +
                              a.noise_reference_tissue);
  } else {
    report.skipped.push_back("noise (acquisition.noise_percent is 0)");
  }
  return report;
}

} // namespace phantasm
