#include "voxelize/voxelize_phantom.hpp"

#include "core/cancellation.hpp"
#include "core/format.hpp"
#include "geometry/triangle_mesh.hpp"
#include "voxelize/dense_landmarks.hpp"
#include "voxelize/fold_warning.hpp"
#include "voxelize/gap_fill.hpp"
#include "voxelize/landmarks.hpp"
#include "voxelize/level_set.hpp"
#include "voxelize/motion_fields.hpp"
#include "voxelize/tissue_volumes.hpp"
#include "voxelize/voxelize_plan.hpp"

#include <algorithm>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>

namespace phantasm {
namespace {

/// Level sets of every organ of one state that the grid needs, and the organs as the voxelizer
/// sees them. Shared: an organ that did not move has one level set for both states.
struct StateLevelSets {
  std::vector<std::shared_ptr<const LevelSet>> level_sets;
  std::vector<VoxelizedOrgan> organs;
};

/// Whether an organ's surface is the same in both states: the same base positions (its patches'
/// bumps are the reference's in both), so the same level set.
bool same_surface(const Organ& reference, const Organ& deformed) {
  return reference.surface && deformed.surface &&
         reference.surface->base_mesh().vertices.rows() == deformed.surface->base_mesh().vertices.rows() &&
         reference.surface->base_mesh().vertices == deformed.surface->base_mesh().vertices;
}

/// @param unmoved_from the reference phantom and its level sets, for the deformed state: the
///        organs whose surface did not move take the reference's level set (null: build all)
/// The organs that get a level set: those with a closed surface in the field of view.
std::vector<std::size_t> organs_to_voxelize(const VoxelizationSettings& settings, const ImageGrid& grid,
                                            const Phantom& phantom) {
  std::vector<std::size_t> chosen;
  for (std::size_t o = 0; o < phantom.organs.size(); ++o) {
    const auto bounds =
        o < settings.organ_bounds_mm.size() ? settings.organ_bounds_mm[o] : std::optional<WorldBox>();
    if (phantom.organs[o].surface && organ_in_field_of_view(bounds, grid)) chosen.push_back(o);
  }
  return chosen;
}

/// The level sets of the chosen organs (by phantom index), with the organs as the voxelizer sees them.
StateLevelSets state_level_sets(const OrganTable& organs, const Phantom& phantom,
                                const std::vector<std::string>& tissues,
                                const std::vector<std::size_t>& chosen,
                                const std::vector<std::shared_ptr<const LevelSet>>& built) {
  StateLevelSets out;
  out.level_sets.reserve(chosen.size());
  for (std::size_t k = 0; k < chosen.size(); ++k) {
    const std::size_t o = chosen[k];
    out.level_sets.push_back(built[k]);
    VoxelizedOrgan v;
    v.level_set = out.level_sets.back().get();
    // Even depths for organs, so that a gap (odd, voxelize/gap_fill.hpp) sits between its
    // container and the organs the container holds.
    v.depth = 2 * organs[o].depth;
    v.label = static_cast<int>(o) + 1;
    v.tissue = static_cast<int>(std::find(tissues.begin(), tissues.end(), phantom.organs[o].tissue) -
                                tissues.begin());
    out.organs.push_back(v);
  }
  return out;
}

StateLevelSets level_sets_of(const VoxelizationSettings& settings, const OrganTable& organs,
                             const ImageGrid& grid, const Phantom& phantom,
                             const std::vector<std::string>& tissues, double voxel_size,
                             OrganHeightRanges& height_ranges, ProgressBar& progress,
                             const std::pair<const Phantom*, const StateLevelSets*>& unmoved_from = {}) {
  const std::vector<std::size_t> chosen = organs_to_voxelize(settings, grid, phantom);
  // Level sets in parallel over organs (each is independent and deterministic). From the patch
  // surfaces directly, or (settings.level_sets_from_tessellation, the former path kept for
  // benchmarks) from tessellations within the tolerance through OpenVDB's mesh-to-volume.
  std::vector<std::shared_ptr<const LevelSet>> built(chosen.size());
  if (const auto [reference, reference_sets] = unmoved_from; reference && reference_sets) {
    for (std::size_t k = 0; k < chosen.size(); ++k) {
      const std::size_t o = chosen[k];
      for (std::size_t r = 0; r < reference_sets->organs.size(); ++r)
        if (static_cast<std::size_t>(reference_sets->organs[r].label - 1) == o &&
            same_surface(reference->organs[o], phantom.organs[o]))
          built[k] = reference_sets->level_sets[r];
    }
  }
  const auto count = static_cast<std::ptrdiff_t>(chosen.size());
  if (settings.level_sets_from_tessellation) {
    std::vector<TriangleMesh> meshes(chosen.size());
#pragma omp parallel for schedule(dynamic, 1)
    for (std::ptrdiff_t k = 0; k < count; ++k) {
      if (cancellation_requested() || built[static_cast<std::size_t>(k)])
        continue; // no exception may leave an OpenMP region
      meshes[static_cast<std::size_t>(k)] =
          phantom.organs[chosen[static_cast<std::size_t>(k)]].surface->tessellate(
              settings.tessellation_tolerance_mm);
    }
    for (std::size_t k = 0; k < chosen.size(); ++k) {
      throw_if_cancelled();
      if (!built[k]) built[k] = std::make_shared<const LevelSet>(meshes[k], voxel_size);
      meshes[k] = TriangleMesh();
      progress.advance();
    }
  } else {
    // Largest base surface first: a level set's work follows its surface area (the band's
    // voxels), and the last organ to start sets when the loop ends. In organ order, the Colin
    // head's largest surface came last and one core idled while it was built.
    std::vector<std::size_t> order(chosen.size());
    std::vector<double> area(chosen.size());
    for (std::size_t k = 0; k < chosen.size(); ++k) {
      order[k] = k;
      area[k] = surface_area(phantom.organs[chosen[k]].surface->base_mesh());
    }
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return area[a] > area[b]; });
#pragma omp parallel for schedule(dynamic, 1)
    for (std::ptrdiff_t k = 0; k < count; ++k) {
      if (cancellation_requested()) continue; // no exception may leave an OpenMP region
      const std::size_t i = order[static_cast<std::size_t>(k)];
      if (!built[i]) {
        const PatchSurface& surface = *phantom.organs[chosen[i]].surface;
        std::optional<std::vector<HeightRange>>& ranges = height_ranges[chosen[i]]; // this iteration's alone
        // Held by a built or stored anatomy; computed here otherwise.
        if (!ranges)
          ranges = surface.height_ranges() ? *surface.height_ranges() : patch_height_ranges(surface);
        built[i] = std::make_shared<const LevelSet>(surface, voxel_size, 3.0, &*ranges);
      }
      progress.advance();
    }
  }
  // A level set cut short by cancellation is incomplete: stop before anything reads it.
  throw_if_cancelled();
  progress.advance(phantom.organs.size() - chosen.size());
  return state_level_sets(organs, phantom, tissues, chosen, built);
}

/// The reference state's level sets and volumes as given (a run with the same inputs built them).
StateLevelSets given_reference(const VoxelizationSettings& settings, const OrganTable& organs,
                               const ImageGrid& grid, const Phantom& reference,
                               const std::vector<std::string>& tissues, ReferenceVoxelization& given,
                               OrganHeightRanges& height_ranges, TissueVolumes& volumes) {
  const std::vector<std::size_t> chosen = organs_to_voxelize(settings, grid, reference);
  if (given.organs.size() != chosen.size() || given.level_sets.size() != chosen.size() ||
      !std::equal(chosen.begin(), chosen.end(), given.organs.begin(),
                  [](std::size_t o, int g) { return static_cast<int>(o) == g; }) ||
      given.height_ranges.size() != reference.organs.size() ||
      given.volumes.labels.size() != static_cast<std::size_t>(grid.voxel_count()))
    throw std::logic_error("voxelize_phantom: a reference state of other organs or another grid");
  height_ranges = std::move(given.height_ranges);
  volumes = std::move(given.volumes);
  return state_level_sets(organs, reference, tissues, chosen, given.level_sets);
}

void keep_level_sets(const Phantom& phantom, const StateLevelSets& sets,
                     std::vector<std::pair<std::string, std::shared_ptr<const LevelSet>>>& kept) {
  for (std::size_t k = 0; k < sets.organs.size(); ++k) {
    const auto organ = static_cast<std::size_t>(sets.organs[k].label - 1);
    kept.emplace_back(phantom.organs[organ].name, sets.level_sets[k]);
  }
}

/// The reference state's level sets (given by `reference_state`, or built, and then kept there
/// when it asks) and tissue volumes, reported.
StateLevelSets voxelize_reference(const VoxelizationSettings& settings, const OrganTable& organs,
                                  const ImageGrid& grid, const Phantom& reference,
                                  std::optional<ReferenceVoxelization>* reference_state,
                                  OrganHeightRanges& height_ranges, VoxelizedPhantom& out,
                                  StageReport& report, ProgressBar& progress) {
  const double voxel_size = out.grid.spacing_mm.minCoeff();
  const bool given = reference_state && reference_state->has_value();
  StateLevelSets sets;
  if (given) {
    sets = given_reference(settings, organs, grid, reference, out.tissues, **reference_state, height_ranges,
                           out.reference);
    reference_state->reset();
    progress.advance(reference.organs.size());
  } else {
    sets = level_sets_of(settings, organs, grid, reference, out.tissues, voxel_size, height_ranges, progress);
  }
  if (reference_state && !given) {
    ReferenceVoxelization& built = reference_state->emplace();
    for (const VoxelizedOrgan& organ : sets.organs)
      built.organs.push_back(organ.label - 1);
    built.level_sets = sets.level_sets;
    built.height_ranges = height_ranges; // before the deformed state adds any
  }
  std::size_t band = 0;
  for (const auto& l : sets.level_sets)
    band += l->active_voxel_count();
  report.modelled.push_back(
      "reference: " + std::to_string(sets.level_sets.size()) + " level sets, " + std::to_string(band) +
      " narrow-band voxels of " + format_number(voxel_size) + " mm, " +
      (settings.level_sets_from_tessellation
           ? "surfaces tessellated within " + format_number(settings.tessellation_tolerance_mm) + " mm"
           : std::string("from the patch surfaces directly")));
  if (!given) {
    progress.set_detail("reference tissue fractions");
    out.reference =
        voxelize_tissues(out.grid, sets.organs, static_cast<int>(out.tissues.size()), settings.supersampling);
  }
  progress.advance();
  return sets;
}

/// The deformed state's level sets (the organs that did not move keep the reference's) and
/// tissue volumes with the gaps the moved organs left, reported.
void voxelize_deformed(const VoxelizationSettings& settings, const OrganTable& organs, const ImageGrid& grid,
                       const Phantom& deformed, const PhantomDeformation* deformation,
                       const Phantom& reference, const StateLevelSets& sets, OrganHeightRanges& height_ranges,
                       int gap_tissue, VoxelizedPhantom& out, StageReport& report, ProgressBar& progress) {
  const double voxel_size = out.grid.spacing_mm.minCoeff();
  progress.set_detail("deformed level sets");
  StateLevelSets moved = level_sets_of(settings, organs, grid, deformed, out.tissues, voxel_size,
                                       height_ranges, progress, {&reference, &sets});
  std::size_t shared = 0;
  for (std::size_t k = 0; k < moved.level_sets.size(); ++k)
    shared += std::count(sets.level_sets.begin(), sets.level_sets.end(), moved.level_sets[k]) > 0 ? 1 : 0;
  report.modelled.push_back("deformed: " + std::to_string(moved.level_sets.size() - shared) +
                            " level sets of moved organs; the " + std::to_string(shared) +
                            " organs that did not move keep their reference level set");
  std::vector<VoxelizedOrgan> with_gaps = moved.organs;
  std::vector<std::shared_ptr<const LevelSet>> grown; // read by the tissue fractions below
  if (deformation) {
    // The space a moved organ leaves in its container is its reference shape; when the whole
    // head grows after the solve (deformation.head_scale), its grown reference shape.
    std::vector<VoxelizedOrgan> left = sets.organs;
    if (!deformation->head.identity()) {
      auto moves = [&](int o) {
        const std::string& by = deformation->organs[static_cast<std::size_t>(o)].moved_by;
        return by == "solver" || by.rfind("embedded in ", 0) == 0;
      };
      for (VoxelizedOrgan& v : left) {
        const int o = v.label - 1;
        const int container = organs[static_cast<std::size_t>(o)].parent;
        if (!moves(o) || container < 0 || moves(container) ||
            !reference.organs[static_cast<std::size_t>(o)].surface)
          continue;
        PatchSurface surface = *reference.organs[static_cast<std::size_t>(o)].surface;
        Eigen::MatrixX3d positions = surface.rest_positions();
        deformation->head.apply_rows(positions);
        surface.set_positions(positions);
        const std::optional<std::vector<HeightRange>>& ranges = height_ranges[static_cast<std::size_t>(o)];
        grown.push_back(
            std::make_shared<const LevelSet>(surface, voxel_size, 3.0, ranges ? &*ranges : nullptr));
        v.level_set = grown.back().get();
      }
    }
    const std::vector<VoxelizedOrgan> gaps =
        gap_organs(settings.gap_fill, gap_tissue, organs, *deformation, left, report);
    with_gaps.insert(with_gaps.end(), gaps.begin(), gaps.end());
  }
  progress.set_detail("deformed tissue fractions");
  // Where no organ differs from the reference state (blocks away from the moved surfaces and
  // the gaps), the reference voxels are the deformed ones: copied, the same bytes.
  out.deformed = voxelize_tissues(out.grid, with_gaps, static_cast<int>(out.tissues.size()),
                                  settings.supersampling, TissuesToReuse{&out.reference, &sets.organs});
  progress.advance();
  if (settings.keep_level_sets) keep_level_sets(deformed, moved, out.deformed_level_sets);
}

/// The reference state's landmarks carried by the deformation, and the displacement fields both
/// ways with their Jacobians and exact masks, reported (and their folds warned of).
void add_motion(const Phantom& reference, const PhantomDeformation& deformation, double landmark_tolerance_mm,
                int dense_per_organ, const std::function<void()>& landmark_done,
                const DeepestCandidates* candidates, VoxelizedPhantom& out, StageReport& report,
                ProgressBar& progress) {
  // Tissue outside the solved bodies does not move: the extension only smooths the step at a
  // moved boundary, over two voxels [choice].
  const double extension = 2.0 * out.grid.spacing_mm.maxCoeff();
  progress.set_detail("displacement fields");
  const DeformationMap map(deformation.bodies, extension, deformation.head);
  // The landmarks first: their distance transforms (8 bytes per voxel of an organ's label box)
  // then do not add to the fields' memory (34 bytes per voxel of the grid), the peak.
  progress.set_detail("landmarks");
  out.landmarks = organ_landmarks(reference, &deformation, &map, landmark_tolerance_mm, &report.warnings,
                                  landmark_done, {&out.grid, &out.reference.labels}, candidates);
  out.dense_landmarks =
      dense_landmarks(reference, &deformation, &map, dense_per_organ, reference.seed, &report.modelled);
  progress.set_detail("displacement fields");
  // Organs that stay where they are carry zero displacement in both fields (by their labels).
  StillTissue still{&out.reference.labels, out.deformed ? &out.deformed->labels : nullptr,
                    still_organ_labels(deformation)};
  out.motion = compute_motion_fields(out.grid, map, still);
  progress.advance();
  report.modelled.push_back("displacement fields both ways: barycentric in the solved tets (exact), outside "
                            "them a Shepard extension of the moved boundary fading out over " +
                            format_number(extension) + " mm (not exact; see the mask)");
  report.accuracy["largest displacement mm"] = out.motion->max_displacement_mm;
  report.accuracy["smallest Jacobian determinant"] = out.motion->min_jacobian;
  report.accuracy["smallest Jacobian determinant in the exact mask"] = out.motion->min_exact_jacobian;
  report.accuracy["largest composition error in the exact masks mm"] = out.motion->max_composition_error_mm;
  report.modelled.push_back(std::to_string(out.motion->inconsistent_voxels) +
                            " voxels left out of the exact masks: composing the two fields there misses "
                            "identity by more than " +
                            format_number(composition_tolerance_voxels) + " voxel");
  // Both fields checked alike: each in its own exact mask, its folds named by the labels of
  // its own grid (the deformed grid's gap label included).
  std::vector<std::string> label_names;
  for (const Organ& organ : reference.organs)
    label_names.push_back(organ.name);
  label_names.push_back(k_gap_label_name);
  const MotionFields& m = *out.motion;
  if (auto warning = fold_warning("from-def_to-ref (the reference grid)", m.jacobian, m.ref_to_def_exact,
                                  out.reference.labels, label_names))
    report.warnings.push_back(*warning);
  if (auto warning =
          fold_warning("from-ref_to-def (the deformed grid)", m.def_to_ref_jacobian, m.def_to_ref_exact,
                       out.deformed ? out.deformed->labels : out.reference.labels, label_names))
    report.warnings.push_back(*warning);
}

} // namespace

ReferenceVoxelization voxelize_reference_state(const VoxelizationSettings& settings, const OrganTable& organs,
                                               const ImageGrid& grid, const Phantom& reference) {
  // As voxelize_phantom and voxelize_reference build it: the tissues in organ order, the level
  // sets at the grid's smallest voxel size, the fractions.
  std::vector<std::string> tissues;
  for (const Organ& organ : reference.organs)
    if (std::find(tissues.begin(), tissues.end(), organ.tissue) == tissues.end())
      tissues.push_back(organ.tissue);
  Reporter silent = Reporter::silent();
  ProgressBar progress(silent, "voxelize", reference.organs.size(), ProgressBar::Unlisted{});
  ReferenceVoxelization state;
  state.height_ranges.resize(reference.organs.size());
  const StateLevelSets sets = level_sets_of(settings, organs, grid, reference, tissues,
                                            grid.spacing_mm.minCoeff(), state.height_ranges, progress);
  for (const VoxelizedOrgan& organ : sets.organs)
    state.organs.push_back(organ.label - 1);
  state.level_sets = sets.level_sets;
  state.volumes =
      voxelize_tissues(grid, sets.organs, static_cast<int>(tissues.size()), settings.supersampling);
  state.deepest_candidates = deepest_candidates(reference, {&grid, &state.volumes.labels});
  return state;
}

VoxelizedPhantom voxelize_phantom(const VoxelizationSettings& settings, const OrganTable& organs,
                                  const ImageGrid& grid, const Phantom& reference, const Phantom* deformed,
                                  const PhantomDeformation* deformation, StageReport& report,
                                  Reporter& reporter, std::optional<ReferenceVoxelization>* reference_state) {
  VoxelizedPhantom out;
  out.grid = grid;
  for (const Organ& organ : reference.organs)
    if (std::find(out.tissues.begin(), out.tissues.end(), organ.tissue) == out.tissues.end())
      out.tissues.push_back(organ.tissue);
  const int states = deformed ? 2 : 1;
  // Steps: each organ's level set and the tissue fractions per state, the displacement fields,
  // and each surfaced organ's landmarks (the deepest-point search takes seconds per organ of
  // real anatomy: the time left counts them).
  const auto landmark_organs =
      static_cast<std::size_t>(std::count_if(reference.organs.begin(), reference.organs.end(),
                                             [](const Organ& o) { return static_cast<bool>(o.surface); }));
  ProgressBar progress(reporter, "voxelize",
                       static_cast<std::size_t>(states) * (reference.organs.size() + 1) + (deformed ? 1 : 0) +
                           landmark_organs);
  const std::function<void()> landmark_done = [&progress] { progress.advance(); };
  // Where the labels cannot tell a depth, the search tessellates the surfaces within a voxel edge
  // (0.5-2 mm): a deepest point
  // needs its depth to within a voxel, and its side of every surface is exact whatever the
  // tolerance (voxelize/landmarks.hpp).
  const double landmark_tolerance_mm = std::clamp(out.grid.spacing_mm.minCoeff(), 0.5, 2.0);
  for (std::size_t o = 0; o < reference.organs.size(); ++o) {
    if (reference.organs[o].sheet)
      report.skipped.push_back(reference.organs[o].name + ": an open sheet has no inside; it fills no voxel");
  }
  const int gap_tissue = deformed ? gap_tissue_index(settings.gap_fill, out.tissues) : -1;
  // The reference level sets outlive the deformed state's voxelization: they are its gaps' shapes.
  progress.set_detail("reference level sets");
  OrganHeightRanges height_ranges(reference.organs.size());
  // The deepest points' candidates come with a given reference state, and go with one built here.
  const bool given = reference_state && reference_state->has_value();
  std::optional<DeepestCandidates> candidates;
  if (given) candidates = std::move((*reference_state)->deepest_candidates);
  const StateLevelSets sets = voxelize_reference(settings, organs, grid, reference, reference_state,
                                                 height_ranges, out, report, progress);
  if (reference_state && !given) {
    candidates = deepest_candidates(reference, {&out.grid, &out.reference.labels});
    (*reference_state)->deepest_candidates = candidates;
  }
  const DeepestCandidates* known_candidates = candidates ? &*candidates : nullptr;
  if (deformed)
    voxelize_deformed(settings, organs, grid, *deformed, deformation, reference, sets, height_ranges,
                      gap_tissue, out, report, progress);
  if (settings.keep_level_sets) keep_level_sets(reference, sets, out.reference_level_sets);
  report.modelled.push_back("fractions from " + std::to_string(settings.supersampling) +
                            "^3 samples in the " + std::to_string(out.reference.supersampled_voxels) +
                            " voxels within half a voxel diagonal of a surface");
  if (deformation)
    add_motion(reference, *deformation, landmark_tolerance_mm, settings.dense_landmarks, landmark_done,
               known_candidates, out, report, progress);
  if (!deformation) {
    out.landmarks = organ_landmarks(reference, nullptr, nullptr, landmark_tolerance_mm, &report.warnings,
                                    landmark_done, {&out.grid, &out.reference.labels}, known_candidates);
    out.dense_landmarks = dense_landmarks(reference, nullptr, nullptr, settings.dense_landmarks,
                                          reference.seed, &report.modelled);
  }
  report.modelled.push_back(
      "landmarks: each organ's deepest point from the distance transform of its reference label (depth "
      "within a voxel), or, for an organ the grid cuts, thinner than a voxel or whose surface is cheaper "
      "to search (fewer than one bump per 200 voxels of its label's box), from distances to its "
      "surfaces tessellated within " +
      format_number(landmark_tolerance_mm) + " mm; which side of a surface, from the patches themselves");
  report.status = "done";
  return out;
}

} // namespace phantasm
