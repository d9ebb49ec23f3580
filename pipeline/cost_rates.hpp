// The rates the cost estimate (pipeline/cost_estimate.hpp) turns counts into memory and time
// with, measured on the 2-core development machine (docs/architecture.md, "Cost estimate").
// Re-measure them with `build/release/tests/test_cost_estimate`, which runs the coarse copies of
// the shipped scenes and the test scenes under /usr/bin/time and prints each estimate against the
// measured peak resident memory and processor time (and fails beyond a factor of two).
#pragma once

namespace phantasm::cost_rates {

/// How the rates were measured (recorded in provenance.json with the estimate).
inline constexpr const char* k_rates_measured_by =
    "build/release/tests/test_cost_estimate on the 2-core development machine (README, Performance)";

/// The threads the estimate assumes (its wall time, the fits that run at once): those of the
/// 2-core machine the rates were measured on, whatever this run has, so that the estimate in the
/// log and provenance is the same on any number of threads.
inline constexpr int k_estimate_threads = 2;

// --- Memory, bytes ------------------------------------------------------------------------
/// The process before any stage holds data: code, libraries, OpenVDB and CGAL's pools, the
/// worker threads' stacks (peak resident of `phantasm run` on cloth.yaml's coarse copy: 77 MB).
inline constexpr double k_base_bytes = 75e6;
/// Per tet at the peak of meshing and solving: CGAL's triangulation during Mesh_3 (about
/// 1 kB a cell, freed after), the solver's matrix factor and constraint data.
inline constexpr double k_bytes_per_tet = 600.0;
/// Fitting one organ (organs are fitted side by side, one per thread, so the largest fits that
/// run at once set the peak): this times 320 / its base size (a coarse base's patches take more
/// samples each: the test scenes' balls of 80 base triangles peak at 105-120 MB with the
/// process's own 75 MB) ...
inline constexpr double k_fit_bytes_at_320 = 8e6;
/// ... plus this per patch (the samples and normal equations of the fit; the Colin head's
/// anatomy, grey and white matter of 20 000 base triangles fitted at once, peaks at 1.16 GB with
/// its labels, at about 1 mm sample spacing of the fit report).
inline constexpr double k_bytes_per_fitted_patch = 20e3;
/// Per narrow-band voxel of a level set (OpenVDB leaf nodes, partly filled).
inline constexpr double k_bytes_per_band_voxel = 8.0;
/// Per dense voxel while the motion fields are made (the deformation map's rasterized field
/// and the search's scratch) on top of the volumes held.
inline constexpr double k_field_transient_bytes = 24.0;
/// Per dense voxel while one image is made: the complex coil image, the object and the bias
/// field (doubles), on top of the volumes held.
inline constexpr double k_image_transient_bytes = 40.0;
/// Per organ whose shape is read from a file or an atlas, per mm^3 of the field of view: its
/// label volume, smoothed indicator and distance samples at the label volume's resolution (about
/// 1 mm), kept for the run (the coarse Colin head: 9 such organs, 1.3 GB at its peak).
inline constexpr double k_file_shape_bytes_per_mm3 = 17.0;

// --- Counts -------------------------------------------------------------------------------
/// A shape known only from its file: its extent as a fraction of the field of view, and each
/// level of nesting as a fraction of its container's extent.
inline constexpr double k_file_shape_extent = 0.9;
inline constexpr double k_file_shape_nesting = 0.8;
/// Mesh_3's tets of cell size bound s have a mean volume of this times s^3.
inline constexpr double k_tet_volume_factor = 0.1;
/// Extra tets of a body mesh per s^2 of interface area (the refined layer at organ boundaries).
inline constexpr double k_interface_tets = 2.0;
/// Narrow-band voxels per voxel area of surface (both sides of a surface, all of its width).
inline constexpr double k_band_width = 6.0;
/// Voxels a surface crosses per voxel area of surface.
inline constexpr double k_crossed_voxels_per_area = 1.5;

// --- Processor time, s ----------------------------------------------------------------------
/// Start, scene parsing, the writer's fixed files.
inline constexpr double k_base_seconds = 0.15;
/// Fitting one organ: this times 320 / its base size, plus k_seconds_per_patch per patch (set
/// with test_cost_estimate once a run measured the fit against its source only: every scene's
/// processor time within 0.6-1.3 of its estimate).
inline constexpr double k_fit_seconds_at_320 = 0.05;
inline constexpr double k_seconds_per_patch = 0.7e-3;
/// Per organ whose shape is read from a file or an atlas, per mm^3 of the field of view:
/// deriving, smoothing and searching its label volume (the coarse Colin head: 12 s an organ).
inline constexpr double k_file_shape_seconds_per_mm3 = 1.6e-6;
/// Per tet CGAL meshes: Mesh_3 with ODT smoothing and sliver checks (a box's structured tets cost
/// nothing).
inline constexpr double k_seconds_per_tet = 50e-6;
/// Per simulated tet per frame and load step: local/global iterations to convergence.
inline constexpr double k_seconds_per_tet_step = 3e-6;
// Per shell triangle per frame and load step: the solver's own rate
// (SolverType::seconds_per_shell_triangle_step, sim/solver_types/).
/// Per frame and load step of a scene with obstacles or collisions: contact detection and the
/// factor's updates (tests/data/scenes/two-balls.yaml, breast.yaml).
inline constexpr double k_seconds_per_contact_step = 0.1;
// The voxelization's rates below were fitted to two measured runs on one thread (bench/
// voxelize_head 1.0 new): data-synthetic/head.yaml, 2240 patches, 7.7 s of CPU, and
// data-synthetic/colin-head.yaml, 54 000 patches (folded grey and white matter), 38.9 s.
/// Per dense voxel and state: labels, fractions away from surfaces, gap fill.
inline constexpr double k_seconds_per_dense_voxel = 0.11e-6;
/// Per narrow-band voxel: the closest patch point of each level-set voxel.
inline constexpr double k_seconds_per_band_voxel = 0.19e-6;
/// Per patch and state at 1 mm voxels (over the voxel area in mm^2 at other sizes): its candidate
/// voxels' closest-triangle searches and patch distances (the patches of a folded surface
/// overlap, so their voxels are tried by several).
inline constexpr double k_seconds_per_level_set_patch_at_1mm = 0.3e-3;
/// Per partial-volume sample.
inline constexpr double k_seconds_per_sample = 19e-9;
/// Per voxel a moved surface crosses: the motion fields' boundary search and extension.
inline constexpr double k_seconds_per_moved_voxel = 7.4e-6;
/// Per dense voxel and image: the signal equations, bias and noise (data-synthetic/head.yaml at
/// full size: 6 images of 7.0e6 voxels with 8 coils in about 6.8 s on one thread).
inline constexpr double k_seconds_per_image_voxel = 60e-9;
/// Per dense voxel, image and receive coil when acquired in k-space: FFTs both ways.
inline constexpr double k_seconds_per_coil_voxel = 12e-9;
/// Per dense voxel of each float volume written: gzip-compressed NIfTI (libdeflate level 1; the
/// full-size head writes its 112 files in about 7.5 s of processor time).
inline constexpr double k_seconds_per_written_voxel = 24e-9;
/// Per patch and state of the surface meshes written (tessellation and .vtp) at the export
/// tolerance k_written_patch_tolerance_mm; a patch's triangles, hence its time, go as one over the
/// tolerance (0.2 x the voxel edge, 0.5 mm at most).
inline constexpr double k_seconds_per_written_patch = 3e-4;
inline constexpr double k_written_patch_tolerance_mm = 0.2;
/// The fraction of a second thread the parallel stages use.
inline constexpr double k_parallel_efficiency = 0.7;

} // namespace phantasm::cost_rates
