// The settings declarations (scene/settings_declarations.hpp): every member of every settings
// struct belongs to a declared field, each declared once, with a help text; and the table
// `phantasm info --settings` prints names every one.

#include "scene/scene_json.hpp"
#include "scene/settings_declarations.hpp"

#include <gtest/gtest.h>

#include <set>

using namespace phantasm;

namespace {

/// Every member of S is the member of a declared field, and every declared field's member is a
/// member of S; names are unique and each field has a type and help.
template <typename S>
void expect_every_member_declared() {
  const S s{};
  const std::vector<const void*> members = settings_members(s);
  const std::set<const void*> all(members.begin(), members.end());
  std::set<const void*> declared;
  std::set<std::string> names;
  for (const SettingField<S>& field : declared_settings<S>()) {
    SCOPED_TRACE(field.name);
    EXPECT_TRUE(all.count(field.member(s))) << "declares no member of the struct";
    declared.insert(field.member(s));
    EXPECT_TRUE(names.insert(field.name).second) << "declared twice";
    EXPECT_FALSE(field.type.empty());
    EXPECT_FALSE(field.help.empty());
    EXPECT_TRUE(field.exact && field.shown && field.change);
  }
  EXPECT_EQ(declared.size(), all.size()) << "a member of the struct is declared by no field";
}

} // namespace

TEST(SettingsDeclarations, EveryMemberOfEverySettingsStructIsDeclared) {
  expect_every_member_declared<GridSettings>();
  expect_every_member_declared<ShapeSettings>();
  expect_every_member_declared<OrganSettings>();
  expect_every_member_declared<AnatomySettings>();
  expect_every_member_declared<VoxelizationSettings>();
  expect_every_member_declared<TissueOverride>();
  expect_every_member_declared<SequenceSettings>();
  expect_every_member_declared<AcquisitionSettings>();
  expect_every_member_declared<MriSettings>();
  expect_every_member_declared<OutputSettings>();
}

// The members by structured binding are the struct's: as many as its size holds at least, and
// distinct.
TEST(SettingsDeclarations, MembersAreDistinctAndInsideTheStruct) {
  const AcquisitionSettings s{};
  const std::vector<const void*> members = settings_members(s);
  EXPECT_EQ(std::set<const void*>(members.begin(), members.end()).size(), members.size());
  for (const void* m : members) {
    EXPECT_GE(static_cast<const char*>(m), reinterpret_cast<const char*>(&s));
    EXPECT_LT(static_cast<const char*>(m), reinterpret_cast<const char*>(&s) + sizeof(s));
  }
}

// A nested struct's and a list's fields are named by their path and written over the elements.
TEST(SettingsDeclarations, ListsAndNestedStructsAreWrittenOverTheirElements) {
  AnatomySettings a;
  a.organs.resize(2);
  a.organs[0].name = "scalp";
  a.organs[1].name = "brain";
  a.organs[1].shape.radii_mm = Eigen::Vector3d(1, 2, 3);
  std::map<std::string, std::string> text;
  for (const SettingField<AnatomySettings>& field : declared_settings<AnatomySettings>())
    text[field.name] = field.exact(a);
  EXPECT_EQ(text.at("organs"), "2");
  EXPECT_EQ(text.at("organs[].name"), "[5:scalp 5:brain]");
  EXPECT_EQ(text.at("organs[].shape.radii_mm"), "[[0x1p+0 0x1p+0 0x1p+0] [0x1p+0 0x1p+1 0x1.8p+1]]");
  EXPECT_EQ(keys_changed_by(cached_anatomy),
            unsigned{cached_anatomy | cached_reference_state | cached_reference_images});
  EXPECT_EQ(keys_changed_by(cached_reference_images), unsigned{cached_reference_images});
}

TEST(SettingsDeclarations, TheTableNamesEverySettingWithItsDefaultAndCaches) {
  Scene scene;
  scene.voxelization.supersampling = 6;
  const std::vector<std::string> rows = settings_table(scene);
  const auto row_of = [&](const std::string& name) {
    for (const std::string& row : rows)
      if (row.rfind(name + " = ", 0) == 0) return row;
    return std::string();
  };
  EXPECT_EQ(
      row_of("voxelization.supersampling"),
      "voxelization.supersampling = 6  (integer, 1 to 16, default 4; shapes reference state)  samples per "
      "voxel edge of the partial-volume fractions");
  EXPECT_NE(row_of("mri.acquisition.coils").find("shapes reference images"), std::string::npos);
  EXPECT_NE(row_of("outputs.vdb").find("shapes no cache"), std::string::npos);
  EXPECT_EQ(rows.size(),
            declared_settings<GridSettings>().size() + declared_settings<AnatomySettings>().size() +
                declared_settings<VoxelizationSettings>().size() + declared_settings<MriSettings>().size() +
                declared_settings<OutputSettings>().size());
}

// provenance.json's sections written from the declarations: numbers keep their fraction, text is
// escaped, and only a section's own keys are written (gap_tissue is the deformation's key).
TEST(SettingsDeclarations, ProvenanceSectionsAreWrittenFromTheDeclarations) {
  Scene scene;
  scene.grid.orientation = "L\"PS\n";
  scene.voxelization.gap_tissue = "csf";
  const nlohmann::json settings = scene_settings_json(scene);
  EXPECT_EQ(settings.at("grid").dump(),
            R"({"center_mm":[0.0,0.0,0.0],"field_of_view_mm":[256.0,256.0,256.0],"orientation":"L\"PS\n",)"
            R"("voxel_size_mm":[1.0,1.0,1.0]})");
  EXPECT_EQ(settings.at("voxelization").dump(), R"({"supersampling":4,"tessellation_tolerance_mm":0.2})");
  EXPECT_EQ(settings.at("anatomy").size(), 6u); // five settings and the organs
  EXPECT_EQ(settings.at("outputs").size(), declared_settings<OutputSettings>().size());
  EXPECT_EQ(json_number(0.1), "0.10000000000000001");
  EXPECT_EQ(nlohmann::json::parse(json_number(0.1)).get<double>(), 0.1);
}
