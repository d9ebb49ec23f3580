#include "core/path_kind.hpp"
#include "scene/parse_sections.hpp"
#include "scene/parse_segmentation.hpp"

namespace phantasm::scene_detail {
namespace {

/// `label`: one label or a list of them, each an integer in [1, 65535] or (atlases) a name of
/// the atlas's label table; names are resolved when the atlas is derived.
void parse_labels(CheckedMap& map, ShapeSettings& shape) {
  const YAML::Node node = map.get("label");
  const std::string path = map.child_path("label");
  const std::string expected =
      shape.atlas.empty() ? "an integer in [1, 65535] or a list of them"
                          : "a label (an integer in [1, 65535] or a name of the atlas's label table) "
                            "or a list of them";
  if (!node.IsDefined()) {
    map.missing("label", expected);
    return;
  }
  std::vector<YAML::Node> items;
  if (node.IsSequence() && node.size() > 0) {
    for (std::size_t i = 0; i < node.size(); ++i)
      items.push_back(node[i]);
  } else if (node.IsScalar()) {
    items.push_back(node);
  } else {
    map.context().problem(node, path, "expected " + expected + ", found " + describe(node));
    return;
  }
  for (std::size_t i = 0; i < items.size(); ++i) {
    const std::string item_path = node.IsSequence() ? path + "[" + std::to_string(i) + "]" : path;
    const YAML::Node& item = items[i];
    const std::string text = item.IsScalar() ? item.Scalar() : std::string();
    const bool number = !text.empty() && text.find_first_not_of("+-0123456789") == std::string::npos;
    const bool name = !text.empty() && !number &&
                      text.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789_") == std::string::npos;
    if (number || shape.atlas.empty()) {
      long long value = 0;
      if (!read_integer(map.context(), item, item_path, 1, 65535, value)) continue;
      map.context().remember(item, item_path);
      if (shape.label == 0) shape.label = static_cast<int>(value);
      shape.labels.push_back(std::to_string(value));
    } else if (name) {
      map.context().remember(item, item_path);
      shape.labels.push_back(text);
    } else {
      map.context().problem(item, item_path, "expected " + expected + ", found " + describe(item));
    }
  }
}

void parse_shape(CheckedMap& map, const std::filesystem::path& scene_folder, ShapeSettings& shape) {
  std::string kind;
  if (!map.choice("type", kind, {"ellipsoid", "superquadric", "box", "sheet", "mesh", "label_volume"},
                  true)) {
    map.accept_remaining_keys();
    return;
  }
  const NumberRule coordinate{-1e5, 1e5, false, false, "mm"};
  if (kind == "ellipsoid" || kind == "superquadric") {
    shape.kind = kind == "ellipsoid" ? ShapeKind::ellipsoid : ShapeKind::superquadric;
    map.vec3("center_mm", shape.center_mm, coordinate, true);
    map.vec3("radii_mm", shape.radii_mm, positive("mm"), true, true);
    map.vec3("rotation_deg", shape.rotation_deg, between(-360.0, 360.0, "degrees"));
    if (shape.kind == ShapeKind::superquadric) {
      // Exponents below 0.1 or above 4 make creases sharper than a patch mesh can follow.
      map.number("exponent_1", shape.exponent_1, between(0.1, 4.0, ""), true);
      map.number("exponent_2", shape.exponent_2, between(0.1, 4.0, ""), true);
    }
    return;
  }
  if (kind == "box" || kind == "sheet") {
    shape.kind = kind == "box" ? ShapeKind::box : ShapeKind::sheet;
    map.vec3("center_mm", shape.center_mm, coordinate, true);
    map.vec3("rotation_deg", shape.rotation_deg, between(-360.0, 360.0, "degrees"));
    const YAML::Node cells = map.get("cells");
    const std::size_t axes = kind == "box" ? 3 : 2;
    const std::string expected = "a list of " + std::to_string(axes) + " integers in [1, 1000]";
    if (kind == "box") {
      map.vec3("size_mm", shape.size_mm, positive("mm"), true);
    } else {
      const YAML::Node size = map.get("size_mm");
      if (!size.IsDefined()) {
        map.missing("size_mm", "a list of 2 numbers in mm greater than 0");
      } else if (!size.IsSequence() || size.size() != 2) {
        map.context().problem(size, map.child_path("size_mm"),
                              "expected a list of 2 numbers in mm greater than 0, found " + describe(size));
      } else {
        for (std::size_t i = 0; i < 2; ++i) {
          read_number(map.context(), size[i], map.child_path("size_mm") + "[" + std::to_string(i) + "]",
                      positive("mm"), shape.size_mm[static_cast<int>(i)]);
        }
        shape.size_mm.z() = 0.0;
      }
    }
    if (!cells.IsDefined()) {
      map.missing("cells", expected);
    } else if (!cells.IsSequence() || cells.size() != axes) {
      map.context().problem(cells, map.child_path("cells"),
                            "expected " + expected + ", found " + describe(cells));
    } else {
      shape.cells.setOnes();
      for (std::size_t i = 0; i < axes; ++i) {
        long long count = 1;
        if (read_integer(map.context(), cells[i], map.child_path("cells") + "[" + std::to_string(i) + "]", 1,
                         1000, count)) {
          shape.cells[static_cast<int>(i)] = static_cast<int>(count);
        }
      }
    }
    return;
  }
  shape.kind = kind == "mesh" ? ShapeKind::mesh : ShapeKind::label_volume;
  if (shape.kind == ShapeKind::label_volume && map.has("atlas")) {
    // A label volume derived at run time from installed data (docs/anatomy-colin27.md).
    map.choice("atlas", shape.atlas, {"colin27"}, true);
    if (map.has("file")) {
      map.context().problem(map.get("file"), map.child_path("file"),
                            "expected either file or atlas, found both");
    }
  } else {
    std::string file;
    if (map.string("file", file, true)) {
      shape.file =
          std::filesystem::path(file).is_absolute() ? std::filesystem::path(file) : scene_folder / file;
      if (const std::string kind_at = path_kind(shape.file); kind_at != "a regular file") {
        map.context().problem(map.get("file"), map.child_path("file"),
                              "expected an existing file, found " +
                                  (kind_at == "no such file" ? std::string("no file") : kind_at) + " at '" +
                                  shape.file.string() + "'");
      } else if (kind == "mesh") {
        const std::string extension = shape.file.extension().string();
        if (extension != ".stl" && extension != ".obj" && extension != ".ply" && extension != ".vtp") {
          map.context().problem(map.get("file"), map.child_path("file"),
                                "expected a .stl, .obj, .ply or .vtp mesh, found '" + extension + "'");
        }
      }
    }
  }
  if (shape.kind == ShapeKind::label_volume) {
    parse_labels(map, shape);
    map.number("smoothing_mm", shape.smoothing_mm, NumberRule{0.0, 10.0, false, false, "mm"});
  }
}

/// The anatomy's settings and its list of organs.
void parse_settings_and_organs(CheckedMap& map, const std::filesystem::path& scene_folder,
                               AnatomySettings& anatomy) {
  map.number("variation", anatomy.variation, between(0.0, 0.3, "relative size"));
  map.integer("base_mesh_triangles", anatomy.base_mesh_triangles, 20, 200000);
  map.number("tet_size_mm", anatomy.tet_size_mm, between(0.5, 500.0, "mm"));
  map.number("tet_facet_distance_mm", anatomy.tet_facet_distance_mm, between(0.05, 100.0, "mm"));
  std::string interfaces;
  if (map.choice("tet_interfaces", interfaces, {"organs", "materials"}))
    anatomy.tet_interfaces = interfaces == "materials" ? TetInterfaces::materials : TetInterfaces::organs;
  for (const char* key : {"tet_facet_distance_mm", "tet_interfaces"}) {
    if (map.has(key) && !(anatomy.tet_size_mm > 0.0)) {
      map.context().problem(
          map.get(key), map.child_path(key),
          "expected anatomy.tet_size_mm beside it (it shapes the tet meshes of that size), found "
          "no anatomy.tet_size_mm");
    }
  }
  const YAML::Node organs = map.get("organs");
  const std::string path = map.child_path("organs");
  if (!organs.IsDefined() && map.has("segmentation")) return; // the segmentation's organs alone
  if (!organs.IsDefined()) {
    map.missing("organs", "a list of organs");
    return;
  }
  if (!organs.IsSequence() || organs.size() == 0) {
    map.context().problem(organs, path, "expected a non-empty list of organs, found " + describe(organs));
    return;
  }
  for (std::size_t i = 0; i < organs.size(); ++i) {
    CheckedMap entry(map.context(), organs[i], path + "[" + std::to_string(i) + "]");
    if (!entry.valid()) continue;
    OrganSettings organ;
    if (entry.string("name", organ.name, true))
      check_name(map.context(), entry.get("name"), entry.child_path("name"), organ.name);
    if (entry.string("tissue", organ.tissue, true))
      check_name(map.context(), entry.get("tissue"), entry.child_path("tissue"), organ.tissue);
    entry.string("material", organ.material);
    entry.string("inside", organ.inside);
    entry.boolean("solid", organ.solid);
    entry.integer("base_mesh_triangles", organ.base_mesh_triangles, 20, 200000);
    entry.number("thickness_mm", organ.thickness_mm, NumberRule{0.0, 1e3, true, false, "mm"});
    if (entry.has("enclosed_volume_tolerance")) {
      double tolerance = 0.0;
      if (entry.number("enclosed_volume_tolerance", tolerance, NumberRule{0.0, 0.5, false, false, ""}))
        organ.enclosed_volume_tolerance = tolerance;
    }
    if (entry.has("shape")) {
      CheckedMap shape(map.context(), entry.get("shape"), entry.child_path("shape"));
      if (shape.valid()) parse_shape(shape, scene_folder, organ.shape);
    } else {
      entry.missing("shape", "a mapping with a type (ellipsoid, superquadric, mesh, label_volume)");
    }
    anatomy.organs.push_back(organ);
  }
}

} // namespace

void parse_anatomy(CheckedMap& map, const std::filesystem::path& scene_folder, AnatomySettings& anatomy) {
  parse_settings_and_organs(map, scene_folder, anatomy);
  if (map.has("segmentation")) {
    // Its organs follow those of the list, which keep their indices (and key paths).
    CheckedMap segmentation(map.context(), map.get("segmentation"), map.child_path("segmentation"));
    if (segmentation.valid()) parse_segmentation(segmentation, scene_folder, anatomy);
  }
}

} // namespace phantasm::scene_detail
