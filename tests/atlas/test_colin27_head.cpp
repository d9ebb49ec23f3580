#include "atlas/colin27_head.hpp"
#include "io/nifti_file.hpp"
#include "tests/support/shared_output.hpp"
#include "tests/support/subprocess.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>

namespace phantasm {
namespace {

using testing::CommandResult;
using testing::run_command;

const std::filesystem::path templates = default_colin27_templates_dir();

/// Skips when the templates are absent, except under CI, where scripts/install-deps.sh
/// installs them and their absence is a failure.
bool templates_missing() {
  if (std::filesystem::is_directory(templates)) return false;
  const char* ci = std::getenv("CI");
  if (ci != nullptr && std::strcmp(ci, "true") == 0)
    ADD_FAILURE() << templates << " is missing: install the Debian package mricron-data";
  return true;
}

/// The derived head as bytes: the grid, the labels, then the table one entry a line.
void write_head(const std::filesystem::path& file, const HeadLabels& head) {
  std::ofstream out(file, std::ios::binary);
  const std::uint64_t count = head.labels.size();
  out.write(reinterpret_cast<const char*>(head.grid.dims.data()), sizeof(int) * 3);
  out.write(reinterpret_cast<const char*>(head.grid.spacing_mm.data()), sizeof(double) * 3);
  out.write(reinterpret_cast<const char*>(head.grid.world_from_voxel.data()), sizeof(double) * 16);
  out.write(reinterpret_cast<const char*>(&count), sizeof(count));
  out.write(reinterpret_cast<const char*>(head.labels.data()),
            static_cast<std::streamsize>(sizeof(std::int32_t) * count));
  for (const HeadLabelInfo& info : head.table)
    out << info.label << '\t' << info.name << '\t' << info.tissue << '\n';
}

HeadLabels read_head(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  HeadLabels head;
  std::uint64_t count = 0;
  in.read(reinterpret_cast<char*>(head.grid.dims.data()), sizeof(int) * 3);
  in.read(reinterpret_cast<char*>(head.grid.spacing_mm.data()), sizeof(double) * 3);
  in.read(reinterpret_cast<char*>(head.grid.world_from_voxel.data()), sizeof(double) * 16);
  in.read(reinterpret_cast<char*>(&count), sizeof(count));
  head.labels.resize(count);
  in.read(reinterpret_cast<char*>(head.labels.data()),
          static_cast<std::streamsize>(sizeof(std::int32_t) * count));
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    HeadLabelInfo info;
    std::string label;
    std::getline(fields, label, '\t');
    std::getline(fields, info.name, '\t');
    std::getline(fields, info.tissue);
    info.label = std::stoi(label);
    head.table.push_back(info);
  }
  return head;
}

/// One derivation shared by the tests (it takes about 5 s): made by the first test to need it, in
/// any process, for this test program's bytes and the templates' (tests/support/shared_output.hpp),
/// and read by the others.
const HeadLabels& derived() {
  static const std::unique_ptr<HeadLabels> head = [] {
    const std::filesystem::path folder = testing::shared_output(
        "colin27-head",
        {"/proc/self/exe", templates / "ch2.nii.gz", templates / "ch2bet.nii.gz", templates / "aal.nii.gz"},
        [](const std::filesystem::path& into) {
          const auto start = std::chrono::steady_clock::now();
          write_head(into / "head.bin", derive_colin27_head(templates));
          std::cout << "derive_colin27_head: "
                    << std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()
                    << " s\n";
          return true;
        });
    return std::make_unique<HeadLabels>(read_head(folder / "head.bin"));
  }();
  return *head;
}

#define SKIP_WITHOUT_TEMPLATES()                                                                             \
  if (templates_missing()) GTEST_SKIP() << templates << " is absent (Debian package mricron-data)"

TEST(Colin27Head, EveryLabelIsPresentWithPlausibleVolumes) {
  SKIP_WITHOUT_TEMPLATES();
  const HeadLabels& head = derived();
  EXPECT_EQ(head.grid.dims, Eigen::Vector3i(181, 217, 181));
  const std::vector<double> ml = label_volumes_ml(head);
  ASSERT_EQ(ml.size(), 19U);
  for (const HeadLabelInfo& info : head.table) {
    std::cout << info.label << ' ' << info.name << ' ' << ml[info.label] << " ml\n";
    EXPECT_GT(ml[info.label], 0.0) << info.name;
  }
  const double gm = ml[colin27_cortical_gm] + ml[colin27_caudate] + ml[colin27_putamen] +
                    ml[colin27_pallidum] + ml[colin27_thalamus];
  EXPECT_GE(gm, 500.0);
  EXPECT_LE(gm, 900.0);
  EXPECT_GE(ml[colin27_white_matter], 350.0);
  EXPECT_LE(ml[colin27_white_matter], 650.0);
  EXPECT_GE(ml[colin27_ventricles], 5.0);
  EXPECT_LE(ml[colin27_ventricles], 60.0);
  double intracranial = 0.0;
  for (int l = colin27_csf; l <= colin27_brainstem; ++l)
    intracranial += ml[l];
  intracranial += ml[colin27_cerebellar_white_matter];
  std::cout << "grey matter " << gm << " ml, intracranial " << intracranial << " ml\n";
  EXPECT_GE(intracranial, 1200.0);
  EXPECT_LE(intracranial, 1900.0);
}

// Outside the brain the scan's intensities order the derived tissues as a T1w head shows them:
// fat (the brightest) above white matter, muscle below it, marrow brighter than cortical bone;
// the skin is the head's outer layer (every voxel of it touches the background within 2 voxels),
// marrow lies inside the skull (no marrow voxel touches anything but skull and marrow), and the
// soft tissues under the skin hold plausible adult volumes.
TEST(Colin27Head, TissuesOutsideTheBrainFollowTheScan) {
  SKIP_WITHOUT_TEMPLATES();
  const HeadLabels& head = derived();
  const NiftiVolume t1 = read_nifti(templates / "ch2.nii.gz");
  std::vector<double> sum(head.table.size(), 0.0), count(head.table.size(), 0.0);
  for (std::size_t n = 0; n < head.labels.size(); ++n) {
    sum[static_cast<std::size_t>(head.labels[n])] += t1.values[n];
    count[static_cast<std::size_t>(head.labels[n])] += 1.0;
  }
  const auto mean = [&](int label) {
    return sum[static_cast<std::size_t>(label)] / count[static_cast<std::size_t>(label)];
  };
  std::cout << "mean T1: fat " << mean(colin27_subcutaneous_fat) << ", white matter "
            << mean(colin27_white_matter) << ", muscle " << mean(colin27_muscle) << ", marrow "
            << mean(colin27_bone_marrow) << ", bone " << mean(colin27_skull) << ", skin "
            << mean(colin27_scalp) << "\n";
  EXPECT_GT(mean(colin27_subcutaneous_fat), 1.15 * mean(colin27_white_matter));
  EXPECT_LT(mean(colin27_muscle), mean(colin27_white_matter));
  EXPECT_GT(mean(colin27_bone_marrow), 1.5 * mean(colin27_skull));
  const std::vector<double> ml = label_volumes_ml(head);
  EXPECT_GE(ml[colin27_subcutaneous_fat], 50.0);
  EXPECT_GE(ml[colin27_muscle], 200.0);
  EXPECT_GE(ml[colin27_bone_marrow], 2.0);
  EXPECT_LE(ml[colin27_bone_marrow], 0.5 * ml[colin27_skull]);
  const Eigen::Vector3i d = head.grid.dims;
  auto at = [&](int i, int j, int k) { return i + std::int64_t(d.x()) * (j + std::int64_t(d.y()) * k); };
  std::int64_t marrow_touching_other = 0, fat_touching_background = 0;
  for (int k = 1; k < d.z() - 1; ++k)
    for (int j = 1; j < d.y() - 1; ++j)
      for (int i = 1; i < d.x() - 1; ++i) {
        const std::int64_t n = at(i, j, k);
        const std::int32_t l = head.labels[n];
        if (l != colin27_bone_marrow && l != colin27_subcutaneous_fat && l != colin27_muscle) continue;
        for (const std::int64_t m : {at(i + 1, j, k), at(i - 1, j, k), at(i, j + 1, k), at(i, j - 1, k),
                                     at(i, j, k + 1), at(i, j, k - 1)}) {
          if (l == colin27_bone_marrow)
            marrow_touching_other += head.labels[m] != colin27_skull && head.labels[m] != colin27_bone_marrow;
          else
            fat_touching_background += head.labels[m] == colin27_background; // the skin covers them
        }
      }
  EXPECT_EQ(marrow_touching_other, 0);
  EXPECT_EQ(fat_touching_background, 0);
}

// The eyes and the orbital fat behind them: one vitreous globe in each orbit, dark on the T1w scan
// (below muscle, like CSF), of an adult eyeball's volume (an axial length of about 24 mm: 6-8 ml,
// the lens and the eye's coats included), placed as mirror images about the midline; the orbital
// fat brighter than white matter, behind the eyes, on both sides.
TEST(Colin27Head, EachOrbitHoldsADarkEyeWithItsFatBehindIt) {
  SKIP_WITHOUT_TEMPLATES();
  const HeadLabels& head = derived();
  const NiftiVolume t1 = read_nifti(templates / "ch2.nii.gz");
  struct Side {
    double ml = 0.0, sum = 0.0;
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  };
  Side eye[2], fat[2];
  double muscle_sum = 0.0, muscle_count = 0.0, wm_sum = 0.0, wm_count = 0.0;
  const Eigen::Vector3i d = head.grid.dims;
  for (std::size_t n = 0; n < head.labels.size(); ++n) {
    const std::int32_t l = head.labels[n];
    if (l == colin27_muscle) muscle_sum += t1.values[n], muscle_count += 1.0;
    if (l == colin27_white_matter) wm_sum += t1.values[n], wm_count += 1.0;
    if (l != colin27_eye && l != colin27_orbital_fat) continue;
    const Eigen::Vector3d x = head.grid.world_from_index(
        Eigen::Vector3d(double(n % std::size_t(d.x())), double(n / std::size_t(d.x()) % std::size_t(d.y())),
                        double(n / (std::size_t(d.x()) * std::size_t(d.y())))));
    Side& s = (l == colin27_eye ? eye : fat)[x.x() > 0.0 ? 1 : 0];
    s.ml += 0.001;
    s.sum += t1.values[n];
    s.centre += 0.001 * x;
  }
  for (int side = 0; side < 2; ++side) {
    ASSERT_GT(eye[side].ml, 0.0);
    ASSERT_GT(fat[side].ml, 0.0);
    eye[side].centre /= eye[side].ml;
    fat[side].centre /= fat[side].ml;
    std::cout << (side ? "right" : "left") << " eye " << eye[side].ml << " ml at "
              << eye[side].centre.transpose() << ", mean T1 " << eye[side].sum / (1000.0 * eye[side].ml)
              << "; orbital fat " << fat[side].ml << " ml, mean T1 "
              << fat[side].sum / (1000.0 * fat[side].ml) << "\n";
    EXPECT_GE(eye[side].ml, 5.0);
    EXPECT_LE(eye[side].ml, 9.0);
    EXPECT_LT(eye[side].sum / (1000.0 * eye[side].ml), muscle_sum / muscle_count);
    EXPECT_GT(fat[side].sum / (1000.0 * fat[side].ml), 1.15 * wm_sum / wm_count);
    EXPECT_GE(fat[side].ml, 1.0);
    EXPECT_LT(fat[side].centre.y(), eye[side].centre.y()); // behind the eye
    EXPECT_GT(eye[side].centre.z(), -60.0);                // in the orbit: below the frontal lobe,
    EXPECT_LT(eye[side].centre.z(), -15.0);                // in front of the temporal poles
    EXPECT_GT(eye[side].centre.y(), 45.0);
  }
  // Mirror images about the midline within a few mm (the template is nearly symmetric).
  EXPECT_NEAR(eye[0].centre.x(), -eye[1].centre.x(), 4.0);
  EXPECT_NEAR(eye[0].centre.y(), eye[1].centre.y(), 4.0);
  EXPECT_NEAR(eye[0].centre.z(), eye[1].centre.z(), 4.0);
  EXPECT_GT(eye[1].centre.x() - eye[0].centre.x(), 50.0); // interpupillary distance, adults 54-74 mm
  EXPECT_LT(eye[1].centre.x() - eye[0].centre.x(), 80.0);
}

// The cerebellum divides by the scan's intensity as the cerebrum does: its white matter (the
// brain's white-matter class inside it) is brighter on the T1w scan than its cortex, lies inside
// the cerebellum (no voxel of it touches CSF, the cerebrum's white matter or the background), and
// holds a plausible share of it: about a fifth of an adult cerebellum is white matter.
TEST(Colin27Head, CerebellarWhiteMatterFollowsTheScan) {
  SKIP_WITHOUT_TEMPLATES();
  const HeadLabels& head = derived();
  const NiftiVolume t1 = read_nifti(templates / "ch2.nii.gz");
  double cortex_sum = 0.0, cortex_count = 0.0, white_sum = 0.0, white_count = 0.0;
  for (std::size_t n = 0; n < head.labels.size(); ++n) {
    if (head.labels[n] == colin27_cerebellum) {
      cortex_sum += t1.values[n];
      cortex_count += 1.0;
    } else if (head.labels[n] == colin27_cerebellar_white_matter) {
      white_sum += t1.values[n];
      white_count += 1.0;
    }
  }
  ASSERT_GT(white_count, 0.0);
  const double cortex = cortex_sum / cortex_count, white = white_sum / white_count;
  const std::vector<double> ml = label_volumes_ml(head);
  const double share =
      ml[colin27_cerebellar_white_matter] / (ml[colin27_cerebellar_white_matter] + ml[colin27_cerebellum]);
  std::cout << "cerebellum: mean T1 cortex " << cortex << ", white matter " << white << "; white matter "
            << ml[colin27_cerebellar_white_matter] << " ml, share " << share << "\n";
  EXPECT_GT(white, 1.1 * cortex);
  EXPECT_GE(share, 0.1);
  EXPECT_LE(share, 0.35);
  const Eigen::Vector3i d = head.grid.dims;
  auto at = [&](int i, int j, int k) { return i + std::int64_t(d.x()) * (j + std::int64_t(d.y()) * k); };
  std::int64_t touching_outside = 0;
  for (int k = 1; k < d.z() - 1; ++k)
    for (int j = 1; j < d.y() - 1; ++j)
      for (int i = 1; i < d.x() - 1; ++i) {
        if (head.labels[at(i, j, k)] != colin27_cerebellar_white_matter) continue;
        for (const std::int64_t m : {at(i + 1, j, k), at(i - 1, j, k), at(i, j + 1, k), at(i, j - 1, k),
                                     at(i, j, k + 1), at(i, j, k - 1)}) {
          const std::int32_t next = head.labels[m];
          touching_outside +=
              next == colin27_csf || next == colin27_white_matter || next == colin27_background;
        }
      }
  std::cout << "cerebellar white-matter faces on CSF, cerebral white matter or background: "
            << touching_outside << "\n";
  EXPECT_LE(touching_outside, 200);
}

TEST(Colin27Head, NestingIsSane) {
  SKIP_WITHOUT_TEMPLATES();
  const HeadLabels& head = derived();
  const NiftiVolume bet = read_nifti(templates / "ch2bet.nii.gz");
  ASSERT_TRUE(bet.grid.world_from_voxel.isApprox(head.grid.world_from_voxel));
  const Eigen::Vector3i d = head.grid.dims;
  auto at = [&](int i, int j, int k) { return i + std::int64_t(d.x()) * (j + std::int64_t(d.y()) * k); };
  std::int64_t wm_touching_background = 0, ventricles_outside = 0;
  for (int k = 1; k < d.z() - 1; ++k)
    for (int j = 1; j < d.y() - 1; ++j)
      for (int i = 1; i < d.x() - 1; ++i) {
        const std::int64_t n = at(i, j, k);
        if (head.labels[n] == colin27_ventricles && bet.values[n] <= 0.0)
          ++ventricles_outside; // the brain mask is ch2bet > 0 with its holes filled
        if (head.labels[n] != colin27_white_matter) continue;
        for (const std::int64_t m : {at(i + 1, j, k), at(i - 1, j, k), at(i, j + 1, k), at(i, j - 1, k),
                                     at(i, j, k + 1), at(i, j, k - 1)})
          wm_touching_background += head.labels[m] == colin27_background;
      }
  EXPECT_EQ(wm_touching_background, 0);
  EXPECT_LE(ventricles_outside, 100) << "ventricle voxels outside ch2bet's support";
}

// The brainstem, the lateral ventricles and the cerebellum keep to their anatomy. Before the
// brainstem was bounded from front to back it took the frontal lobe's basal white matter (its
// label reached y = 56 mm, 60 mm in front of the thalamus) and the cerebellum's (y = -74 mm);
// before the ventricles kept clear of the hindbrain and the fissure they held the fourth
// ventricle and the cisterns around the brainstem and the cerebellum (4724 voxels touching
// either) and the interhemispheric fissure behind the thalamus (2771 voxels within 4 mm of the
// midline there; 867 with the hindbrain rule alone); before the cerebellum took its unlabelled
// white matter, 1863 cerebral white-matter voxels touched it.
TEST(Colin27Head, BrainstemVentriclesAndCerebellumKeepToTheirAnatomy) {
  SKIP_WITHOUT_TEMPLATES();
  const HeadLabels& head = derived();
  const Eigen::Vector3i d = head.grid.dims;
  auto at = [&](int i, int j, int k) { return i + std::int64_t(d.x()) * (j + std::int64_t(d.y()) * k); };
  auto world = [&](int i, int j, int k) { return head.grid.world_from_index(Eigen::Vector3d(i, j, k)); };
  double stem_front = -1e9, stem_back = 1e9, thalamus_front = -1e9, thalamus_back = 1e9, thalamus_x = 0.0;
  std::int64_t thalamus_voxels = 0;
  for (int k = 0; k < d.z(); ++k)
    for (int j = 0; j < d.y(); ++j)
      for (int i = 0; i < d.x(); ++i) {
        const Eigen::Vector3d p = world(i, j, k);
        if (head.labels[at(i, j, k)] == colin27_brainstem) {
          stem_front = std::max(stem_front, p.y());
          stem_back = std::min(stem_back, p.y());
        }
        if (head.labels[at(i, j, k)] != colin27_thalamus) continue;
        thalamus_front = std::max(thalamus_front, p.y());
        thalamus_back = std::min(thalamus_back, p.y());
        thalamus_x += p.x();
        ++thalamus_voxels;
      }
  ASSERT_GT(thalamus_voxels, 0);
  thalamus_x /= double(thalamus_voxels);
  std::int64_t ventricle_on_hindbrain = 0, white_matter_on_cerebellum = 0, ventricles = 0, fissure = 0;
  for (int k = 1; k < d.z() - 1; ++k)
    for (int j = 1; j < d.y() - 1; ++j)
      for (int i = 1; i < d.x() - 1; ++i) {
        const std::int32_t label = head.labels[at(i, j, k)];
        if (label != colin27_ventricles && label != colin27_white_matter) continue;
        if (label == colin27_ventricles) {
          ++ventricles;
          const Eigen::Vector3d p = world(i, j, k);
          fissure += std::abs(p.x() - thalamus_x) < 4.0 && p.y() < thalamus_back;
        }
        for (const std::int64_t m : {at(i + 1, j, k), at(i - 1, j, k), at(i, j + 1, k), at(i, j - 1, k),
                                     at(i, j, k + 1), at(i, j, k - 1)}) {
          const std::int32_t next = head.labels[m];
          if (label == colin27_ventricles)
            ventricle_on_hindbrain += next == colin27_brainstem || next == colin27_cerebellum ||
                                      next == colin27_cerebellar_white_matter;
          else
            white_matter_on_cerebellum +=
                next == colin27_cerebellum || next == colin27_cerebellar_white_matter;
        }
      }
  std::cout << "brainstem y " << stem_back << " to " << stem_front << " mm (thalamus " << thalamus_back
            << " to " << thalamus_front << "), ventricle voxels on the hindbrain " << ventricle_on_hindbrain
            << ", near the midline behind the thalamus " << fissure
            << ", white-matter voxels on the cerebellum " << white_matter_on_cerebellum << "\n";
  // Midbrain, pons and medulla span about 40 mm from front to back, and none lies in front of
  // the thalamus.
  EXPECT_LE(stem_front - stem_back, 50.0);
  EXPECT_LE(stem_front, thalamus_front);
  EXPECT_GT(ventricles, 10000); // the lateral ventricles stay (about 23 ml)
  EXPECT_EQ(ventricle_on_hindbrain, 0);
  EXPECT_LE(fissure, 400);
  EXPECT_LE(white_matter_on_cerebellum, 100);
}

TEST(Colin27Head, DeepNucleiMatchAal) {
  SKIP_WITHOUT_TEMPLATES();
  const HeadLabels& head = derived();
  ImageGrid aal_grid;
  const std::vector<std::int32_t> aal = read_nifti_labels(templates / "aal.nii.gz", &aal_grid);
  const NiftiVolume bet = read_nifti(templates / "ch2bet.nii.gz");
  ASSERT_TRUE(aal_grid.world_from_voxel.isApprox(head.grid.world_from_voxel));
  const struct {
    Colin27Label label;
    int first, last;
  } regions[] = {{colin27_caudate, 71, 72}, {colin27_putamen, 73, 74}, {colin27_thalamus, 77, 78}};
  for (const auto& r : regions) {
    std::int64_t both = 0, ours = 0, theirs = 0;
    for (std::size_t n = 0; n < aal.size(); ++n) {
      const bool a = head.labels[n] == r.label;
      const bool b = aal[n] >= r.first && aal[n] <= r.last && bet.values[n] > 0.0;
      both += a && b;
      ours += a;
      theirs += b;
    }
    const double dice = 2.0 * double(both) / double(ours + theirs);
    std::cout << "label " << r.label << " Dice " << dice << "\n";
    EXPECT_GE(dice, 0.9) << "label " << r.label;
  }
}

// A second derivation gives what the shared one (derived(), often made in another process and
// read back from its file) holds: the same labels, grid and table.
TEST(Colin27Head, IsDeterministic) {
  SKIP_WITHOUT_TEMPLATES();
  const HeadLabels again = derive_colin27_head(templates);
  EXPECT_TRUE(again.labels == derived().labels);
  EXPECT_EQ(again.grid.dims, derived().grid.dims);
  EXPECT_EQ(again.grid.spacing_mm, derived().grid.spacing_mm);
  EXPECT_EQ(again.grid.world_from_voxel, derived().grid.world_from_voxel);
  ASSERT_EQ(again.table.size(), derived().table.size());
  for (std::size_t n = 0; n < again.table.size(); ++n) {
    EXPECT_EQ(again.table[n].label, derived().table[n].label) << n;
    EXPECT_EQ(again.table[n].name, derived().table[n].name) << n;
    EXPECT_EQ(again.table[n].tissue, derived().table[n].tissue) << n;
  }
}

TEST(Colin27Head, AMissingTemplateIsNamed) {
  const std::filesystem::path empty = std::filesystem::temp_directory_path() / "phantasm_colin27_empty";
  std::filesystem::create_directories(empty);
  try {
    (void)derive_colin27_head(empty);
    FAIL() << "no error";
  } catch (const std::exception& error) {
    EXPECT_NE(std::string(error.what()).find("ch2.nii.gz"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("mricron-data"), std::string::npos) << error.what();
  }
}

TEST(AtlasCommand, WritesALabelVolumeNibabelReads) {
  SKIP_WITHOUT_TEMPLATES();
  const std::filesystem::path folder = std::filesystem::temp_directory_path() / "phantasm_atlas_command";
  std::filesystem::remove_all(folder);
  std::filesystem::create_directories(folder);
  const std::filesystem::path out = folder / "labels.nii.gz";
  const CommandResult run = run_command({PHANTASM_EXECUTABLE, "atlas", "colin27", "-o", out.string(), "-q"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(std::filesystem::exists(folder / "labels.tsv"));
  std::ofstream(folder / "check.py") << "import sys, nibabel, numpy\n"
                                        "img = nibabel.load(sys.argv[1])\n"
                                        "ref = nibabel.load(sys.argv[2])\n"
                                        "d = numpy.asarray(img.dataobj)\n"
                                        "assert d.shape == (181, 217, 181), d.shape\n"
                                        "assert numpy.allclose(img.affine, ref.affine), img.affine\n"
                                        "assert set(numpy.unique(d)) == set(range(19)), numpy.unique(d)\n"
                                        "print('ok')\n";
  const CommandResult check = run_command(
      {PHANTASM_PYTHON, (folder / "check.py").string(), out.string(), (templates / "ch2.nii.gz").string()});
  EXPECT_EQ(check.exit_code, 0) << check.out << check.err;
  EXPECT_EQ(check.out, "ok\n") << check.err;
}

TEST(AtlasCommand, AMissingTemplatesFolderIsABadInput) {
  const CommandResult run = run_command({PHANTASM_EXECUTABLE, "atlas", "colin27", "-o",
                                         "/tmp/phantasm_never.nii.gz", "--templates", "/nonexistent"});
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("mricron-data"), std::string::npos) << run.err;
}

} // namespace
} // namespace phantasm
