#include "pipeline/run_pipeline.hpp"

#include "anatomy/anatomy_plan.hpp"
#include "anatomy/phantom.hpp"
#include "atlas/atlas_labels.hpp"
#include "core/abandonable_work.hpp"
#include "core/cancellation.hpp"
#include "core/error.hpp"
#include "core/sha256.hpp"
#include "io/dataset_layout.hpp"
#include "io/shape_files.hpp"
#include "mri/mri_plan.hpp"
#include "pipeline/anatomy_cache.hpp"
#include "pipeline/anatomy_checks.hpp"
#include "pipeline/atlas_labels_cache.hpp"
#include "pipeline/body_mesh_cache.hpp"
#include "pipeline/cost_estimate.hpp"
#include "pipeline/growth_atlas.hpp"
#include "pipeline/material_maps_stage.hpp"
#include "pipeline/reference_cache.hpp"
#include "pipeline/reference_images_cache.hpp"
#include "report/subject_report.hpp"
#include "sim/deform_phantom.hpp"
#include "sim/sim_plan.hpp"
#include "voxelize/voxelize_phantom.hpp"
#include "voxelize/voxelize_plan.hpp"

#include <atomic>
#include <chrono>
#include <ctime>
#include <filesystem>
#include <future>
#include <map>
#include <omp.h>
#include <string>
#include <tuple>

namespace phantasm {
namespace {

/// Prints what a stage adds to its report while it runs (its plan was printed before).
class StageLines {
public:
  explicit StageLines(const StageReport& report)
      : m_modelled(report.modelled.size()), m_skipped(report.skipped.size()),
        m_warnings(report.warnings.size()) {}
  void print_new(const StageReport& report, Reporter& reporter) const {
    for (std::size_t k = m_warnings; k < report.warnings.size(); ++k)
      reporter.warning(report.stage, report.warnings[k]);
    for (std::size_t k = m_modelled; k < report.modelled.size(); ++k)
      reporter.modelled(report.stage, report.modelled[k]);
    for (std::size_t k = m_skipped; k < report.skipped.size(); ++k)
      reporter.skipped(report.stage, report.skipped[k]);
  }

private:
  std::size_t m_modelled, m_skipped, m_warnings;
};

/// Times the stages one after another: lap() records the wall and processor time since the last.
class StageClock {
public:
  explicit StageClock(std::vector<StageTiming>& timings) : m_timings(timings) {}
  void lap(const char* stage) {
    const auto wall = std::chrono::steady_clock::now();
    const std::clock_t cpu = std::clock(); // the process's, every thread summed
    m_timings.push_back({stage, std::chrono::duration<double>(wall - m_wall).count(),
                         static_cast<double>(cpu - m_cpu) / CLOCKS_PER_SEC});
    m_wall = wall;
    m_cpu = cpu;
  }

private:
  std::vector<StageTiming>& m_timings;
  std::chrono::steady_clock::time_point m_wall = std::chrono::steady_clock::now();
  std::clock_t m_cpu = std::clock();
};

/// Derives the label volumes organs name by atlas (once per run) and records what was derived,
/// from which inputs, and the sources to cite, in the log and the provenance.
/// @param derived_volumes receives each derived volume by atlas name (null: kept nowhere)
/// @param cache the anatomy cache's folder, which keeps the derived volumes (empty: none)
AtlasLoader atlas_loader(StageReport& report, Reporter& reporter,
                         std::map<std::string, AtlasLabelVolume>* derived_volumes = nullptr,
                         const std::filesystem::path& cache = {}) {
  return [&report, &reporter, derived_volumes, cache](const std::string& atlas) {
    AtlasLabels derived = derive_atlas_labels_cached(atlas, cache, reporter);
    for (const std::string& line : derived.provenance) {
      report.modelled.push_back(line);
      reporter.modelled(report.stage, line);
    }
    AtlasLabelVolume volume;
    volume.grid = derived.head.grid;
    volume.source = derived.source;
    for (const HeadLabelInfo& info : derived.head.table)
      if (info.label != 0) volume.names[info.name] = info.label;
    volume.labels = std::make_shared<const std::vector<std::int32_t>>(std::move(derived.head.labels));
    if (derived_volumes) (*derived_volumes)[atlas] = volume;
    return volume;
  };
}

} // namespace

std::map<std::string, ShapeData> read_scene_shape_files(const Scene& scene, StageReport& report,
                                                        Reporter& reporter) {
  return read_shape_files(scene.anatomy, atlas_loader(report, reporter), scene.grid.grid());
}

namespace {

/// The anatomy stage: reads the scene's shape files and builds every organ; records fit errors.
/// @param anatomy_key receives the anatomy's cache key when there is a cache (the reference
///        cache's key starts from it)
/// @param atlases receives the atlas volumes the organs were made from (the tissue regions' labels)
Phantom build_anatomy(const Scene& scene, const std::filesystem::path& cache, StageReport& report,
                      Reporter& reporter, std::string& anatomy_key,
                      std::map<std::string, AtlasLabelVolume>& atlases) {
  const std::map<std::string, ShapeData> files =
      read_shape_files(scene.anatomy, atlas_loader(report, reporter, &atlases, cache), scene.grid.grid());
  Phantom phantom = build_phantom_cached(scene.anatomy, files, cache, report, reporter, &anatomy_key);
  for (const Organ& organ : phantom.organs) {
    if (!organ.surface) continue;
    report.accuracy[organ.name + " fit to source mean mm"] = organ.fit.source_mean_mm;
    report.accuracy[organ.name + " fit to source p95 mm"] = organ.fit.source_p95_mm;
    report.accuracy[organ.name + " fit to source max mm"] = organ.fit.source_max_mm;
    report.accuracy[organ.name + " fit relative volume error"] = organ.fit.volume_error;
  }
  report.status = "done";
  return phantom;
}

} // namespace

std::vector<StageReport> plan_stages(const Scene& scene) {
  return {plan_anatomy(scene.anatomy, scene.organs), plan_sim(scene.deformation, scene.organs),
          plan_voxelize(scene.voxelization, scene.organs, scene.grid),
          plan_mri(scene.mri, scene.organs, scene.grid)};
}

namespace {

/// Runs the stages; what they reject is named by its key path (SettingError).
void run_stages(const Scene& scene, Reporter& reporter, SimulationStage until,
                const std::filesystem::path& cache, Simulation& result) {
  StageClock clock(result.timings);
  result.stages = plan_stages(scene);
  // The cost before the work heads the log: each organ's effective settings and what the run
  // will build and need (deterministic for the scene, so the log stays the same run to run).
  for (const std::string& line : cost_lines(estimate_cost(scene)))
    reporter.modelled("estimate", line);
  for (const auto& stage : result.stages) {
    // Settings a plan finds pointless (a flip angle that excites nothing, ...) warn before work;
    // they stay in the report, so provenance.json records them and --strict refuses them.
    for (const auto& line : stage.warnings)
      reporter.warning(stage.stage, line);
    for (const auto& line : stage.modelled)
      reporter.modelled(stage.stage, line);
    for (const auto& line : stage.skipped)
      reporter.skipped(stage.stage, line);
  }
  // Growth regions are resolved before the anatomy is built: a misnamed one stops the run at once.
  const DeformationSettings deformation = with_growth_atlas(scene.deformation, result.stages[1], reporter);
  std::string anatomy_key;
  std::map<std::string, AtlasLabelVolume> atlases;
  result.phantom = build_anatomy(scene, cache, result.stages[0], reporter, anatomy_key, atlases);
  check_built_anatomy(scene, result.phantom); // organs read from files, obstacles at rest
  clock.lap("anatomy");
  if (until == SimulationStage::anatomy) return;

  // The reference state needs the anatomy alone: built (or read from the cache) on a thread of
  // its own while the deformation is solved (its body mesh and most of its solve use one core).
  // One thread, so that its parallel loops stay off the solver's second core.
  // If the deformation fails, the reference state is not wanted: its thread stops at its next
  // poll (declared in this order, the flag outlives the future, which waits for the thread after
  // the guard has set the flag).
  std::atomic<bool> reference_state_unwanted{false};
  std::future<std::pair<std::optional<ReferenceVoxelization>, bool>> reference_state;
  const StopOnFailure stop_reference_state(reference_state_unwanted);
  if (scene.deformation.mode != DeformationMode::none && until >= SimulationStage::voxelization) {
    const bool stored =
        reference_state_stored(anatomy_key, scene.voxelization, scene.organs, scene.grid.grid(), cache);
    reference_state = std::async(
        std::launch::async, [&scene, &result, &anatomy_key, &cache, stored, &reference_state_unwanted] {
          const QuietProgressDetails quiet;
          const StopThisThreadWhen unwanted(reference_state_unwanted);
          omp_set_num_threads(1);
          if (stored) // read, or left to the voxelization stage when damaged (it says so)
            return std::make_pair(read_stored_reference_state(anatomy_key, scene.voxelization, scene.organs,
                                                              scene.grid.grid(), result.phantom.organs.size(),
                                                              cache),
                                  true);
          return std::make_pair(std::optional<ReferenceVoxelization>(voxelize_reference_state(
                                    scene.voxelization, scene.organs, scene.grid.grid(), result.phantom)),
                                false);
        });
  }
  StageReport& sim = result.stages[1];
  if (scene.deformation.mode != DeformationMode::none) {
    const StageLines lines(sim);
    // The bodies' tet meshes are the anatomy's for every subject: kept beside it, meshed once.
    result.deformation = deform_phantom(deformation, scene.organs, result.phantom, sim, reporter,
                                        body_mesh_cache(anatomy_key, cache, sim, reporter));
    lines.print_new(sim, reporter);
    result.deformed = deformed_phantom(result.phantom, *result.deformation);
  }
  clock.lap("deformation");
  if (until == SimulationStage::deformation) return;

  if (!cache.empty()) {
    result.reference_entries.folder = cache;
    result.reference_entries.state_key =
        reference_cache_key(anatomy_key, scene.voxelization, scene.organs, scene.grid.grid());
  }
  StageReport& voxelize = result.stages[2];
  const StageLines voxelize_lines(voxelize);
  std::optional<ReferenceVoxelization> built;
  bool built_read = false;
  if (reference_state.valid()) std::tie(built, built_read) = reference_state.get();
  // The reference state is the same for every subject of this anatomy, grid and voxelization:
  // kept beside the anatomy, so that it is voxelized once.
  result.volumes = voxelize_phantom_cached(anatomy_key, scene.voxelization, scene.organs, scene.grid.grid(),
                                           result.phantom, result.deformed ? &*result.deformed : nullptr,
                                           result.deformation ? &*result.deformation : nullptr, cache,
                                           voxelize, reporter, built ? &*built : nullptr, built_read);
  // Tissue regions and texture, after the cached reference state (which holds neither): the
  // reference state's files then have a key of their own.
  attach_material_maps(scene, atlases, result.volumes, voxelize);
  if (const std::string text = material_maps_key_text(scene);
      !text.empty() && !result.reference_entries.state_key.empty())
    result.reference_entries.state_key = sha256_hex(result.reference_entries.state_key + "\n" + text);
  voxelize_lines.print_new(voxelize, reporter);
  clock.lap("voxelization");
  if (until == SimulationStage::voxelization) return;

  StageReport& mri = result.stages[3];
  if (scene.mri.images && !scene.mri.sequences.empty()) {
    const StageLines mri_lines(mri);
    // So are the reference state's images with the same MRI settings: kept beside it, so that
    // only the deformed state's images are synthesized per subject.
    result.images = synthesize_images_cached(result.reference_entries.state_key, scene.mri, scene.organs,
                                             result.volumes, cache, mri, reporter);
    result.reference_entries.images_key = reference_images_key(result.reference_entries.state_key, scene.mri);
    mri_lines.print_new(mri, reporter);
  }
  clock.lap("mri");
}

} // namespace

Simulation simulate(const Scene& scene, Reporter& reporter, SimulationStage until,
                    const std::filesystem::path& anatomy_cache) {
  Simulation result;
  // The stages write nothing: a run asked to stop may be abandoned anywhere in them when a
  // library call (CGAL's mesh optimisers) does not return to a poll within half a second.
  const AbandonableWork abandonable;
  try {
    run_stages(scene, reporter, until, anatomy_cache, result);
  } catch (const SettingError& error) {
    // Stages name the setting; the scene knows where it was written.
    throw InputError(
        Diagnostic{scene.location_of(error.key_path()), error.key_path(), error.message()}.format());
  }
  return result;
}

RunSummary run_scene(const Scene& scene, const RunOptions& options, Reporter& reporter) {
  std::error_code error;
  const bool existed = !options.output_created && std::filesystem::exists(options.output, error);
  prepare_output_folder(options.output, options.force);
  RunSummary summary;
  std::vector<StageTiming> timings;
  try {
    check_dataset_names(scene); // before the stages run, not after
    const Simulation simulation = simulate(scene, reporter, SimulationStage::mri, options.anatomy_cache);
    if (options.strict) {
      const std::vector<std::string> warnings = stage_warnings(simulation.stages);
      if (!warnings.empty()) {
        std::string message = "--strict: the run warned, no subject written:";
        for (const std::string& line : warnings)
          message += "\n  " + line;
        throw StrictError(message);
      }
    }
    timings = simulation.timings;
    StageClock clock(timings);
    summary = write_dataset(scene, simulation, options.output, reporter);
    clock.lap("writing");
  } catch (const InputError&) {
    // Bad input found by a stage (a label missing from its volume, ...): leave nothing behind,
    // as when the scene itself is rejected.
    if (!existed && std::filesystem::is_empty(options.output, error))
      std::filesystem::remove(options.output, error);
    throw;
  } catch (const Cancelled&) {
    throw;
  } catch (const std::exception& failure) {
    // The subject's report says why it failed (the files it would show are not all there).
    try {
      write_failed_subject_report(options.output, scene.outputs.subject, failure.what(),
                                  reporter.log_lines());
    } catch (const std::exception&) { // the failure itself is what the user must see
    }
    throw;
  }
  // Read back from the files, with the simulation's memory already returned.
  write_subject_report(options.output, scene.outputs.subject, timings);
  return summary;
}

} // namespace phantasm
