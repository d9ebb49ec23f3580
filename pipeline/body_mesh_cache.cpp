#include "pipeline/body_mesh_cache.hpp"

#include "core/byte_codec.hpp"
#include "core/error.hpp"
#include "core/sha256.hpp"
#include "io/atomic_file.hpp"
#include "io/output_path.hpp"
#include "pipeline/cache_entry.hpp"

namespace phantasm {
namespace {

namespace fs = std::filesystem;

// The file's first line; the key follows on the second, the mesh after it.
constexpr const char* k_body_mesh_magic = "phantasm body mesh cache 1\n";

/// The entry's line of the log and the provenance (the stage prints it): the same whether this run
/// built the entry or read it (log lines are deterministic; which it did is a screen note).
void record_body_mesh_entry(const std::string& key, StageReport& report) {
  report.modelled.push_back(
      "body tet mesh of nested organs kept in the body mesh cache as entry " + key.substr(0, 16) +
      " (the first run with this anatomy and these bodies builds it, the others read it)");
}

/// The mesh of `inputs` from the entry, or built and stored there.
NestedBodyMesh cached_body_mesh(const std::string& key, const fs::path& folder,
                                const std::function<NestedBodyMesh()>& build, StageReport& report,
                                Reporter& reporter) {
  std::error_code error;
  fs::create_directories(folder, error);
  if (error)
    throw InputError(folder.string() + ": body mesh cache: " + folder_creation_problem(folder, error));
  const fs::path entry = folder / ("body-mesh-" + key + ".bin");
  const CacheKeyLock lock(folder / ("body-mesh-" + key + ".lock"), "body mesh cache");
  const std::string header = std::string(k_body_mesh_magic) + key + "\n";
  if (fs::exists(entry)) {
    const std::string bytes = read_cache_entry(entry);
    try {
      if (bytes.compare(0, header.size(), header) != 0) throw DamagedBytes("another key or format");
      NestedBodyMesh mesh = decode_nested_body_mesh(std::string_view(bytes).substr(header.size()));
      record_body_mesh_entry(key, report);
      reporter.note("[deformation] body tet mesh read from the body mesh cache: " + entry.string());
      return mesh;
    } catch (const DamagedBytes& damaged) {
      const std::string line =
          entry.string() + ": a damaged body mesh cache entry (" + damaged.what() + "); built again";
      report.modelled.push_back(line); // the mesh built again is sound: nothing for --strict
      reporter.warning(report.stage, line);
    }
  }
  NestedBodyMesh mesh = build();
  write_file_atomically(entry, header + encode_nested_body_mesh(mesh));
  record_body_mesh_entry(key, report);
  reporter.note("[deformation] body tet mesh stored in the body mesh cache: " + entry.string());
  return mesh;
}

} // namespace

std::string body_mesh_cache_key(const std::string& anatomy_key, const std::string& inputs) {
  if (anatomy_key.empty()) return {};
  return sha256_hex(std::string(k_body_mesh_magic) + "anatomy " + anatomy_key + "\n" + inputs);
}

std::string encode_nested_body_mesh(const NestedBodyMesh& mesh) {
  ByteWriter out;
  out.matrix(mesh.mesh.vertices);
  out.matrix(mesh.mesh.tets);
  out.matrix(mesh.mesh.boundary_faces);
  out.matrix(mesh.mesh.subdomains);
  const SliverRepairs& r = mesh.repairs;
  for (int count : {r.vertex_moves, r.peeled, r.relabelled, r.flips, r.splits, r.collapses})
    out.value(count);
  return out.take();
}

NestedBodyMesh decode_nested_body_mesh(std::string_view bytes) {
  ByteReader in(bytes, "body mesh");
  NestedBodyMesh mesh;
  in.matrix(mesh.mesh.vertices);
  in.matrix(mesh.mesh.tets);
  in.matrix(mesh.mesh.boundary_faces);
  in.matrix(mesh.mesh.subdomains);
  SliverRepairs& r = mesh.repairs;
  for (int* count : {&r.vertex_moves, &r.peeled, &r.relabelled, &r.flips, &r.splits, &r.collapses})
    *count = in.value<int>();
  if (!in.done()) in.damaged("bytes after the mesh");
  const auto vertices = mesh.mesh.vertices.rows();
  const auto in_range = [vertices](const auto& indices) {
    return indices.size() == 0 || (indices.minCoeff() >= 0 && indices.maxCoeff() < vertices);
  };
  if (!in_range(mesh.mesh.tets) || !in_range(mesh.mesh.boundary_faces))
    in.damaged("vertex indices out of range");
  if (mesh.mesh.subdomains.size() != mesh.mesh.tets.rows()) in.damaged("a subdomain count unlike the tets'");
  return mesh;
}

BodyMeshSource body_mesh_cache(const std::string& anatomy_key, const fs::path& folder, StageReport& report,
                               Reporter& reporter) {
  if (folder.empty() || anatomy_key.empty()) return {};
  return [anatomy_key, folder, &report, &reporter](const std::string& inputs,
                                                   const std::function<NestedBodyMesh()>& build) {
    return cached_body_mesh(body_mesh_cache_key(anatomy_key, inputs), folder, build, report, reporter);
  };
}

} // namespace phantasm
