#include "pipeline/reference_cache.hpp"

#include "core/byte_codec.hpp"
#include "core/error.hpp"
#include "core/sha256.hpp"
#include "io/atomic_file.hpp"
#include "io/byte_compression.hpp"
#include "io/output_path.hpp"
#include "io/vdb_file.hpp"
#include "pipeline/cache_entry.hpp"
#include "scene/settings_declarations.hpp"
#include "voxelize/voxelize_phantom.hpp"

#include <optional>
#include <sstream>

namespace phantasm {
namespace {

namespace fs = std::filesystem;

// The file's first line; the key follows on the second, the compressed state after it. The
// format number is also part of the key.
constexpr const char* k_reference_magic = "phantasm reference cache 3\n";

/// The grid, the declared voxelization settings that shape the reference state
/// (scene/settings_declarations.cpp) and the organ table, one per line.
std::string inputs_text(const VoxelizationSettings& s, const OrganTable& organs, const ImageGrid& grid) {
  std::ostringstream out;
  out << "grid " << exact_text(grid.dims) << " spacing " << exact_text(grid.spacing_mm)
      << " world_from_voxel " << exact_text(grid.world_from_voxel) << "\n"
      << key_text(declared_settings<VoxelizationSettings>(), s, cached_reference_state);
  out << "organs " << organs.size() << "\n";
  for (const OrganEntry& organ : organs)
    out << " " << organ.name << " tissue " << organ.tissue << " parent " << organ.parent << " depth "
        << organ.depth << "\n";
  return out.str();
}

/// The entry's line of the log and the provenance: the same whether this run built the entry or
/// read it (log lines are deterministic; which it did is a screen note).
void record_reference_entry(const std::string& key, StageReport& report) {
  report.modelled.push_back("reference state (level sets, labels, fractions) kept in the reference cache as "
                            "entry " +
                            key.substr(0, 16) +
                            " (the first run with this anatomy, grid and voxelization builds it, the "
                            "others read it)");
}

} // namespace

std::string reference_cache_key(const std::string& anatomy_key, const VoxelizationSettings& settings,
                                const OrganTable& organs, const ImageGrid& grid) {
  if (anatomy_key.empty()) return {};
  return sha256_hex(std::string(k_reference_magic) + "anatomy " + anatomy_key + "\n" +
                    inputs_text(settings, organs, grid));
}

std::string encode_tissue_volumes(const TissueVolumes& volumes) {
  ByteWriter out;
  out.array(volumes.labels);
  out.array(volumes.label_tissues);
  out.value(static_cast<std::int64_t>(volumes.tissue_count));
  out.array(volumes.partial_voxels);
  out.array(volumes.partial_fractions);
  out.value(static_cast<std::uint64_t>(volumes.supersampled_voxels));
  return out.take();
}

TissueVolumes decode_tissue_volumes(std::string_view bytes) {
  ByteReader in(bytes, "tissue volumes");
  TissueVolumes volumes;
  in.array(volumes.labels);
  in.array(volumes.label_tissues);
  const auto tissues = in.value<std::int64_t>();
  if (tissues < 0 || tissues > static_cast<std::int64_t>(bytes.size()))
    in.damaged("a tissue count out of range");
  volumes.tissue_count = static_cast<int>(tissues);
  for (const int tissue : volumes.label_tissues)
    if (tissue < -1 || tissue >= volumes.tissue_count) in.damaged("a label's tissue out of range");
  for (const std::int32_t label : volumes.labels)
    if (label < 0 || static_cast<std::size_t>(label) >= volumes.label_tissues.size())
      in.damaged("a label without a tissue entry");
  in.array(volumes.partial_voxels);
  in.array(volumes.partial_fractions);
  for (std::size_t k = 0; k < volumes.partial_voxels.size(); ++k)
    if (volumes.partial_voxels[k] >= volumes.labels.size() ||
        (k > 0 && volumes.partial_voxels[k] <= volumes.partial_voxels[k - 1]))
      in.damaged("partial voxels out of range or order");
  if (volumes.partial_fractions.size() != volumes.partial_voxels.size() * volumes.fractions_per_voxel())
    in.damaged("fractions of another count than the partial voxels");
  volumes.supersampled_voxels = static_cast<std::size_t>(in.value<std::uint64_t>());
  if (!in.done()) in.damaged("bytes after the volumes");
  return volumes;
}

std::string encode_reference_state(const ReferenceVoxelization& state, const TissueVolumes& volumes) {
  ByteWriter out;
  out.array(state.organs);
  std::vector<const void*> grids;
  for (const auto& level_set : state.level_sets) {
    out.value(level_set->voxel_size_mm());
    out.value(level_set->half_width_voxels());
    grids.push_back(level_set->grid());
  }
  out.text(encode_float_grids(grids));
  out.value(static_cast<std::uint64_t>(state.height_ranges.size()));
  for (const auto& ranges : state.height_ranges) {
    out.value(static_cast<std::uint8_t>(ranges.has_value()));
    if (ranges) out.array(*ranges);
  }
  out.text(encode_tissue_volumes(volumes));
  out.value(static_cast<std::uint8_t>(state.deepest_candidates.has_value()));
  if (state.deepest_candidates) {
    out.value(static_cast<std::uint64_t>(state.deepest_candidates->size()));
    for (const std::vector<Eigen::Vector3d>& own : *state.deepest_candidates) {
      Eigen::MatrixX3d rows(static_cast<Eigen::Index>(own.size()), 3);
      for (std::size_t k = 0; k < own.size(); ++k)
        rows.row(static_cast<Eigen::Index>(k)) = own[k].transpose();
      out.matrix(rows);
    }
  }
  return out.take();
}

ReferenceVoxelization decode_reference_state(std::string_view bytes, std::size_t voxels,
                                             std::size_t phantom_organs) {
  ByteReader in(bytes, "reference state");
  ReferenceVoxelization state;
  in.array(state.organs);
  for (std::size_t k = 0; k < state.organs.size(); ++k)
    if (state.organs[k] < 0 || static_cast<std::size_t>(state.organs[k]) >= phantom_organs ||
        (k > 0 && state.organs[k] <= state.organs[k - 1]))
      in.damaged("level sets of organs the phantom does not have, or out of order");
  std::vector<std::pair<double, double>> sizes(state.organs.size());
  for (auto& [voxel_size, half_width] : sizes) {
    voxel_size = in.value<double>();
    half_width = in.value<double>();
  }
  std::vector<std::shared_ptr<void>> grids = decode_float_grids(in.view());
  if (grids.size() != state.organs.size()) in.damaged("another number of level sets than organs");
  for (std::size_t k = 0; k < grids.size(); ++k)
    state.level_sets.push_back(
        std::make_shared<const LevelSet>(std::move(grids[k]), sizes[k].first, sizes[k].second));
  const auto organs = in.value<std::uint64_t>();
  if (organs != phantom_organs) in.damaged("height bounds of another number of organs than the phantom's");
  state.height_ranges.resize(organs);
  for (auto& ranges : state.height_ranges) {
    const auto present = in.value<std::uint8_t>();
    if (present > 1) in.damaged("a flag that is neither 0 nor 1");
    if (present) in.array(ranges.emplace());
  }
  state.volumes = decode_tissue_volumes(in.view());
  if (state.volumes.labels.size() != voxels) in.damaged("volumes of another voxel count than the grid");
  const auto has_candidates = in.value<std::uint8_t>();
  if (has_candidates > 1) in.damaged("a flag that is neither 0 nor 1");
  if (has_candidates) {
    if (in.value<std::uint64_t>() != phantom_organs)
      in.damaged("deepest-point candidates of another number of organs than the phantom's");
    DeepestCandidates& candidates = state.deepest_candidates.emplace(phantom_organs);
    for (std::vector<Eigen::Vector3d>& own : candidates) {
      Eigen::MatrixX3d rows;
      in.matrix(rows);
      if (!rows.allFinite()) in.damaged("a deepest-point candidate that is not finite");
      for (Eigen::Index k = 0; k < rows.rows(); ++k)
        own.push_back(rows.row(k).transpose());
    }
  }
  if (!in.done()) in.damaged("bytes after the state");
  return state;
}

VoxelizedPhantom voxelize_phantom_cached(const std::string& anatomy_key, const VoxelizationSettings& settings,
                                         const OrganTable& organs, const ImageGrid& grid,
                                         const Phantom& reference, const Phantom* deformed,
                                         const PhantomDeformation* deformation, const fs::path& folder,
                                         StageReport& report, Reporter& reporter,
                                         ReferenceVoxelization* built, bool built_read_from_cache) {
  const std::string key =
      folder.empty() ? std::string() : reference_cache_key(anatomy_key, settings, organs, grid);
  if (!key.empty() && built && built_read_from_cache) {
    std::optional<ReferenceVoxelization> state(std::move(*built));
    VoxelizedPhantom volumes =
        voxelize_phantom(settings, organs, grid, reference, deformed, deformation, report, reporter, &state);
    reporter.note("[voxelize] reference state read from the reference cache: " +
                  (folder / ("reference-" + key + ".bin")).string() +
                  " (voxelized by an earlier run with the same anatomy, grid and settings)");
    record_reference_entry(key, report);
    return volumes;
  }
  if (key.empty()) {
    if (!built)
      return voxelize_phantom(settings, organs, grid, reference, deformed, deformation, report, reporter);
    std::optional<ReferenceVoxelization> given(std::move(*built));
    return voxelize_phantom(settings, organs, grid, reference, deformed, deformation, report, reporter,
                            &given);
  }
  std::error_code error;
  fs::create_directories(folder, error);
  if (error)
    throw InputError(folder.string() + ": reference cache: " + folder_creation_problem(folder, error));
  const fs::path entry = folder / ("reference-" + key + ".bin");
  // Held while this run voxelizes: a process that needs the same entry waits for it.
  const CacheKeyLock lock(folder / ("reference-" + key + ".lock"), "reference cache");
  const std::string header = std::string(k_reference_magic) + key + "\n";
  std::optional<ReferenceVoxelization> state;
  if (fs::exists(entry)) {
    const std::string bytes = read_cache_entry(entry);
    try {
      if (bytes.compare(0, header.size(), header) != 0) throw DamagedBytes("another key or format");
      state = decode_reference_state(decompress_bytes(std::string_view(bytes).substr(header.size())),
                                     static_cast<std::size_t>(grid.voxel_count()), reference.organs.size());
    } catch (const DamagedBytes& damaged) {
      const std::string line =
          entry.string() + ": a damaged reference cache entry (" + damaged.what() + "); voxelized again";
      // Not a stage warning: the state voxelized again is sound, so --strict has nothing to refuse.
      report.modelled.push_back(line);
      reporter.warning("voxelize", line);
    }
  }
  const bool read = state.has_value();
  // A state built beforehand is handed over (voxelize_phantom takes it as read), and what the
  // entry stores besides the volumes is kept for it.
  std::optional<ReferenceVoxelization> to_store;
  if (!read && built) {
    to_store.emplace();
    to_store->organs = built->organs;
    to_store->level_sets = built->level_sets;
    to_store->height_ranges = built->height_ranges;
    to_store->deepest_candidates = built->deepest_candidates;
    state = std::move(*built);
  }
  VoxelizedPhantom volumes =
      voxelize_phantom(settings, organs, grid, reference, deformed, deformation, report, reporter, &state);
  if (to_store) state = std::move(to_store);
  if (read) {
    reporter.note("[voxelize] reference state read from the reference cache: " + entry.string() +
                  " (voxelized by an earlier run with the same anatomy, grid and settings)");
  } else {
    write_file_atomically(entry, header + compress_bytes(encode_reference_state(*state, volumes.reference)));
    reporter.note("[voxelize] reference state stored in the reference cache: " + entry.string());
  }
  record_reference_entry(key, report);
  return volumes;
}

std::optional<ReferenceVoxelization>
read_stored_reference_state(const std::string& anatomy_key, const VoxelizationSettings& settings,
                            const OrganTable& organs, const ImageGrid& grid, std::size_t phantom_organs,
                            const fs::path& folder) {
  if (folder.empty()) return std::nullopt;
  const std::string key = reference_cache_key(anatomy_key, settings, organs, grid);
  const fs::path entry = folder / ("reference-" + key + ".bin");
  std::error_code error;
  if (!fs::exists(entry, error)) return std::nullopt;
  const std::string header = std::string(k_reference_magic) + key + "\n";
  try {
    const std::string bytes = read_cache_entry(entry);
    if (bytes.compare(0, header.size(), header) != 0) return std::nullopt;
    return decode_reference_state(decompress_bytes(std::string_view(bytes).substr(header.size())),
                                  static_cast<std::size_t>(grid.voxel_count()), phantom_organs);
  } catch (const DamagedBytes&) {
    return std::nullopt;
  }
}

bool reference_state_stored(const std::string& anatomy_key, const VoxelizationSettings& settings,
                            const OrganTable& organs, const ImageGrid& grid, const fs::path& folder) {
  if (folder.empty()) return false;
  std::error_code error;
  return fs::exists(
      folder / ("reference-" + reference_cache_key(anatomy_key, settings, organs, grid) + ".bin"), error);
}

} // namespace phantasm
