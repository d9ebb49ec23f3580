// The settings declarations (scene/settings_declarations.hpp): every member of every settings
// struct belongs to a declared field, each declared once, with a help text; and the table
// `phantasm info --settings` prints names every one.

#include "scene/scene_json.hpp"
#include "scene/settings_declarations.hpp"
#include "sim/load_type.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>

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
  expect_every_member_declared<MaterialSettings>();
  expect_every_member_declared<SolverSettings>();
  expect_every_member_declared<LoadSettings>();
  expect_every_member_declared<ObstacleSettings>();
  expect_every_member_declared<CollisionSettings>();
  expect_every_member_declared<OrganMechanics>();
  expect_every_member_declared<DeformationSettings>();
}

// A load's settings are declared from the load type registry: its scene keys, units and bounds,
// and the types that read each.
TEST(SettingsDeclarations, LoadSettingsAreDeclaredFromTheLoadTypeRegistry) {
  std::map<std::string, const SettingField<LoadSettings>*> fields;
  for (const SettingField<LoadSettings>& field : declared_settings<LoadSettings>())
    fields[field.name] = &field;
  for (const LoadType* type : load_types()) {
    for (const LoadParameter& p : type->parameters) {
      SCOPED_TRACE(std::string(type->name) + " " + p.key);
      if (p.kind == LoadParameter::Kind::mapping) continue;
      ASSERT_TRUE(fields.count(p.key)) << "a scene key of a load type that no declared setting has";
      EXPECT_EQ(fields.at(p.key)->unit, p.unit);
      EXPECT_NE(fields.at(p.key)->help.find(type->name), std::string::npos);
      // The bounds the parser checks (the parameter's) are the declared ones.
      if (p.kind == LoadParameter::Kind::number || p.kind == LoadParameter::Kind::vector3) {
        ASSERT_TRUE(fields.at(p.key)->rule);
        const NumberRule& rule = *fields.at(p.key)->rule;
        EXPECT_EQ(rule.min, p.min);
        EXPECT_EQ(rule.max, p.max);
        EXPECT_EQ(rule.min_exclusive, p.min_exclusive);
        EXPECT_EQ(rule.max_exclusive, p.max_exclusive);
      }
    }
  }
  EXPECT_EQ(fields.at("volume_change")->bounds, "above -1 to 10");
  EXPECT_EQ(fields.at("region.radius_mm")->bounds, "above 0");
  EXPECT_EQ(fields.at("rotation.axis")->bounds, "-1e6 to 1e6, not zero");
  EXPECT_EQ(fields.at("organ")->help, "displacement, growth: the organ it acts on");
  EXPECT_EQ(fields.at("type")->keys, unsigned{cached_body_meshes});
  EXPECT_EQ(fields.at("acceleration_m_s2")->keys, unsigned{no_cached_result});
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
            unsigned{cached_anatomy | cached_reference_state | cached_reference_images | cached_body_meshes});
  EXPECT_EQ(keys_changed_by(cached_reference_images), unsigned{cached_reference_images});
  EXPECT_EQ(keys_changed_by(cached_body_meshes), unsigned{cached_body_meshes});
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
  EXPECT_EQ(row_of("deformation.loads[].organ"),
            "deformation.loads[].organ = []  (text, an organ that is not fixed; shapes body mesh)  "
            "displacement, growth: the organ it acts on");
  EXPECT_NE(row_of("deformation.solver.max_iterations").find("default 2000; shapes no cache"),
            std::string::npos);
  EXPECT_EQ(rows.size(),
            declared_settings<GridSettings>().size() + declared_settings<AnatomySettings>().size() +
                declared_settings<DeformationSettings>().size() +
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
  EXPECT_EQ(settings.at("deformation").at("solver").dump(),
            R"({"max_iterations":2000,"method":"local_global","position_tolerance_mm":0.0001,)"
            R"("relative_energy_tolerance":1e-06,"relative_residual_tolerance":0.001,"threads":0})");
  EXPECT_EQ(settings.at("deformation").at("mode"), "none");
  EXPECT_EQ(settings.at("deformation").at("time_step_s").dump(), nlohmann::json(1.0 / 30.0).dump());
  EXPECT_EQ(settings.at("deformation").at("gap_tissue"), scene.voxelization.gap_fill); // as resolved
  EXPECT_EQ(settings.at("deformation").at("head_scale").dump(),
            R"({"axes":[1.0,1.0,1.0],"center_mm":null,"scale":1.0})");
  // six settings, the solver, the head's scale, three lists, the gap
  EXPECT_EQ(settings.at("deformation").size(), 12u);
  EXPECT_EQ(settings.at("acquisition").at("receiver_gain"), "automatic");
  EXPECT_TRUE(settings.at("acquisition").at("acquired_voxel_mm").is_null());
  EXPECT_EQ(settings.at("acquisition").at("image_datatype"), "float32");
  Scene listed;
  listed.mri.regions = {{"scalp", "subcutaneous_fat", "fat_subcutaneous", ""},
                        {"grey_matter", "csf", "csf", "sulcal_csf"}};
  listed.mri.tissues.push_back(TissueOverride{"gel", 1000.0, std::nullopt, std::nullopt, 1.0});
  listed.deformation.materials.push_back(MaterialSettings{"gel", 3000.0, 0.45, 1000.0});
  listed.deformation.collisions.push_back(CollisionSettings{{"a", "b"}});
  const nlohmann::json lists = scene_settings_json(listed);
  EXPECT_EQ(lists.at("tissue_regions").dump(),
            R"([{"label":"subcutaneous_fat","name":"","organ":"scalp","tissue":"fat_subcutaneous"},)"
            R"({"label":"csf","name":"sulcal_csf","organ":"grey_matter","tissue":"csf"}])");
  EXPECT_EQ(lists.at("tissues").dump(), R"({"gel":{"PD":1.0,"T1_ms":1000.0,"T2_ms":null,"T2star_ms":null}})");
  EXPECT_EQ(lists.at("materials").dump(),
            R"({"gel":{"density_kg_m3":1000.0,"poisson_ratio":0.45,"youngs_modulus_Pa":3000.0}})");
  EXPECT_EQ(lists.at("deformation").at("collisions").dump(), R"([{"organs":["a","b"]}])");
  EXPECT_EQ(json_number(0.1), "0.10000000000000001");
  EXPECT_EQ(nlohmann::json::parse(json_number(0.1)).get<double>(), 0.1);
}

namespace {

/// The rows of the tables of docs/scene-format.md by the title of the section ("## `grid`") they
/// are in.
std::map<std::string, std::string> docs_tables() {
  std::ifstream file(std::filesystem::path(PHANTASM_SOURCE_DIR) / "docs" / "scene-format.md");
  std::map<std::string, std::string> tables;
  std::string section, line;
  while (std::getline(file, line)) {
    if (line.rfind("## ", 0) == 0) section = line.substr(3);
    if (line.rfind("|", 0) == 0) tables[section] += line + "\n";
  }
  return tables;
}

/// A setting's scene key: the last part of its name ("organs[].shape.radii_mm": radii_mm).
std::string scene_key(const std::string& name) {
  const std::size_t dot = name.find_last_of('.');
  return dot == std::string::npos ? name : name.substr(dot + 1);
}

/// Every declared setting of S that the scene file gives in its own section (not one the scene
/// derives, nor a key of another section), but those of `skipped`, has its key in a row of the
/// tables of the docs' section `section(name)`.
template <typename S>
void expect_documented(const std::map<std::string, std::string>& tables,
                       const std::function<std::string(const std::string&)>& section,
                       const std::set<std::string>& skipped = {}) {
  for (const SettingField<S>& field : declared_settings<S>()) {
    if (field.derived || !field.in_section || skipped.count(field.name)) continue;
    const std::string title = section(field.name);
    SCOPED_TRACE(field.name + " in the section " + title);
    ASSERT_TRUE(tables.count(title)) << "no table in that section";
    EXPECT_NE(tables.at(title).find("`" + scene_key(field.name) + "`"), std::string::npos)
        << "a declared setting that the docs' table does not name";
  }
}

} // namespace

// The docs' tables (docs/scene-format.md) name every declared setting of the scene file in the
// section it is written in, so that they cannot fall behind the declarations.
TEST(SettingsDeclarations, TheDocsTablesNameEveryDeclaredSetting) {
  const std::map<std::string, std::string> tables = docs_tables();
  ASSERT_FALSE(tables.empty()) << "docs/scene-format.md not read";
  const auto in = [](const std::string& title) {
    return [title](const std::string&) { return "`" + title + "`"; };
  };
  expect_documented<GridSettings>(tables, in("grid"));
  // A shape's labels are its key label given as a list.
  expect_documented<AnatomySettings>(tables, in("anatomy"), {"organs[].shape.labels"});
  expect_documented<VoxelizationSettings>(tables, in("voxelization"));
  expect_documented<DeformationSettings>(tables, in("deformation"));
  // A material's and a tissue's name is its key.
  expect_documented<MaterialSettings>(tables, in("materials"), {"name"});
  expect_documented<TissueOverride>(tables, in("tissues"), {"tissue"});
  expect_documented<OutputSettings>(tables, in("outputs"));
  // The MRI settings are written in sections of their own: the lists' keys at the top level.
  expect_documented<MriSettings>(tables,
                                 [](const std::string& name) -> std::string {
                                   if (name.find_first_of(".[") == std::string::npos) return "Top level";
                                   const std::string first = name.substr(0, name.find_first_of(".["));
                                   if (first == "regions" || first == "texture")
                                     return "`tissue_regions` and `texture`";
                                   return "`" + first + "`";
                                 },
                                 {"regions", "tissues[].tissue"});
  EXPECT_NE(tables.at("Top level").find("`tissue_regions`"), std::string::npos);
}
