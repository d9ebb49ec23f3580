#include "pipeline/dataset_writer.hpp"

#include "core/cancellation.hpp"
#include "core/error.hpp"
#include "core/format.hpp"
#include "core/parallel_tasks.hpp"
#include "core/sha256.hpp"
#include "core/version.hpp"
#include "geometry/ras_lps.hpp"
#include "io/atomic_file.hpp"
#include "io/dataset_layout.hpp"
#include "io/json_file.hpp"
#include "io/mesh_file.hpp"
#include "io/nifti_file.hpp"
#include "io/output_path.hpp"
#include "io/preview_png.hpp"
#include "io/vdb_file.hpp"
#include "mri/sequence_type.hpp"
#include "pipeline/cost_estimate.hpp"
#include "pipeline/finite_outputs.hpp"
#include "pipeline/material_maps_stage.hpp"
#include "pipeline/reference_files_cache.hpp"
#include "scene/scene_json.hpp"
#include "voxelize/landmarks.hpp"
#include "voxelize/level_set.hpp"
#include "voxelize/voxelized_phantom.hpp"

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <exception>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>
#include <thread>
#include <utility>
#include <vector>

namespace phantasm {
namespace {

/// One file of the dataset: where it goes, and what makes its bytes there (run when the file's
/// turn comes, so that what it reads, e.g. the log so far, is complete by then).
struct PlannedFile {
  std::filesystem::path path;
  std::function<void(const std::filesystem::path&)> write;
};

/// What a file's bytes follow from besides the code. A reference-session file's are the same in
/// every subject that shares the reference state (and, for images, the MRI settings): a run with
/// a cache copies the bytes an earlier subject stored (pipeline/reference_files_cache.hpp).
enum class FileSource {
  subject,          ///< this subject's deformation, or the scene as a whole
  reference_state,  ///< the reference state's key: its labels, fractions and meshes
  reference_images, ///< its images' key: their images, previews and parameter maps
};

/// The dataset's files in the order they are written. The one list is both the progress count
/// and what is written, so the two cannot drift apart.
class DatasetPlan {
public:
  DatasetPlan(const ReferenceEntries& entries, const DatasetLayout& layout, Reporter& reporter)
      : m_entries(entries), m_root(layout.root()), m_subject("sub-" + layout.subject()),
        m_reporter(reporter) {}

  /// A file made by one of io's format writers.
  void file(std::filesystem::path path, FileWriter write, FileSource source = FileSource::subject) {
    write = from(path, std::move(write), source);
    m_files.push_back({std::move(path), std::move(write)});
  }
  /// `write` of a file at `path`, through the cache when its bytes follow from a reference entry.
  FileWriter from(const std::filesystem::path& path, FileWriter write, FileSource source) const {
    if (source == FileSource::subject) return write;
    // The file's path in the dataset without the subject: the same in every subject (its folder
    // too, since an image and a parameter map may have one name).
    std::string role = path.lexically_relative(m_root).generic_string();
    for (std::size_t at = role.find(m_subject); at != std::string::npos; at = role.find(m_subject, at))
      role.replace(at, m_subject.size(), "sub-");
    return write_through_cache(
        m_entries.folder, source == FileSource::reference_state ? m_entries.state_key : m_entries.images_key,
        role, std::move(write), m_reporter);
  }
  void text(std::filesystem::path path, std::function<std::string()> content) {
    file(std::move(path), [content = std::move(content)](const std::filesystem::path& p) {
      write_file_atomically(p, content());
    });
  }
  void json(std::filesystem::path path, std::function<nlohmann::json()> content) {
    file(std::move(path),
         [content = std::move(content)](const std::filesystem::path& p) { write_json_file(p, content()); });
  }
  const std::vector<PlannedFile>& files() const { return m_files; }

private:
  std::vector<PlannedFile> m_files;
  ReferenceEntries m_entries;
  std::filesystem::path m_root;
  std::string m_subject; ///< "sub-<label>"
  Reporter& m_reporter;
};

/// The source of a file of `state` whose reference-session bytes follow from `reference`.
FileSource source_in(PhantomState state, FileSource reference) {
  return state == PhantomState::reference ? reference : FileSource::subject;
}

nlohmann::json stage_json(const StageReport& report) {
  return {{"stage", report.stage},     {"status", report.status},     {"modelled", report.modelled},
          {"skipped", report.skipped}, {"warnings", report.warnings}, {"accuracy", report.accuracy}};
}

nlohmann::json generated_by() {
  return nlohmann::json::array(
      {{{"Name", "phantasm"},
        {"Version", version},
        {"Description", "Deformable anatomical MRI phantom with exact ground truth"}}});
}

/// The labels of the dseg maps, and for each the entity values that name its files: organ_entity
/// in the organ-<value> of its meshes, tissue_entity in the label-<value> of its tissue's probseg
/// (bids_entity_value of the names).
std::string dseg_table(const Scene& scene) {
  std::ostringstream text;
  text << "index\tname\ttissue\torgan_entity\ttissue_entity\n";
  const auto row = [&text](int index, const std::string& name, const std::string& tissue) {
    text << index << '\t' << name << '\t' << tissue << '\t' << bids_entity_value(name) << '\t'
         << bids_entity_value(tissue) << '\n';
  };
  row(0, "background", "background");
  int index = 1;
  for (const auto& organ : scene.anatomy.organs)
    row(index++, organ.name, organ.tissue);
  // The space a moved organ leaves in a container that stays (deformed state only).
  if (scene.voxelization.deformed) row(index, k_gap_label_name, scene.voxelization.gap_fill);
  // Tissue regions within organs (tissue_regions), after the gap's index.
  index = first_region_label(scene);
  for (const TissueRegionSettings& region : scene.mri.regions)
    row(index++, region_name(region), region.tissue);
  return text.str();
}

/// The column descriptions of dseg.tsv (a BIDS sidecar of a TSV file).
nlohmann::json dseg_table_sidecar() {
  return {
      {"index", {{"Description", "label value in the dseg maps"}, {"Units", "n/a (label)"}}},
      {"name", {{"Description", "organ name as the scene gives it"}}},
      {"tissue", {{"Description", "tissue of the organ (its MR parameters and probseg map)"}}},
      {"organ_entity",
       {{"Description", "value of the organ entity in the file names of the organ's meshes "
                        "(organ-<value>): the name in camelCase, since BIDS splits names at '_' and '-'"}}},
      {"tissue_entity",
       {{"Description", "value of the label entity in the file name of the tissue's probseg map "
                        "(label-<value>): the tissue name in camelCase"}}}};
}

/// The ground truth's README.
std::string derivatives_readme(const Scene& scene) {
  return "# " + scene.name +
         " ground truth\n\nExact ground truth of the synthetic MRI dataset one folder up, " +
         "made by phantasm " + std::string(version) +
         ": per subject and state (ses-ref, ses-def) label maps (dseg, numbered as in dseg.tsv), tissue "
         "fractions (probseg), PD, T1, T2 and T2* maps (relaxation times in seconds), landmarks (CSV, "
         "RAS mm), organ meshes (VTK) and, when asked for, OpenVDB grids; per subject the displacement "
         "fields between the states (xfm: from-A_to-B brings an image of state A onto the grid of state "
         "B; ITK convention, LPS mm), their exact masks and Jacobians, provenance.json, log.txt and the "
         "scene as run. Every image has a JSON sidecar stating its units.\n";
}

/// bids-validator 1.x applies the rules of raw data to a derivative dataset: the derivative
/// files BIDS defines (dseg, probseg, xfm, masks) and the ones it does not cover yet (meshes,
/// landmarks, grids, previews, provenance) are listed for it to pass over
/// (docs/use-with-your-tools.md, bids-validator).
std::string derivatives_bidsignore() {
  return "# Derivative files bids-validator 1.x does not know (it checks raw-data names only).\n"
         "/dseg.*\n"
         "*_dseg.*\n"
         "*_probseg.*\n"
         "*_xfm.*\n"
         "*_desc-exact_mask.*\n"
         "*_jacobian.*\n"
         "*_landmarks.*\n"
         "*_mesh.vtp\n"
         "*_tetmesh.vtu\n"
         "*_grids.vdb\n"
         "/sub-*/ses-*/previews/\n"
         "/sub-*/provenance.json\n"
         "/sub-*/log.txt\n"
         "/sub-*/scene.yaml\n"
         "/sub-*/timing.json\n"
         "/sub-*/page-summary.json\n"
         "/sub-*.html\n"
         "/index.html\n"
         "/cache/\n";
}

/// The raw dataset's README: what the dataset is and where the ground truth lies.
std::string dataset_readme(const Scene& scene) {
  return "# " + scene.name + "\n\nA synthetic MRI dataset made by phantasm " + std::string(version) +
         " from the scene file derivatives/phantasm/sub-*/scene.yaml: simulated images of a phantom "
         "in two states, ses-ref (reference) and ses-def (deformed). No person was imaged.\n\n"
         "derivatives/phantasm holds the exact ground truth: label maps (dseg, with dseg.tsv), tissue "
         "fractions (probseg), relaxation-time maps in seconds (T1map, T2map, T2starmap), PDmap, "
         "displacement fields between the states in the BIDS and ITK convention "
         "(from-<state>_to-<state>_mode-image_xfm: brings an image of the first state onto the grid "
         "of the second), their exact masks and Jacobians, landmarks, meshes and OpenVDB grids.\n";
}

/// How closely exported surfaces follow the patch surfaces: a fifth of the smallest voxel edge
/// (invisible at image resolution, and a few MB per organ; the voxelizer's own tolerance,
/// voxelization.tessellation_tolerance_mm, is finer), never coarser than 0.5 mm.
double mesh_export_tolerance_mm(const Scene& scene) {
  return std::min(
      0.5, std::max(scene.voxelization.tessellation_tolerance_mm, 0.2 * scene.grid.voxel_size_mm.minCoeff()));
}

/// A simulated body's tet mesh in one state (rest or deformed vertices) with, per tet, the dseg
/// label of its organ ("organ_label", its organs' names in the field data) and, deformed, the
/// displacement of each vertex and the det F of each tet.
void write_body_tet_mesh(const std::filesystem::path& path, const Phantom& phantom, const DeformedBody& body,
                         bool deformed) {
  const TetMesh mesh{deformed ? body.deformed_mm : body.rest_mm, body.tets, {}, {}};
  // dseg labels number the organs from 1 in scene order (dseg_table).
  CellArray labels{"organ_label", {}, true, "", {}};
  std::vector<bool> present(phantom.organs.size(), false);
  for (const int organ : body.tet_organ) {
    labels.values.push_back(organ + 1);
    present[static_cast<std::size_t>(organ)] = true;
  }
  for (std::size_t o = 0; o < present.size(); ++o)
    if (present[o]) labels.value_names.emplace_back(static_cast<int>(o) + 1, phantom.organs[o].name);
  std::vector<PointArray> arrays;
  std::vector<CellArray> cell_arrays{std::move(labels)};
  if (deformed) {
    const Eigen::MatrixX3d displacement = body.deformed_mm - body.rest_mm;
    PointArray array{"displacement_mm", 3, {}, "RAS", "mm"};
    for (Eigen::Index v = 0; v < displacement.rows(); ++v)
      for (int c = 0; c < 3; ++c)
        array.values.push_back(displacement(v, c));
    arrays.push_back(std::move(array));
    cell_arrays.push_back({"det_F", body.det_F, false, "", {}});
  }
  write_vtu(path, mesh, arrays, cell_arrays);
}

/// True when two patch surfaces are the same surface: the same base mesh at the same rest and
/// current positions, with the same bumps (an organ the deformation held fixed).
bool same_patch_surface(const PatchSurface& a, const PatchSurface& b) {
  if (a.patch_count() != b.patch_count() || a.base_mesh().vertices != b.base_mesh().vertices ||
      a.base_mesh().faces != b.base_mesh().faces || a.rest_positions() != b.rest_positions())
    return false;
  for (Eigen::Index t = 0; t < a.patch_count(); ++t) {
    const std::vector<PatchBump>& x = a.bumps(t);
    const std::vector<PatchBump>& y = b.bumps(t);
    if (x.size() != y.size()) return false;
    for (std::size_t k = 0; k < x.size(); ++k) {
      if (x[k].center_uv != y[k].center_uv || x[k].shape_uv != y[k].shape_uv ||
          x[k].amplitude_mm != y[k].amplitude_mm)
        return false;
    }
  }
  return true;
}

/// The bytes of a file this run wrote.
/// @throws std::runtime_error naming the file when it cannot be read whole
std::string written_file_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  if (!in || !bytes) throw std::runtime_error(path.string() + ": cannot read back the file this run wrote");
  return std::move(bytes).str();
}

/// An organ's reference surface file, written once whichever of the two states' writers asks
/// first: the deformed state of an organ that did not move copies its bytes instead of
/// tessellating and encoding the same surface again (the skull of a head: tens of MB).
struct ReferenceSurfaceFile {
  std::filesystem::path path;
  std::function<void(const std::filesystem::path&)> write;
  std::once_flag written; // a write that throws leaves it unset: the next caller writes again

  void ensure_written() {
    std::call_once(written, [this] { write(path); });
  }
};

/// The reference surface files of the organs, by organ index (plan_organ_meshes fills it in the
/// reference state and reads it in the deformed one).
using ReferenceSurfaceFiles = std::map<std::size_t, std::shared_ptr<ReferenceSurfaceFile>>;

/// Each organ's surface (.vtp: the patch surface tessellated within mesh_export_tolerance_mm, or
/// the sheet) and tet mesh (.vtu) in one state. A simulated body's tet mesh is the one solved
/// (write_body_tet_mesh: with organs nested in it, one mesh of all of them), other organs' their
/// own. The deformed state's tet meshes carry each vertex's displacement from the reference (RAS
/// mm, as the files' field data say); a deformed surface the same as the reference one is a copy
/// of its file (`surfaces`, filled by the reference state's call).
void plan_organ_meshes(const Scene& scene, const Phantom& phantom, PhantomState state,
                       const DatasetLayout& layout, DatasetPlan& plan,
                       const std::vector<DeformedBody>* bodies, ReferenceSurfaceFiles& surfaces,
                       const Phantom* reference = nullptr) {
  const double tolerance = mesh_export_tolerance_mm(scene);
  for (std::size_t index = 0; index < phantom.organs.size(); ++index) {
    const Organ& organ = phantom.organs[index];
    if (organ.surface || organ.sheet) {
      const auto write_surface = [&organ, tolerance](const std::filesystem::path& path) {
        if (!organ.surface) {
          write_vtp(path, *organ.sheet);
          return;
        }
        const TriangleMesh surface = organ.surface->tessellate(tolerance);
        throw_if_cancelled(); // a cancelled tessellation is empty: never written
        write_vtp(path, surface);
      };
      const auto shared = surfaces.find(index);
      if (!reference && organ.surface) {
        auto file = std::make_shared<ReferenceSurfaceFile>();
        file->path = layout.mesh(state, organ.name);
        file->write = plan.from(file->path, write_surface, FileSource::reference_state);
        surfaces[index] = file;
        plan.file(file->path, [file](const std::filesystem::path&) { file->ensure_written(); });
      } else if (reference && organ.surface && shared != surfaces.end() && reference->organs[index].surface &&
                 same_patch_surface(*organ.surface, *reference->organs[index].surface)) {
        plan.file(layout.mesh(state, organ.name), [file = shared->second](const std::filesystem::path& path) {
          file->ensure_written();
          write_file_atomically(path, written_file_bytes(file->path));
        });
      } else {
        plan.file(layout.mesh(state, organ.name), write_surface,
                  source_in(state, FileSource::reference_state));
      }
    }
    if (!organ.solid) continue;
    const DeformedBody* body = nullptr;
    for (std::size_t b = 0; bodies && b < bodies->size() && !body; ++b)
      if ((*bodies)[b].organ == organ.name) body = &(*bodies)[b];
    if (body) {
      plan.file(layout.tet_mesh(state, organ.name),
                [&phantom, body, deformed = reference != nullptr](const std::filesystem::path& path) {
                  write_body_tet_mesh(path, phantom, *body, deformed);
                });
      continue;
    }
    plan.file(
        layout.tet_mesh(state, organ.name),
        [&organ, reference, index](const std::filesystem::path& path) {
          std::vector<PointArray> arrays;
          if (reference) {
            const Eigen::MatrixX3d displacement =
                organ.solid->vertices - reference->organs[index].solid->vertices;
            PointArray array{"displacement_mm", 3, {}, "RAS", "mm"};
            for (Eigen::Index v = 0; v < displacement.rows(); ++v)
              for (int c = 0; c < 3; ++c)
                array.values.push_back(displacement(v, c));
            arrays.push_back(std::move(array));
          }
          write_vtu(path, *organ.solid, arrays);
        },
        source_in(state, FileSource::reference_state));
  }
}

nlohmann::json bodies_json(const std::vector<DeformedBody>& bodies) {
  nlohmann::json list = nlohmann::json::array();
  for (const DeformedBody& b : bodies)
    list.push_back(
        {{"organ", b.organ}, {"smallest_det_F", b.smallest_det_F}, {"inverted_tets", b.inverted_tets}});
  return list;
}

nlohmann::json solves_json(const std::vector<SolveReport>& solves) {
  nlohmann::json list = nlohmann::json::array();
  for (const SolveReport& s : solves) {
    nlohmann::json solve = {{"solver", s.solver},
                            {"iterations", s.iterations},
                            {"stopped_by", s.stopped_by},
                            {"converged", s.converged},
                            {"relative_residual", s.relative_residual},
                            {"force_scale_N", s.force_scale_N},
                            {"residual_N", s.residual_N},
                            {"initial_energy_J", s.initial_energy_J},
                            {"final_energy_J", s.final_energy_J}};
    if (!s.residuals_N.empty()) solve["residuals_N"] = s.residuals_N; // the report's convergence plot
    if (s.stability_steps > 0) { // the stability check at the equilibrium (sim/solve_report.hpp)
      solve["stability_ratio"] = s.stability_ratio;
      solve["stability_steps"] = s.stability_steps;
      solve["stability_settled"] = s.stability_settled;
    }
    if (s.rank_updates > 0 || s.contacts > 0) {
      solve["vertices_in_contact"] = s.contacts;
      solve["contact_changes"] = s.contact_changes;
      solve["rank_updates"] = s.rank_updates;
    }
    list.push_back(std::move(solve));
  }
  return list;
}

/// How the image's receiver gain was chosen (docs/volumes-and-images.md, Receiver gain).
std::string receiver_gain_rule(const AcquisitionSettings& a) {
  return a.receiver_gain
             ? "the scene's acquisition.receiver_gain"
             : "automatic: " + a.noise_reference_tissue +
                   " at 1000, the brightest tissue at most 20000 (docs/volumes-and-images.md, Receiver gain)";
}

/// BIDS sidecar of one image: timing in seconds, flip angle in degrees, field strength, and how
/// noise and bias were modelled.
nlohmann::json image_sidecar(const Scene& scene, const MrImages& images, const MrImage& image) {
  const SequenceSettings& s = *image.sequence;
  nlohmann::json j = {{"MagneticFieldStrength", scene.mri.field_strength_T},
                      {"PulseSequenceType", sequence_type(s.kind).name},
                      {"RepetitionTime", s.TR_ms / 1000.0},
                      {"EchoTime", s.TE_ms / 1000.0},
                      {"NoiseSigma", image.noise_sigma},
                      {"NoisePercent", scene.mri.acquisition.noise_percent},
                      {"NoiseReferenceTissue", scene.mri.acquisition.noise_reference_tissue},
                      {"BiasPercent", scene.mri.acquisition.bias_percent},
                      {"ReceiveCoils", images.coils},
                      {"CoilCombinationMethod", images.coils > 1 ? "sum of squares" : "single uniform coil"},
                      {"Units", "scanner units: proton density (CSF = 1) times ReceiverGain"},
                      {"ReceiverGain", image.receiver_gain},
                      {"ReceiverGainRule", receiver_gain_rule(scene.mri.acquisition)},
                      {"ImageDatatype", to_string(scene.mri.acquisition.image_datatype)},
                      {"GeneratedBy", "phantasm " + std::string(version)}};
  // The sequence's own fields, from its member of the registry (mri/sequences/).
  for (const auto& [key, value] : sequence_type(s.kind).sidecar(s))
    j[key] = sequence_value_json(value);
  if (images.kspace) {
    const KspaceSampling& k = *images.kspace;
    j["AcquisitionMatrix"] = {k.acquired.x(), k.acquired.y(), k.acquired.z()};
    j["ReconstructionMatrix"] = {k.dims.x(), k.dims.y(), k.dims.z()};
    j["KspaceTruncation"] = "central samples kept, no filter (Gibbs ringing); zero-filled reconstruction";
    if (k.slice_thickness_voxels > 0.0) j["SliceThickness"] = scene.mri.acquisition.slice_thickness_mm;
  } else {
    j["KspaceTruncation"] = "none (images sampled directly on the grid)";
  }
  return j;
}

/// The four ground-truth parameter maps of one state, each with its sidecar.
/// @param texture the state's texture (null: none), recorded in the T1 and PD maps' sidecars
void plan_parameter_maps(const ImageGrid& grid, const ParameterMaps& maps, PhantomState state,
                         const DatasetLayout& layout, DatasetPlan& plan, const TextureMaps* texture) {
  struct Map {
    const char* suffix;
    const std::vector<float>* values;
    const char* units;
    const char* description;
    float scale; ///< from the values in memory to the units of the file
  };
  // BIDS quantitative maps hold relaxation times in seconds; the signal model works in ms.
  const Map list[] = {
      {"PDmap", &maps.PD, "arbitrary (water = 1)",
       "proton density: fraction-weighted sum over the voxel's tissues", 1.0f},
      {"T1map", &maps.T1_ms, "s", "T1: fraction-weighted mean over the voxel's tissues that have one", 1e-3f},
      {"T2map", &maps.T2_ms, "s", "T2: fraction-weighted mean over the voxel's tissues that have one", 1e-3f},
      {"T2starmap", &maps.T2star_ms, "s",
       "T2*: fraction-weighted mean over the voxel's tissues that have one", 1e-3f}};
  for (const Map& map : list) {
    const std::filesystem::path path = layout.parameter_map(state, map.suffix);
    plan.file(
        path,
        [&grid, map](const std::filesystem::path& p) {
          std::vector<float> values(*map.values);
          for (float& value : values)
            value *= map.scale;
          write_nifti(p, grid, values, {NiftiIntent::none, 1, std::string("phantasm ") + map.suffix});
        },
        source_in(state, FileSource::reference_images));
    const bool textured = texture && (map.values == &maps.T1_ms || map.values == &maps.PD);
    plan.json(sidecar_path(path), [map, textured, texture] {
      nlohmann::json j{{"Units", map.units},
                       {"Description", map.description},
                       {"GeneratedBy", "phantasm " + std::string(version)}};
      j["Texture"] = textured ? texture->description : "none";
      return j;
    });
  }
}

/// Parameter maps, then every image with its sidecar (and preview when asked for).
void plan_images(const ImageGrid& grid, const Scene& scene, const MrImages& images, const VoxelizedPhantom& v,
                 const DatasetLayout& layout, DatasetPlan& plan) {
  if (images.reference_maps)
    plan_parameter_maps(grid, *images.reference_maps, PhantomState::reference, layout, plan,
                        v.reference_texture ? &*v.reference_texture : nullptr);
  if (images.deformed_maps)
    plan_parameter_maps(grid, *images.deformed_maps, PhantomState::deformed, layout, plan,
                        v.deformed_texture ? &*v.deformed_texture : nullptr);
  for (PhantomState state : {PhantomState::reference, PhantomState::deformed}) {
    for (const MrImage& image : state == PhantomState::reference ? images.reference : images.deformed) {
      const std::filesystem::path path = layout.anat_image(state, image.sequence->name);
      plan.file(
          path,
          [&grid, &image, datatype = scene.mri.acquisition.image_datatype](const std::filesystem::path& p) {
            const NiftiWriteOptions options{NiftiIntent::none, 1, "phantasm " + image.sequence->name};
            if (datatype == ImageDatatype::float32)
              write_nifti(p, grid, image.magnitude, options);
            else
              write_nifti_whole_numbers(p, grid, image.magnitude, datatype == ImageDatatype::int16, options);
          },
          source_in(state, FileSource::reference_images));
      plan.json(sidecar_path(path),
                [&scene, &images, &image] { return image_sidecar(scene, images, image); });
      if (scene.outputs.previews) {
        plan.file(
            layout.preview(state, image.sequence->name),
            [&grid, &image](const std::filesystem::path& p) { write_preview_png(p, grid, image.magnitude); },
            source_in(state, FileSource::reference_images));
      }
    }
  }
}

/// The sidecar of transform(from, to): the field that brings a `from` image onto the `to` grid.
nlohmann::json field_sidecar(PhantomState from, PhantomState to, const std::string& mask,
                             const std::string& jacobian) {
  const std::string f = session_label(from), t = session_label(to);
  return {{"Description", "Displacement field that brings an image of the " + f + " state into the " + t +
                              " state's space (BIDS from-" + f + "_to-" + t + "): it lives on the " + t +
                              " grid, and a point x of the " + t + " state is at x + u(x) in the " + f +
                              " state. ITK, ANTs (antsApplyTransforms -r ses-" + t +
                              " image) and transformix resample a ses-" + f + " image onto the " + t +
                              " grid with it."},
          {"Convention",
           "ITK displacement field: 5-D NIfTI (X, Y, Z, 1, 3), intent 1007 (vector), components in "
           "world LPS millimetres (RAS with x and y negated), x_moving = x_fixed + u(x_fixed)"},
          {"Units", "mm"},
          {"FromSession", "ses-" + f},
          {"ToSession", "ses-" + t},
          {"FixedImageSession", "ses-" + t},
          {"MovingImageSession", "ses-" + f},
          {"ExactMask", mask},
          {"ExactMaskDescription",
           "1 where u is the solved motion (inside the simulated tets, or tissue that does not "
           "move), 0 where it is the smooth extension outside them"},
          {"Jacobian", jacobian}};
}

/// Both displacement fields with their exactness masks and sidecars, and their Jacobians.
void plan_fields(const Scene& scene, const VoxelizedPhantom& v, const DatasetLayout& layout,
                 DatasetPlan& plan) {
  // transform(from, to) lives on `to`'s grid: the reference grid's field carries reference
  // points into the deformed state (ref_to_def), and brings deformed images onto it.
  const auto on_reference_grid = [](PhantomState to) { return to == PhantomState::reference; };
  const std::pair<PhantomState, PhantomState> directions[] = {
      {PhantomState::deformed, PhantomState::reference}, {PhantomState::reference, PhantomState::deformed}};
  if (scene.outputs.displacement_fields) {
    for (const auto& [from, to] : directions) {
      const bool ref_grid = on_reference_grid(to);
      const std::filesystem::path field = layout.transform(from, to);
      plan.file(field, [&v, ref_grid](const std::filesystem::path& p) {
        // The ITK/elastix convention (README.md, Output): 5-D, components in LPS mm.
        write_nifti(p, v.grid,
                    lps_from_ras_components(ref_grid ? v.motion->ref_to_def : v.motion->def_to_ref),
                    {NiftiIntent::displacement, 3, "phantasm displacement, LPS mm"});
      });
      const std::filesystem::path mask = layout.transform_mask(from, to);
      plan.file(mask, [&v, ref_grid](const std::filesystem::path& p) {
        const auto& exact = ref_grid ? v.motion->ref_to_def_exact : v.motion->def_to_ref_exact;
        write_nifti_labels(p, v.grid, std::vector<std::int32_t>(exact.begin(), exact.end()),
                           {NiftiIntent::none, 1, "1 where the field is exact"});
      });
      plan.json(sidecar_path(field),
                [from = from, to = to, name = mask.filename().string(),
                 jacobian = scene.outputs.jacobian
                                ? layout.jacobian(from, to).filename().string()
                                : std::string()] { return field_sidecar(from, to, name, jacobian); });
      plan.json(sidecar_path(mask), [&v, ref_grid, field = field.filename().string()] {
        // The values' hash lets phantasm eval refuse a mask changed after the run.
        const auto& exact = ref_grid ? v.motion->ref_to_def_exact : v.motion->def_to_ref_exact;
        std::string inside(exact.size(), '\0');
        for (std::size_t i = 0; i < exact.size(); ++i)
          inside[i] = exact[i] != 0 ? 1 : 0;
        return nlohmann::json{{"Description", "1 where the field " + field +
                                                  " is the solved motion, 0 where it is the smooth "
                                                  "extension outside the simulated bodies"},
                              {"Units", "n/a (0 or 1)"},
                              {"ValuesSha256", sha256_hex(inside)},
                              {"ValuesSha256Description",
                               "SHA-256 of the mask's values, one byte per voxel (1 inside), i fastest"}};
      });
    }
  }
  if (scene.outputs.jacobian) {
    for (const auto& [from, to] : directions) {
      const bool ref_grid = on_reference_grid(to);
      const std::filesystem::path path = layout.jacobian(from, to);
      plan.file(path, [&v, ref_grid](const std::filesystem::path& p) {
        write_nifti(p, v.grid, ref_grid ? v.motion->jacobian : v.motion->def_to_ref_jacobian,
                    {NiftiIntent::none, 1, "det(I + grad u) of the field"});
      });
      plan.json(sidecar_path(path), [field = layout.transform(from, to).filename().string(), t = to] {
        return nlohmann::json{
            {"Description", "det(I + grad u) of the displacement field " + field +
                                " (central differences, on the ses-" + session_label(t) +
                                " grid): the local volume ratio of the other state to this one"},
            {"Units", "n/a (ratio of volumes)"}};
      });
    }
  }
}

/// One state's landmarks and, when the scene asks for them, its dense landmarks: CSV files with sidecars.
void plan_landmarks(const VoxelizedPhantom& v, const DatasetLayout& layout, PhantomState state,
                    DatasetPlan& plan) {
  const bool deformed = state == PhantomState::deformed;
  const auto sidecar = [](const char* description) {
    return [description] {
      return nlohmann::json{{"Description", description},
                            {"Columns", {"name", "organ", "x_mm", "y_mm", "z_mm"}},
                            {"Units", "mm, world RAS (the images' affine frame)"}};
    };
  };
  plan.text(layout.landmarks(state), [&v, deformed] { return landmarks_csv(v.landmarks, deformed); });
  plan.json(sidecar_path(layout.landmarks(state)),
            sidecar("named material points of the organs, the same points in both states"));
  if (v.dense_landmarks.empty()) return;
  plan.text(layout.dense_landmarks(state),
            [&v, deformed] { return landmarks_csv(v.dense_landmarks, deformed); });
  plan.json(
      sidecar_path(layout.dense_landmarks(state)),
      sidecar("seeded material points spread over each organ's own material (outputs.dense_landmarks per "
              "organ), the same points in both states, row by row"));
}

/// Labels, fractions, .vdb grids, landmarks, and the fields (plan_fields).
void plan_volumes(const Scene& scene, const VoxelizedPhantom& v, const DatasetLayout& layout,
                  DatasetPlan& plan) {
  const std::vector<std::pair<PhantomState, const TissueVolumes*>> states = {
      {PhantomState::reference, &v.reference}, {PhantomState::deformed, v.deformed ? &*v.deformed : nullptr}};
  for (const auto& [state, volumes] : states) {
    if (!volumes) continue;
    if (scene.outputs.labels) {
      plan.file(
          layout.dseg(state),
          [&v, volumes = volumes](const std::filesystem::path& p) {
            write_nifti_labels(p, v.grid, volumes->labels, {NiftiIntent::label, 1, "phantasm dseg"});
          },
          source_in(state, FileSource::reference_state));
      plan.json(sidecar_path(layout.dseg(state)), [] {
        return nlohmann::json{{"Description", "organ of the largest fraction in each voxel; the values are "
                                              "the index column of dseg.tsv (0 background)"},
                              {"Units", "n/a (label)"},
                              {"GeneratedBy", "phantasm " + std::string(version)}};
      });
    }
    if (scene.outputs.fractions) {
      for (std::size_t t = 0; t < v.tissues.size(); ++t) {
        plan.file(
            layout.probseg(state, v.tissues[t]),
            [&v, volumes = volumes, t](const std::filesystem::path& p) {
              write_nifti(p, v.grid, volumes->fraction_volume(static_cast<int>(t)),
                          {NiftiIntent::none, 1, "fraction of " + v.tissues[t]});
            },
            source_in(state, FileSource::reference_state));
        plan.json(sidecar_path(layout.probseg(state, v.tissues[t])), [&v, t] {
          return nlohmann::json{{"Description", "fraction of each voxel's volume taken by the tissue"},
                                {"Tissue", v.tissues[t]},
                                {"Units", "n/a (volume fraction, 0 to 1)"},
                                {"GeneratedBy", "phantasm " + std::string(version)}};
        });
      }
    }
  }
  if (scene.outputs.vdb) {
    for (const auto& [state, volumes] : states) {
      if (!volumes) continue;
      plan.file(layout.vdb(state), [&v, state = state, volumes = volumes](const std::filesystem::path& p) {
        VdbContents contents;
        for (const auto& [organ, level_set] :
             state == PhantomState::reference ? v.reference_level_sets : v.deformed_level_sets)
          contents.level_sets.emplace_back(organ, level_set->grid());
        contents.grid = &v.grid;
        contents.labels = &volumes->labels;
        for (std::size_t t = 0; t < v.tissues.size(); ++t)
          contents.fractions.emplace_back(
              v.tissues[t], [volumes = volumes, t] { return volumes->fraction_volume(static_cast<int>(t)); });
        write_vdb(p, contents);
      });
    }
  }
  if (scene.outputs.landmarks) {
    for (const auto& [state, volumes] : states)
      if (volumes) plan_landmarks(v, layout, state, plan);
  }
  if (v.motion) plan_fields(scene, v, layout, plan);
}

/// Every file of the dataset, in the order it is written; provenance.json last (its list of files
/// is `written`, filled as the files before it are written).
DatasetPlan plan_dataset(const Scene& scene, const Simulation& simulation, const DatasetLayout& layout,
                         Reporter& reporter, const RunSummary& summary) {
  const Phantom& phantom = simulation.phantom;
  const std::optional<Phantom>& deformed = simulation.deformed;
  const std::optional<PhantomDeformation>& deformation = simulation.deformation;

  DatasetPlan plan(simulation.reference_entries, layout, reporter);
  // Authors: the program that made the data (the scene file names no people).
  plan.json(layout.dataset_description(), [&scene] {
    return nlohmann::json{{"Name", scene.name},
                          {"BIDSVersion", "1.9.0"},
                          {"DatasetType", "raw"},
                          {"Authors", nlohmann::json::array({"phantasm " + std::string(version)})},
                          {"GeneratedBy", generated_by()}};
  });
  plan.text(layout.readme(), [&scene] { return dataset_readme(scene); });
  plan.json(layout.derivatives_description(), [&scene] {
    return nlohmann::json{{"Name", scene.name + " ground truth"},
                          {"BIDSVersion", "1.9.0"},
                          {"DatasetType", "derivative"},
                          {"Authors", nlohmann::json::array({"phantasm " + std::string(version)})},
                          {"GeneratedBy", generated_by()}};
  });
  plan.text(layout.derivatives_readme(), [&scene] { return derivatives_readme(scene); });
  plan.text(layout.derivatives_bidsignore(), [] { return derivatives_bidsignore(); });
  plan.text(layout.dseg_table(), [&scene] { return dseg_table(scene); });
  plan.json(sidecar_path(layout.dseg_table()), [] { return dseg_table_sidecar(); });
  plan.text(layout.scene_copy(), [&scene] { return scene.source_text; });
  if (scene.outputs.meshes) {
    reporter.modelled("anatomy", "organ meshes for ParaView: surfaces tessellated within " +
                                     format_number(mesh_export_tolerance_mm(scene)) +
                                     " mm, tet meshes as built (a simulated body's as solved, with the dseg "
                                     "label of each tet's organ)");
    const std::vector<DeformedBody>* bodies = deformation ? &deformation->bodies : nullptr;
    ReferenceSurfaceFiles surfaces;
    plan_organ_meshes(scene, phantom, PhantomState::reference, layout, plan, bodies, surfaces);
    if (deformed)
      plan_organ_meshes(scene, *deformed, PhantomState::deformed, layout, plan, bodies, surfaces, &phantom);
  } else {
    reporter.skipped("anatomy", "organ meshes (outputs.meshes is false)");
    // The solved bodies' tet meshes in both states are the exact map the fields sample, which
    // `phantasm pair` composes between subjects (evaluation/subject_pairs.hpp): written whenever
    // the fields are, as the full profile writes them.
    if (deformation && deformed && scene.outputs.displacement_fields && !deformation->bodies.empty()) {
      reporter.modelled("anatomy",
                        "the solved bodies' tet meshes all the same, in both states: the exact map "
                        "the fields sample, which phantasm pair composes between subjects");
      for (const DeformedBody& body : deformation->bodies) {
        plan.file(layout.tet_mesh(PhantomState::reference, body.organ),
                  [&phantom, &body](const std::filesystem::path& path) {
                    write_body_tet_mesh(path, phantom, body, false);
                  });
        plan.file(layout.tet_mesh(PhantomState::deformed, body.organ),
                  [&phantom, &body](const std::filesystem::path& path) {
                    write_body_tet_mesh(path, phantom, body, true);
                  });
      }
    }
  }
  plan_volumes(scene, simulation.volumes, layout, plan);
  plan_images(simulation.volumes.grid, scene, simulation.images, simulation.volumes, layout, plan);

  plan.text(layout.log(), [&reporter] {
    std::string log;
    for (const auto& line : reporter.log_lines())
      log += line + "\n";
    return log;
  });
  plan.json(layout.provenance(), [&scene, &summary, &deformation] {
    nlohmann::json stages = nlohmann::json::array();
    for (const auto& stage : summary.stages)
      stages.push_back(stage_json(stage));
    nlohmann::json files = nlohmann::json::array();
    for (const auto& file : summary.files)
      files.push_back(file.generic_string());
    return nlohmann::json{
        {"phantasm_version", version},
        {"scene", {{"file", scene.file.filename().string()}, {"sha256", scene.sha256}}},
        {"seed", scene.seed},
        {"settings", scene_settings_json(scene)},
        {"estimate", cost_json(estimate_cost(scene))},
        {"stages", stages},
        {"solves", deformation ? solves_json(deformation->solves) : nlohmann::json::array()},
        {"converged", !deformation || std::all_of(deformation->solves.begin(), deformation->solves.end(),
                                                  [](const SolveReport& s) { return s.converged; })},
        {"bodies", deformation ? bodies_json(deformation->bodies) : nlohmann::json::array()},
        {"warnings", stage_warnings(summary.stages)},
        {"files", files}};
  });
  return plan;
}

} // namespace

std::vector<std::string> stage_warnings(const std::vector<StageReport>& stages) {
  std::vector<std::string> lines;
  for (const StageReport& stage : stages)
    for (const std::string& warning : stage.warnings)
      lines.push_back("[" + stage.stage + "] " + warning);
  return lines;
}

void check_dataset_names(const Scene& scene) {
  std::map<std::string, std::string> organs, tissues;
  const auto add = [](std::map<std::string, std::string>& seen, const std::string& name, const char* kind,
                      const char* entity) {
    const std::string value = bids_entity_value(name);
    if (value.empty()) {
      throw InputError(std::string(kind) + " '" + name + "': expected a name with a letter or digit (the " +
                       entity + " entity of its files)");
    }
    const auto [at, inserted] = seen.emplace(value, name);
    if (!inserted && at->second != name) {
      throw InputError(std::string(kind) + "s '" + at->second + "' and '" + name + "' would both be " +
                       entity + "-" + value +
                       " in file names (BIDS entity values hold letters and digits only): "
                       "rename one of them");
    }
  };
  for (const auto& organ : scene.anatomy.organs) {
    add(organs, organ.name, "organ", "organ");
    add(tissues, organ.tissue, "tissue", "label");
  }
}

namespace {

/// Writes the files on as many threads as OpenMP may use (OMP_NUM_THREADS; a batch gives each
/// subject its share), each thread taking the next file in plan order. The first exception (a
/// cancellation, a full disk) stops every thread from starting another file and is rethrown
/// once all have ended; a file being written when it came is finished or, if its own writer
/// threw, left as no file at all (every writer writes a temporary and renames it).
void write_in_parallel(const std::vector<const PlannedFile*>& files, ProgressBar& progress) {
  run_tasks_in_parallel(files.size(), static_cast<std::size_t>(std::max(1, omp_get_max_threads())),
                        [&](std::size_t i) {
                          throw_if_cancelled();
                          progress.set_detail(files[i]->path.filename().string());
                          files[i]->write(files[i]->path);
                          progress.advance();
                        });
}

} // namespace

RunSummary write_dataset(const Scene& scene, const Simulation& simulation,
                         const std::filesystem::path& output, Reporter& reporter) {
  check_dataset_names(scene);
  require_finite_outputs(simulation, scene.file); // a NaN is refused before the first file
  RunSummary summary;
  summary.stages = simulation.stages;
  const DatasetLayout layout(output, scene.outputs.subject);
  const DatasetPlan plan = plan_dataset(scene, simulation, layout, reporter, summary);
  // No name from the scene may lead a file out of the dataset (io/output_path.hpp).
  for (const PlannedFile& file : plan.files())
    require_inside(layout.root(), file.path);
  // provenance.json marks a complete subject: an earlier run's marker goes before any file is
  // replaced, so a run that fails or is killed from here on leaves a subject that says it is
  // incomplete, never one that mixes two runs under an old marker.
  std::error_code removed;
  std::filesystem::remove(layout.provenance(), removed);
  if (removed) {
    throw std::runtime_error(
        layout.provenance().string() +
        ": cannot remove the completion marker of the earlier run: " + removed.message());
  }
  // Both sessions' anat folders exist even without images (the BIDS layout names them).
  for (PhantomState state : {PhantomState::reference, PhantomState::deformed})
    std::filesystem::create_directories(layout.anat_image(state, "T1w").parent_path());

  ProgressBar progress(reporter, "writing", plan.files().size());
  // The log and provenance.json (the completion marker, which lists every file before it) are
  // written last, in that order; the files before them depend on nothing written and go in
  // parallel, each on one thread (a surface mesh's tessellation, a compressed volume).
  std::vector<const PlannedFile*> independent, last;
  for (const PlannedFile& file : plan.files())
    (file.path == layout.log() || file.path == layout.provenance() ? last : independent).push_back(&file);
  write_in_parallel(independent, progress);
  for (const PlannedFile& file : plan.files()) {
    if (file.path != layout.log() && file.path != layout.provenance())
      summary.files.push_back(std::filesystem::relative(file.path, layout.root()));
  }
  for (const PlannedFile* file : last) {
    progress.set_detail(file->path.filename().string());
    file->write(file->path);
    summary.files.push_back(std::filesystem::relative(file->path, layout.root()));
    progress.advance();
    throw_if_cancelled();
  }
  return summary;
}

} // namespace phantasm
