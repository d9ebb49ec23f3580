#include "pipeline/dataset_writer.hpp"

#include "core/cancellation.hpp"
#include "core/format.hpp"
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
#include "scene/scene_json.hpp"
#include "voxelize/landmarks.hpp"
#include "voxelize/level_set.hpp"
#include "voxelize/voxelized_phantom.hpp"

#include <algorithm>
#include <functional>
#include <sstream>
#include <utility>

namespace phantasm {
namespace {

/// One file of the dataset: where it goes, and what makes its bytes there (run when the file's
/// turn comes, so that what it reads, e.g. the log so far, is complete by then).
struct PlannedFile {
  std::filesystem::path path;
  std::function<void(const std::filesystem::path&)> write;
};

/// The dataset's files in the order they are written. The one list is both the progress count
/// and what is written, so the two cannot drift apart.
class DatasetPlan {
public:
  /// A file made by one of io's format writers.
  void file(std::filesystem::path path, std::function<void(const std::filesystem::path&)> write) {
    m_files.push_back({std::move(path), std::move(write)});
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
};

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

std::string dseg_table(const Scene& scene) {
  std::ostringstream text;
  text << "index\tname\ttissue\n0\tbackground\tbackground\n";
  int index = 1;
  for (const auto& organ : scene.anatomy.organs)
    text << index++ << '\t' << organ.name << '\t' << organ.tissue << '\n';
  // The space a moved organ leaves in a container that stays (deformed state only).
  if (scene.voxelization.deformed)
    text << index << '\t' << k_gap_label_name << '\t' << scene.voxelization.gap_fill << '\n';
  return text.str();
}

/// How closely exported surfaces follow the patch surfaces: a fifth of the smallest voxel edge
/// (invisible at image resolution, and a few MB per organ; the voxelizer's own tolerance,
/// voxelization.tessellation_tolerance_mm, is finer), never coarser than 0.5 mm.
double mesh_export_tolerance_mm(const Scene& scene) {
  return std::min(
      0.5, std::max(scene.voxelization.tessellation_tolerance_mm, 0.2 * scene.grid.voxel_size_mm.minCoeff()));
}

/// Each organ's surface (.vtp: the patch surface tessellated within mesh_export_tolerance_mm, or
/// the sheet) and tet mesh (.vtu) in one state. The deformed state's tet meshes carry each
/// vertex's displacement from the reference (mm).
void plan_organ_meshes(const Scene& scene, const Phantom& phantom, PhantomState state,
                       const DatasetLayout& layout, DatasetPlan& plan, const Phantom* reference = nullptr) {
  const double tolerance = mesh_export_tolerance_mm(scene);
  for (std::size_t index = 0; index < phantom.organs.size(); ++index) {
    const Organ& organ = phantom.organs[index];
    if (organ.surface || organ.sheet) {
      plan.file(layout.mesh(state, organ.name), [&organ, tolerance](const std::filesystem::path& path) {
        write_vtp(path, organ.surface ? organ.surface->tessellate(tolerance) : *organ.sheet);
      });
    }
    if (organ.solid) {
      plan.file(layout.tet_mesh(state, organ.name),
                [&organ, reference, index](const std::filesystem::path& path) {
                  std::vector<PointArray> arrays;
                  if (reference) {
                    const Eigen::MatrixX3d displacement =
                        organ.solid->vertices - reference->organs[index].solid->vertices;
                    PointArray array{"displacement_mm", 3, {}};
                    for (Eigen::Index v = 0; v < displacement.rows(); ++v)
                      for (int c = 0; c < 3; ++c)
                        array.values.push_back(displacement(v, c));
                    arrays.push_back(std::move(array));
                  }
                  write_vtu(path, *organ.solid, arrays);
                });
    }
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
    if (s.rank_updates > 0 || s.contacts > 0) {
      solve["vertices_in_contact"] = s.contacts;
      solve["contact_changes"] = s.contact_changes;
      solve["rank_updates"] = s.rank_updates;
    }
    list.push_back(std::move(solve));
  }
  return list;
}

/// BIDS sidecar of one image: timing in seconds, flip angle in degrees, field strength, and how
/// noise and bias were modelled.
nlohmann::json image_sidecar(const Scene& scene, const MrImages& images, const MrImage& image) {
  const SequenceSettings& s = *image.sequence;
  nlohmann::json j = {{"MagneticFieldStrength", scene.mri.field_strength_T},
                      {"PulseSequenceType", to_string(s.kind)},
                      {"RepetitionTime", s.TR_ms / 1000.0},
                      {"EchoTime", s.TE_ms / 1000.0},
                      {"FlipAngle", s.kind == SequenceKind::spin_echo ? 90.0 : s.flip_deg},
                      {"NoiseSigma", image.noise_sigma},
                      {"NoisePercent", scene.mri.acquisition.noise_percent},
                      {"NoiseReferenceTissue", scene.mri.acquisition.noise_reference_tissue},
                      {"BiasPercent", scene.mri.acquisition.bias_percent},
                      {"ReceiveCoils", images.coils},
                      {"CoilCombinationMethod", images.coils > 1 ? "sum of squares" : "single uniform coil"},
                      {"Units", "arbitrary (proton density 1 = 1)"},
                      {"GeneratedBy", "phantasm " + std::string(version)}};
  if (s.kind == SequenceKind::inversion_recovery || s.kind == SequenceKind::mprage)
    j["InversionTime"] = s.TI_ms / 1000.0;
  if (images.kspace) {
    const KspaceSampling& k = *images.kspace;
    j["AcquisitionMatrix"] = {k.acquired.x(), k.acquired.y(), k.acquired.z()};
    j["ReconstructionMatrix"] = {k.dims.x(), k.dims.y(), k.dims.z()};
    j["KspaceTruncation"] = "central samples kept, no filter (Gibbs ringing); zero-filled reconstruction";
    if (k.slice_thickness_voxels > 0.0) j["SliceThickness"] = scene.mri.acquisition.slice_thickness_mm;
  } else {
    j["KspaceTruncation"] = "none (images sampled directly on the grid)";
  }
  if (s.kind == SequenceKind::inversion_recovery) j["InversionRecoveryReadout"] = to_string(s.readout);
  if (s.kind == SequenceKind::mprage) {
    // The timing the signal model assumes (docs/volumes-and-images.md, MPRAGE timing).
    j["InversionRecoveryReadout"] = "gradient_echo";
    j["EchoSpacing"] = s.echo_spacing_ms / 1000.0;
    j["TurboFactor"] = s.turbo_factor;
    j["RepetitionTimePreparation"] = s.TR_ms / 1000.0;
    j["RepetitionTimeExcitation"] = s.echo_spacing_ms / 1000.0;
    j["InversionTimeMeasuredTo"] =
        "excitation of the centre echo of the train (echo TurboFactor/2, counted from 0)";
  }
  return j;
}

/// The four ground-truth parameter maps of one state, each with its sidecar.
void plan_parameter_maps(const ImageGrid& grid, const ParameterMaps& maps, PhantomState state,
                         const DatasetLayout& layout, DatasetPlan& plan) {
  struct Map {
    const char* suffix;
    const std::vector<float>* values;
    const char* units;
    const char* description;
  };
  const Map list[] = {
      {"PDmap", &maps.PD, "arbitrary (water = 1)",
       "proton density: fraction-weighted sum over the voxel's tissues"},
      {"T1map", &maps.T1_ms, "ms", "T1: fraction-weighted mean over the voxel's tissues that have one"},
      {"T2map", &maps.T2_ms, "ms", "T2: fraction-weighted mean over the voxel's tissues that have one"},
      {"T2starmap", &maps.T2star_ms, "ms",
       "T2*: fraction-weighted mean over the voxel's tissues that have one"}};
  for (const Map& map : list) {
    const std::filesystem::path path = layout.parameter_map(state, map.suffix);
    plan.file(path, [&grid, map](const std::filesystem::path& p) {
      write_nifti(p, grid, *map.values, {NiftiIntent::none, 1, std::string("phantasm ") + map.suffix});
    });
    plan.json(sidecar_path(path), [map] {
      return nlohmann::json{{"Units", map.units},
                            {"Description", map.description},
                            {"GeneratedBy", "phantasm " + std::string(version)}};
    });
  }
}

/// Parameter maps, then every image with its sidecar (and preview when asked for).
void plan_images(const ImageGrid& grid, const Scene& scene, const MrImages& images,
                 const DatasetLayout& layout, DatasetPlan& plan) {
  if (images.reference_maps)
    plan_parameter_maps(grid, *images.reference_maps, PhantomState::reference, layout, plan);
  if (images.deformed_maps)
    plan_parameter_maps(grid, *images.deformed_maps, PhantomState::deformed, layout, plan);
  for (PhantomState state : {PhantomState::reference, PhantomState::deformed}) {
    for (const MrImage& image : state == PhantomState::reference ? images.reference : images.deformed) {
      const std::filesystem::path path = layout.anat_image(state, image.sequence->name);
      plan.file(path, [&grid, &image](const std::filesystem::path& p) {
        write_nifti(p, grid, image.magnitude, {NiftiIntent::none, 1, "phantasm " + image.sequence->name});
      });
      plan.json(sidecar_path(path),
                [&scene, &images, &image] { return image_sidecar(scene, images, image); });
      if (scene.outputs.previews) {
        plan.file(
            layout.preview(state, image.sequence->name),
            [&grid, &image](const std::filesystem::path& p) { write_preview_png(p, grid, image.magnitude); });
      }
    }
  }
}

nlohmann::json field_sidecar(PhantomState from, PhantomState to, const std::string& mask) {
  const std::string f = session_label(from), t = session_label(to);
  return {{"Description", "Displacement field from the " + f + " state to the " + t +
                              " state: a point x of the " + f + " grid is at x + u(x) in the " + t +
                              " state. With fixed image = ses-" + f + " and moving image = ses-" + t +
                              ", elastix/transformix and ITK resample the " + t + " image onto the " + f +
                              " grid with it."},
          {"Convention",
           "ITK displacement field: 5-D NIfTI (X, Y, Z, 1, 3), intent 1007 (vector), components in "
           "world LPS millimetres (RAS with x and y negated), x_moving = x_fixed + u(x_fixed)"},
          {"FixedImageSession", "ses-" + f},
          {"MovingImageSession", "ses-" + t},
          {"ExactMask", mask},
          {"ExactMaskDescription",
           "1 where u is the solved motion (inside the simulated tets, or tissue that does not "
           "move), 0 where it is the smooth extension outside them"}};
}

/// Labels, fractions, .vdb grids, landmarks, both fields with masks and sidecars, the Jacobian.
void plan_volumes(const Scene& scene, const VoxelizedPhantom& v, const DatasetLayout& layout,
                  DatasetPlan& plan) {
  const std::vector<std::pair<PhantomState, const TissueVolumes*>> states = {
      {PhantomState::reference, &v.reference}, {PhantomState::deformed, v.deformed ? &*v.deformed : nullptr}};
  for (const auto& [state, volumes] : states) {
    if (!volumes) continue;
    if (scene.outputs.labels) {
      plan.file(layout.dseg(state), [&v, volumes = volumes](const std::filesystem::path& p) {
        write_nifti_labels(p, v.grid, volumes->labels, {NiftiIntent::label, 1, "phantasm dseg"});
      });
    }
    if (scene.outputs.fractions) {
      for (std::size_t t = 0; t < v.tissues.size(); ++t) {
        plan.file(layout.probseg(state, v.tissues[t]),
                  [&v, volumes = volumes, t](const std::filesystem::path& p) {
                    write_nifti(p, v.grid, volumes->fractions[t],
                                {NiftiIntent::none, 1, "fraction of " + v.tissues[t]});
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
          contents.fractions.emplace_back(v.tissues[t], &volumes->fractions[t]);
        write_vdb(p, contents);
      });
    }
  }
  if (scene.outputs.landmarks) {
    for (const auto& [state, volumes] : states) {
      if (!volumes) continue;
      plan.text(layout.landmarks(state),
                [&v, state = state] { return landmarks_csv(v.landmarks, state == PhantomState::deformed); });
    }
  }
  if (!v.motion) return;
  if (scene.outputs.displacement_fields) {
    for (const auto& [from, to] : {std::pair{PhantomState::reference, PhantomState::deformed},
                                   std::pair{PhantomState::deformed, PhantomState::reference}}) {
      const bool forward = from == PhantomState::reference;
      const std::filesystem::path field = layout.transform(from, to);
      plan.file(field, [&v, forward](const std::filesystem::path& p) {
        // The ITK/elastix convention (README.md, Output): 5-D, components in LPS mm.
        write_nifti(p, v.grid, lps_from_ras_components(forward ? v.motion->ref_to_def : v.motion->def_to_ref),
                    {NiftiIntent::displacement, 3, "phantasm displacement, LPS mm"});
      });
      const std::filesystem::path mask = layout.transform_mask(from, to);
      plan.file(mask, [&v, forward](const std::filesystem::path& p) {
        const auto& exact = forward ? v.motion->ref_to_def_exact : v.motion->def_to_ref_exact;
        write_nifti_labels(p, v.grid, std::vector<std::int32_t>(exact.begin(), exact.end()),
                           {NiftiIntent::none, 1, "1 where the field is exact"});
      });
      plan.json(sidecar_path(field), [from = from, to = to, name = mask.filename().string()] {
        return field_sidecar(from, to, name);
      });
    }
  }
  if (scene.outputs.jacobian) {
    plan.file(layout.jacobian(), [&v](const std::filesystem::path& p) {
      write_nifti(p, v.grid, v.motion->jacobian, {NiftiIntent::none, 1, "det(I + grad u), ref to def"});
    });
  }
}

/// Every file of the dataset, in the order it is written; provenance.json last (its list of files
/// is `written`, filled as the files before it are written).
DatasetPlan plan_dataset(const Scene& scene, const Simulation& simulation, const DatasetLayout& layout,
                         Reporter& reporter, const RunSummary& summary) {
  const Phantom& phantom = simulation.phantom;
  const std::optional<Phantom>& deformed = simulation.deformed;
  const std::optional<PhantomDeformation>& deformation = simulation.deformation;

  DatasetPlan plan;
  plan.json(layout.dataset_description(), [&scene] {
    return nlohmann::json{{"Name", scene.name},
                          {"BIDSVersion", "1.9.0"},
                          {"DatasetType", "raw"},
                          {"GeneratedBy", generated_by()}};
  });
  plan.json(layout.derivatives_description(), [&scene] {
    return nlohmann::json{{"Name", scene.name + " ground truth"},
                          {"BIDSVersion", "1.9.0"},
                          {"DatasetType", "derivative"},
                          {"GeneratedBy", generated_by()}};
  });
  plan.text(layout.dseg_table(), [&scene] { return dseg_table(scene); });
  plan.text(layout.scene_copy(), [&scene] { return scene.source_text; });
  if (scene.outputs.meshes) {
    reporter.modelled("anatomy", "organ meshes for ParaView: surfaces tessellated within " +
                                     format_number(mesh_export_tolerance_mm(scene)) +
                                     " mm, tet meshes as built");
    plan_organ_meshes(scene, phantom, PhantomState::reference, layout, plan);
    if (deformed) plan_organ_meshes(scene, *deformed, PhantomState::deformed, layout, plan, &phantom);
  } else {
    reporter.skipped("anatomy", "organ meshes (outputs.meshes is false)");
  }
  plan_volumes(scene, simulation.volumes, layout, plan);
  plan_images(simulation.volumes.grid, scene, simulation.images, layout, plan);

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

RunSummary write_dataset(const Scene& scene, const Simulation& simulation,
                         const std::filesystem::path& output, Reporter& reporter) {
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
  for (const PlannedFile& file : plan.files()) {
    progress.set_detail(file.path.filename().string());
    file.write(file.path);
    summary.files.push_back(std::filesystem::relative(file.path, layout.root()));
    progress.advance();
    throw_if_cancelled();
  }
  return summary;
}

} // namespace phantasm
