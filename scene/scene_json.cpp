#include "scene/scene_json.hpp"

#include "anatomy/shape_source.hpp"
#include "mri/sequence_type.hpp"
#include "scene/settings_declarations.hpp"
#include "sim/load_type.hpp"

#include <variant>

namespace phantasm {
namespace {

/// The settings of a section that its struct's declarations write (scene/settings_declarations.cpp):
/// every field of the section's own keys, but not its lists, nested structs or derived values.
template <typename S>
nlohmann::json declared_json(const S& settings) {
  nlohmann::json j = nlohmann::json::object();
  for (const SettingField<S>& f : declared_settings<S>())
    if (!f.derived && f.in_section && f.type != "list" && f.name.find_first_of(".[") == std::string::npos)
      j[f.name] = nlohmann::json::parse(f.json(settings));
  return j;
}

nlohmann::json vec3(const Eigen::Vector3d& v) {
  return nlohmann::json::array({v.x(), v.y(), v.z()});
}

/// A shape's settings: its type and the keys its member of the shape source registry reads.
nlohmann::json shape_json(const ShapeSettings& shape) {
  nlohmann::json j = {{"type", to_string(shape.kind)}};
  for (const ShapeParameter& p : shape_source(shape.kind).parameters) {
    switch (p.kind) {
    case ShapeParameter::Kind::vector3:
    case ShapeParameter::Kind::extent2: j[p.key] = vec3(shape.*p.vector); break;
    case ShapeParameter::Kind::cells: j[p.key] = {shape.cells.x(), shape.cells.y(), shape.cells.z()}; break;
    case ShapeParameter::Kind::number: j[p.key] = shape.*p.number; break;
    case ShapeParameter::Kind::file:
      if (shape.atlas.empty())
        j[p.key] = shape.file.string();
      else
        j["atlas"] = shape.atlas;
      break;
    case ShapeParameter::Kind::labels:
      if (shape.atlas.empty() && shape.labels.size() <= 1)
        j[p.key] = shape.label;
      else
        j[p.key] = shape.labels;
      break;
    }
  }
  return j;
}

nlohmann::json organ_json(const OrganSettings& organ) {
  const nlohmann::json shape = shape_json(organ.shape);
  return {{"name", organ.name},
          {"tissue", organ.tissue},
          {"material", organ.material},
          {"inside", organ.inside},
          {"solid", organ.solid},
          {"thickness_mm", organ.thickness_mm},
          {"enclosed_volume_tolerance", organ.enclosed_volume_tolerance
                                            ? nlohmann::json(*organ.enclosed_volume_tolerance)
                                            : nlohmann::json(nullptr)},
          {"base_mesh_triangles", organ.base_mesh_triangles},
          {"shape", shape}};
}

/// A load's settings: its type and the keys its member of the load type registry records (a key
/// of a nested mapping under the mapping's key).
nlohmann::json load_json(const LoadSettings& load) {
  const LoadType& type = load_type(load.kind);
  nlohmann::json j = {{"type", type.name}};
  for (const LoadParameter& p : type.parameters) {
    if (p.recorded != nullptr && !p.recorded(load)) continue;
    const std::string path = p.key;
    const std::size_t dot = path.find('.');
    nlohmann::json& value = dot == std::string::npos ? j[path] : j[path.substr(0, dot)][path.substr(dot + 1)];
    switch (p.kind) {
    case LoadParameter::Kind::number: value = load.*p.number; break;
    case LoadParameter::Kind::vector3: value = vec3(load.*p.vector); break;
    case LoadParameter::Kind::organ:
    case LoadParameter::Kind::choice: value = load.*p.text; break;
    case LoadParameter::Kind::organs:
    case LoadParameter::Kind::name_or_names: value = load.*p.names; break;
    case LoadParameter::Kind::motion: value = to_string(load.motion); break;
    case LoadParameter::Kind::mapping: value = nlohmann::json::object(); break;
    }
  }
  return j;
}

nlohmann::json sequence_json(const SequenceSettings& s) {
  const SequenceType& type = sequence_type(s.kind);
  nlohmann::json j = {{"name", s.name}, {"type", type.name}, {"TR_ms", s.TR_ms}, {"TE_ms", s.TE_ms}};
  for (const auto& [key, value] : type.provenance(s))
    j[key] = sequence_value_json(value);
  return j;
}

} // namespace

nlohmann::json sequence_value_json(const SequenceValue& value) {
  return std::visit([](const auto& v) { return nlohmann::json(v); }, value);
}

nlohmann::json scene_settings_json(const Scene& scene) {
  nlohmann::json materials = nlohmann::json::object();
  for (const auto& m : scene.deformation.materials) {
    nlohmann::json& material = materials[m.name] = declared_json(m);
    material.erase("name"); // the material's key
  }
  nlohmann::json tissues = nlohmann::json::object();
  for (const auto& t : scene.mri.tissues) {
    nlohmann::json& tissue = tissues[t.tissue] = declared_json(t);
    tissue.erase("tissue"); // the tissue's key
  }
  nlohmann::json organs = nlohmann::json::array();
  for (const auto& organ : scene.anatomy.organs)
    organs.push_back(organ_json(organ));
  nlohmann::json loads = nlohmann::json::array();
  for (const auto& load : scene.deformation.loads)
    loads.push_back(load_json(load));
  nlohmann::json collisions = nlohmann::json::array();
  for (const auto& c : scene.deformation.collisions)
    collisions.push_back(declared_json(c));
  nlohmann::json obstacles = nlohmann::json::array();
  for (const auto& o : scene.deformation.obstacles) {
    nlohmann::json j = {{"type", to_string(o.shape)},
                        {"displacement_mm", vec3(o.displacement_mm)},
                        {"motion", to_string(o.motion)},
                        {"period_s", o.period_s}};
    if (o.shape == ObstacleShape::half_space) {
      j["point_mm"] = vec3(o.point_mm);
      j["normal"] = vec3(o.normal);
    } else {
      j["center_mm"] = vec3(o.point_mm);
      j["radius_mm"] = o.radius_mm;
    }
    obstacles.push_back(j);
  }
  nlohmann::json sequences = nlohmann::json::array();
  for (const auto& s : scene.mri.sequences)
    sequences.push_back(sequence_json(s));
  nlohmann::json regions = nlohmann::json::array();
  for (const auto& r : scene.mri.regions)
    regions.push_back(declared_json(r));

  const DeformationSettings& d = scene.deformation;
  nlohmann::json anatomy = declared_json(scene.anatomy);
  anatomy["organs"] = organs;
  nlohmann::json deformation = declared_json(d);
  deformation["solver"] = declared_json(d.solver);
  deformation["head_scale"] = declared_json(d.head_scale);
  deformation["loads"] = loads;
  deformation["obstacles"] = obstacles;
  deformation["collisions"] = collisions;
  deformation["gap_tissue"] = scene.voxelization.gap_fill; // the gap's tissue as resolved
  nlohmann::json acquisition = declared_json(scene.mri.acquisition);
  if (!scene.mri.acquisition.receiver_gain) acquisition["receiver_gain"] = "automatic"; // as the docs name it
  return {
      {"name", scene.name},
      {"seed", scene.seed},
      {"field_strength_T", scene.mri.field_strength_T},
      {"grid", declared_json(scene.grid)},
      {"materials", materials},
      {"tissues", tissues},
      {"anatomy", anatomy},
      {"deformation", deformation},
      {"voxelization", declared_json(scene.voxelization)},
      {"sequences", sequences},
      {"tissue_regions", regions},
      {"texture", declared_json(scene.mri.texture)},
      {"acquisition", acquisition},
      {"outputs", declared_json(scene.outputs)},
  };
}

} // namespace phantasm
