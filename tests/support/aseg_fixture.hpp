#pragma once

// A small FreeSurfer-style segmentation the tests write: an aseg label volume with an excerpt of
// its lookup table and the same names as a BIDS dseg.tsv (anatomy.segmentation,
// docs/scene-format.md); and a real one: the derived Colin 27 labels renumbered as an aseg.

#include "io/nifti_file.hpp"
#include "tests/support/files.hpp"

#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace phantasm::testing {

/// A small brain in FreeSurfer's aseg numbering on a 2 mm grid of 48^3 voxels centred on the
/// origin: CSF (24) fills a ball of radius 42 mm; the cerebrum, a ball of radius 30 mm at
/// z = 8 mm, is cortex (3 left, 42 right) over white matter (2, 41) within 24 mm, which holds the
/// lateral ventricles (4, 43) and thalami (10, 49); the hippocampi (17, 53) lie in the cortex and
/// the brainstem (16) below the cerebrum. With `extra`, one voxel of label `extra` at the centre.
inline void write_aseg(const std::filesystem::path& path, std::int32_t extra = 0) {
  ImageGrid grid;
  grid.dims = {48, 48, 48};
  grid.world_from_voxel.topLeftCorner<3, 3>() *= 2.0;
  grid.world_from_voxel.topRightCorner<3, 1>() = Eigen::Vector3d::Constant(-47.0);
  std::vector<std::int32_t> labels(static_cast<std::size_t>(grid.voxel_count()), 0);
  std::size_t n = 0;
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i, ++n) {
        const Eigen::Vector3d p = grid.world_from_index(Eigen::Vector3d(i, j, k));
        const Eigen::Vector3d c = p - Eigen::Vector3d(0, 0, 8); // in the cerebrum's frame
        const bool left = p.x() < 0.0;
        const auto side = [&](std::int32_t l, std::int32_t r) { return left ? l : r; };
        const Eigen::Vector3d mirrored(std::abs(c.x()), c.y(), c.z());
        std::int32_t label = 0;
        if (p.norm() < 42.0) label = 24;
        if ((p - Eigen::Vector3d(0, 0, -30)).norm() < 7.0) label = 16;
        if (c.norm() < 30.0) label = side(3, 42);
        if (c.norm() < 24.0) label = side(2, 41);
        if ((mirrored - Eigen::Vector3d(9, 4, 4)).norm() < 5.0) label = side(4, 43);
        if ((mirrored - Eigen::Vector3d(9, -8, -4)).norm() < 4.5) label = side(10, 49);
        if ((mirrored - Eigen::Vector3d(26, -4, -8)).norm() < 3.5) label = side(17, 53);
        labels[n] = label;
      }
  if (extra != 0) labels[voxel_index(grid.dims, 24, 24, 24)] = extra;
  write_nifti_labels(path, grid, labels);
}

/// The lines of FreeSurferColorLUT.txt for these labels and a few the volume does not have.
inline const char* const k_lut = R"(#$Id: FreeSurferColorLUT.txt (excerpt)
#No. Label Name:                            R   G   B   A

0   Unknown                                 0   0   0   0
2   Left-Cerebral-White-Matter              245 245 245 0
3   Left-Cerebral-Cortex                    205 62  78  0
4   Left-Lateral-Ventricle                  120 18  134 0
10  Left-Thalamus                           0   118 14  0
11  Left-Caudate                            122 186 220 0
16  Brain-Stem                              119 159 176 0
17  Left-Hippocampus                        220 216 20  0
24  CSF                                     60  60  60  0
41  Right-Cerebral-White-Matter             245 245 245 0
42  Right-Cerebral-Cortex                   205 62  78  0
43  Right-Lateral-Ventricle                 120 18  134 0
49  Right-Thalamus                          0   118 14  0
53  Right-Hippocampus                       220 216 20  0
)";

/// The same names as a BIDS dseg.tsv (columns index, name and an abbreviation).
inline std::string dseg_tsv() {
  std::string text = "index\tname\tabbreviation\n";
  std::istringstream lut(k_lut);
  for (std::string line; std::getline(lut, line);) {
    std::istringstream words(line);
    std::string index, name;
    if (line.empty() || line[0] == '#' || !(words >> index >> name)) continue;
    text += index + "\t" + name + "\t" + name.substr(0, 3) + "\n";
  }
  return text;
}

/// A new folder `name` holding aseg.nii.gz (with `extra` as in write_aseg),
/// FreeSurferColorLUT.txt and aseg_dseg.tsv.
inline std::filesystem::path write_aseg_fixture(const std::string& name, std::int32_t extra = 0) {
  const std::filesystem::path folder = fresh_folder(name);
  write_aseg(folder / "aseg.nii.gz", extra);
  write_text_file(folder / "FreeSurferColorLUT.txt", k_lut);
  write_text_file(folder / "aseg_dseg.tsv", dseg_tsv());
  return folder;
}

/// A Colin 27 label (`phantasm atlas colin27`, by its name in labels.tsv) and its FreeSurfer aseg
/// numbers on the left (x < 0) and the right; one number for both sides where aseg has one.
struct ColinAsegLabel {
  std::string name;
  std::int32_t left = 0, right = 0;
};

/// The Colin labels that aseg has: the head outside the intracranial space (scalp, skull,
/// subcutaneous fat, muscle, marrow, eyes, orbital fat) has no aseg label and is background.
inline const std::vector<ColinAsegLabel>& colin_aseg_labels() {
  static const std::vector<ColinAsegLabel> labels = {
      {"csf", 24, 24},         {"cortical_grey_matter", 3, 42},
      {"white_matter", 2, 41}, {"lateral_ventricles", 4, 43},
      {"caudate", 11, 50},     {"putamen", 12, 51},
      {"pallidum", 13, 52},    {"thalamus", 10, 49},
      {"cerebellum", 8, 47},   {"cerebellar_white_matter", 7, 46},
      {"brainstem", 16, 16}};
  return labels;
}

/// The lines of FreeSurferColorLUT.txt for the numbers of colin_aseg_labels().
inline const char* const k_colin_lut = R"(#$Id: FreeSurferColorLUT.txt (excerpt)
0   Unknown                         0   0   0   0
2   Left-Cerebral-White-Matter      245 245 245 0
3   Left-Cerebral-Cortex            205 62  78  0
4   Left-Lateral-Ventricle          120 18  134 0
7   Left-Cerebellum-White-Matter    220 248 164 0
8   Left-Cerebellum-Cortex          230 148 34  0
10  Left-Thalamus                   0   118 14  0
11  Left-Caudate                    122 186 220 0
12  Left-Putamen                    236 13  176 0
13  Left-Pallidum                   12  48  255 0
16  Brain-Stem                      119 159 176 0
24  CSF                             60  60  60  0
41  Right-Cerebral-White-Matter     245 245 245 0
42  Right-Cerebral-Cortex           205 62  78  0
43  Right-Lateral-Ventricle         120 18  134 0
46  Right-Cerebellum-White-Matter   220 248 164 0
47  Right-Cerebellum-Cortex         230 148 34  0
49  Right-Thalamus                  0   118 14  0
50  Right-Caudate                   122 186 220 0
51  Right-Putamen                   236 13  176 0
52  Right-Pallidum                  13  48  255 0
)";

/// Writes `aseg`: the Colin labels `labels` (with their table `table`, the labels.tsv `phantasm
/// atlas colin27` writes beside them) renumbered by colin_aseg_labels(), the side by the sign of
/// the voxel centre's x (RAS), on every `step`-th voxel of their grid (the same world space,
/// voxels `step` times larger).
/// @throws std::runtime_error when the table lacks a name of colin_aseg_labels()
inline void write_colin_as_aseg(const std::filesystem::path& labels, const std::filesystem::path& table,
                                const std::filesystem::path& aseg, int step) {
  std::map<std::string, std::int32_t> number_of;
  std::istringstream lines(read_file(table));
  std::string line;
  std::getline(lines, line); // label name tissue volume_ml
  while (std::getline(lines, line)) {
    std::istringstream fields(line);
    std::int32_t label = 0;
    std::string name;
    if (fields >> label >> name) number_of[name] = label;
  }
  std::map<std::int32_t, ColinAsegLabel> renumber;
  for (const ColinAsegLabel& entry : colin_aseg_labels()) {
    if (number_of.count(entry.name) == 0) throw std::runtime_error(table.string() + " has no " + entry.name);
    renumber[number_of.at(entry.name)] = entry;
  }
  ImageGrid grid;
  const std::vector<std::int32_t> colin = read_nifti_labels(labels, &grid);
  ImageGrid coarse = grid;
  for (int a = 0; a < 3; ++a)
    coarse.dims[a] = (grid.dims[a] + step - 1) / step;
  coarse.world_from_voxel.topLeftCorner<3, 3>() *= static_cast<double>(step);
  std::vector<std::int32_t> out(static_cast<std::size_t>(coarse.voxel_count()), 0);
  for (int k = 0; k < coarse.dims.z(); ++k)
    for (int j = 0; j < coarse.dims.y(); ++j)
      for (int i = 0; i < coarse.dims.x(); ++i) {
        const auto found = renumber.find(colin[voxel_index(grid.dims, i * step, j * step, k * step)]);
        if (found == renumber.end()) continue;
        const bool left = coarse.world_from_index(Eigen::Vector3d(i, j, k)).x() < 0.0;
        out[voxel_index(coarse.dims, i, j, k)] = left ? found->second.left : found->second.right;
      }
  write_nifti_labels(aseg, coarse, out);
}

} // namespace phantasm::testing
