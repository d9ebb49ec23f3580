#include "pipeline/run_pipeline.hpp"

#include "anatomy/anatomy_plan.hpp"
#include "anatomy/phantom.hpp"
#include "core/cancellation.hpp"
#include "core/format.hpp"
#include "core/version.hpp"
#include "io/atomic_file.hpp"
#include "io/dataset_layout.hpp"
#include "io/json_file.hpp"
#include "io/mesh_file.hpp"
#include "io/nifti_file.hpp"
#include "io/preview_png.hpp"
#include "io/shape_files.hpp"
#include "io/vdb_file.hpp"
#include "mri/mri_plan.hpp"
#include "mri/synthesize_images.hpp"
#include "scene/scene_json.hpp"
#include "sim/deform_phantom.hpp"
#include "sim/sim_plan.hpp"
#include "voxelize/voxelize_phantom.hpp"
#include "voxelize/voxelize_plan.hpp"

#include <optional>
#include <sstream>

namespace phantasm {
namespace {

nlohmann::json stage_json(const StageReport& report) {
  return {{"stage", report.stage},
          {"status", report.status},
          {"modelled", report.modelled},
          {"skipped", report.skipped},
          {"accuracy", report.accuracy}};
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
  return text.str();
}

/// Writes files in order, with a progress bar, and remembers what was written.
class DatasetWriter {
public:
  DatasetWriter(const DatasetLayout& layout, Reporter& reporter, std::size_t expected_files)
      : m_layout(layout), m_progress(reporter, "writing", expected_files) {}

  void text(const std::filesystem::path& path, const std::string& content) {
    write_file_atomically(path, content);
    done(path);
  }
  void json(const std::filesystem::path& path, const nlohmann::json& content) {
    write_json_file(path, content);
    done(path);
  }
  /// Records a file written by one of io's format writers.
  void written(const std::filesystem::path& path) { done(path); }
  const std::vector<std::filesystem::path>& files() const { return m_files; }

private:
  void done(const std::filesystem::path& path) {
    m_files.push_back(std::filesystem::relative(path, m_layout.root()));
    m_progress.advance();
    throw_if_cancelled();
  }

  const DatasetLayout& m_layout;
  ProgressBar m_progress;
  std::vector<std::filesystem::path> m_files;
};

/// Prints what a stage adds to its report while it runs (its plan was printed before).
class StageLines {
public:
  explicit StageLines(const StageReport& report)
      : m_modelled(report.modelled.size()), m_skipped(report.skipped.size()) {}
  void print_new(const StageReport& report, Reporter& reporter) const {
    for (std::size_t k = m_modelled; k < report.modelled.size(); ++k)
      reporter.modelled(report.stage, report.modelled[k]);
    for (std::size_t k = m_skipped; k < report.skipped.size(); ++k)
      reporter.skipped(report.stage, report.skipped[k]);
  }

private:
  std::size_t m_modelled, m_skipped;
};

/// The anatomy stage: reads the scene's shape files and builds every organ; records fit errors.
Phantom build_anatomy(const Scene& scene, StageReport& report, Reporter& reporter) {
  const std::map<std::string, ShapeData> files = read_shape_files(scene);
  Phantom phantom = build_phantom(scene, files, reporter);
  for (const Organ& organ : phantom.organs) {
    if (!organ.surface) continue;
    report.accuracy[organ.name + " fit Hausdorff mm"] = organ.fit.hausdorff_mm;
    report.accuracy[organ.name + " fit mean distance mm"] = organ.fit.mean_distance_mm;
    report.accuracy[organ.name + " fit relative volume error"] = organ.fit.volume_error;
  }
  report.status = "done";
  return phantom;
}

/// Number of mesh files write_organ_meshes writes for one state.
std::size_t organ_mesh_count(const Scene& scene, const Phantom& phantom) {
  if (!scene.outputs.meshes) return 0;
  std::size_t count = 0;
  for (const Organ& organ : phantom.organs)
    count += (organ.surface || organ.sheet ? 1 : 0) + (organ.solid ? 1 : 0);
  return count;
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
void write_organ_meshes(const Scene& scene, const Phantom& phantom, PhantomState state,
                        const DatasetLayout& layout, DatasetWriter& writer,
                        const Phantom* reference = nullptr) {
  const double tolerance = mesh_export_tolerance_mm(scene);
  std::size_t index = 0;
  for (const Organ& organ : phantom.organs) {
    if (organ.surface || organ.sheet) {
      const std::filesystem::path path = layout.mesh(state, organ.name);
      write_vtp(path, organ.surface ? organ.surface->tessellate(tolerance) : *organ.sheet);
      writer.written(path);
    }
    if (organ.solid) {
      const std::filesystem::path path = layout.tet_mesh(state, organ.name);
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
      writer.written(path);
    }
    ++index;
  }
}

nlohmann::json solves_json(const std::vector<SolveReport>& solves) {
  nlohmann::json list = nlohmann::json::array();
  for (const SolveReport& s : solves) {
    nlohmann::json solve = {{"solver", s.solver},
                            {"iterations", s.iterations},
                            {"stopped_by", s.stopped_by},
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
  nlohmann::json j = {
      {"MagneticFieldStrength", scene.field_strength_T},
      {"PulseSequenceType", to_string(s.kind)},
      {"RepetitionTime", s.TR_ms / 1000.0},
      {"EchoTime", (s.kind == SequenceKind::bssfp && s.TE_ms < 0 ? 0.5 * s.TR_ms : s.TE_ms) / 1000.0},
      {"FlipAngle", s.kind == SequenceKind::spin_echo ? 90.0 : s.flip_deg},
      {"NoiseSigma", image.noise_sigma},
      {"NoisePercent", scene.acquisition.noise_percent},
      {"NoiseReferenceTissue", scene.acquisition.noise_reference_tissue},
      {"BiasPercent", scene.acquisition.bias_percent},
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
    if (k.slice_thickness_voxels > 0.0) j["SliceThickness"] = scene.acquisition.slice_thickness_mm;
  } else {
    j["KspaceTruncation"] = "none (images sampled directly on the grid)";
  }
  if (s.kind == SequenceKind::mprage) {
    j["EchoSpacing"] = s.echo_spacing_ms / 1000.0;
    j["TurboFactor"] = s.turbo_factor;
  }
  return j;
}

/// Number of image files write_images writes (image, sidecar, and a preview when asked for;
/// four parameter maps with sidecars per state).
std::size_t image_file_count(const Scene& scene, const MrImages& images) {
  return (scene.outputs.previews ? 3 : 2) * (images.reference.size() + images.deformed.size()) +
         8 * ((images.reference_maps ? 1 : 0) + (images.deformed_maps ? 1 : 0));
}

void write_parameter_maps(const ImageGrid& grid, const ParameterMaps& maps, PhantomState state,
                          const DatasetLayout& layout, DatasetWriter& writer) {
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
    write_nifti(path, grid, *map.values, {NiftiIntent::none, 1, std::string("phantasm ") + map.suffix});
    writer.written(path);
    writer.json(sidecar_path(path), {{"Units", map.units},
                                     {"Description", map.description},
                                     {"GeneratedBy", "phantasm " + std::string(version)}});
  }
}

void write_images(const ImageGrid& grid, const Scene& scene, const MrImages& images,
                  const DatasetLayout& layout, DatasetWriter& writer) {
  if (images.reference_maps)
    write_parameter_maps(grid, *images.reference_maps, PhantomState::reference, layout, writer);
  if (images.deformed_maps)
    write_parameter_maps(grid, *images.deformed_maps, PhantomState::deformed, layout, writer);
  for (PhantomState state : {PhantomState::reference, PhantomState::deformed}) {
    for (const MrImage& image : state == PhantomState::reference ? images.reference : images.deformed) {
      const std::filesystem::path path = layout.anat_image(state, image.sequence->name);
      write_nifti(path, grid, image.magnitude, {NiftiIntent::none, 1, "phantasm " + image.sequence->name});
      writer.written(path);
      writer.json(sidecar_path(path), image_sidecar(scene, images, image));
      if (scene.outputs.previews) {
        const std::filesystem::path preview = layout.preview(state, image.sequence->name);
        write_preview_png(preview, grid, image.magnitude);
        writer.written(preview);
      }
    }
  }
}

/// Number of volume files write_volumes writes.
std::size_t volume_file_count(const Scene& scene, const VoxelizedPhantom& v) {
  const std::size_t states = v.deformed ? 2 : 1;
  std::size_t count = 0;
  if (scene.outputs.labels) count += states;
  if (scene.outputs.fractions) count += states * v.tissues.size();
  if (v.motion && scene.outputs.displacement_fields) count += 2 * 3; // field, sidecar, mask per direction
  if (v.motion && scene.outputs.jacobian) count += 1;
  if (scene.outputs.landmarks) count += states;
  if (scene.outputs.vdb) count += states;
  return count;
}

/// A field in the ITK/elastix convention (DESIGN.md): 5-D, components in LPS mm.
std::vector<float> lps_components(const std::vector<float>& ras) {
  std::vector<float> lps = ras;
  const std::size_t count = ras.size() / 3;
  for (std::size_t i = 0; i < 2 * count; ++i)
    lps[i] = -lps[i];
  return lps;
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

/// Labels, fractions, both fields with sidecars and masks, the Jacobian.
void write_volumes(const Scene& scene, const VoxelizedPhantom& v, const DatasetLayout& layout,
                   DatasetWriter& writer) {
  const std::vector<std::pair<PhantomState, const TissueVolumes*>> states = {
      {PhantomState::reference, &v.reference}, {PhantomState::deformed, v.deformed ? &*v.deformed : nullptr}};
  for (const auto& [state, volumes] : states) {
    if (!volumes) continue;
    if (scene.outputs.labels) {
      write_nifti_labels(layout.dseg(state), v.grid, volumes->labels,
                         {NiftiIntent::label, 1, "phantasm dseg"});
      writer.written(layout.dseg(state));
    }
    if (scene.outputs.fractions) {
      for (std::size_t t = 0; t < v.tissues.size(); ++t) {
        write_nifti(layout.probseg(state, v.tissues[t]), v.grid, volumes->fractions[t],
                    {NiftiIntent::none, 1, "fraction of " + v.tissues[t]});
        writer.written(layout.probseg(state, v.tissues[t]));
      }
    }
  }
  if (scene.outputs.vdb) {
    for (const auto& [state, volumes] : states) {
      if (!volumes) continue;
      VdbContents contents;
      contents.level_sets =
          state == PhantomState::reference ? &v.reference_level_sets : &v.deformed_level_sets;
      contents.grid = &v.grid;
      contents.labels = &volumes->labels;
      for (std::size_t t = 0; t < v.tissues.size(); ++t)
        contents.fractions.emplace_back(v.tissues[t], &volumes->fractions[t]);
      write_vdb(layout.vdb(state), contents);
      writer.written(layout.vdb(state));
    }
  }
  if (scene.outputs.landmarks) {
    for (const auto& [state, volumes] : states) {
      if (!volumes) continue;
      writer.text(layout.landmarks(state), landmarks_csv(v.landmarks, state == PhantomState::deformed));
    }
  }
  if (!v.motion) return;
  if (scene.outputs.displacement_fields) {
    for (const auto& [from, to] : {std::pair{PhantomState::reference, PhantomState::deformed},
                                   std::pair{PhantomState::deformed, PhantomState::reference}}) {
      const bool forward = from == PhantomState::reference;
      const std::filesystem::path field = layout.transform(from, to);
      write_nifti(field, v.grid, lps_components(forward ? v.motion->ref_to_def : v.motion->def_to_ref),
                  {NiftiIntent::displacement, 3, "phantasm displacement, LPS mm"});
      writer.written(field);
      const std::filesystem::path mask = layout.transform_mask(from, to);
      const auto& exact = forward ? v.motion->ref_to_def_exact : v.motion->def_to_ref_exact;
      write_nifti_labels(mask, v.grid, std::vector<std::int32_t>(exact.begin(), exact.end()),
                         {NiftiIntent::none, 1, "1 where the field is exact"});
      writer.written(mask);
      writer.json(sidecar_path(field), field_sidecar(from, to, mask.filename().string()));
    }
  }
  if (scene.outputs.jacobian) {
    write_nifti(layout.jacobian(), v.grid, v.motion->jacobian,
                {NiftiIntent::none, 1, "det(I + grad u), ref to def"});
    writer.written(layout.jacobian());
  }
}

} // namespace

std::vector<StageReport> plan_stages(const Scene& scene) {
  return {plan_anatomy(scene), plan_sim(scene), plan_voxelize(scene), plan_mri(scene)};
}

Simulation simulate(const Scene& scene, Reporter& reporter, SimulationStage until) {
  Simulation result;
  result.stages = plan_stages(scene);
  for (const auto& stage : result.stages) {
    for (const auto& line : stage.modelled)
      reporter.modelled(stage.stage, line);
    for (const auto& line : stage.skipped)
      reporter.skipped(stage.stage, line);
  }
  result.phantom = build_anatomy(scene, result.stages[0], reporter);
  if (until == SimulationStage::anatomy) return result;

  StageReport& sim = result.stages[1];
  if (scene.deformation.mode != DeformationMode::none) {
    const StageLines lines(sim);
    result.deformation = deform_phantom(scene, result.phantom, sim, reporter);
    lines.print_new(sim, reporter);
    result.deformed = deformed_phantom(result.phantom, *result.deformation);
  }
  if (until == SimulationStage::deformation) return result;

  StageReport& voxelize = result.stages[2];
  const StageLines voxelize_lines(voxelize);
  result.volumes = voxelize_phantom(scene, result.phantom, result.deformed ? &*result.deformed : nullptr,
                                    result.deformation ? &*result.deformation : nullptr, voxelize, reporter);
  voxelize_lines.print_new(voxelize, reporter);
  if (until == SimulationStage::voxelization) return result;

  StageReport& mri = result.stages[3];
  if (scene.outputs.images && !scene.sequences.empty()) {
    const StageLines mri_lines(mri);
    result.images = synthesize_images(scene, result.volumes, mri, reporter);
    mri_lines.print_new(mri, reporter);
  }
  return result;
}

RunSummary run_scene(const Scene& scene, const RunOptions& options, Reporter& reporter) {
  prepare_output_folder(options.output, options.force);
  const Simulation simulation = simulate(scene, reporter);
  return write_dataset(scene, simulation, options.output, reporter);
}

RunSummary write_dataset(const Scene& scene, const Simulation& simulation,
                         const std::filesystem::path& output, Reporter& reporter) {
  RunSummary summary;
  summary.stages = simulation.stages;
  const Phantom& phantom = simulation.phantom;
  const std::optional<Phantom>& deformed = simulation.deformed;
  const std::optional<PhantomDeformation>& deformation = simulation.deformation;
  const VoxelizedPhantom& volumes = simulation.volumes;
  const MrImages& images = simulation.images;

  const DatasetLayout layout(output, scene.outputs.subject);
  DatasetWriter writer(layout, reporter,
                       6 + organ_mesh_count(scene, phantom) * (deformed ? 2 : 1) +
                           volume_file_count(scene, volumes) + image_file_count(scene, images));
  writer.json(layout.dataset_description(), {{"Name", scene.name},
                                             {"BIDSVersion", "1.9.0"},
                                             {"DatasetType", "raw"},
                                             {"GeneratedBy", generated_by()}});
  writer.json(layout.derivatives_description(), {{"Name", scene.name + " ground truth"},
                                                 {"BIDSVersion", "1.9.0"},
                                                 {"DatasetType", "derivative"},
                                                 {"GeneratedBy", generated_by()}});
  writer.text(layout.dseg_table(), dseg_table(scene));
  writer.text(layout.scene_copy(), scene.source_text);
  for (PhantomState state : {PhantomState::reference, PhantomState::deformed}) {
    std::filesystem::create_directories(layout.anat_image(state, "T1w").parent_path());
  }
  if (scene.outputs.meshes) {
    reporter.modelled("anatomy", "organ meshes for ParaView: surfaces tessellated within " +
                                     format_number(mesh_export_tolerance_mm(scene)) +
                                     " mm, tet meshes as built");
    write_organ_meshes(scene, phantom, PhantomState::reference, layout, writer);
    if (deformed) write_organ_meshes(scene, *deformed, PhantomState::deformed, layout, writer, &phantom);
  } else {
    reporter.skipped("anatomy", "organ meshes (outputs.meshes is false)");
  }
  write_volumes(scene, volumes, layout, writer);
  write_images(volumes.grid, scene, images, layout, writer);

  std::string log;
  for (const auto& line : reporter.log_lines())
    log += line + "\n";
  writer.text(layout.log(), log);

  nlohmann::json stages = nlohmann::json::array();
  for (const auto& stage : summary.stages)
    stages.push_back(stage_json(stage));
  nlohmann::json files = nlohmann::json::array();
  for (const auto& file : writer.files())
    files.push_back(file.generic_string());
  writer.json(layout.provenance(),
              {{"phantasm_version", version},
               {"scene", {{"file", scene.file.filename().string()}, {"sha256", scene.sha256}}},
               {"seed", scene.seed},
               {"settings", scene_settings_json(scene)},
               {"stages", stages},
               {"solves", deformation ? solves_json(deformation->solves) : nlohmann::json::array()},
               {"files", files}});
  summary.files = writer.files();
  return summary;
}

} // namespace phantasm
