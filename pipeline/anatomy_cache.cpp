#include "pipeline/anatomy_cache.hpp"

#include "anatomy/phantom.hpp"
#include "core/build_id.hpp"
#include "core/error.hpp"
#include "core/sha256.hpp"
#include "io/atomic_file.hpp"
#include "io/output_path.hpp"
#include "pipeline/cache_entry.hpp"
#include "scene/settings_declarations.hpp"

#include <sstream>

namespace phantasm {

namespace {

namespace fs = std::filesystem;

// The file's first line; the key follows on the second, the geometry after it.
constexpr const char* k_magic = "phantasm anatomy cache 2\n";

template <typename Derived>
std::string bytes_hash(const Eigen::PlainObjectBase<Derived>& m) {
  return std::to_string(m.rows()) + "x" + std::to_string(m.cols()) + ":" +
         sha256_hex(std::string_view(reinterpret_cast<const char*>(m.data()),
                                     sizeof(typename Derived::Scalar) * static_cast<std::size_t>(m.size())));
}

/// Every declared anatomy setting that shapes the anatomy (scene/settings_declarations.cpp),
/// one per line.
std::string settings_text(const AnatomySettings& a) {
  return key_text(declared_settings<AnatomySettings>(), a, cached_anatomy);
}

/// The shape data by content (label volumes shared by organs are hashed once).
std::string files_text(const std::map<std::string, ShapeData>& files) {
  std::ostringstream out;
  std::map<const void*, std::string> label_hashes;
  for (const auto& [organ, data] : files) {
    out << "file of " << organ << " from " << data.source << "\n";
    if (data.mesh)
      out << " mesh " << bytes_hash(data.mesh->vertices) << " " << bytes_hash(data.mesh->faces) << "\n";
    if (data.label_grid) {
      out << " grid " << exact_text(data.label_grid->dims) << " " << exact_text(data.label_grid->spacing_mm)
          << " " << exact_text(data.label_grid->world_from_voxel) << "\n";
    }
    if (data.labels) {
      std::string& hash = label_hashes[data.labels.get()];
      if (hash.empty()) {
        hash = sha256_hex(std::string_view(reinterpret_cast<const char*>(data.labels->data()),
                                           data.labels->size() * sizeof(std::int32_t)));
      }
      out << " labels " << data.labels->size() << " " << hash << "\n";
    }
    out << " target labels";
    for (std::int32_t l : data.target_labels)
      out << " " << l;
    out << "\n";
  }
  return out.str();
}

/// The entry's line of the log and the provenance: the same whether this run built the entry or
/// read it (log lines are deterministic; which it did is a screen note).
void record_entry(const std::string& key, StageReport& report, Reporter& reporter) {
  const std::string line = "organ geometry kept in the anatomy cache as entry " + key.substr(0, 16) +
                           " (the first run with these settings and inputs builds it, the others read it)";
  report.modelled.push_back(line);
  reporter.modelled("anatomy", line);
}

} // namespace

std::string anatomy_cache_key(const AnatomySettings& anatomy, const std::map<std::string, ShapeData>& files) {
  const std::string build = code_build_id();
  if (build.empty()) return {};
  return sha256_hex(std::string(k_magic) + "build " + build + "\n" + settings_text(anatomy) +
                    files_text(files));
}

Phantom build_phantom_cached(const AnatomySettings& anatomy, const std::map<std::string, ShapeData>& files,
                             const fs::path& folder, StageReport& report, Reporter& reporter,
                             std::string* key_out) {
  if (folder.empty()) return build_phantom(anatomy, files, reporter);
  const std::string key = anatomy_cache_key(anatomy, files);
  if (key_out) *key_out = key;
  if (key.empty()) {
    const std::string line =
        "anatomy cache: not used (this build of phantasm has no build id to tell its entries apart)";
    report.skipped.push_back(line);
    reporter.skipped("anatomy", line);
    return build_phantom(anatomy, files, reporter);
  }
  std::error_code error;
  fs::create_directories(folder, error);
  if (error) throw InputError(folder.string() + ": anatomy cache: " + folder_creation_problem(folder, error));
  const fs::path entry = folder / ("anatomy-" + key + ".bin");
  const CacheKeyLock lock(folder / ("anatomy-" + key + ".lock"), "anatomy cache");
  const std::string header = std::string(k_magic) + key + "\n";
  if (fs::exists(entry)) {
    const std::string bytes = read_cache_entry(entry);
    try {
      if (bytes.compare(0, header.size(), header) != 0) throw DamagedGeometry("another key or format");
      Phantom phantom =
          phantom_from_geometry(anatomy, files, std::string_view(bytes).substr(header.size()), reporter);
      record_entry(key, report, reporter);
      reporter.note("[anatomy] organs read from the anatomy cache: " + entry.string() +
                    " (built by an earlier run with the same settings and inputs)");
      return phantom;
    } catch (const DamagedGeometry& damaged) {
      const std::string line =
          entry.string() + ": a damaged anatomy cache entry (" + damaged.what() + "); built again";
      // Not a stage warning: the anatomy built again is sound, so --strict has nothing to refuse.
      report.modelled.push_back(line);
      reporter.warning("anatomy", line);
    }
  }
  Phantom phantom = build_phantom(anatomy, files, reporter);
  write_file_atomically(entry, header + encode_organ_geometry(phantom));
  record_entry(key, report, reporter);
  reporter.note("[anatomy] organs stored in the anatomy cache: " + entry.string());
  return phantom;
}

} // namespace phantasm
