#include "pipeline/atlas_labels_cache.hpp"

#include "core/build_id.hpp"
#include "core/byte_codec.hpp"
#include "core/error.hpp"
#include "core/sha256.hpp"
#include "io/atomic_file.hpp"
#include "io/output_path.hpp"
#include "pipeline/cache_entry.hpp"

namespace phantasm {
namespace {

namespace fs = std::filesystem;

// The file's first line; the key follows on the second, the labels after it.
constexpr const char* k_atlas_labels_magic = "phantasm atlas labels cache 1\n";

} // namespace

std::string atlas_labels_cache_key(const std::string& atlas, const fs::path& templates_dir) {
  const std::string build = code_build_id();
  if (build.empty()) return {};
  std::string text = std::string(k_atlas_labels_magic) + "build " + build + "\natlas " + atlas + " in " +
                     templates_dir.string() + "\n";
  for (const fs::path& input : atlas_input_files(atlas, templates_dir)) {
    std::error_code error;
    if (!fs::is_regular_file(input, error)) return {};
    text += input.filename().string() + " " + sha256_hex(read_cache_entry(input)) + "\n";
  }
  return sha256_hex(text);
}

std::string encode_atlas_labels(const AtlasLabels& labels) {
  ByteWriter out;
  const ImageGrid& grid = labels.head.grid;
  out.matrix(grid.dims);
  out.matrix(grid.spacing_mm);
  out.matrix(grid.world_from_voxel);
  out.array(labels.head.labels);
  out.value(static_cast<std::uint64_t>(labels.head.table.size()));
  for (const HeadLabelInfo& info : labels.head.table) {
    out.value(info.label);
    out.text(info.name);
    out.text(info.tissue);
  }
  out.text(labels.source);
  out.value(static_cast<std::uint64_t>(labels.provenance.size()));
  for (const std::string& line : labels.provenance)
    out.text(line);
  return out.take();
}

AtlasLabels decode_atlas_labels(std::string_view bytes) {
  ByteReader in(bytes, "atlas labels");
  AtlasLabels labels;
  ImageGrid& grid = labels.head.grid;
  in.matrix(grid.dims);
  in.matrix(grid.spacing_mm);
  in.matrix(grid.world_from_voxel);
  in.array(labels.head.labels);
  if (grid.dims.minCoeff() < 0 || labels.head.labels.size() != static_cast<std::size_t>(grid.voxel_count()))
    in.damaged("labels of another count than the grid's voxels");
  const auto entries = in.value<std::uint64_t>();
  if (entries > bytes.size()) in.damaged("a label table longer than the bytes");
  labels.head.table.resize(entries);
  for (HeadLabelInfo& info : labels.head.table) {
    info.label = in.value<std::int32_t>();
    info.name = in.text();
    info.tissue = in.text();
  }
  labels.source = in.text();
  const auto lines = in.value<std::uint64_t>();
  if (lines > bytes.size()) in.damaged("more provenance lines than bytes");
  labels.provenance.resize(lines);
  for (std::string& line : labels.provenance)
    line = in.text();
  if (!in.done()) in.damaged("bytes after the labels");
  return labels;
}

AtlasLabels derive_atlas_labels_cached(const std::string& atlas, const fs::path& folder, Reporter& reporter,
                                       const fs::path& templates_dir) {
  const std::string key = folder.empty() ? std::string() : atlas_labels_cache_key(atlas, templates_dir);
  if (key.empty()) return derive_atlas_labels(atlas, templates_dir);
  std::error_code error;
  fs::create_directories(folder, error);
  if (error)
    throw InputError(folder.string() + ": atlas labels cache: " + folder_creation_problem(folder, error));
  const fs::path entry = folder / ("atlas-" + key + ".bin");
  const CacheKeyLock lock(folder / ("atlas-" + key + ".lock"), "atlas labels cache");
  const std::string header = std::string(k_atlas_labels_magic) + key + "\n";
  if (fs::exists(entry)) {
    const std::string bytes = read_cache_entry(entry);
    try {
      if (bytes.compare(0, header.size(), header) != 0) throw DamagedBytes("another key or format");
      AtlasLabels labels = decode_atlas_labels(std::string_view(bytes).substr(header.size()));
      reporter.note("[anatomy] " + atlas + " labels read from the cache: " + entry.string());
      return labels;
    } catch (const DamagedBytes& damaged) {
      reporter.warning("anatomy", entry.string() + ": a damaged atlas labels cache entry (" + damaged.what() +
                                      "); derived again");
    }
  }
  AtlasLabels labels = derive_atlas_labels(atlas, templates_dir);
  write_file_atomically(entry, header + encode_atlas_labels(labels));
  reporter.note("[anatomy] " + atlas + " labels stored in the cache: " + entry.string());
  return labels;
}

} // namespace phantasm
