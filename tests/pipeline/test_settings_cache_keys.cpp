// Settings declared once (scene/settings_declarations.hpp) against the caches' keys: each declared
// setting, changed in turn, changes the key of every cached result it shapes (and of those made
// from them) and no other key. A setting a key forgets, or one a key reads without declaring that
// it shapes it, fails here: a stale cache hit, or a cache that never hits.

#include "pipeline/anatomy_cache.hpp"
#include "pipeline/reference_cache.hpp"
#include "pipeline/reference_images_cache.hpp"
#include "scene/settings_declarations.hpp"
#include "tests/pipeline/cache_fixtures.hpp"

#include <gtest/gtest.h>

#include <array>
#include <functional>

using namespace phantasm;
using namespace phantasm::testing;
namespace fs = std::filesystem;

namespace {

const fs::path k_small_head = fs::path(PHANTASM_SOURCE_DIR) / "tests" / "data" / "scenes" / "small-head.yaml";

/// The anatomy, reference state and reference images keys of a scene, in that order.
std::array<std::string, 3> keys_of(const Scene& scene) {
  const std::map<std::string, ShapeData> files; // analytic shapes only
  const std::string anatomy = anatomy_cache_key(scene.anatomy, files);
  const std::string reference =
      reference_cache_key(anatomy, scene.voxelization, scene.organs, scene.grid.grid());
  return {anatomy, reference, reference_images_key(reference, scene.mri)};
}

/// A scene whose every list holds an element, so that a change of a list's field has one to
/// change: the small head with a tissue value, an MPRAGE and an inversion recovery.
Scene base_scene() {
  Scene scene = scene_of(k_small_head);
  SequenceSettings mprage;
  mprage.name = "UNIT1";
  mprage.kind = SequenceKind::mprage;
  mprage.TR_ms = 2300;
  mprage.TE_ms = 3;
  mprage.TI_ms = 900;
  mprage.flip_deg = 9;
  mprage.echo_spacing_ms = 7;
  mprage.turbo_factor = 160;
  scene.mri.sequences.insert(scene.mri.sequences.begin(), mprage);
  scene.anatomy.organs[0].shape.labels = {"1"};
  scene.anatomy.organs[0].enclosed_volume_tolerance = 0.1;
  scene.mri.acquisition.acquired_voxel_mm = Eigen::Vector3d(2, 2, 2);
  return scene;
}

/// Changes each declared field of the part of a scene `part` returns, in turn, and checks the
/// keys: those of keys_changed_by(field.keys) change, the others do not. With `resolve`, the
/// scene's derived values are filled again after a change of a setting read from the file (a
/// setting such as outputs.parameter_maps reaches a key through them).
template <typename S>
void expect_each_setting_changes_its_keys(const std::function<S&(Scene&)>& part, bool resolve) {
  Scene base = base_scene();
  const std::array<std::string, 3> base_keys = keys_of(base);
  ASSERT_EQ(base_keys[0].size(), 64u) << "no build id: the caches would be off";
  const std::array<unsigned, 3> bits{cached_anatomy, cached_reference_state, cached_reference_images};
  const std::array<const char*, 3> names{"anatomy", "reference state", "reference images"};
  for (const SettingField<S>& field : declared_settings<S>()) {
    SCOPED_TRACE(field.name);
    Scene changed = base;
    const std::string before = field.exact(part(changed));
    field.change(part(changed));
    ASSERT_NE(field.exact(part(changed)), before) << "the change changed nothing";
    if (resolve && !field.derived) resolve_stage_settings(changed);
    const std::array<std::string, 3> keys = keys_of(changed);
    const unsigned expected = keys_changed_by(field.keys);
    for (std::size_t k = 0; k < keys.size(); ++k)
      EXPECT_EQ(keys[k] != base_keys[k], (expected & bits[k]) != 0) << "the " << names[k] << " key";
  }
}

} // namespace

TEST(SettingsCacheKeys, EachGridSettingChangesItsKeysAndNoOther) {
  expect_each_setting_changes_its_keys<GridSettings>([](Scene& s) -> GridSettings& { return s.grid; }, false);
}

TEST(SettingsCacheKeys, EachAnatomySettingChangesItsKeysAndNoOther) {
  expect_each_setting_changes_its_keys<AnatomySettings>(
      [](Scene& s) -> AnatomySettings& { return s.anatomy; }, false);
}

TEST(SettingsCacheKeys, EachVoxelizationSettingChangesItsKeysAndNoOther) {
  expect_each_setting_changes_its_keys<VoxelizationSettings>(
      [](Scene& s) -> VoxelizationSettings& { return s.voxelization; }, false);
}

TEST(SettingsCacheKeys, EachMriSettingChangesItsKeysAndNoOther) {
  expect_each_setting_changes_its_keys<MriSettings>([](Scene& s) -> MriSettings& { return s.mri; }, false);
}

// The outputs reach the stages' settings through resolve_stage_settings(): only the parameter
// maps shape a cached result.
TEST(SettingsCacheKeys, EachOutputSettingChangesItsKeysAndNoOther) {
  expect_each_setting_changes_its_keys<OutputSettings>([](Scene& s) -> OutputSettings& { return s.outputs; },
                                                       true);
}

// The checker itself: a key that forgets a setting is caught. The anatomy's declaration with
// one field's cache bits cleared claims a key the anatomy key text then lacks.
TEST(SettingsCacheKeys, AKeyTextWithoutAFieldMissesItsChange) {
  std::vector<SettingField<AnatomySettings>> fields = declared_settings<AnatomySettings>();
  AnatomySettings a = base_scene().anatomy;
  const std::string full = key_text(fields, a, cached_anatomy);
  fields[0].keys = no_cached_result;
  AnatomySettings changed = a;
  fields[0].change(changed);
  EXPECT_EQ(key_text(fields, changed, cached_anatomy), key_text(fields, a, cached_anatomy));
  EXPECT_NE(key_text(declared_settings<AnatomySettings>(), changed, cached_anatomy), full);
}
