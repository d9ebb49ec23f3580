// The reference images cache (pipeline/reference_images_cache.hpp): stored reference images
// decode to the same bytes, every MRI setting that makes them reaches the key (and what only the
// deformed state or the outputs read does not), runs with the cache cold, warm and without it
// write the same files, subjects that differ in the deformation share the entry, and a damaged
// entry is made again.

#include "core/byte_codec.hpp"
#include "mri/synthesize_images.hpp"
#include "pipeline/anatomy_cache.hpp"
#include "pipeline/reference_cache.hpp"
#include "pipeline/reference_images_cache.hpp"
#include "pipeline/run_pipeline.hpp"
#include "scene/scene.hpp"
#include "tests/pipeline/cache_fixtures.hpp"
#include "tests/support/files.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <functional>

using namespace phantasm;
using namespace phantasm::testing;
namespace fs = std::filesystem;

namespace {

const fs::path k_small_head = fs::path(PHANTASM_SOURCE_DIR) / "tests" / "data" / "scenes" / "small-head.yaml";

/// The small head acquired as the sweeps' heads are: in k-space, with coils, noise and bias (each
/// seeded per image), so that a reference image made again with another seed or state differs;
/// a third sequence is named as a parameter map (T1map), so that an image and a map have one
/// file name in two folders.
std::string acquired_small_head_text() {
  std::string text = read_file(k_small_head);
  const std::string t2w = "  - {name: T2w, type: spin_echo, TR_ms: 4000, TE_ms: 100}\n";
  text.insert(text.find(t2w) + t2w.size(), "  - {name: T1map, type: spin_echo, TR_ms: 500, TE_ms: 10}\n");
  return text + "\nacquisition: {kspace: true, acquired_voxel_mm: 2.4, coils: 4, noise_percent: 3, "
                "bias_percent: 20}\n";
}

/// A scene of the text, loaded from a file of that name in `folder`.
Scene scene_of_text(const fs::path& folder, const std::string& name, const std::string& text) {
  const fs::path file = folder / name;
  fs::create_directories(folder);
  write_text_file(file, text);
  return scene_of(file);
}

/// The text with `from` (which must be there once) replaced by `to`.
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  if (at == std::string::npos || text.find(from, at + 1) != std::string::npos)
    throw std::runtime_error("not once in the scene: " + from);
  return text.replace(at, from.size(), to);
}

bool same_floats(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

void expect_same_images(const std::vector<MrImage>& a, const std::vector<MrImage>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t q = 0; q < a.size(); ++q) {
    EXPECT_TRUE(same_floats(a[q].magnitude, b[q].magnitude)) << q;
    EXPECT_EQ(a[q].noise_sigma, b[q].noise_sigma) << q;
  }
}

void expect_same_maps(const std::optional<ParameterMaps>& a, const std::optional<ParameterMaps>& b) {
  ASSERT_EQ(a.has_value(), b.has_value());
  if (!a) return;
  EXPECT_TRUE(same_floats(a->PD, b->PD));
  EXPECT_TRUE(same_floats(a->T1_ms, b->T1_ms));
  EXPECT_TRUE(same_floats(a->T2_ms, b->T2_ms));
  EXPECT_TRUE(same_floats(a->T2star_ms, b->T2star_ms));
}

/// The entries of a cache folder whose names start with `prefix`: "images-" (the reference
/// images), "file-" (the reference session's files).
std::vector<fs::path> entries_named(const fs::path& cache, const std::string& prefix) {
  std::vector<fs::path> entries;
  for (const auto& entry : fs::directory_iterator(cache))
    if (entry.path().filename().string().rfind(prefix, 0) == 0 && entry.path().extension() == ".bin")
      entries.push_back(entry.path());
  std::sort(entries.begin(), entries.end());
  return entries;
}

std::vector<fs::path> images_entries(const fs::path& cache) {
  return entries_named(cache, "images-");
}

/// The path of a subject-01 file in subject `id`'s folders.
std::string of_subject(std::string path, const std::string& id) {
  for (std::size_t at = path.find("sub-01"); at != std::string::npos; at = path.find("sub-01", at))
    path.replace(at + 4, 2, id);
  return path;
}

} // namespace

// The reference images made alone and given back give what one call makes of both states, bit for
// bit, with the same report lines; encoded and decoded, the same bytes; bytes cut short, of
// another count or another grid are refused.
TEST(ReferenceImagesCache, GivenReferenceImagesMakeTheSameResultAndDecodeToTheSameBytes) {
  const fs::path folder = fresh_folder("reference-images-given");
  const Scene scene = scene_of_text(folder, "head.yaml", acquired_small_head_text());
  Reporter quiet = Reporter::silent();
  const Simulation sim = simulate(scene, quiet, SimulationStage::voxelization);
  ASSERT_TRUE(sim.volumes.deformed.has_value());
  StageReport whole_report, alone_report, given_report;
  const MrImages whole = synthesize_images(scene.mri, scene.organs, sim.volumes, whole_report, quiet);
  ASSERT_EQ(whole.reference.size(), 3u);
  ASSERT_TRUE(whole.reference_maps.has_value());

  SynthesisOptions alone_options;
  alone_options.reference_only = true;
  MrImages alone =
      synthesize_images(scene.mri, scene.organs, sim.volumes, alone_report, quiet, std::move(alone_options));
  EXPECT_TRUE(alone.deformed.empty());
  EXPECT_FALSE(alone.deformed_maps.has_value());
  expect_same_images(alone.reference, whole.reference);
  expect_same_maps(alone.reference_maps, whole.reference_maps);
  EXPECT_EQ(alone_report.modelled, whole_report.modelled);

  const std::size_t voxels = sim.volumes.reference.labels.size();
  ReferenceImages kept{std::move(alone.reference), std::move(alone.reference_maps)};
  const std::string bytes = encode_reference_images(kept);
  ReferenceImages read = decode_reference_images(bytes, 3, true, voxels);
  expect_same_images(read.images, kept.images);
  expect_same_maps(read.maps, kept.maps);
  EXPECT_TRUE(encode_reference_images(read) == bytes); // an entry is a function of its images
  EXPECT_THROW(decode_reference_images(bytes.substr(0, bytes.size() - 1), 3, true, voxels), DamagedBytes);
  EXPECT_THROW(decode_reference_images(bytes.substr(0, bytes.size() / 2), 3, true, voxels), DamagedBytes);
  EXPECT_THROW(decode_reference_images(bytes, 4, true, voxels), DamagedBytes);
  EXPECT_THROW(decode_reference_images(bytes, 3, false, voxels), DamagedBytes);
  EXPECT_THROW(decode_reference_images(bytes, 3, true, voxels + 1), DamagedBytes);
  std::string flipped = bytes;
  flipped[bytes.size() / 4] ^= 0x10; // inside the first image's stored floats: its check fails
  EXPECT_THROW(decode_reference_images(flipped, 3, true, voxels), DamagedBytes);

  SynthesisOptions given_options;
  given_options.reference = std::move(read);
  const MrImages given =
      synthesize_images(scene.mri, scene.organs, sim.volumes, given_report, quiet, std::move(given_options));
  expect_same_images(given.reference, whole.reference);
  expect_same_images(given.deformed, whole.deformed);
  expect_same_maps(given.reference_maps, whole.reference_maps);
  expect_same_maps(given.deformed_maps, whole.deformed_maps);
  EXPECT_EQ(given.coils, whole.coils);
  EXPECT_EQ(given.kspace.has_value(), whole.kspace.has_value());
  for (std::size_t q = 0; q < given.reference.size(); ++q)
    EXPECT_EQ(given.reference[q].sequence, &scene.mri.sequences[q]);
  EXPECT_EQ(given_report.modelled, whole_report.modelled);
  EXPECT_EQ(given_report.skipped, whole_report.skipped);

  // Images of other settings are refused, not misused.
  SynthesisOptions wrong;
  wrong.reference = ReferenceImages{{given.reference[0]}, given.reference_maps};
  StageReport wrong_report;
  EXPECT_THROW(synthesize_images(scene.mri, scene.organs, sim.volumes, wrong_report, quiet, std::move(wrong)),
               std::invalid_argument);
}

// A change of any MRI setting the reference images are made from gives another key; the images
// flag (the stage runs only with it) does not.
TEST(ReferenceImagesCache, EveryMriSettingOfTheReferenceImagesChangesTheKey) {
  const fs::path folder = fresh_folder("reference-images-key");
  const Scene scene = scene_of_text(folder, "head.yaml", acquired_small_head_text());
  struct Inputs {
    std::string reference_key;
    MriSettings mri;
  };
  Inputs base{std::string(64, 'a'), scene.mri};
  base.mri.tissues.push_back({"csf", 4000.0, std::nullopt, 90.0, std::nullopt});
  base.mri.sequences.push_back(
      {"FLAIR", SequenceKind::inversion_recovery, 9000, 120, 90, 2500, Readout::spin_echo, 0, 0});
  base.mri.sequences.push_back(
      {"MPRAGE", SequenceKind::mprage, 2300, 3, 9, 900, Readout::gradient_echo, 7.1, 176});
  ASSERT_EQ(base.mri.sequences.size(), 5u);
  ASSERT_FALSE(base.mri.tissues.empty());
  const auto key_of = [](const Inputs& in) { return reference_images_key(in.reference_key, in.mri); };
  using Change = std::function<void(Inputs&)>;
  const auto last_tissue = [](Inputs& in) -> TissueOverride& { return in.mri.tissues.back(); };
  const auto sequence = [](Inputs& in, std::size_t q) -> SequenceSettings& { return in.mri.sequences[q]; };
  const std::vector<Change> changes = {
      [](Inputs& in) { in.reference_key[0] = 'b'; },
      [](Inputs& in) { in.mri.field_strength_T = 1.5; },
      [&](Inputs& in) { last_tissue(in).tissue = "csg"; },
      [&](Inputs& in) { *last_tissue(in).T1_ms += 1e-9; },
      [&](Inputs& in) { last_tissue(in).T2_ms = 2000.0; },
      [&](Inputs& in) { last_tissue(in).T2star_ms.reset(); },
      [&](Inputs& in) { last_tissue(in).PD = 1.0; },
      [](Inputs& in) { in.mri.tissues.pop_back(); },
      [&](Inputs& in) { sequence(in, 0).name = "T1x"; },
      [&](Inputs& in) { sequence(in, 0).kind = SequenceKind::bssfp; },
      [&](Inputs& in) { sequence(in, 0).TR_ms += 1e-12; },
      [&](Inputs& in) { sequence(in, 1).TE_ms += 1e-12; },
      [&](Inputs& in) { sequence(in, 0).flip_deg += 1.0; },
      [&](Inputs& in) { sequence(in, 3).TI_ms += 1.0; },
      [&](Inputs& in) { sequence(in, 3).readout = Readout::gradient_echo; },
      [&](Inputs& in) { sequence(in, 4).echo_spacing_ms += 0.1; },
      [&](Inputs& in) { sequence(in, 4).turbo_factor += 1; },
      [](Inputs& in) { std::swap(in.mri.sequences[0], in.mri.sequences[1]); }, // the noise seeds' order
      [](Inputs& in) { in.mri.sequences.pop_back(); },
      [](Inputs& in) { in.mri.acquisition.kspace = !in.mri.acquisition.kspace; },
      [](Inputs& in) { in.mri.acquisition.kspace_oversampling += 1; },
      [](Inputs& in) { in.mri.acquisition.acquired_voxel_mm->z() += 1e-9; },
      [](Inputs& in) { in.mri.acquisition.acquired_voxel_mm.reset(); },
      [](Inputs& in) { in.mri.acquisition.slice_thickness_mm = 3.0; },
      [](Inputs& in) { in.mri.acquisition.noise_percent *= 1.0 + 1e-12; },
      [](Inputs& in) { in.mri.acquisition.noise_reference_tissue = "gray_matter"; },
      [](Inputs& in) { in.mri.acquisition.bias_percent += 1.0; },
      [](Inputs& in) { in.mri.acquisition.coils += 1; },
      [](Inputs& in) { in.mri.acquisition.receiver_gain = 3e4; },
      [](Inputs& in) { in.mri.seed += 1; },
      [](Inputs& in) { in.mri.parameter_maps = !in.mri.parameter_maps; },
  };
  expect_every_change_changes_the_key<Inputs>(base, changes, key_of);
  const std::string base_key = key_of(base);
  Inputs without_images = base;
  without_images.mri.images = !without_images.mri.images;
  EXPECT_EQ(key_of(without_images), base_key);
  EXPECT_TRUE(reference_images_key("", base.mri).empty());
}

// Runs of the acquired small head without the cache, with it cold (makes the entry) and warm
// (reads it) write the same bytes in every file; cold and warm logs and provenance are the same
// too, and name the entry. A subject that differs in the deformation's size and the outputs
// shares the entry and its reference images are the same bytes; one with another seed, noise or
// sequence makes its own. A damaged entry is made again (a line, no stage warning), the data
// bytes unchanged.
TEST(ReferenceImagesCache, RunsWithTheCacheColdWarmAndWithoutWriteTheSameFiles) {
  const fs::path folder = fresh_folder("reference-images-cache");
  const fs::path cache = folder / "cache";
  const std::string text = acquired_small_head_text();
  const auto run = [&](const std::string& name, const std::string& scene_text, const fs::path& cache_folder) {
    // One file name for all: provenance.json names the scene's file.
    const Scene scene = scene_of_text(folder / "scenes" / name, "head.yaml", scene_text);
    RunOptions options;
    options.output = folder / name;
    options.anatomy_cache = cache_folder;
    Reporter quiet = Reporter::silent();
    const RunSummary summary = run_scene(scene, options, quiet);
    return std::make_pair(summary, files_of(summary, options.output));
  };
  const auto [none_summary, none] = run("none", text, {});
  const auto [cold_summary, cold] = run("cold", text, cache);
  const std::vector<fs::path> entries = images_entries(cache);
  ASSERT_EQ(entries.size(), 1u);
  const auto [warm_summary, warm] = run("warm", text, cache);
  ASSERT_GT(none.size(), 50u);
  ASSERT_EQ(cold.size(), none.size());
  ASSERT_EQ(warm.size(), none.size());
  const std::string line = "MR images and parameter maps kept in the reference cache as entry";
  for (const auto& [path, bytes] : none) {
    SCOPED_TRACE(path);
    ASSERT_TRUE(cold.count(path) && warm.count(path));
    EXPECT_TRUE(cold.at(path) == warm.at(path));
    if (is_record(path)) {
      if (is_page_summary(path)) continue;
      EXPECT_EQ(bytes.find(line), std::string::npos);
      EXPECT_NE(cold.at(path).find(line), std::string::npos);
      continue;
    }
    EXPECT_TRUE(cold.at(path) == bytes);
  }
  EXPECT_TRUE(contains(warm_summary.stages[3].modelled, line));
  EXPECT_EQ(images_entries(cache), entries);
  // The reference session's images, previews, maps, labels, fractions and meshes: their bytes
  // stored by the cold run, copied by the warm one (the same bytes, checked above).
  std::size_t reference_files = 0;
  for (const auto& [path, bytes] : none) {
    const bool reference = path.find("ses-ref") != std::string::npos;
    const auto ends = [&path = path](const std::string& end) {
      return path.size() > end.size() && path.compare(path.size() - end.size(), end.size(), end) == 0;
    };
    reference_files += reference && (ends(".nii.gz") || ends(".png") || ends(".vtp") ||
                                     (ends("_tetmesh.vtu") && path.find("greyMatter") == std::string::npos));
  }
  const std::vector<fs::path> file_entries = entries_named(cache, "file-");
  EXPECT_EQ(reference_files, 17u); // 3 images, 3 previews, 4 maps, dseg, 3 probseg, 3 surfaces
  EXPECT_EQ(file_entries.size(), reference_files); // the simulated body's tet mesh is the subject's

  // What a deformation sweep varies, another subject, and outputs the reference session does
  // not depend on: the same entries, every reference-session file the same bytes as without the
  // cache (copied from the entries); the deformed images differ.
  const std::string def_t1w = "sub-01/ses-def/anat/sub-01_ses-def_T1w.nii.gz";
  ASSERT_TRUE(none.count(def_t1w));
  const std::string shifted_text =
      replaced(replaced(text, "displacement_mm: [-2, 0, -3]", "displacement_mm: [-4, 0, -6]"),
               "subject: \"01\"", "subject: \"02\"\n  landmarks: false\n  jacobian: false");
  const auto [shifted_summary, shifted] = run("shifted", shifted_text, cache);
  EXPECT_EQ(images_entries(cache), entries);
  EXPECT_EQ(entries_named(cache, "file-"), file_entries);
  std::size_t compared = 0;
  for (const auto& [path, bytes] : none) {
    if (path.find("ses-ref") == std::string::npos || path.find("landmarks") != std::string::npos) continue;
    SCOPED_TRACE(path);
    ASSERT_TRUE(shifted.count(of_subject(path, "02")));
    EXPECT_TRUE(shifted.at(of_subject(path, "02")) == bytes);
    ++compared;
  }
  EXPECT_GT(compared, reference_files);
  EXPECT_FALSE(shifted.at(of_subject(def_t1w, "02")) == none.at(def_t1w));
  EXPECT_TRUE(contains(shifted_summary.stages[3].modelled, line));

  // Another noise level, sequence timing or seed: entries of their own.
  run("noisier", replaced(text, "noise_percent: 3", "noise_percent: 4"), cache);
  EXPECT_EQ(images_entries(cache).size(), 2u);
  run("longer_te", replaced(text, "TR_ms: 4000, TE_ms: 100", "TR_ms: 4000, TE_ms: 90"), cache);
  EXPECT_EQ(images_entries(cache).size(), 3u);
  run("reseeded", replaced(text, "seed: 3", "seed: 4"), cache);
  EXPECT_EQ(images_entries(cache).size(), 4u);

  // Cut short, and a flipped bit in an image's stored floats: made again, the same data.
  const std::string stored = read_file(entries[0]);
  for (const std::string& damage :
       {stored.substr(0, stored.size() - 100),
        std::string(stored).replace(stored.size() / 3, 1, 1, stored[stored.size() / 3] ^ 1)}) {
    write_text_file(entries[0], damage);
    const auto [damaged_summary, damaged] = run("damaged", text, cache);
    EXPECT_TRUE(contains(damaged_summary.stages[3].modelled, "a damaged reference images cache entry"));
    EXPECT_TRUE(damaged_summary.stages[3].warnings.empty()); // made again soundly: nothing for --strict
    for (const auto& [path, bytes] : none) {
      if (is_record(path)) continue;
      EXPECT_TRUE(damaged.at(path) == bytes) << path;
    }
    EXPECT_TRUE(read_file(entries[0]) == stored); // stored anew, whole
    fs::remove_all(folder / "damaged");
  }
}
