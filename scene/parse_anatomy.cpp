#include "anatomy/shape_source.hpp"
#include "core/path_kind.hpp"
#include "scene/declared_keys.hpp"
#include "scene/parse_sections.hpp"
#include "scene/parse_segmentation.hpp"

#include <algorithm>

namespace phantasm::scene_detail {
namespace {

/// `label`: one label or a list of them, each an integer in [1, 65535] or (atlases) a name of
/// the atlas's label table; names are resolved when the atlas is derived.
void parse_labels(CheckedMap& map, ShapeSettings& shape) {
  const YAML::Node node = map.get("label");
  const std::string path = map.child_path("label");
  const NumberRule rule = declared_rule<ShapeSettings>("label");
  const std::string integer = rule.describe_integer();
  const std::string expected =
      shape.atlas.empty()
          ? integer + " or a list of them"
          : "a label (" + integer + " or a name of the atlas's label table) or a list of them";
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
      if (!read_integer(map.context(), item, item_path, static_cast<long long>(rule.min),
                        static_cast<long long>(rule.max), value))
        continue;
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

/// A parameter's range for messages.
NumberRule rule_of(const ShapeParameter& p) {
  return NumberRule{p.min, p.max, p.min_exclusive, p.max_exclusive, p.unit};
}

/// Kind::extent2: two numbers into x and y, z set to 0.
void parse_extent2(CheckedMap& map, const ShapeParameter& p, ShapeSettings& shape) {
  const NumberRule rule = rule_of(p);
  const std::string expected = "a list of 2 numbers" + rule.describe().substr(std::string("a number").size());
  const YAML::Node size = map.get(p.key);
  if (!size.IsDefined()) {
    if (p.required) map.missing(p.key, expected);
  } else if (!size.IsSequence() || size.size() != 2) {
    map.context().problem(size, map.child_path(p.key), "expected " + expected + ", found " + describe(size));
  } else {
    for (std::size_t i = 0; i < 2; ++i) {
      read_number(map.context(), size[i], map.child_path(p.key) + "[" + std::to_string(i) + "]", rule,
                  (shape.*p.vector)[static_cast<int>(i)]);
    }
    (shape.*p.vector).z() = 0.0;
  }
}

/// Kind::cells: `axes` integers in the declared bounds of `cells`, the other axes 1.
void parse_cells(CheckedMap& map, const ShapeParameter& p, ShapeSettings& shape) {
  const YAML::Node cells = map.get(p.key);
  const std::size_t axes = static_cast<std::size_t>(p.axes);
  const NumberRule rule = declared_rule<ShapeSettings>("cells");
  const std::string expected = "a list of " + std::to_string(axes) + " integers" +
                               rule.describe_integer().substr(std::string("an integer").size());
  if (!cells.IsDefined()) {
    if (p.required) map.missing(p.key, expected);
  } else if (!cells.IsSequence() || cells.size() != axes) {
    map.context().problem(cells, map.child_path(p.key),
                          "expected " + expected + ", found " + describe(cells));
  } else {
    shape.cells.setOnes();
    for (std::size_t i = 0; i < axes; ++i) {
      long long count = 1;
      if (read_integer(map.context(), cells[i], map.child_path(p.key) + "[" + std::to_string(i) + "]",
                       static_cast<long long>(rule.min), static_cast<long long>(rule.max), count)) {
        shape.cells[static_cast<int>(i)] = static_cast<int>(count);
      }
    }
  }
}

/// Kind::file: an existing file relative to the scene's folder (of the accepted extensions), or,
/// where allowed, an atlas instead.
void parse_file(CheckedMap& map, const ShapeParameter& p, const std::filesystem::path& scene_folder,
                ShapeSettings& shape) {
  if (p.atlas_allowed && map.has("atlas")) {
    // A label volume derived at run time from installed data (docs/anatomy-colin27.md).
    map.choice("atlas", shape.atlas, {"colin27"}, true);
    if (map.has(p.key)) {
      map.context().problem(map.get(p.key), map.child_path(p.key),
                            "expected either file or atlas, found both");
    }
    return;
  }
  std::string file;
  if (!map.string(p.key, file, p.required)) return;
  shape.file = std::filesystem::path(file).is_absolute() ? std::filesystem::path(file) : scene_folder / file;
  if (const std::string kind_at = path_kind(shape.file); kind_at != "a regular file") {
    map.context().problem(map.get(p.key), map.child_path(p.key),
                          "expected an existing file, found " +
                              (kind_at == "no such file" ? std::string("no file") : kind_at) + " at '" +
                              shape.file.string() + "'");
  } else if (!p.extensions.empty()) {
    const std::string extension = shape.file.extension().string();
    if (std::find(p.extensions.begin(), p.extensions.end(), extension) == p.extensions.end()) {
      std::string accepted;
      for (std::size_t i = 0; i < p.extensions.size(); ++i)
        accepted += (i == 0 ? "" : i + 1 == p.extensions.size() ? " or " : ", ") + p.extensions[i];
      map.context().problem(map.get(p.key), map.child_path(p.key),
                            "expected a " + accepted + " mesh, found '" + extension + "'");
    }
  }
}

/// A shape: its type, then the keys its member of the shape source registry reads.
void parse_shape(CheckedMap& map, const std::filesystem::path& scene_folder, ShapeSettings& shape) {
  std::string kind;
  if (!map.choice("type", kind, shape_source_names(), true)) {
    map.accept_remaining_keys();
    return;
  }
  const ShapeSource& source = *find_shape_source(kind);
  shape.kind = source.kind;
  for (const ShapeParameter& p : source.parameters) {
    switch (p.kind) {
    case ShapeParameter::Kind::vector3:
      map.vec3(p.key, shape.*p.vector, rule_of(p), p.required, p.scalar_allowed);
      break;
    case ShapeParameter::Kind::extent2: parse_extent2(map, p, shape); break;
    case ShapeParameter::Kind::cells: parse_cells(map, p, shape); break;
    case ShapeParameter::Kind::number: map.number(p.key, shape.*p.number, rule_of(p), p.required); break;
    case ShapeParameter::Kind::file: parse_file(map, p, scene_folder, shape); break;
    case ShapeParameter::Kind::labels: parse_labels(map, shape); break;
    }
  }
}

/// The anatomy's settings and its list of organs.
void parse_settings_and_organs(CheckedMap& map, const std::filesystem::path& scene_folder,
                               AnatomySettings& anatomy) {
  read_declared(map, anatomy);
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
    for (const char* key : {"name", "tissue"}) // names that reach file names
      if (read_declared_keys(entry, organ, {key}).count(key))
        check_name(map.context(), entry.get(key), entry.child_path(key),
                   key[0] == 'n' ? organ.name : organ.tissue);
    read_declared(entry, organ, {"name", "tissue"});
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
