#include "pipeline/material_maps_stage.hpp"

#include "atlas/colin27_head.hpp"
#include "core/error.hpp"
#include "core/format.hpp"
#include "core/settings_declaration.hpp"
#include "io/nifti_file.hpp"
#include "io/shape_files.hpp"
#include "mri/texture_signal.hpp"
#include "mri/tissue_parameters.hpp"
#include "voxelize/material_maps.hpp"
#include "voxelize/texture_spectrum.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>

namespace phantasm {
namespace {

int tissue_index(std::vector<std::string>& tissues, const std::string& tissue) {
  auto found = std::find(tissues.begin(), tissues.end(), tissue);
  if (found == tissues.end()) {
    tissues.push_back(tissue);
    return static_cast<int>(tissues.size()) - 1;
  }
  return static_cast<int>(found - tissues.begin());
}

void attach_regions(const Scene& scene, const std::map<std::string, AtlasLabelVolume>& atlases,
                    VoxelizedPhantom& v, StageReport& report) {
  const auto& regions = scene.mri.regions;
  // Regions per atlas: one region volume each (the atlas's labels on the image grid).
  std::map<std::string, std::vector<TissueRegion>> by_atlas;
  for (std::size_t i = 0; i < regions.size(); ++i) {
    const TissueRegionSettings& r = regions[i];
    const OrganSettings& organ = *scene.find_organ(r.organ); // the scene's checks made sure
    const std::string& atlas = organ.shape.atlas;
    const auto volume = atlases.find(atlas);
    if (volume == atlases.end())
      throw SettingError("tissue_regions[" + std::to_string(i) + "].organ",
                         "expected an organ whose atlas the anatomy read, found '" + r.organ +
                             "' of atlas '" + atlas + "', which was not read");
    const auto label = volume->second.names.find(r.label);
    if (label == volume->second.names.end()) {
      std::string known;
      for (const auto& [name, value] : volume->second.names)
        known += (known.empty() ? "" : ", ") + name;
      throw SettingError("tissue_regions[" + std::to_string(i) + "].label",
                         "expected a label of " + volume->second.source + " (" + known + "), found '" +
                             r.label + "'");
    }
    TissueRegion region;
    region.name = region_name(r);
    region.atlas_label = r.label;
    region.organ_label = scene.organs.index_of(r.organ) + 1;
    region.region_value = label->second;
    region.label = first_region_label(scene) + static_cast<std::int32_t>(i);
    region.tissue = tissue_index(v.tissues, r.tissue);
    by_atlas[atlas].push_back(region);
  }
  const int tissue_count = static_cast<int>(v.tissues.size());
  widen_tissues(v.reference, tissue_count);
  if (v.deformed) widen_tissues(*v.deformed, tissue_count);
  for (const auto& [atlas, list] : by_atlas) {
    const AtlasLabelVolume& volume = atlases.at(atlas);
    const std::vector<std::int32_t> reference = resample_labels(v.grid, volume.grid, *volume.labels);
    const std::vector<std::size_t> counts = apply_tissue_regions(v.reference, reference, list);
    std::vector<std::size_t> deformed_counts;
    if (v.deformed && v.motion)
      deformed_counts = apply_tissue_regions(
          *v.deformed,
          carry_labels(v.grid, held_region_values(v.reference.labels, reference, list), v.motion->def_to_ref),
          list);
    for (std::size_t k = 0; k < list.size(); ++k) {
      std::string line = "tissue region " + list[k].name + " (dseg " + std::to_string(list[k].label) + ", " +
                         v.tissues[static_cast<std::size_t>(list[k].tissue)] +
                         "): " + std::to_string(counts[k]) + " reference voxels of organ " +
                         scene.organs[static_cast<std::size_t>(list[k].organ_label - 1)].name + " that " +
                         volume.source + " labels " + list[k].atlas_label;
      if (!deformed_counts.empty())
        line += ", " + std::to_string(deformed_counts[k]) +
                " deformed voxels of that organ whose reference position (the exact map, from-ref_to-def) "
                "lies in the region";
      report.modelled.push_back(line);
      report.accuracy["tissue region " + list[k].name + " reference voxels"] = static_cast<double>(counts[k]);
    }
  }
}

std::vector<bool> textured_tissues(const TextureSettings& texture, const std::vector<std::string>& tissues) {
  std::vector<bool> textured(tissues.size(), texture.tissues.empty());
  for (std::size_t t = 0; t < tissues.size(); ++t)
    if (std::find(texture.tissues.begin(), texture.tissues.end(), tissues[t]) != texture.tissues.end())
      textured[t] = true;
  return textured;
}

/// The scan's intensity on the image grid; the scan must cover every voxel of a textured tissue,
/// to within k_scan_margin of its voxels beyond its outermost voxel centres (there the nearest
/// edge's values): an atlas organ's surface may reach as far past the template's grid as the
/// atlas's padding (atlas/atlas_labels.hpp).
constexpr double k_scan_margin = 2.0;

std::vector<float> scan_on_grid(const std::filesystem::path& path, const VoxelizedPhantom& v,
                                const std::vector<bool>& textured) {
  const NiftiVolume scan = read_nifti(path);
  std::vector<float> values(scan.values.begin(), scan.values.end());
  std::vector<float> on_grid = resample_values(v.grid, scan.grid, values, std::nanf(""));
  const TissueVolumes& ref = v.reference;
  const auto nx = static_cast<std::size_t>(v.grid.dims.x()), ny = static_cast<std::size_t>(v.grid.dims.y());
  for (std::size_t voxel = 0; voxel < ref.labels.size(); ++voxel) {
    const int tissue = ref.label_tissues[static_cast<std::size_t>(ref.labels[voxel])];
    if (tissue < 0 || !textured[static_cast<std::size_t>(tissue)] || std::isfinite(on_grid[voxel])) continue;
    const Eigen::Vector3d ijk(static_cast<double>(voxel % nx), static_cast<double>(voxel / nx % ny),
                              static_cast<double>(voxel / (nx * ny)));
    const Eigen::Vector3d world = v.grid.world_from_index(ijk);
    const Eigen::Vector3d at = scan.grid.index_from_world(world);
    const Eigen::Vector3d last = (scan.grid.dims.array() - 1).cast<double>();
    if ((at.array() >= -k_scan_margin).all() && (at.array() <= last.array() + k_scan_margin).all()) {
      const Eigen::Vector3d clamped = at.cwiseMax(Eigen::Vector3d::Zero()).cwiseMin(last);
      on_grid[voxel] = value_at(scan.grid, values, scan.grid.world_from_index(clamped), std::nanf(""));
      continue;
    }
    throw InputError(path.string() + ": expected a texture scan whose grid covers the anatomy (to within " +
                     format_number(k_scan_margin) + " of its voxels), found voxel " + format_vector(ijk) +
                     " of tissue " + v.tissues[static_cast<std::size_t>(tissue)] + " (world " +
                     format_vector(world) + " mm) outside it (texture.scan)");
  }
  return on_grid;
}

/// A measured figure with 3 significant digits, for the description.
std::string three_digits(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", value);
  return text;
}

/// Per tissue of the phantom, the T1 gain matched to the sequence texture.match names (the
/// others, untextured, keep T1_gain); `text` says how, for the description.
std::vector<double> matched_gains(const Scene& scene, const std::vector<std::string>& tissues,
                                  const std::vector<bool>& textured, StageReport& report, std::string& text) {
  const TextureSettings& t = scene.mri.texture;
  const auto sequence = std::find_if(scene.mri.sequences.begin(), scene.mri.sequences.end(),
                                     [&](const SequenceSettings& s) { return s.name == t.match; });
  if (sequence == scene.mri.sequences.end()) // the scene's checks made sure
    throw SettingError("texture.match", "expected one of the scene's sequences, found '" + t.match + "'");
  const auto parameters = resolve_tissue_parameters(scene.mri, scene.organs);
  std::vector<double> gains(tissues.size(), t.T1_gain);
  std::string figures;
  for (std::size_t k = 0; k < tissues.size(); ++k) {
    const auto found = parameters.find(tissues[k]);
    if (!textured[k] || found == parameters.end()) continue;
    const std::optional<MatchedT1Gain> matched =
        matched_T1_gain(*sequence, relaxation_of(found->second), t.PD_gain);
    figures += (figures.empty() ? "" : ", ") + tissues[k] + " ";
    if (!matched) {
      figures += three_digits(t.T1_gain) + " (no signal in " + t.match + ": T1_gain)";
      continue;
    }
    gains[k] = matched->gain;
    figures += three_digits(matched->gain) + (matched->clamped ? " (clamped)" : "");
    report.accuracy["texture " + tissues[k] + " T1 gain"] = matched->gain;
    if (matched->clamped)
      report.warnings.push_back("texture.match: " + tissues[k] + "'s " + t.match +
                                " signal hardly follows T1 (d ln S / d ln T1 = " +
                                three_digits(-matched->sensitivity) + "), so its T1 gain is held at " +
                                three_digits(matched->gain) + " and its texture is fainter than the scan's");
  }
  text = "T1 x exp(-g d), g per tissue so that " + t.match + "'s signal changes by d to first order (" +
         figures + ")";
  return gains;
}

void attach_texture(const Scene& scene, VoxelizedPhantom& v, StageReport& report) {
  const TextureSettings& t = scene.mri.texture;
  const std::vector<bool> textured = textured_tissues(t, v.tissues);
  TextureGains gains{t.T1_gain, t.PD_gain, t.max_deviation};
  std::string names;
  for (std::size_t k = 0; k < textured.size(); ++k)
    if (textured[k]) names += (names.empty() ? "" : ", ") + v.tissues[k];
  std::string gain_text = "T1 x exp(-" + format_number(t.T1_gain) + " d)";
  if (!t.match.empty())
    gains.T1_gain_by_tissue = matched_gains(scene, v.tissues, textured, report, gain_text);
  std::string description;
  const std::filesystem::path path =
      t.scan.empty() ? default_colin27_templates_dir() / "ch2.nii.gz" : std::filesystem::path(t.scan);
  const std::uint64_t seed = scene.seed * 0x9E3779B97F4A7C15ull + 0x7E57u;
  if (t.source == TextureSource::scan) {
    v.reference_texture =
        texture_from_intensity(v.reference, textured, scan_on_grid(path, v, textured), gains);
    description = "from the scan " + path.string() + ": d = intensity / its mean over the tissue - 1";
  } else if (t.spectrum == RandomSpectrum::scan) {
    // Each textured tissue's figures measured on the scan (d as the scan texture's, clamped
    // alike), then a seeded field per tissue with them: the correlated part's standard deviation,
    // the white share (the scan's noise, which the images add their own of) left out.
    std::vector<int> region(v.reference.labels.size(), -1);
    for (std::size_t voxel = 0; voxel < region.size(); ++voxel) {
      const int tissue = v.reference.label_tissues[static_cast<std::size_t>(v.reference.labels[voxel])];
      if (tissue >= 0 && textured[static_cast<std::size_t>(tissue)]) region[voxel] = tissue;
    }
    TextureSpectrumOptions options;
    options.max_deviation = t.max_deviation;
    const std::vector<TextureSpectrum> measured = measure_texture_spectra(
        v.grid, scan_on_grid(path, v, textured), region, static_cast<int>(v.tissues.size()), options);
    std::vector<TextureField> fields(v.tissues.size());
    std::string figures;
    for (std::size_t k = 0; k < measured.size(); ++k) {
      if (!textured[k] || !measured[k].voxels) continue;
      const TextureSpectrum& m = measured[k];
      fields[k] = {m.texture_sd, m.correlation_mm};
      figures += (figures.empty() ? "" : "; ") + v.tissues[k] + " sd " + three_digits(m.texture_sd) + ", s " +
                 three_digits(m.correlation_mm) + " mm (measured sd " + three_digits(m.deviation_sd) +
                 ", white share " + three_digits(m.white_share) + ", " + std::to_string(m.voxels) +
                 " voxels)";
      report.accuracy["texture " + v.tissues[k] + " sd"] = m.texture_sd;
      report.accuracy["texture " + v.tissues[k] + " correlation mm"] = m.correlation_mm;
      report.accuracy["texture " + v.tissues[k] + " white share"] = m.white_share;
    }
    v.reference_texture = texture_from_random_fields(v.grid, v.reference, textured, seed, fields, gains);
    description = "from seeded random fields (seed " + std::to_string(scene.seed) +
                  "), one per tissue, with the spectrum measured on the scan " + path.string() +
                  " (d = intensity / its mean over the tissue - 1; its autocorrelation at lags of 1 to 12 "
                  "voxels fitted by a exp(-r^2 / (4 s^2)), white Gaussian noise smoothed by a Gaussian of s, "
                  "the white share 1 - a left out): " +
                  figures;
  } else {
    v.reference_texture =
        texture_from_random_field(v.grid, v.reference, textured, seed, t.correlation_mm, t.random_sd, gains);
    description = "from a seeded random field (seed " + std::to_string(scene.seed) +
                  "): d Gaussian, standard deviation " + format_number(t.random_sd) +
                  ", smoothed by a Gaussian of " + format_number(t.correlation_mm) + " mm";
  }
  description += "; " + gain_text + ", PD x exp(" + format_number(t.PD_gain) + " d), d within +-" +
                 format_number(t.max_deviation) + "; tissues " + names +
                 "; the deformed state's factors are the reference's at each voxel's reference position "
                 "(the exact map, from-ref_to-def), trilinear";
  v.reference_texture->description = description;
  if (v.deformed && v.motion)
    v.deformed_texture = carry_texture(v.grid, *v.reference_texture, v.motion->def_to_ref);
  report.modelled.push_back("texture " + description);
}

} // namespace

std::int32_t first_region_label(const Scene& scene) {
  return static_cast<std::int32_t>(scene.anatomy.organs.size()) + 2; // after the organs and the gap
}

void attach_material_maps(const Scene& scene, const std::map<std::string, AtlasLabelVolume>& atlases,
                          VoxelizedPhantom& volumes, StageReport& report) {
  if (!scene.mri.regions.empty()) attach_regions(scene, atlases, volumes, report);
  if (scene.mri.texture.source != TextureSource::none) attach_texture(scene, volumes, report);
}

std::string material_maps_key_text(const Scene& scene) {
  if (scene.mri.regions.empty() && scene.mri.texture.source == TextureSource::none) return {};
  std::string text = "material maps\n";
  for (const TissueRegionSettings& r : scene.mri.regions)
    text += "region " + r.organ + " " + r.label + " " + r.tissue + "\n";
  const TextureSettings& t = scene.mri.texture;
  text += std::string("texture ") + to_string(t.source) + " " + t.scan + " " + exact_text(t.T1_gain) + " " +
          exact_text(t.PD_gain) + " " + exact_text(t.max_deviation) + " " + exact_text(t.random_sd) + " " +
          exact_text(t.correlation_mm) + " spectrum " +
          (t.spectrum == RandomSpectrum::scan ? "scan" : "given") + " seed " + std::to_string(scene.seed);
  // The matched gains also read the sequence and the tissues' parameters, which the reference
  // images' key holds (pipeline/reference_images_cache.cpp), as it holds everything they read.
  if (!t.match.empty()) text += " match " + t.match;
  for (const std::string& tissue : t.tissues)
    text += " " + tissue;
  return text + "\n";
}

} // namespace phantasm
