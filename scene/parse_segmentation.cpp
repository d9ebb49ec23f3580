#include "scene/parse_segmentation.hpp"

#include "core/error.hpp"
#include "core/path_kind.hpp"
#include "io/nifti_file.hpp"
#include "io/segmentation.hpp"
#include "scene/declared_keys.hpp"

#include <fstream>
#include <set>
#include <sstream>
#include <tuple>

namespace phantasm::scene_detail {
namespace {

/// An organ of a mapping: the table names whose labels it takes.
struct MappedOrgan {
  std::string name;
  std::string tissue;
  std::string inside; ///< the mapping's organ that contains it; empty for the outermost
  bool solid = false;
  std::vector<std::string> names;
  std::string material = std::string(); ///< a key of the scene's materials; empty for none
  YAML::Node at = YAML::Node();         ///< its entry in the scene (a list mapping), else undefined
};

/// FreeSurfer's structures (the aseg names of FreeSurferColorLUT.txt, which SynthSeg shares) as
/// organs nested like the Colin head's (docs/scene-format.md, `anatomy.segmentation`): the
/// intracranial CSF holds the brain and is the one solid organ; the cortex holds the cerebral
/// white matter, which holds the lateral ventricles and the deep grey nuclei.
std::vector<MappedOrgan> freesurfer_mapping() {
  std::vector<MappedOrgan> organs = {
      {"csf", "csf", "", true, {"CSF", "3rd-Ventricle", "4th-Ventricle", "5th-Ventricle", "Optic-Chiasm"}},
      {"grey_matter", "gray_matter", "csf", false, {"Left-Cerebral-Cortex", "Right-Cerebral-Cortex"}},
      {"white_matter",
       "white_matter",
       "grey_matter",
       false,
       {"Left-Cerebral-White-Matter", "Right-Cerebral-White-Matter", "WM-hypointensities",
        "Left-WM-hypointensities", "Right-WM-hypointensities", "non-WM-hypointensities",
        "Left-non-WM-hypointensities", "Right-non-WM-hypointensities", "Left-vessel", "Right-vessel",
        "CC_Posterior", "CC_Mid_Posterior", "CC_Central", "CC_Mid_Anterior", "CC_Anterior"}},
      {"brainstem", "white_matter", "csf", false, {"Brain-Stem"}},
  };
  // name, tissue, container, the table's names after "Left-" or "Right-"
  const std::vector<MappedOrgan> sided = {
      {"lateral_ventricle",
       "csf",
       "white_matter",
       false,
       {"Lateral-Ventricle", "Inf-Lat-Vent", "choroid-plexus"}},
      {"thalamus", "gray_matter", "white_matter", false, {"Thalamus", "Thalamus-Proper"}},
      {"caudate", "gray_matter", "white_matter", false, {"Caudate"}},
      {"putamen", "gray_matter", "white_matter", false, {"Putamen"}},
      {"pallidum", "gray_matter", "white_matter", false, {"Pallidum"}},
      {"accumbens", "gray_matter", "white_matter", false, {"Accumbens-area"}},
      {"ventral_dc", "gray_matter", "white_matter", false, {"VentralDC"}},
      {"hippocampus", "gray_matter", "grey_matter", false, {"Hippocampus"}},
      {"amygdala", "gray_matter", "grey_matter", false, {"Amygdala"}},
      {"cerebellum", "gray_matter", "csf", false, {"Cerebellum-Cortex"}},
      {"cerebellum_white_matter", "white_matter", "", false, {"Cerebellum-White-Matter"}},
  };
  for (const char* side : {"left", "right"}) {
    const std::string prefix = side[0] == 'l' ? "Left-" : "Right-";
    for (MappedOrgan organ : sided) {
      organ.inside = organ.inside.empty() ? std::string(side) + "_cerebellum" : organ.inside;
      organ.name = std::string(side) + "_" + organ.name;
      for (std::string& name : organ.names)
        name = prefix + name;
      organs.push_back(organ);
    }
  }
  return organs;
}

std::string trimmed(const std::string& text) {
  const std::size_t first = text.find_first_not_of(" \t\r");
  if (first == std::string::npos) return "";
  return text.substr(first, text.find_last_not_of(" \t\r") - first + 1);
}

std::vector<std::string> split_tabs(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream stream(line);
  for (std::string field; std::getline(stream, field, '\t');)
    fields.push_back(trimmed(field));
  return fields;
}

/// A label value in [1, 65535] (0 is the background), or -1.
long long label_value(const std::string& text) {
  if (text.empty() || text.size() > 6 || text.find_first_not_of("0123456789") != std::string::npos) return -1;
  const long long value = std::stoll(text);
  return value <= 65535 ? value : -1;
}

/// Whether `name` matches the shell-style pattern: `*` any run of characters (none too), `?` any
/// one character, every other character itself.
bool matches(const std::string& pattern, const std::string& name) {
  std::size_t p = 0, n = 0, star = std::string::npos, resume = 0;
  while (n < name.size()) {
    if (p < pattern.size() && (pattern[p] == '?' || pattern[p] == name[n])) {
      ++p;
      ++n;
    } else if (p < pattern.size() && pattern[p] == '*') {
      star = p++;
      resume = n;
    } else if (star != std::string::npos) {
      p = star + 1;
      n = ++resume;
    } else {
      return false;
    }
  }
  while (p < pattern.size() && pattern[p] == '*')
    ++p;
  return p == pattern.size();
}

bool is_pattern(const std::string& name) {
  return name.find_first_of("*?") != std::string::npos;
}

/// The mapping's organs: the built-in `freesurfer`, or a list of {organ, tissue, material, inside, solid,
/// labels}.
std::vector<MappedOrgan> parse_mapping(CheckedMap& map) {
  const YAML::Node node = map.get("mapping");
  const std::string path = map.child_path("mapping");
  if (!node.IsDefined()) {
    map.missing("mapping", "freesurfer or a list of organs with the table's names of their labels");
    return {};
  }
  if (node.IsScalar()) {
    if (node.Scalar() == "freesurfer") {
      map.context().remember(node, path);
      return freesurfer_mapping();
    }
    map.context().problem(node, path,
                          "expected freesurfer or a list of organs with the table's names of their labels, "
                          "found '" +
                              node.Scalar() + "'");
    return {};
  }
  if (!node.IsSequence() || node.size() == 0) {
    map.context().problem(node, path,
                          "expected freesurfer or a non-empty list of organs, found " + describe(node));
    return {};
  }
  std::vector<MappedOrgan> organs;
  for (std::size_t i = 0; i < node.size(); ++i) {
    CheckedMap entry(map.context(), node[i], path + "[" + std::to_string(i) + "]");
    if (!entry.valid()) continue;
    MappedOrgan organ;
    if (entry.string("organ", organ.name, true))
      check_name(map.context(), entry.get("organ"), entry.child_path("organ"), organ.name);
    if (entry.string("tissue", organ.tissue, true))
      check_name(map.context(), entry.get("tissue"), entry.child_path("tissue"), organ.tissue);
    if (entry.string("material", organ.material))
      check_name(map.context(), entry.get("material"), entry.child_path("material"), organ.material);
    entry.string("inside", organ.inside);
    entry.boolean("solid", organ.solid);
    entry.string_list("labels", organ.names, true);
    organ.at = node[i];
    organs.push_back(organ);
  }
  return organs;
}

/// Expands the mapping's name patterns (`*`, `?`: the table's names they match, in the table's
/// order) and maps each name to its organ.
/// @return false, with the problem reported, for a pattern matching nothing or a name two organs list
bool resolve_names(CheckedMap& map, const std::filesystem::path& table_file,
                   const std::map<std::int32_t, std::string>& table, std::vector<MappedOrgan>& organs,
                   std::map<std::string, std::size_t>& organ_of_name) {
  // Patterns (`*`, `?`) stand for the table's names they match, in the table's order.
  for (std::size_t o = 0; o < organs.size(); ++o) {
    std::vector<std::string> names;
    for (const std::string& name : organs[o].names) {
      if (!is_pattern(name)) {
        names.push_back(name);
        continue;
      }
      const std::size_t before = names.size();
      for (const auto& [label, entry] : table)
        if (matches(name, entry)) names.push_back(entry);
      if (names.size() == before) {
        map.context().problem(organs[o].at, map.child_path("mapping") + "[" + std::to_string(o) + "].labels",
                              "expected a name of " + table_file.string() + " matching the pattern '" + name +
                                  "' (organ " + organs[o].name + "), found none");
        return false;
      }
    }
    organs[o].names = names;
  }
  for (std::size_t o = 0; o < organs.size(); ++o) {
    for (const std::string& name : organs[o].names) {
      const auto [first, added] = organ_of_name.emplace(name, o);
      if (!added && first->second != o) { // twice in one organ (two patterns, say) is no conflict
        map.context().problem(organs[o].at, map.child_path("mapping") + "[" + std::to_string(o) + "].labels",
                              "expected each name in one organ, found '" + name + "' in organ " +
                                  organs[o].name + " and in organ " + organs[first->second].name);
        return false;
      }
    }
  }
  return true;
}

/// Appends the mapped organs with voxels (their labels in `labels`) to `anatomy.organs`, each
/// inside its nearest container with voxels; `atlas` names their volume when it is not the file.
void append_mapped_organs(CheckedMap& map, const std::vector<MappedOrgan>& organs,
                          const std::vector<std::vector<std::string>>& labels,
                          const std::filesystem::path& file, double smoothing_mm, const std::string& atlas,
                          AnatomySettings& anatomy) {
  // Organs with voxels, each inside its nearest container with voxels.
  std::map<std::string, std::size_t> index_of;
  for (std::size_t o = 0; o < organs.size(); ++o)
    index_of.emplace(organs[o].name, o);
  for (std::size_t o = 0; o < organs.size(); ++o) {
    if (labels[o].empty()) continue;
    OrganSettings organ;
    organ.name = organs[o].name;
    organ.tissue = organs[o].tissue;
    organ.material = organs[o].material;
    organ.solid = organs[o].solid;
    std::string inside = organs[o].inside;
    for (std::size_t depth = 0; depth <= organs.size() && !inside.empty(); ++depth) {
      const auto container = index_of.find(inside);
      if (container == index_of.end()) {
        organ.inside = inside; // an organ of the scene's organs list; the consistency check names it
        break;
      }
      if (!labels[container->second].empty()) {
        organ.inside = inside;
        break;
      }
      inside = organs[container->second].inside;
    }
    organ.shape.kind = ShapeKind::label_volume;
    organ.shape.file = file;
    organ.shape.atlas = atlas;
    organ.shape.labels = labels[o];
    const std::string& front = labels[o].front();
    organ.shape.label = front.find_first_not_of("0123456789") == std::string::npos ? std::stoi(front) : 0;
    organ.shape.smoothing_mm = smoothing_mm;
    // Messages about the organ (its shape read later, say) point at the entry that made it.
    map.context().remember(organs[o].at.IsDefined() ? organs[o].at : map.node(),
                           "anatomy.organs[" + std::to_string(anatomy.organs.size()) + "]");
    anatomy.organs.push_back(organ);
  }
}

} // namespace

std::map<std::int32_t, std::string> read_label_table(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file.string() + ": cannot be read");
  const bool tsv = file.extension() == ".tsv";
  std::map<std::int32_t, std::string> table;
  std::size_t index_column = 0, name_column = 0;
  bool header = tsv;
  int number = 0;
  for (std::string line; std::getline(in, line);) {
    ++number;
    const std::string where = file.string() + ":" + std::to_string(number) + ": ";
    std::string index, name;
    if (tsv) {
      if (trimmed(line).empty()) continue;
      const std::vector<std::string> fields = split_tabs(line);
      if (header) {
        const auto find = [&](const char* column) {
          for (std::size_t c = 0; c < fields.size(); ++c)
            if (fields[c] == column) return c;
          throw InputError(where +
                           "expected a header with the tab-separated columns index and name "
                           "(BIDS dseg.tsv), found '" +
                           trimmed(line) + "'");
        };
        index_column = find("index");
        name_column = find("name");
        header = false;
        continue;
      }
      if (fields.size() > std::max(index_column, name_column)) {
        index = fields[index_column];
        name = fields[name_column];
      }
      if (label_value(index) < 0 || name.empty()) {
        throw InputError(where + "expected a label in [0, 65535] under index and a name under name, found '" +
                         trimmed(line) + "'");
      }
    } else {
      const std::string content = trimmed(line.substr(0, line.find('#')));
      if (content.empty()) continue;
      std::istringstream fields(content);
      std::vector<std::string> words;
      for (std::string word; fields >> word;)
        words.push_back(word);
      bool colour = words.size() == 6;
      for (std::size_t w = 2; colour && w < 6; ++w)
        colour = label_value(words[w]) >= 0 && label_value(words[w]) <= 255;
      if (!colour || label_value(words[0]) < 0) {
        throw InputError(where + "expected 'index name R G B A' (a FreeSurfer lookup table line), found '" +
                         content + "'");
      }
      index = words[0];
      name = words[1];
    }
    const auto value = static_cast<std::int32_t>(label_value(index));
    if (!table.emplace(value, name).second) {
      throw InputError(where + "expected each label once, found label " + index + " again ('" + name +
                       "'; earlier '" + table.at(value) + "')");
    }
  }
  if (header) {
    throw InputError(file.string() +
                     ": expected a header with the columns index and name, found an empty file");
  }
  return table;
}

namespace {

/// Each organ's labels (as text) from the volume's labels with voxels: every one named in the table
/// and mapped to an organ, or a problem at `table` or `mapping` and false.
bool labels_by_organ(CheckedMap& map, const std::filesystem::path (&files)[2],
                     const std::map<std::int32_t, std::string>& table, const std::set<std::int32_t>& present,
                     const std::map<std::string, std::size_t>& organ_of_name, std::size_t organ_count,
                     std::vector<std::vector<std::string>>& labels) {
  labels.assign(organ_count, {});
  for (const std::int32_t label : present) {
    const auto named = table.find(label);
    if (named == table.end()) {
      map.context().problem(map.get("table"), map.child_path("table"),
                            files[0].string() + ": label " + std::to_string(label) +
                                " has voxels but no line in " + files[1].string() +
                                ": expected every label of the volume in its table");
      return false;
    }
    const auto organ = organ_of_name.find(named->second);
    if (organ == organ_of_name.end()) {
      map.context().problem(map.get("mapping"), map.child_path("mapping"),
                            files[0].string() + ": label " + std::to_string(label) + " ('" + named->second +
                                "') has voxels but no organ in the mapping: expected an organ listing '" +
                                named->second + "' among its labels");
      return false;
    }
    labels[organ->second].push_back(std::to_string(label));
  }
  return true;
}

/// With a T1 the organs take their labels from the segmentation's head (the volume's labels with
/// the tissues outside the brain derived from the T1, atlas/atlas_labels.hpp), named as an atlas.
/// The scalp (the whole head) and the skull come first; the mapping's outermost organ takes the
/// outer CSF and lies in the skull with the mapping's other outermost organs.
void append_head_organs(CheckedMap& map, const std::vector<MappedOrgan>& organs,
                        std::vector<std::vector<std::string>>& labels, const std::filesystem::path& volume,
                        const std::filesystem::path& t1_file, double smoothing_mm, AnatomySettings& anatomy) {
  for (std::size_t o = 0; o < organs.size(); ++o) {
    if (organs[o].name != "scalp" && organs[o].name != "skull") continue;
    map.context().problem(organs[o].at.IsDefined() ? organs[o].at : map.get("mapping"),
                          map.child_path("mapping") + "[" + std::to_string(o) + "].organ",
                          "expected an organ name other than scalp and skull, which t1 adds, found '" +
                              organs[o].name + "'");
    return;
  }
  const std::string atlas = segmentation_atlas_name(volume, t1_file);
  const std::size_t first = anatomy.organs.size();
  for (const auto& [name, tissue, inside, names] :
       {std::tuple<const char*, const char*, const char*, std::vector<std::string>>{
            "scalp", "skin", "", {"scalp", "subcutaneous_fat", "muscle"}},
        {"skull", "bone_cortical", "scalp", {"skull", "bone_marrow"}}}) {
    OrganSettings organ;
    organ.name = name;
    organ.tissue = tissue;
    organ.inside = inside;
    organ.solid = false;
    organ.shape.kind = ShapeKind::label_volume;
    organ.shape.atlas = atlas;
    organ.shape.labels = names;
    organ.shape.smoothing_mm = smoothing_mm;
    map.context().remember(map.get("t1"), "anatomy.organs[" + std::to_string(anatomy.organs.size()) + "]");
    anatomy.organs.push_back(organ);
  }
  std::size_t outermost = 0;
  while (outermost + 1 < organs.size() && !organs[outermost].inside.empty())
    ++outermost;
  labels[outermost].push_back("outer_csf");
  append_mapped_organs(map, organs, labels, volume, smoothing_mm, atlas, anatomy);
  for (std::size_t o = first + 2; o < anatomy.organs.size(); ++o)
    if (anatomy.organs[o].inside.empty()) anatomy.organs[o].inside = "skull";
}

} // namespace

void parse_segmentation(CheckedMap& map, const std::filesystem::path& scene_folder,
                        AnatomySettings& anatomy) {
  std::filesystem::path files[2];
  bool found = true;
  const char* keys[2] = {"file", "table"};
  for (int f = 0; f < 2; ++f) {
    std::string text;
    if (!map.string(keys[f], text, true)) {
      found = false;
      continue;
    }
    files[f] = std::filesystem::path(text).is_absolute() ? std::filesystem::path(text) : scene_folder / text;
    if (const std::string kind = path_kind(files[f]); kind != "a regular file") {
      map.context().problem(map.get(keys[f]), map.child_path(keys[f]),
                            "expected an existing file, found " +
                                (kind == "no such file" ? std::string("no file") : kind) + " at '" +
                                files[f].string() + "'");
      found = false;
    }
  }
  // The T1 of the same subject, for the head's tissues outside the brain.
  std::filesystem::path t1_file;
  if (std::string text; map.string("t1", text)) {
    t1_file = std::filesystem::path(text).is_absolute() ? std::filesystem::path(text) : scene_folder / text;
    if (const std::string kind = path_kind(t1_file); kind != "a regular file") {
      map.context().problem(map.get("t1"), map.child_path("t1"),
                            "expected an existing T1 image (NIfTI) of the segmentation's subject, found " +
                                (kind == "no such file" ? std::string("no file") : kind) + " at '" +
                                t1_file.string() + "'");
      found = false;
    }
  }
  double smoothing_mm = 1.0;
  map.number("smoothing_mm", smoothing_mm, declared_rule<ShapeSettings>("smoothing_mm"));
  std::vector<MappedOrgan> organs = parse_mapping(map);
  if (!found || organs.empty()) return;

  std::map<std::int32_t, std::string> table;
  std::set<std::int32_t> present;
  try {
    table = read_label_table(files[1]);
  } catch (const InputError& error) {
    map.context().problem(map.get("table"), map.child_path("table"), error.what());
    return;
  }
  std::map<std::string, std::size_t> organ_of_name;
  if (!resolve_names(map, files[1], table, organs, organ_of_name)) return;
  ImageGrid grid;
  std::vector<std::int32_t> volume;
  try {
    volume = read_nifti_labels(files[0], &grid);
    for (const std::int32_t label : volume)
      if (label != 0) present.insert(label);
  } catch (const InputError& error) {
    map.context().problem(map.get("file"), map.child_path("file"), error.what());
    return;
  }
  if (!t1_file.empty()) {
    try {
      check_t1_covers_labels(files[0], grid, volume, t1_file, read_nifti(t1_file).grid);
    } catch (const InputError& error) {
      map.context().problem(map.get("t1"), map.child_path("t1"), error.what());
      return;
    }
  }

  if (present.empty()) {
    map.context().problem(map.get("file"), map.child_path("file"),
                          files[0].string() + ": expected labels (voxels other than 0), found none");
    return;
  }
  std::vector<std::vector<std::string>> labels;
  if (!labels_by_organ(map, files, table, present, organ_of_name, organs.size(), labels)) return;

  if (t1_file.empty()) {
    append_mapped_organs(map, organs, labels, files[0], smoothing_mm, {}, anatomy);
    return;
  }
  append_head_organs(map, organs, labels, files[0], t1_file, smoothing_mm, anatomy);
}

} // namespace phantasm::scene_detail
