// `phantasm eval` against real clients: the identity gives the true landmark motion, the ground
// truth scores perfectly, a known affine turned into a field by Debian's transformix (`-def all`)
// is read in our convention and scored as the transform says, bad results get clear messages.

#include "evaluation/registration_metrics.hpp"
#include "io/nifti_file.hpp"
#include "tests/apps/cli_fixtures.hpp"
#include "tests/apps/transformix_parameters.hpp"
#include "tests/support/subprocess.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <map>
#include <sstream>

using namespace phantasm::testing;
namespace fs = std::filesystem;

namespace {

const Eigen::Vector3d k_lps(-1.0, -1.0, 1.0);

/// A small-head dataset, made once for the tests of this file.
const fs::path& small_dataset() {
  static const fs::path out = [] {
    const fs::path folder = fresh_folder("eval-dataset") / "out";
    const CommandResult run =
        run_command({k_phantasm, "run", k_small_scene.string(), "-o", folder.string(), "-q"});
    EXPECT_EQ(run.exit_code, 0) << run.err;
    return folder;
  }();
  return out;
}

fs::path subject_folder() {
  return small_dataset() / "derivatives" / "phantasm" / "sub-01";
}

std::map<std::string, Eigen::Vector3d> landmarks(const std::string& session) {
  std::istringstream csv(read_file(subject_folder() / ("ses-" + session) / "landmarks" /
                                   ("sub-01_ses-" + session + "_landmarks.csv")));
  std::map<std::string, Eigen::Vector3d> points;
  std::string line;
  std::getline(csv, line);
  while (std::getline(csv, line)) {
    std::istringstream fields(line);
    std::string name, organ, x, y, z;
    std::getline(fields, name, ',');
    std::getline(fields, organ, ',');
    std::getline(fields, x, ',');
    std::getline(fields, y, ',');
    std::getline(fields, z);
    points[name] = Eigen::Vector3d(std::stod(x), std::stod(y), std::stod(z));
  }
  return points;
}

nlohmann::json evaluate(const std::vector<std::string>& result_options, const fs::path& json) {
  std::vector<std::string> command = {k_phantasm, "eval", small_dataset().string()};
  command.insert(command.end(), result_options.begin(), result_options.end());
  command.insert(command.end(), {"--json", json.string()});
  const CommandResult run = run_command(command);
  EXPECT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("mean Dice"), std::string::npos) << run.out;
  return nlohmann::json::parse(read_file(json));
}

phantasm::ImageGrid reference_grid() {
  phantasm::ImageGrid grid;
  phantasm::read_nifti_labels(subject_folder() / "ses-ref" / "anat" / "sub-01_ses-ref_dseg.nii.gz", &grid);
  return grid;
}

} // namespace

TEST(EvalCommand, IdentityGivesTheTrueMotionAndTheGroundTruthScoresPerfectly) {
  const fs::path folder = fresh_folder("eval-identity");
  const nlohmann::json identity = evaluate({"--identity"}, folder / "identity.json");
  const auto ref = landmarks("ref"), def = landmarks("def");
  ASSERT_EQ(identity["landmarks"].size(), ref.size());
  double moved = 0.0;
  for (const auto& landmark : identity["landmarks"]) {
    const std::string name = landmark["name"];
    const double truth = (def.at(name) - ref.at(name)).norm();
    EXPECT_NEAR(landmark["tre_mm"].get<double>(), truth, 1e-9) << name;
    moved = std::max(moved, truth);
  }
  EXPECT_GT(moved, 0.3); // the scene moves landmarks: otherwise the test would prove nothing
  EXPECT_EQ(identity["jacobian"]["folding_voxels"], 0);
  EXPECT_DOUBLE_EQ(identity["jacobian"]["log_jacobian_sd"].get<double>(), 0.0);

  // The field on the fixed (reference) grid that brings the moving (deformed) image there.
  const fs::path truth_field = subject_folder() / "xfm" / "sub-01_from-def_to-ref_mode-image_xfm.nii.gz";
  const nlohmann::json truth = evaluate({"--field", truth_field.string()}, folder / "truth.json");
  const double voxel = 2.0;
  EXPECT_LT(truth["tre_mm"]["mean"].get<double>(), 0.1 * voxel);
  EXPECT_LT(truth["tre_mm"]["p95"].get<double>(), 0.1 * voxel);
  EXPECT_LT(truth["tre_mm"]["mean"].get<double>(), identity["tre_mm"]["mean"].get<double>());
  // Every landmark, not only most: each is a point of its organ's material and moves with it, so
  // the ground truth carries it within 0.1 voxel (trilinear interpolation of the field is all
  // that is left).
  EXPECT_LT(truth["tre_mm"]["max"].get<double>(), 0.1 * voxel);
  for (const auto& landmark : truth["landmarks"])
    EXPECT_LT(landmark["tre_mm"].get<double>(), 0.1 * voxel) << landmark["name"];
  // The deepest point of each organ's own material lies in a voxel labelled with that organ, in
  // both states (not in a nested organ, as a shell's centroid would).
  std::map<std::string, int> index_of;
  {
    std::istringstream tsv(read_file(small_dataset() / "derivatives" / "phantasm" / "dseg.tsv"));
    std::string line;
    std::getline(tsv, line);
    while (std::getline(tsv, line)) {
      std::istringstream fields(line);
      std::string index, name;
      std::getline(fields, index, '\t');
      std::getline(fields, name, '\t');
      index_of[name] = std::stoi(index);
    }
  }
  int deepest = 0;
  for (const auto& [session, points] : {std::pair{"ref", ref}, std::pair{"def", def}}) {
    phantasm::ImageGrid grid;
    const std::vector<std::int32_t> labels =
        phantasm::read_nifti_labels(subject_folder() / ("ses-" + std::string(session)) / "anat" /
                                        ("sub-01_ses-" + std::string(session) + "_dseg.nii.gz"),
                                    &grid);
    for (const auto& [name, x] : points) {
      const std::size_t cut = name.rfind("_deepest");
      if (cut == std::string::npos) continue;
      const Eigen::Vector3i ijk = grid.index_from_world(x).array().round().cast<int>();
      const std::size_t v =
          (static_cast<std::size_t>(ijk.z()) * grid.dims.y() + ijk.y()) * grid.dims.x() + ijk.x();
      EXPECT_EQ(labels.at(v), index_of.at(name.substr(0, cut))) << session << " " << name;
      ++deepest;
    }
  }
  EXPECT_EQ(deepest, 2 * 3); // three organs, two states
  EXPECT_EQ(truth["endpoint_error_mm"]["max"].get<double>(), 0.0);
  EXPECT_GT(truth["endpoint_error_mm"]["count"].get<int>(), 10000);
  ASSERT_EQ(truth["labels"].size(), 3u);
  for (const auto& label : truth["labels"])
    EXPECT_GE(label["dice"].get<double>(), 0.98) << label["name"];
  EXPECT_EQ(truth["jacobian"]["folding_voxels"], 0);

  // The ground truth's own warped labels (nearest neighbour): the same Dice as the field gives.
  const fs::path def_labels = subject_folder() / "ses-def" / "anat" / "sub-01_ses-def_dseg.nii.gz";
  const phantasm::DisplacementField field = phantasm::read_displacement_field(truth_field);
  phantasm::ImageGrid def_grid;
  const auto warped =
      phantasm::warp_labels(phantasm::read_nifti_labels(def_labels, &def_grid), def_grid, field);
  phantasm::write_nifti_labels(folder / "warped.nii.gz", field.grid, warped);
  const nlohmann::json by_labels =
      evaluate({"--labels", (folder / "warped.nii.gz").string()}, folder / "l.json");
  EXPECT_TRUE(by_labels["tre_mm"].is_null());
  EXPECT_EQ(by_labels["labels"], truth["labels"]);
}

// The dense landmarks (ses-*/landmarks/*_desc-dense_landmarks.csv, the landmarks' format): the
// same names in both states, up to 300 per organ; without registration each organ's TRE is its true
// motion (mean over its points, from the files), with the ground truth's field a tenth of it.
TEST(EvalCommand, DenseLandmarksAreScoredPerOrganAsTheirTrueMotionWithoutRegistration) {
  std::map<std::string, std::map<std::string, Eigen::Vector3d>> states;
  std::map<std::string, std::string> organ_of;
  for (const std::string session : {"ref", "def"}) {
    std::istringstream csv(read_file(subject_folder() / ("ses-" + session) / "landmarks" /
                                     ("sub-01_ses-" + session + "_desc-dense_landmarks.csv")));
    std::string line;
    std::getline(csv, line);
    EXPECT_EQ(line, "name,organ,x_mm,y_mm,z_mm");
    while (std::getline(csv, line)) {
      // name and organ hold no spaces: the row read as five words
      std::replace(line.begin(), line.end(), ',', ' ');
      std::istringstream fields(line);
      std::string name, organ;
      Eigen::Vector3d x;
      ASSERT_TRUE(fields >> name >> organ >> x.x() >> x.y() >> x.z()) << line;
      states[session][name] = x;
      organ_of[name] = organ;
    }
  }
  ASSERT_GE(states["ref"].size(), 600u);
  ASSERT_EQ(states["def"].size(), states["ref"].size());
  std::map<std::string, std::pair<double, int>> motion; // per organ: sum of |def - ref|, count
  for (const auto& [name, x] : states["ref"]) {
    ASSERT_TRUE(states["def"].count(name)) << name;
    motion[organ_of[name]].first += (states["def"][name] - x).norm();
    ++motion[organ_of[name]].second;
  }
  const fs::path folder = fresh_folder("eval-dense");
  const nlohmann::json identity = evaluate({"--identity"}, folder / "identity.json");
  ASSERT_EQ(identity["dense_tre_mm"]["by_structure"].size(), 3u);
  for (const auto& s : identity["dense_tre_mm"]["by_structure"]) {
    const auto& [sum, count] = motion.at(s["structure"].get<std::string>());
    EXPECT_EQ(s["count"].get<int>(), count);
    EXPECT_LE(count, 300);
    EXPECT_NEAR(s["mean"].get<double>(), sum / count, 1e-9) << s["structure"];
  }
  EXPECT_GT(identity["dense_tre_mm"]["max"].get<double>(), 0.5);
  const fs::path truth_field = subject_folder() / "xfm" / "sub-01_from-def_to-ref_mode-image_xfm.nii.gz";
  const nlohmann::json truth = evaluate({"--field", truth_field.string()}, folder / "truth.json");
  EXPECT_LT(truth["dense_tre_mm"]["mean"].get<double>(), 0.2);
  EXPECT_LT(truth["dense_tre_mm"]["mean"].get<double>(),
            0.2 * identity["dense_tre_mm"]["mean"].get<double>());
}

// The convention cross-check: transformix writes the field of a known affine (LPS, x_moving =
// A (x - c) + c + t); read as our fields are, it holds that displacement at every voxel, and
// eval scores each landmark as the transform moves it. A sign or axis-order error fails both.
TEST(EvalCommand, TransformixFieldOfAKnownAffineFollowsOurConvention) {
  const fs::path folder = fresh_folder("eval-affine");
  const phantasm::ImageGrid grid = reference_grid();
  const double angle = 4.0 * M_PI / 180.0;
  Eigen::Matrix3d a = Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
                      Eigen::Vector3d(1.02, 0.98, 1.0).asDiagonal();
  const Eigen::Vector3d t(1.5, -2.5, 4.0), c(3.0, -7.0, 11.0);
  std::ostringstream p;
  p.precision(17);
  p << "(Transform \"AffineTransform\")\n(NumberOfParameters 12)\n(TransformParameters";
  for (int r = 0; r < 3; ++r)
    for (int col = 0; col < 3; ++col)
      p << ' ' << a(r, col);
  p << ' ' << t.x() << ' ' << t.y() << ' ' << t.z() << ")\n(CenterOfRotationPoint " << c.x() << ' ' << c.y()
    << ' ' << c.z() << ")\n"
    << transformix_grid_lines(grid);
  write_text_file(folder / "affine.txt", p.str());
  const CommandResult transformix = run_command({"/usr/bin/transformix", "-def", "all", "-tp",
                                                 (folder / "affine.txt").string(), "-out", folder.string()});
  ASSERT_EQ(transformix.exit_code, 0) << transformix.out << transformix.err;
  const fs::path field_path = folder / "deformationField.nii.gz";
  const phantasm::DisplacementField field = phantasm::read_displacement_field(field_path);
  ASSERT_EQ(field.grid.dims, grid.dims);
  ASSERT_TRUE(field.grid.world_from_voxel.isApprox(grid.world_from_voxel, 1e-6));
  double worst = 0.0;
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i) {
        const Eigen::Vector3d x = grid.world_from_index(Eigen::Vector3d(i, j, k)).cwiseProduct(k_lps);
        const Eigen::Vector3d expected = a * (x - c) + c + t - x;
        const std::size_t v = (static_cast<std::size_t>(k) * grid.dims.y() + j) * grid.dims.x() + i;
        worst = std::max(worst, (field.lps_mm[v] - expected).norm());
      }
  EXPECT_LT(worst, 1e-4);

  const nlohmann::json scored = evaluate({"--field", field_path.string()}, folder / "affine.json");
  const auto def = landmarks("def");
  const auto ref = landmarks("ref");
  for (const auto& landmark : scored["landmarks"]) {
    const std::string name = landmark["name"];
    const Eigen::Vector3d x = ref.at(name).cwiseProduct(k_lps);
    const Eigen::Vector3d carried = (a * (x - c) + c + t).cwiseProduct(k_lps);
    EXPECT_NEAR(landmark["tre_mm"].get<double>(), (carried - def.at(name)).norm(), 1e-3) << name;
  }
}

TEST(EvalCommand, BadResultsGetClearMessages) {
  const fs::path folder = fresh_folder("eval-bad");
  const CommandResult make = run_command(
      {PHANTASM_PYTHON, "-c",
       "import nibabel as nib, numpy as np, sys\n"
       "nib.Nifti1Image(np.zeros((4, 4, 4, 3), np.float32), np.eye(4)).to_filename(sys.argv[1])\n"
       "nib.Nifti1Image(np.zeros((4, 4, 4, 1, 3), np.float32), np.eye(4)).to_filename(sys.argv[2])\n",
       (folder / "four_d.nii.gz").string(), (folder / "small.nii.gz").string()});
  ASSERT_EQ(make.exit_code, 0) << make.err;
  CommandResult run = run_command(
      {k_phantasm, "eval", small_dataset().string(), "--field", (folder / "four_d.nii.gz").string()});
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("four_d.nii.gz: expected a 5-D vector image (X, Y, Z, 1, 3) in the ITK convention, "
                         "found a 4-D (X, Y, Z, 3) volume"),
            std::string::npos)
      << run.err;
  run = run_command(
      {k_phantasm, "eval", small_dataset().string(), "--field", (folder / "small.nii.gz").string()});
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("small.nii.gz: expected the fixed image's grid (48 x 56 x 52 voxels"),
            std::string::npos)
      << run.err;
  run = run_command({k_phantasm, "eval", small_dataset().string(), "--identity", "--labels", "x.nii.gz"});
  EXPECT_EQ(run.exit_code, 2);
  run = run_command({k_phantasm, "eval", folder.string(), "--identity"});
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("expected a phantasm dataset with a complete subject "
                         "(derivatives/phantasm/sub-<id>/provenance.json), found none"),
            std::string::npos)
      << run.err;
}

// The landmark files are read strictly: an empty file or another header is an error naming the
// file (and line); a header alone is a dataset without landmarks, reported as such.
TEST(EvalCommand, LandmarkFilesWithoutAHeaderAreRefusedAndNoLandmarksAreSaidSo) {
  const fs::path copy = fresh_folder("eval-landmarks") / "out";
  fs::copy(small_dataset(), copy, fs::copy_options::recursive);
  const fs::path csv =
      copy / "derivatives" / "phantasm" / "sub-01" / "ses-ref" / "landmarks" / "sub-01_ses-ref_landmarks.csv";
  ASSERT_TRUE(fs::exists(csv));
  write_text_file(csv, "");
  CommandResult run = run_command({k_phantasm, "eval", copy.string(), "--identity"});
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("sub-01_ses-ref_landmarks.csv: expected the header name,organ,x_mm,y_mm,z_mm and a "
                         "line per landmark, found an empty file"),
            std::string::npos)
      << run.err;
  write_text_file(csv, "label,x,y,z\nscalp,1,2,3\n");
  run = run_command({k_phantasm, "eval", copy.string(), "--identity"});
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("sub-01_ses-ref_landmarks.csv:1: expected the header name,organ,x_mm,y_mm,z_mm, "
                         "found 'label,x,y,z'"),
            std::string::npos)
      << run.err;
  write_text_file(csv, "name,organ,x_mm,y_mm,z_mm\n");
  run = run_command({k_phantasm, "eval", copy.string(), "--identity"});
  EXPECT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("TRE mm                 none (no landmarks in the dataset)"), std::string::npos)
      << run.out;
}
