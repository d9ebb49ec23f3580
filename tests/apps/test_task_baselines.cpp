// The benchmark kit's runner (scripts/register_task.py) and its baselines, run through the same
// command template a user's method uses: on a coarse copy of the main job's pair (the Colin head
// of data-synthetic/colin-head.yaml, 4 mm) elastix and dipy's SyN bring the landmarks closer than
// no registration does; a method's field in each convention reaches eval as written; the truth's
// two directions are inverse consistent and a mismatched pair is not; bad templates, failing
// methods and a reverse field of another size are refused with nothing written.

#include "evaluation/field_conventions.hpp"
#include "io/nifti_file.hpp"
#include "tests/apps/cli_fixtures.hpp"
#include "tests/support/coarse_runs.hpp"
#include "tests/support/shared_output.hpp"
#include "tests/support/subprocess.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <iomanip>
#include <iostream>
#include <sstream>

using namespace phantasm::testing;
namespace fs = std::filesystem;

namespace {

const std::string k_runner = (k_source_dir / "scripts" / "register_task.py").string();
const std::string k_result = "disp_0001_0000_0001_0001.nii.gz";
const std::string k_reverse = "disp_0001_0001_0001_0000.nii.gz";

struct Made {
  fs::path dataset, task, truth;
};

/// The task of `dataset` (root/task, with its truth in root/task-truth).
Made task_of(const fs::path& dataset, const fs::path& root) {
  const Made m{dataset, root / "task", root / "task-truth"};
  const CommandResult task = run_command({k_phantasm, "task", dataset.string(), "-o", m.task.string(), "-q"});
  EXPECT_EQ(task.exit_code, 0) << task.err;
  return m;
}

/// A dataset of `scene` (root/out) and its task.
Made made_task(const fs::path& scene, const fs::path& root) {
  const CommandResult run =
      run_command({k_phantasm, "run", scene.string(), "-o", (root / "out").string(), "-q"});
  EXPECT_EQ(run.exit_code, 0) << run.err;
  return task_of(root / "out", root);
}

/// The small head's dataset and task, which four tests of this file read: made once per build of
/// the program and bytes of the scene (tests/support/shared_output.hpp), not once per test process.
const Made& small_task() {
  static const Made made = [] {
    const fs::path root = shared_output("baselines-small-task", {k_small_scene}, [](const fs::path& folder) {
      made_task(k_small_scene, folder);
      return !::testing::Test::HasFailure();
    });
    return Made{root / "out", root / "task", root / "task-truth"};
  }();
  return made;
}

/// The main job's pair made coarse (tests/support/coarse_scenes.hpp: 4 mm voxels, 320-triangle
/// surfaces, one T1w sequence, no meshes): the dataset of the Colin head's measured coarse run
/// (tests/support/coarse_runs.hpp, which its own test checks) and its task.
const Made& colin_task() {
  static const Made made = task_of(shared_coarse_colin_run().out, fresh_folder("baselines-colin"));
  return made;
}

/// Runs the runner on a task into `results`; extra arguments after the folders.
CommandResult register_task(const Made& m, const fs::path& results, std::vector<std::string> extra) {
  std::vector<std::string> argv = {PHANTASM_PYTHON, k_runner, m.task.string(), "-o", results.string()};
  argv.insert(argv.end(), extra.begin(), extra.end());
  return run_command(argv);
}

/// Scores a results folder with eval's defaults (the Learn2Reg convention).
nlohmann::json scores_of(const Made& m, const fs::path& results) {
  const fs::path json = results.parent_path() / (results.filename().string() + ".json");
  const CommandResult eval = run_command(
      {k_phantasm, "eval", m.task.string(), "--results", results.string(), "--json", json.string(), "-q"});
  EXPECT_EQ(eval.exit_code, 0) << eval.err;
  return eval.exit_code == 0 ? nlohmann::json::parse(read_file(json)) : nlohmann::json::object();
}

fs::path xfm(const Made& m, const std::string& direction) {
  return m.dataset / "derivatives" / "phantasm" / "sub-01" / "xfm" /
         ("sub-01_" + direction + "_mode-image_xfm.nii.gz");
}

/// A template that copies `forward` (and `backward`, when given) as a method's outputs.
std::string copying_template(const fs::path& forward, const fs::path& backward = {}) {
  if (backward.empty()) return "cp '" + forward.string() + "' {output}";
  return "sh -c 'cp \"$0\" \"$1\" && cp \"$2\" \"$3\"' '" + forward.string() + "' {output} '" +
         backward.string() + "' {inverse_output}";
}

/// One row of the baselines' table in docs/benchmark-tasks.md.
void print_row(const std::string& name, const nlohmann::json& pair, const nlohmann::json& seconds) {
  auto cell = [](const nlohmann::json& value, int digits) {
    if (!value.is_number()) return std::string("-");
    std::ostringstream text;
    text << std::fixed << std::setprecision(digits) << value.get<double>();
    return text.str();
  };
  const nlohmann::json& consistency = pair["inverse_consistency_mm"];
  std::cout << "| " << name << " | " << cell(pair["tre_mm"]["mean"], 2) << " | " << cell(pair["mean_dice"], 3)
            << " | " << cell(pair["mean_hd95_mm"], 2) << " | " << cell(pair["endpoint_error_mm"]["mean"], 2)
            << " | " << cell(pair["ndv"]["percent"], 3) << " | "
            << cell(pair["jacobian_central_differences"]["log_jacobian_sd"], 3) << " | "
            << (consistency.is_object() ? cell(consistency["mean"], 4) : std::string("-")) << " | "
            << cell(seconds, 1) << " |" << std::endl;
}

} // namespace

TEST(TaskBaselines, EachLowersTheLandmarkErrorOfTheMainJobsCoarsePairBelowNoRegistration) {
  const Made& m = colin_task();
  const fs::path root = m.task.parent_path();
  std::map<std::string, nlohmann::json> pairs;
  const std::vector<std::pair<std::string, std::string>> baselines = {
      {"none", ""}, {"elastix", "--iterations 100"}, {"syn", ""}};
  for (const auto& [name, options] : baselines) {
    const fs::path results = root / ("results-" + name);
    const CommandResult run = register_task(m, results, {"--baseline", name, "--baseline-args", options});
    ASSERT_EQ(run.exit_code, 0) << name << ": " << run.out << run.err;
    const nlohmann::json record = nlohmann::json::parse(read_file(results / "register_task.json"));
    EXPECT_EQ(record["pairs"].size(), 1u) << name;
    const nlohmann::json scores = scores_of(m, results);
    ASSERT_EQ(scores["pairs"].size(), 1u) << name;
    pairs[name] = scores["pairs"][0];
    print_row(name, scores["pairs"][0], record["pairs"][0]["wall_seconds"]);
    // Each baseline's convention was turned into the one eval reads: no misreading suspected.
    EXPECT_TRUE(scores["warnings"].empty()) << name << ": " << scores["warnings"];
  }
  const double none = pairs["none"]["tre_mm"]["mean"].get<double>();
  EXPECT_GT(none, 0.3); // the landmarks moved: otherwise a lower error would prove nothing
  EXPECT_EQ(pairs["none"]["inverse_consistency_mm"]["max"].get<double>(), 0.0);
  for (const char* name : {"elastix", "syn"}) {
    const nlohmann::json& pair = pairs[name];
    // Measured: none 0.92 mm, elastix 0.46 mm, SyN 0.56 mm (docs/benchmark-tasks.md).
    EXPECT_LT(pair["tre_mm"]["mean"].get<double>(), 0.8 * none) << name;
    EXPECT_GT(pair["mean_dice"].get<double>(), pairs["none"]["mean_dice"].get<double>()) << name;
    EXPECT_LT(pair["ndv"]["percent"].get<double>(), 0.1) << name;
  }
  // SyN returns both directions; they compose to nearly the identity (measured 0.004 mm).
  ASSERT_TRUE(pairs["syn"]["inverse_consistency_mm"].is_object());
  EXPECT_LT(pairs["syn"]["inverse_consistency_mm"]["mean"].get<double>(), 0.1);
  EXPECT_TRUE(pairs["elastix"]["inverse_consistency_mm"].is_null());
}

TEST(TaskBaselines, AMethodsFieldInEachConventionReachesEvalAsWritten) {
  const Made& m = small_task();
  phantasm::ImageGrid grid;
  phantasm::read_nifti_labels(m.task / "labelsTr" / "PHANTASM_0001_0000.nii.gz", &grid);
  const phantasm::DisplacementField truth =
      phantasm::read_field(m.truth / k_result, phantasm::FieldConvention::learn2reg, grid);
  const fs::path root = fresh_folder("baselines-conventions");
  for (const auto convention :
       {phantasm::FieldConvention::learn2reg, phantasm::FieldConvention::itk,
        phantasm::FieldConvention::mrtrix_displacement, phantasm::FieldConvention::mrtrix_deformation}) {
    const std::string name = phantasm::to_string(convention);
    const fs::path written = root / (name + ".nii.gz");
    phantasm::write_field(written, truth, convention);
    const fs::path results = root / ("results-" + name);
    const CommandResult run =
        register_task(m, results, {"--command", copying_template(written), "--convention", name});
    ASSERT_EQ(run.exit_code, 0) << name << ": " << run.err;
    const nlohmann::json scores = scores_of(m, results);
    ASSERT_EQ(scores["pairs"].size(), 1u) << name;
    // float32 positions of a deformation round to about 1e-5 mm.
    EXPECT_LT(scores["pairs"][0]["endpoint_error_mm"]["max"].get<double>(), 1e-3) << name;
    EXPECT_TRUE(scores["warnings"].empty()) << name << ": " << scores["warnings"];
  }
  // Declared in the wrong convention (voxels read as mm on a 2 mm grid): wrong, and eval says how.
  const fs::path results = root / "results-misdeclared";
  ASSERT_EQ(register_task(m, results,
                          {"--command", copying_template(root / "learn2reg.nii.gz"), "--convention",
                           "mrtrix-displacement"})
                .exit_code,
            0);
  const nlohmann::json scores = scores_of(m, results);
  EXPECT_GT(scores["pairs"][0]["endpoint_error_mm"]["max"].get<double>(), 1.0);
  ASSERT_EQ(scores["warnings"].size(), 1u) << scores["warnings"];
  EXPECT_NE(scores["warnings"][0].get<std::string>().find("displacements in voxels where mm are expected"),
            std::string::npos)
      << scores["warnings"][0];
}

TEST(TaskBaselines, TheTruthsTwoDirectionsAreInverseConsistentAndAMismatchedPairIsNot) {
  const Made& m = small_task();
  const fs::path root = fresh_folder("baselines-inverse");
  // The dataset's own fields, ITK convention: from the deformed state to the reference (the
  // task's forward direction, fixed = reference) and back.
  const fs::path forward = xfm(m, "from-def_to-ref"), backward = xfm(m, "from-ref_to-def");
  ASSERT_EQ(register_task(m, root / "truth",
                          {"--command", copying_template(forward, backward), "--convention", "itk"})
                .exit_code,
            0);
  EXPECT_TRUE(fs::exists(root / "truth" / k_reverse));
  const nlohmann::json truth = scores_of(m, root / "truth")["pairs"][0];
  EXPECT_EQ(truth["endpoint_error_mm"]["max"].get<double>(), 0.0);
  const nlohmann::json& consistent = truth["inverse_consistency_mm"];
  ASSERT_TRUE(consistent.is_object()) << truth;
  EXPECT_GT(consistent["count"].get<int>(), 1000);
  // Exact maps, composed through trilinear interpolation: measured mean 0.0003 mm, max 0.2 mm
  // (a tenth of a 2 mm voxel, where a boundary's motion changes within a voxel).
  EXPECT_LT(consistent["mean"].get<double>(), 0.01);
  EXPECT_LT(consistent["max"].get<double>(), 0.5);

  // The forward field returned as its own reverse: points move twice as far instead of home.
  ASSERT_EQ(register_task(m, root / "mismatched",
                          {"--command", copying_template(forward, forward), "--convention", "itk"})
                .exit_code,
            0);
  const nlohmann::json inconsistent = scores_of(m, root / "mismatched")["pairs"][0]["inverse_consistency_mm"];
  ASSERT_TRUE(inconsistent.is_object());
  phantasm::ImageGrid grid;
  phantasm::read_nifti_labels(m.task / "labelsTr" / "PHANTASM_0001_0000.nii.gz", &grid);
  const phantasm::DisplacementField moved =
      phantasm::read_field(m.truth / k_result, phantasm::FieldConvention::learn2reg, grid);
  const phantasm::NiftiVolume mask = phantasm::read_nifti(m.truth / "mask_0001_0000_0001_0001.nii.gz");
  double largest = 0.0;
  for (std::size_t v = 0; v < moved.lps_mm.size(); ++v)
    if (mask.values[v] > 0.5) largest = std::max(largest, moved.lps_mm[v].norm());
  ASSERT_GT(largest, 1.0);
  EXPECT_GT(inconsistent["max"].get<double>(), 1.5 * largest);
  EXPECT_GT(inconsistent["mean"].get<double>(), 20.0 * consistent["mean"].get<double>());
}

TEST(TaskBaselines, BadTemplatesAndFailingMethodsAreRefusedWithNothingWritten) {
  const Made& m = small_task();
  const fs::path root = fresh_folder("baselines-bad");
  struct Case {
    std::vector<std::string> arguments;
    int exit_code;
    std::string message;
  };
  const std::vector<Case> cases = {
      {{"--command", "cp {fixed} /dev/null"}, 2, "expected the placeholder {output}"},
      {{"--command", "cp {fixd} {output}"}, 2, "found {fixd}"},
      {{"--command", "cp {fixed {output}"}, 2, "a lone brace"},
      {{"--command", "false {fixed} {output}"}, 1, "the method failed on the pair 0001_0000 -> 0001_0001"},
      {{"--command", "true {fixed} {output}"}, 1, "the method wrote no {output}"},
      // The fixed image is an int16 image of 3-D shape: not a field of 3 components.
      {{"--command", "cp {fixed} {output}"}, 1, "expected a learn2reg field of 48 x 56 x 52 voxels"}};
  for (std::size_t c = 0; c < cases.size(); ++c) {
    const fs::path results = root / ("results-" + std::to_string(c));
    const CommandResult run = register_task(m, results, cases[c].arguments);
    EXPECT_EQ(run.exit_code, cases[c].exit_code) << cases[c].arguments[1] << ": " << run.err;
    EXPECT_NE(run.err.find(cases[c].message), std::string::npos) << cases[c].arguments[1] << ": " << run.err;
    EXPECT_FALSE(fs::exists(results)) << cases[c].arguments[1];
  }
  EXPECT_TRUE(fs::is_empty(root)) << "a staging folder was left behind";
  // A folder that is not a task, and an occupied results folder.
  const CommandResult not_a_task = run_command(
      {PHANTASM_PYTHON, k_runner, m.dataset.string(), "-o", (root / "r").string(), "--baseline", "none"});
  EXPECT_EQ(not_a_task.exit_code, 2);
  EXPECT_NE(not_a_task.err.find("expected a task folder of phantasm task"), std::string::npos)
      << not_a_task.err;
  fs::create_directories(root / "occupied");
  write_text_file(root / "occupied" / "file.txt", "x");
  const CommandResult occupied = register_task(m, root / "occupied", {"--baseline", "none"});
  EXPECT_EQ(occupied.exit_code, 2);
  EXPECT_NE(occupied.err.find("expected a new or empty folder"), std::string::npos) << occupied.err;
}

TEST(TaskBaselines, ABadReverseFieldIsRefusedNamingItWithNothingWritten) {
  // The reverse direction is read and checked as the result is: a field of another size is refused,
  // naming the file, exit 2, no scores written.
  const Made& m = small_task();
  const fs::path results = fresh_folder("baselines-bad-reverse");
  fs::copy_file(m.truth / k_result, results / k_result);
  phantasm::ImageGrid smaller;
  phantasm::read_nifti_labels(m.task / "labelsTr" / "PHANTASM_0001_0001.nii.gz", &smaller);
  smaller.dims -= Eigen::Vector3i(1, 0, 0);
  phantasm::write_field(results / k_reverse, phantasm::zero_field(smaller),
                        phantasm::FieldConvention::learn2reg);
  const fs::path json = results.parent_path() / "bad-reverse.json";
  const CommandResult eval = run_command(
      {k_phantasm, "eval", m.task.string(), "--results", results.string(), "--json", json.string(), "-q"});
  EXPECT_EQ(eval.exit_code, 2) << eval.err;
  EXPECT_NE(eval.err.find(k_reverse + ": expected a field on the fixed grid (48 x 56 x 52 voxels"),
            std::string::npos)
      << eval.err;
  EXPECT_FALSE(fs::exists(json));
}
