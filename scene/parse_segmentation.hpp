// `anatomy.segmentation`: a whole label volume with its table of names (a FreeSurfer lookup
// table or a BIDS dseg.tsv), expanded at scene load into label_volume organs by a mapping from
// names to organs. Internal to the scene target.
#pragma once

#include "scene/parse_sections.hpp"

#include <cstdint>
#include <map>

namespace phantasm::scene_detail {

/// Reads a label table: a BIDS `dseg.tsv` (a `.tsv` file: a header naming the columns `index`
/// and `name`, then one row per label) or a FreeSurfer lookup table (any other file: lines
/// `index name R G B A`, `#` comments). Throws InputError naming the file and line of a line that
/// does not parse or a label given twice.
std::map<std::int32_t, std::string> read_label_table(const std::filesystem::path& file);

/// Parses `anatomy.segmentation` and appends its organs with voxels to `anatomy.organs` in the mapping's
/// order, each inside its nearest container with voxels. A mapping's name with `*` or `?` is a
/// shell-style pattern standing for the table's names it matches (one matching none is an error).
/// With `t1` (a T1 of the same subject that must cover the labelled voxels) the organs are first
/// `scalp` and `skull`, then the mapping's (its outermost with the outer CSF, in the skull), all
/// of the segmentation's head: an atlas derived at run time (io/segmentation.hpp,
/// atlas/atlas_labels.hpp).
void parse_segmentation(CheckedMap& map, const std::filesystem::path& scene_folder, AnatomySettings& anatomy);

} // namespace phantasm::scene_detail
