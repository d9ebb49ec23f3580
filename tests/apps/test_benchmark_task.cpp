// `phantasm task` and `phantasm eval TASK --results DIR`: the exported task read by a Learn2Reg-style
// loader written from the format's description (tests/apps/check_learn2reg_task.py), the ground
// truth scoring zero error, the usual misreadings scoring wrong with the warning that names them,
// bad results refused with nothing written, and each field convention checked by its own tool
// (transformix, mrtransform, dipy) carrying labels from one state to the other.

#include "evaluation/field_conventions.hpp"
#include "io/nifti_file.hpp"
#include "tests/apps/cli_fixtures.hpp"
#include "tests/apps/transformix_parameters.hpp"
#include "tests/support/shared_output.hpp"
#include "tests/support/subprocess.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <gtest/gtest.h>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

using namespace phantasm::testing;
namespace fs = std::filesystem;

namespace {

const std::string k_checker = (k_source_dir / "tests" / "apps" / "check_learn2reg_task.py").string();
const std::string k_result = "disp_0001_0000_0001_0001.nii.gz";

/// A small-head dataset and its task (T1w fixed, T1w moving), which the tests of this file read:
/// made once per build of the program and bytes of the scene (tests/support/shared_output.hpp),
/// not once per test process.
struct Made {
  fs::path dataset, task, truth;
};
const Made& small_task() {
  static const Made made = [] {
    const fs::path root = shared_output("benchmark-small-task", {k_small_scene}, [](const fs::path& folder) {
      const CommandResult run =
          run_command({k_phantasm, "run", k_small_scene.string(), "-o", (folder / "out").string(), "-q"});
      EXPECT_EQ(run.exit_code, 0) << run.err;
      if (run.exit_code != 0) return false;
      const CommandResult task = run_command({k_phantasm, "task", (folder / "out").string(), "-o",
                                              (folder / "task").string(), "--name", "SMALL"});
      EXPECT_EQ(task.exit_code, 0) << task.err;
      return task.exit_code == 0;
    });
    return Made{root / "out", root / "task", root / "task-truth"};
  }();
  return made;
}

phantasm::ImageGrid fixed_grid() {
  phantasm::ImageGrid grid;
  phantasm::read_nifti_labels(small_task().task / "labelsTr" / "SMALL_0001_0000.nii.gz", &grid);
  return grid;
}

struct Scored {
  CommandResult run;
  nlohmann::json scores;
};
Scored score(const fs::path& results, const std::string& convention = "learn2reg") {
  // In a folder of the test's own, removed with the others when the tests pass (beside the results
  // in /tmp, it stayed).
  static int scored = 0;
  const fs::path json = fresh_folder("benchmark-scores-" + std::to_string(++scored)) / "scores.json";
  Scored s;
  s.run = run_command({k_phantasm, "eval", small_task().task.string(), "--results", results.string(),
                       "--convention", convention, "--json", json.string(), "-q"});
  if (s.run.exit_code == 0) s.scores = nlohmann::json::parse(read_file(json));
  return s;
}

/// A results folder holding one field: the truth changed by `change` (voxel displacement at a voxel).
fs::path result_folder(const std::string& name,
                       const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& change) {
  const phantasm::ImageGrid grid = fixed_grid();
  const phantasm::DisplacementField truth =
      phantasm::read_field(small_task().truth / k_result, phantasm::FieldConvention::learn2reg, grid);
  const Eigen::Matrix3d ras_from_index = grid.world_from_voxel.topLeftCorner<3, 3>();
  std::vector<Eigen::Vector3d> ras = phantasm::ras_displacements(truth);
  for (auto& u : ras)
    u = ras_from_index * change(ras_from_index.inverse() * u);
  const fs::path folder = fresh_folder("benchmark-results-" + name);
  phantasm::write_field(folder / k_result, phantasm::field_from_ras(grid, ras),
                        phantasm::FieldConvention::learn2reg);
  return folder;
}

} // namespace

TEST(TaskCommand, ExportsALearn2RegTaskThatALoaderWrittenFromTheFormatReads) {
  const Made& m = small_task();
  const nlohmann::json dataset = nlohmann::json::parse(read_file(m.task / "SMALL_dataset.json"));
  EXPECT_EQ(dataset["name"], "SMALL");
  EXPECT_EQ(dataset["numRegistration_val"], 1);
  EXPECT_EQ(dataset["registration_val"][0]["fixed"], "./imagesTr/SMALL_0001_0000.nii.gz");
  EXPECT_EQ(dataset["registration_val"][0]["moving"], "./imagesTr/SMALL_0001_0001.nii.gz");
  EXPECT_EQ(dataset["tensorImageShape"]["0"], nlohmann::json({48, 56, 52}));
  // The images are the dataset's: reference T1w fixed, deformed T1w moving.
  EXPECT_EQ(read_file(m.task / "imagesTr" / "SMALL_0001_0000.nii.gz"),
            read_file(m.dataset / "sub-01" / "ses-ref" / "anat" / "sub-01_ses-ref_T1w.nii.gz"));
  EXPECT_EQ(read_file(m.task / "imagesTr" / "SMALL_0001_0001.nii.gz"),
            read_file(m.dataset / "sub-01" / "ses-def" / "anat" / "sub-01_ses-def_T1w.nii.gz"));
  // The truth is apart from the task: nothing of it lies in the task folder.
  EXPECT_FALSE(fs::exists(m.task / k_result));
  for (const auto& entry : fs::recursive_directory_iterator(m.task))
    EXPECT_EQ(entry.path().filename().string().rfind("disp_", 0), std::string::npos) << entry.path();

  const CommandResult loader =
      run_command({PHANTASM_PYTHON, k_checker, "load", m.task.string(), m.truth.string()});
  ASSERT_EQ(loader.exit_code, 0) << loader.out << loader.err;
  const nlohmann::json report = nlohmann::json::parse(loader.out);
  ASSERT_EQ(report["pairs"].size(), 1u);
  const nlohmann::json& pair = report["pairs"][0];
  EXPECT_EQ(pair["result"], k_result);
  EXPECT_GE(pair["keypoints"].get<int>(), 10);
  // Read as Learn2Reg reads a result, the truth carries the keypoints onto their moving
  // positions (within 0.05 voxel, trilinear interpolation) though they moved, and warps the
  // moving labels closer to the fixed ones than they were.
  EXPECT_LT(pair["tre_truth_voxels_max"].get<double>(), 0.05);
  EXPECT_GT(pair["tre_identity_voxels_max"].get<double>(), 0.1);
  EXPECT_GT(pair["dice_truth"].get<double>(), pair["dice_identity"].get<double>());

  // A task into a folder that holds files, or of a contrast the dataset lacks: exit 2, nothing made.
  const fs::path other = fresh_folder("benchmark-task-bad");
  const CommandResult occupied = run_command({k_phantasm, "task", m.dataset.string(), "-o", m.task.string()});
  EXPECT_EQ(occupied.exit_code, 2);
  EXPECT_NE(occupied.err.find("expected a new or empty folder"), std::string::npos) << occupied.err;
  const CommandResult contrast = run_command(
      {k_phantasm, "task", m.dataset.string(), "-o", (other / "t").string(), "--moving-contrast", "FLAIR"});
  EXPECT_EQ(contrast.exit_code, 2);
  EXPECT_NE(
      contrast.err.find("--moving-contrast: expected a contrast of the dataset (T1w, T2w), found 'FLAIR'"),
      std::string::npos)
      << contrast.err;
  EXPECT_FALSE(fs::exists(other / "t"));
  EXPECT_FALSE(fs::exists(other / "t-truth"));
  // The truth inside the task, named with a trailing slash: refused all the same.
  const CommandResult inside =
      run_command({k_phantasm, "task", m.dataset.string(), "-o", (other / "s").string() + "/", "--truth",
                   (other / "s" / "truth").string()});
  EXPECT_EQ(inside.exit_code, 2);
  EXPECT_NE(inside.err.find("--truth: expected a folder apart from the task"), std::string::npos)
      << inside.err;
  EXPECT_FALSE(fs::exists(other / "s"));
  // A task's option without --results is refused, not ignored.
  const CommandResult alone = run_command(
      {k_phantasm, "eval", m.dataset.string(), "--identity", "--csv", (other / "scores.csv").string()});
  EXPECT_EQ(alone.exit_code, 2) << alone.err;
  EXPECT_NE(alone.err.find("--csv requires --results"), std::string::npos) << alone.err;
  EXPECT_FALSE(fs::exists(other / "scores.csv"));
}

TEST(TaskCommand, PairsCanCrossContrasts) {
  const Made& m = small_task();
  const fs::path root = fresh_folder("benchmark-task-cross");
  const CommandResult task = run_command({k_phantasm, "task", m.dataset.string(), "-o",
                                          (root / "cross").string(), "--moving-contrast", "T2w", "-q"});
  ASSERT_EQ(task.exit_code, 0) << task.err;
  const nlohmann::json dataset = nlohmann::json::parse(read_file(root / "cross" / "PHANTASM_dataset.json"));
  EXPECT_EQ(dataset["modality"]["0"], "MR T1w");
  EXPECT_EQ(dataset["modality"]["1"], "MR T2w");
  EXPECT_EQ(read_file(root / "cross" / "imagesTr" / "PHANTASM_0001_0001.nii.gz"),
            read_file(m.dataset / "sub-01" / "ses-def" / "anat" / "sub-01_ses-def_T2w.nii.gz"));
  // The truth does not depend on the contrast.
  EXPECT_EQ(read_file(root / "cross-truth" / k_result), read_file(m.truth / k_result));
}

TEST(EvalTask, TheGroundTruthScoresZeroErrorAndDrawsNoWarning) {
  const fs::path results = fresh_folder("benchmark-truth-results");
  fs::copy_file(small_task().truth / k_result, results / k_result);
  const Scored s = score(results);
  ASSERT_EQ(s.run.exit_code, 0) << s.run.err;
  const nlohmann::json& pair = s.scores["pairs"][0];
  EXPECT_EQ(pair["endpoint_error_mm"]["max"].get<double>(), 0.0);
  EXPECT_GT(pair["endpoint_error_mm"]["count"].get<int>(), 1000);
  EXPECT_LT(pair["tre_mm"]["max"].get<double>(), 0.1);
  EXPECT_EQ(pair["ndv"]["percent"].get<double>(), 0.0);
  EXPECT_TRUE(s.scores["warnings"].empty()) << s.scores["warnings"];
  EXPECT_EQ(s.run.err.find("warning"), std::string::npos) << s.run.err;
}

// The dataset's dense landmarks reach the truth (name, organ, fixed and moving voxel
// coordinates) and are scored per structure: no registration scores each organ's true motion
// (its mean and 95th percentile, computed here from the file), the truth itself scores zero
// within the trilinear interpolation of its field.
TEST(EvalTask, DenseKeypointsScoreTheTrueMotionWithoutRegistrationAndZeroForTheTruth) {
  const Made& m = small_task();
  const nlohmann::json truth = nlohmann::json::parse(read_file(m.truth / "truth.json"));
  ASSERT_TRUE(truth["pairs"][0].contains("dense_keypoints"));
  const std::string csv = read_file(m.truth / truth["pairs"][0]["dense_keypoints"].get<std::string>());
  std::istringstream lines(csv);
  std::string line;
  std::getline(lines, line);
  EXPECT_EQ(line, "name,organ,fixed_i,fixed_j,fixed_k,moving_i,moving_j,moving_k");
  const phantasm::ImageGrid grid = fixed_grid();
  std::map<std::string, std::vector<double>> motion; // per organ, |moving - fixed| in mm
  while (std::getline(lines, line)) {
    std::vector<std::string> cells;
    std::istringstream fields(line);
    for (std::string cell; std::getline(fields, cell, ',');)
      cells.push_back(cell);
    ASSERT_EQ(cells.size(), 8u) << line;
    const Eigen::Vector3d fixed(std::stod(cells[2]), std::stod(cells[3]), std::stod(cells[4]));
    const Eigen::Vector3d moving(std::stod(cells[5]), std::stod(cells[6]), std::stod(cells[7]));
    motion[cells[1]].push_back((grid.world_from_index(moving) - grid.world_from_index(fixed)).norm());
  }
  // The small head's three organs, 300 points each (the default) where the map is exact over
  // enough of the organ: its grey matter's 77 coarse tets leave much of it outside.
  ASSERT_EQ(motion.size(), 3u);
  std::size_t rows = 0;
  for (const auto& [organ, values] : motion) {
    EXPECT_LE(values.size(), 300u) << organ;
    EXPECT_GE(values.size(), 200u) << organ;
    rows += values.size();
  }

  const Scored none = score(
      result_folder("dense-none", [](const Eigen::Vector3d&) { return Eigen::Vector3d::Zero().eval(); }));
  ASSERT_EQ(none.run.exit_code, 0) << none.run.err;
  const nlohmann::json& dense = none.scores["pairs"][0]["dense_tre_mm"];
  ASSERT_EQ(dense["count"].get<std::size_t>(), rows);
  ASSERT_EQ(dense["by_structure"].size(), 3u);
  double moved_most = 0.0;
  for (const auto& s : dense["by_structure"]) {
    std::vector<double> values = motion.at(s["structure"].get<std::string>());
    double sum = 0.0;
    for (double v : values)
      sum += v;
    std::sort(values.begin(), values.end());
    const double at = 0.95 * static_cast<double>(values.size() - 1);
    const auto below = static_cast<std::size_t>(at);
    const double p95 =
        values[below] + (at - static_cast<double>(below)) * (values[below + 1] - values[below]);
    EXPECT_NEAR(s["mean"].get<double>(), sum / static_cast<double>(values.size()), 1e-5) << s["structure"];
    EXPECT_NEAR(s["p95"].get<double>(), p95, 1e-5) << s["structure"];
    moved_most = std::max(moved_most, s["max"].get<double>());
  }
  EXPECT_GT(moved_most, 0.5); // the points move: otherwise the test would prove nothing
  EXPECT_NEAR(none.scores["summary"]["mean_dense_tre_mm"].get<double>(), dense["mean"].get<double>(), 1e-12);

  const Scored exact = score(result_folder("dense-truth", [](const Eigen::Vector3d& u) { return u; }));
  ASSERT_EQ(exact.run.exit_code, 0) << exact.run.err;
  const nlohmann::json& zero = exact.scores["pairs"][0]["dense_tre_mm"];
  // The small head's voxels are 2 mm: within a tenth of a voxel on average, and a few points
  // where a moved organ slides along one that stays (the field steps within a voxel there).
  EXPECT_LT(zero["mean"].get<double>(), 0.2);
  EXPECT_LT(zero["mean"].get<double>(), 0.2 * dense["mean"].get<double>());
}

TEST(EvalTask, EachMisreadingOfTheTruthScoresWrongAndDrawsTheWarningThatNamesIt) {
  const Eigen::Vector3d spacing = fixed_grid().spacing_mm;
  struct Case {
    std::string name, warning;
    fs::path results;
  };
  std::vector<Case> cases = {
      {"shift", "constant offset of (1, 0, 0) voxels",
       result_folder("shift",
                     [](const Eigen::Vector3d& u) { return Eigen::Vector3d(u + Eigen::Vector3d(1, 0, 0)); })},
      {"flip", "component i reversed",
       result_folder("flip", [](const Eigen::Vector3d& u) { return Eigen::Vector3d(-u.x(), u.y(), u.z()); })},
      {"mm", "in mm where voxels are expected", result_folder("mm", [&](const Eigen::Vector3d& u) {
         return Eigen::Vector3d(u.cwiseProduct(spacing));
       })}};
  // The inverse: the dataset's other field (from the reference to the deformed state), written as
  // a Learn2Reg result on the same grid.
  const fs::path inverse = fresh_folder("benchmark-results-inverse");
  phantasm::write_field(inverse / k_result,
                        phantasm::read_field(small_task().dataset / "derivatives" / "phantasm" / "sub-01" /
                                                 "xfm" / "sub-01_from-ref_to-def_mode-image_xfm.nii.gz",
                                             phantasm::FieldConvention::itk, fixed_grid()),
                        phantasm::FieldConvention::learn2reg);
  cases.push_back({"inverse", "the inverse direction", inverse});
  for (const Case& c : cases) {
    const Scored s = score(c.results);
    ASSERT_EQ(s.run.exit_code, 0) << c.name << ": " << s.run.err;
    const nlohmann::json& pair = s.scores["pairs"][0];
    EXPECT_GT(pair["endpoint_error_mm"]["max"].get<double>(), 1.0) << c.name; // the truth: 0
    ASSERT_EQ(s.scores["warnings"].size(), 1u) << c.name << ": " << s.scores["warnings"];
    EXPECT_NE(s.scores["warnings"][0].get<std::string>().find(c.warning), std::string::npos)
        << c.name << ": " << s.scores["warnings"][0];
    EXPECT_NE(s.run.err.find("warning: "), std::string::npos) << c.name;
  }
}

TEST(EvalTask, BadResultsAreRefusedNamingTheFileWithNothingWritten) {
  const Made& m = small_task();
  const fs::path root = fresh_folder("benchmark-bad-results");
  const CommandResult made =
      run_command({PHANTASM_PYTHON, k_checker, "bad", (m.truth / k_result).string(), root.string()});
  ASSERT_EQ(made.exit_code, 0) << made.err;
  fs::create_directories(root / "missing");
  fs::create_directories(root / "extra");
  fs::copy_file(m.truth / k_result, root / "extra" / k_result);
  fs::copy_file(m.truth / k_result, root / "extra" / "disp_0002_0000_0002_0001.nii.gz");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"missing", "missing: " + k_result},
      {"extra", "not pairs of the task: disp_0002_0000_0002_0001.nii.gz"},
      {"int16", "expected float32 or float64 displacements"},
      {"nan", "expected finite"},
      {"shape", "expected a field on the fixed grid (48 x 56 x 52 voxels"}};
  for (const auto& [folder, message] : cases) {
    const fs::path json = root / (folder + ".json"), csv = root / (folder + ".csv");
    const CommandResult run =
        run_command({k_phantasm, "eval", m.task.string(), "--results", (root / folder).string(), "--json",
                     json.string(), "--csv", csv.string()});
    EXPECT_EQ(run.exit_code, 2) << folder << ": " << run.err;
    EXPECT_NE(run.err.find(message), std::string::npos) << folder << ": " << run.err;
    EXPECT_EQ(raw_library_marker(run.err), "") << run.err;
    EXPECT_FALSE(fs::exists(json)) << folder;
    EXPECT_FALSE(fs::exists(csv)) << folder;
  }
  // An ITK field of the right size on another voxel-to-world matrix (shifted 10 mm): its vectors
  // are world mm of another space, refused naming the file and nothing written.
  {
    phantasm::ImageGrid shifted = fixed_grid();
    shifted.world_from_voxel(0, 3) += 10.0;
    const phantasm::DisplacementField truth =
        phantasm::read_field(m.truth / k_result, phantasm::FieldConvention::learn2reg, fixed_grid());
    fs::create_directories(root / "affine");
    phantasm::write_field(root / "affine" / k_result,
                          phantasm::field_from_ras(shifted, phantasm::ras_displacements(truth)),
                          phantasm::FieldConvention::itk);
    const fs::path json = root / "affine.json";
    const CommandResult run =
        run_command({k_phantasm, "eval", m.task.string(), "--results", (root / "affine").string(),
                     "--convention", "itk", "--json", json.string()});
    EXPECT_EQ(run.exit_code, 2) << run.err;
    EXPECT_NE(run.err.find(k_result + ": expected a field on the fixed grid's voxel-to-world matrix"),
              std::string::npos)
        << run.err;
    EXPECT_FALSE(fs::exists(json));
  }
  // A ground truth of another task: refused.
  const fs::path cross = root / "cross";
  ASSERT_EQ(run_command({k_phantasm, "task", m.dataset.string(), "-o", cross.string(), "--name", "SMALL",
                         "--moving-contrast", "T2w", "-q"})
                .exit_code,
            0);
  const CommandResult mixed =
      run_command({k_phantasm, "eval", m.task.string(), "--results", (root / "extra").string(), "--truth",
                   (root / "cross-truth").string()});
  EXPECT_EQ(mixed.exit_code, 2);
  EXPECT_NE(mixed.err.find("a task and truth of different datasets"), std::string::npos) << mixed.err;
}

TEST(FieldConventionTools, EachConventionsOwnToolCarriesTheLabelsAsPhantasmDoes) {
  // A field whose every component moves: a rotation of 8 degrees about an oblique axis through
  // the centre and a shift of (3, -2, 1.5) mm, so a transposed, flipped or scaled reading would
  // carry the labels elsewhere.
  const Made& m = small_task();
  const phantasm::ImageGrid grid = fixed_grid();
  const Eigen::Matrix3d rotation =
      Eigen::AngleAxisd(8.0 * M_PI / 180.0, Eigen::Vector3d(0.3, 0.5, 1.0).normalized()).toRotationMatrix();
  std::vector<Eigen::Vector3d> ras(static_cast<std::size_t>(grid.voxel_count()));
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i) {
        const Eigen::Vector3d x = grid.world_from_index(Eigen::Vector3d(i, j, k));
        ras[phantasm::voxel_index(grid.dims, i, j, k)] = rotation * x - x + Eigen::Vector3d(3.0, -2.0, 1.5);
      }
  const phantasm::DisplacementField field = phantasm::field_from_ras(grid, ras);
  const fs::path root = fresh_folder("benchmark-tools");
  const fs::path moving_labels = m.task / "labelsTr" / "SMALL_0001_0001.nii.gz";
  phantasm::ImageGrid moving_grid;
  const std::vector<std::int32_t> moving = phantasm::read_nifti_labels(moving_labels, &moving_grid);
  const std::vector<std::int32_t> expected = phantasm::warp_labels(moving, moving_grid, field);
  std::size_t moved = 0;
  for (std::size_t v = 0; v < moving.size(); ++v)
    moved += expected[v] != moving[v];
  ASSERT_GT(moved, 1000u); // the field moves labels: otherwise agreement would prove nothing

  auto agreement = [&](const fs::path& warped_path, const std::string& tool) {
    phantasm::ImageGrid warped_grid;
    const std::vector<std::int32_t> warped = phantasm::read_nifti_labels(warped_path, &warped_grid);
    EXPECT_EQ(warped_grid.dims, grid.dims) << tool;
    if (warped.size() != expected.size()) return;
    std::size_t differ = 0;
    for (std::size_t v = 0; v < warped.size(); ++v)
      differ += warped[v] != expected[v];
    // Nearest-neighbour ties at half voxels may round either way: a few voxels, not a misreading.
    EXPECT_LT(static_cast<double>(differ), 0.02 * static_cast<double>(moved))
        << tool << ": " << differ << " of " << moved << " moved voxels differ";
  };

  // ITK: transformix with a DeformationFieldTransform.
  phantasm::write_field(root / "itk.nii.gz", field, phantasm::FieldConvention::itk);
  write_text_file(root / "parameters.txt", deformation_field_parameters(root / "itk.nii.gz", grid));
  fs::create_directories(root / "transformix");
  const CommandResult transformix =
      run_command({"/usr/bin/transformix", "-in", moving_labels.string(), "-out",
                   (root / "transformix").string(), "-tp", (root / "parameters.txt").string()});
  ASSERT_EQ(transformix.exit_code, 0) << transformix.out << transformix.err;
  agreement(root / "transformix" / "result.nii.gz", "transformix");

  // MRtrix3: mrtransform -warp with the deformation (positions in scanner space).
  phantasm::write_field(root / "deformation.nii.gz", field, phantasm::FieldConvention::mrtrix_deformation);
  const CommandResult mrtransform = run_command({"/usr/bin/mrtransform", "-quiet", moving_labels.string(),
                                                 "-warp", (root / "deformation.nii.gz").string(), "-interp",
                                                 "nearest", (root / "mrtrix.nii.gz").string()});
  ASSERT_EQ(mrtransform.exit_code, 0) << mrtransform.err;
  agreement(root / "mrtrix.nii.gz", "mrtransform");
  // MRtrix3's own conversion of our displacement gives our deformation.
  phantasm::write_field(root / "displacement.nii.gz", field, phantasm::FieldConvention::mrtrix_displacement);
  const CommandResult convert =
      run_command({"/usr/bin/warpconvert", "-quiet", (root / "displacement.nii.gz").string(),
                   "displacement2deformation", (root / "converted.nii.gz").string()});
  ASSERT_EQ(convert.exit_code, 0) << convert.err;
  const phantasm::DisplacementField converted =
      phantasm::read_field(root / "converted.nii.gz", phantasm::FieldConvention::mrtrix_deformation, grid);
  double worst = 0.0;
  for (std::size_t v = 0; v < converted.lps_mm.size(); ++v)
    worst = std::max(worst, (converted.lps_mm[v] - field.lps_mm[v]).norm());
  EXPECT_LT(worst, 1e-3);

  // dipy: DiffeomorphicMap with the displacement in world mm as its forward field.
  const CommandResult dipy = run_command(
      {PHANTASM_PYTHON, k_checker, "dipy", (m.task / "labelsTr" / "SMALL_0001_0000.nii.gz").string(),
       moving_labels.string(), (root / "displacement.nii.gz").string(), (root / "dipy.nii.gz").string()});
  ASSERT_EQ(dipy.exit_code, 0) << dipy.err;
  agreement(root / "dipy.nii.gz", "dipy");
}

TEST(TaskCommand, ASweepGivesOnePairPerSubjectAndEachTruthScoresZero) {
  const fs::path root = fresh_folder("benchmark-sweep");
  const CommandResult batch = run_command(
      {k_phantasm, "batch", (k_source_dir / "tests" / "data" / "sweeps" / "three-subjects.yaml").string(),
       "-o", (root / "out").string(), "-q"});
  ASSERT_EQ(batch.exit_code, 0) << batch.err;
  const CommandResult task =
      run_command({k_phantasm, "task", (root / "out").string(), "-o", (root / "task").string(), "-q"});
  ASSERT_EQ(task.exit_code, 0) << task.err;
  const nlohmann::json truth = nlohmann::json::parse(read_file(root / "task-truth" / "truth.json"));
  ASSERT_EQ(truth["pairs"].size(), 3u);
  fs::create_directories(root / "results");
  std::set<std::string> subjects;
  for (const auto& pair : truth["pairs"]) {
    subjects.insert(pair["subject"].get<std::string>());
    fs::copy_file(root / "task-truth" / pair["result"].get<std::string>(),
                  root / "results" / pair["result"].get<std::string>());
  }
  EXPECT_EQ(subjects.size(), 3u);
  const CommandResult eval =
      run_command({k_phantasm, "eval", (root / "task").string(), "--results", (root / "results").string(),
                   "--csv", (root / "scores.csv").string(), "--json", (root / "scores.json").string(), "-q"});
  ASSERT_EQ(eval.exit_code, 0) << eval.err;
  std::istringstream csv(read_file(root / "scores.csv"));
  std::string line;
  std::getline(csv, line);
  int rows = 0;
  while (std::getline(csv, line)) {
    ++rows;
    std::vector<std::string> cells;
    std::istringstream fields(line);
    for (std::string cell; std::getline(fields, cell, ',');)
      cells.push_back(cell);
    ASSERT_EQ(cells.size(), 14u) << line;
    EXPECT_EQ(cells[8], "0") << line;  // endpoint error mean, mm
    EXPECT_EQ(cells[13], "0") << line; // warnings
  }
  EXPECT_EQ(rows, 3);
  // Results per varied factor of the sweep (participants.tsv: the seed, 11, 12 and 13).
  const nlohmann::json scores = nlohmann::json::parse(read_file(root / "scores.json"));
  const nlohmann::json& seeds = scores["by_factor"]["seed"];
  ASSERT_EQ(seeds.size(), 3u) << scores["by_factor"];
  for (const char* seed : {"11", "12", "13"}) {
    ASSERT_TRUE(seeds.contains(seed)) << seeds;
    EXPECT_EQ(seeds[seed]["pairs"], 1);
    EXPECT_EQ(seeds[seed]["mean_endpoint_error_mm"].get<double>(), 0.0);
  }
}
