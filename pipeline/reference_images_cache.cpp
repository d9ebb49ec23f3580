#include "pipeline/reference_images_cache.hpp"

#include "core/byte_codec.hpp"
#include "core/error.hpp"
#include "core/sha256.hpp"
#include "io/atomic_file.hpp"
#include "io/byte_compression.hpp"
#include "io/output_path.hpp"
#include "pipeline/cache_entry.hpp"
#include "scene/settings_declarations.hpp"

#include <array>
#include <cstdint>
#include <cstring>
#include <optional>
#include <utility>

namespace phantasm {
namespace {

namespace fs = std::filesystem;

// The file's first line; the key follows on the second, the images after it. The format number
// is also part of the key.
constexpr const char* k_images_magic = "phantasm reference images cache 2\n";

/// Every declared MRI setting that shapes the reference images and maps
/// (scene/settings_declarations.cpp), one per line.
std::string settings_text(const MriSettings& mri) {
  return key_text(declared_settings<MriSettings>(), mri, cached_reference_images);
}

std::string_view bytes_of(const std::vector<float>& values) {
  return {reinterpret_cast<const char*>(values.data()), values.size() * sizeof(float)};
}

/// The values of a compressed piece that must hold `voxels` floats.
std::vector<float> floats_of(std::string_view compressed, std::size_t voxels, const ByteReader& in) {
  const std::string bytes = decompress_bytes(compressed);
  if (bytes.size() != voxels * sizeof(float)) in.damaged("a volume of another size than the grid");
  std::vector<float> values(voxels);
  if (voxels > 0) std::memcpy(values.data(), bytes.data(), bytes.size());
  return values;
}

/// The maps in the order they are stored.
template <typename Maps>
auto map_list(Maps& maps) {
  return std::array{&maps.PD, &maps.T1_ms, &maps.T2_ms, &maps.T2star_ms};
}

/// The entry's line of the log and the provenance: the same whether this run made the images or
/// read them (log lines are deterministic; which it did is a screen note).
void record_images_entry(const std::string& key, const MriSettings& mri, StageReport& report) {
  report.modelled.push_back(std::string("reference state's MR images") +
                            (mri.parameter_maps ? " and parameter maps" : "") +
                            " kept in the reference cache as entry " + key.substr(0, 16) +
                            " (the first run with this reference state and these MRI settings makes "
                            "them, the others read them)");
}

} // namespace

std::string reference_images_key(const std::string& reference_key, const MriSettings& mri) {
  if (reference_key.empty()) return {};
  return sha256_hex(std::string(k_images_magic) + "reference " + reference_key + "\n" + settings_text(mri));
}

std::string encode_reference_images(const ReferenceImages& images) {
  ByteWriter out;
  out.value(static_cast<std::uint64_t>(images.images.size()));
  for (const MrImage& image : images.images) {
    out.value(image.noise_sigma);
    out.text(compress_bytes(bytes_of(image.magnitude), 0));
  }
  out.value(static_cast<std::uint8_t>(images.maps.has_value()));
  if (images.maps)
    for (const std::vector<float>* map : map_list(*images.maps))
      out.text(compress_bytes(bytes_of(*map), 1));
  return out.take();
}

ReferenceImages decode_reference_images(std::string_view bytes, std::size_t sequences, bool maps,
                                        std::size_t voxels) {
  ByteReader in(bytes, "reference images");
  ReferenceImages images;
  if (in.value<std::uint64_t>() != sequences) in.damaged("another number of images than sequences");
  images.images.resize(sequences);
  for (MrImage& image : images.images) {
    image.noise_sigma = in.value<double>();
    image.magnitude = floats_of(in.view(), voxels, in);
  }
  const auto has_maps = in.value<std::uint8_t>();
  if (has_maps > 1) in.damaged("a flag that is neither 0 nor 1");
  if (static_cast<bool>(has_maps) != maps) in.damaged("parameter maps where none were expected, or none");
  if (maps)
    for (std::vector<float>* map : map_list(images.maps.emplace()))
      *map = floats_of(in.view(), voxels, in);
  if (!in.done()) in.damaged("bytes after the images");
  return images;
}

MrImages synthesize_images_cached(const std::string& reference_key, const MriSettings& mri,
                                  const OrganTable& organs, const VoxelizedPhantom& volumes,
                                  const fs::path& folder, StageReport& report, Reporter& reporter) {
  const std::string key = folder.empty() ? std::string() : reference_images_key(reference_key, mri);
  if (key.empty()) return synthesize_images(mri, organs, volumes, report, reporter);
  std::error_code error;
  fs::create_directories(folder, error);
  if (error)
    throw InputError(folder.string() + ": reference images cache: " + folder_creation_problem(folder, error));
  // Not "reference-": batch counts those files as reference states.
  const fs::path entry = folder / ("images-" + key + ".bin");
  SynthesisOptions options;
  {
    // Held while this run makes the reference images (not the deformed ones): a process that
    // needs the same entry waits for it.
    const CacheKeyLock lock(folder / ("images-" + key + ".lock"), "reference images cache");
    const std::string header = std::string(k_images_magic) + key + "\n";
    if (fs::exists(entry)) {
      const std::string bytes = read_cache_entry(entry);
      try {
        if (bytes.compare(0, header.size(), header) != 0) throw DamagedBytes("another key or format");
        options.reference =
            decode_reference_images(std::string_view(bytes).substr(header.size()), mri.sequences.size(),
                                    mri.parameter_maps, volumes.reference.labels.size());
      } catch (const DamagedBytes& damaged) {
        const std::string line =
            entry.string() + ": a damaged reference images cache entry (" + damaged.what() + "); made again";
        // Not a stage warning: the images made again are sound, so --strict has nothing to refuse.
        report.modelled.push_back(line);
        reporter.warning("mri", line);
      }
    }
    if (options.reference) {
      reporter.note("[mri] reference images read from the reference cache: " + entry.string() +
                    " (made by an earlier run with the same reference state and MRI settings)");
    } else {
      // The reference state alone; its report lines are those the call below makes again.
      StageReport made_report;
      SynthesisOptions reference_only;
      reference_only.reference_only = true;
      MrImages made =
          synthesize_images(mri, organs, volumes, made_report, reporter, std::move(reference_only));
      options.reference = ReferenceImages{std::move(made.reference), std::move(made.reference_maps)};
      write_file_atomically(entry, header + encode_reference_images(*options.reference));
      reporter.note("[mri] reference images stored in the reference cache: " + entry.string());
    }
  }
  MrImages images = synthesize_images(mri, organs, volumes, report, reporter, std::move(options));
  record_images_entry(key, mri, report);
  return images;
}

} // namespace phantasm
