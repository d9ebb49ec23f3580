// The reference cache: the voxelized reference state (level sets, the patches' height bounds,
// labels and fractions) stored under the content hash of everything that shapes it, so that the
// subjects of a sweep that share anatomy and seed and differ in what comes after (the
// deformation, the noise, the sequences) voxelize the reference state once.
#pragma once

#include "anatomy/organ.hpp"
#include "core/grid.hpp"
#include "core/organ_table.hpp"
#include "core/progress.hpp"
#include "core/stage_report.hpp"
#include "sim/phantom_deformation.hpp"
#include "voxelize/voxelize_settings.hpp"
#include "voxelize/voxelized_phantom.hpp"

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

namespace phantasm {

struct ReferenceVoxelization; // voxelize/voxelize_phantom.hpp: the voxelizer stays private here

/// The content hash (SHA-256, hex) that names a reference state: the anatomy's key
/// (anatomy_cache_key: the anatomy settings, the shape files and the build id of the code), the
/// grid (dimensions, spacing and affine, bit for bit), the voxelization settings the reference
/// state depends on (supersampling, how level sets are made, the organs' nominal bounds), the
/// organ table (names, tissues, nesting) and the entry's format. Settings of the deformed state
/// alone (gap fill, field extension) and of the outputs leave it unchanged. Empty when the
/// anatomy key is (no build id: nothing may be kept across runs).
std::string reference_cache_key(const std::string& anatomy_key, const VoxelizationSettings& settings,
                                const OrganTable& organs, const ImageGrid& grid);

/// Tissue volumes as bytes: the one place that knows TissueVolumes' members.
std::string encode_tissue_volumes(const TissueVolumes& volumes);

/// The tissue volumes of encode_tissue_volumes() bytes.
/// @throws DamagedBytes when the bytes do not hold them
TissueVolumes decode_tissue_volumes(std::string_view bytes);

/// A reference state as bytes: its level sets (every value of their trees), the organs they
/// belong to, the patches' height bounds and the tissue volumes (given apart: voxelize_phantom
/// gives them back in its result).
std::string encode_reference_state(const ReferenceVoxelization& state, const TissueVolumes& volumes);

/// The reference state of encode_reference_state() bytes; voxelize_phantom given it makes the
/// same result, bit for bit, as when it built it.
/// @param voxels the grid's voxel count: the volumes must hold as many
/// @param phantom_organs the reference phantom's organ count: the level sets' organs (ascending)
///        must be among them, and every organ must have its height bounds' place
/// @throws DamagedBytes when the bytes do not hold such a state (a stored entry that does not fit
///         the run is voxelized again, never handed to voxelize_phantom)
ReferenceVoxelization decode_reference_state(std::string_view bytes, std::size_t voxels,
                                             std::size_t phantom_organs);

/// voxelize_phantom() through a cache folder: the reference state stored under the key of these
/// inputs is read when there, else built and stored (atomically, compressed). Processes that need
/// the same key at once build it once: the others wait on the key's lock file (cancellable) and
/// read what the first stored. A damaged entry is built again, with a warning. The entry's line
/// goes to the report (the same whether the state was built or read); which it was, to the screen.
/// @param anatomy_key the reference phantom's anatomy_cache_key(); empty: no cache
/// @param folder the cache folder (made when missing); empty: no cache, voxelize_phantom() alone
/// @param built null, or the reference state voxelize_reference_state() built for these inputs
///        (while the deformation was solved): taken (moved from) instead of building the state
///        when the cache does not hold it
/// @param built_read_from_cache `built` is the entry of these inputs, read by
///        read_stored_reference_state(): taken as the read entry, without reading it again
VoxelizedPhantom voxelize_phantom_cached(const std::string& anatomy_key, const VoxelizationSettings& settings,
                                         const OrganTable& organs, const ImageGrid& grid,
                                         const Phantom& reference, const Phantom* deformed,
                                         const PhantomDeformation* deformation,
                                         const std::filesystem::path& folder, StageReport& report,
                                         Reporter& reporter, ReferenceVoxelization* built = nullptr,
                                         bool built_read_from_cache = false);

/// True when the cache folder holds a reference state entry under these inputs' key (read or
/// damaged, voxelize_phantom_cached tells): a run need not build the state beforehand.
bool reference_state_stored(const std::string& anatomy_key, const VoxelizationSettings& settings,
                            const OrganTable& organs, const ImageGrid& grid,
                            const std::filesystem::path& folder);

/// The reference state stored under these inputs' key, read and decoded (entries are written
/// whole, so no lock is needed to read one); none when there is no such entry or it is damaged
/// (voxelize_phantom_cached then reads it again and says so). For a run that reads the entry while
/// the deformation is solved.
std::optional<ReferenceVoxelization>
read_stored_reference_state(const std::string& anatomy_key, const VoxelizationSettings& settings,
                            const OrganTable& organs, const ImageGrid& grid, std::size_t phantom_organs,
                            const std::filesystem::path& folder);

} // namespace phantasm
