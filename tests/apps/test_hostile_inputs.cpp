// Hostile inputs and faults (#20): names that would make paths outside the output folder, two
// writers into one dataset, a --force run killed while it writes, files that are not what they
// claim, sweeps too large to expand. Each is refused with file, line or option, expected, found.
#include "tests/apps/cli_fixtures.hpp"
#include "tests/support/subprocess.hpp"

#include "core/error.hpp"
#include "io/nifti_file.hpp"
#include "io/output_path.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sys/stat.h>

#include <chrono>
#include <csignal>
#include <limits>
#include <thread>
#include <tuple>

using namespace phantasm::testing;
namespace fs = std::filesystem;

namespace {

/// A one-ball scene; `organ` and `tissue` are YAML scalars written as given.
std::string ball_scene(const std::string& organ, const std::string& tissue, double voxel_mm = 2.0) {
  return "phantasm: 1\nname: ball\nseed: 1\nfield_strength_T: 3.0\ngrid:\n  field_of_view_mm: 64\n"
         "  voxel_size_mm: " +
         std::to_string(voxel_mm) + "\nanatomy:\n  organs:\n    - name: " + organ +
         "\n      tissue: " + tissue +
         "\n      shape: {type: ellipsoid, center_mm: [0, 0, 0], radii_mm: 20}\n";
}

/// A ball of 4 mm voxels, its bottom cap held and its top cap pushed `push_mm` along z.
std::string pushed_ball_scene(double push_mm) {
  return ball_scene("ball", "gray_matter", 4.0) + "      material: soft\n" +
         "materials:\n  soft: {youngs_modulus_Pa: 3000, poisson_ratio: 0.45}\n"
         "deformation:\n  mode: quasi_static\n  loads:\n"
         "    - {type: displacement, organ: ball, displacement_mm: [0, 0, " +
         std::to_string(push_mm) +
         "], region: {center_mm: [0, 0, 20], radius_mm: 8}}\n"
         "    - {type: displacement, organ: ball, displacement_mm: [0, 0, 0], "
         "region: {center_mm: [0, 0, -20], radius_mm: 8}}\n";
}

/// Every path under a folder whose name holds `text`.
std::vector<fs::path> paths_named(const fs::path& folder, const std::string& text) {
  std::vector<fs::path> found;
  for (const auto& entry : fs::recursive_directory_iterator(folder))
    if (entry.path().filename().string().find(text) != std::string::npos) found.push_back(entry.path());
  return found;
}

/// Waits until `ready` holds (up to 60 s); false when it never did.
template <class Predicate>
bool wait_for(Predicate ready) {
  for (int i = 0; i < 3000; ++i) {
    if (ready()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

bool has_temporary_file(const fs::path& folder) {
  std::error_code error;
  if (!fs::is_directory(folder, error)) return false;
  for (auto it = fs::recursive_directory_iterator(folder, error); it != fs::recursive_directory_iterator();
       it.increment(error)) {
    if (error) return false;
    if (it->path().filename().string().find(".phantasm-tmp-") != std::string::npos) return true;
  }
  return false;
}

} // namespace

TEST(HostileNames, OrganAndTissueNamesThatLeaveTheFolderAreRefusedAndNothingIsWrittenOutside) {
  const fs::path root = fresh_folder("hostile-names");
  const fs::path deep = root / "a" / "b" / "c" / "d";
  fs::create_directories(deep);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"../../../../ESCAPED", "gray_matter"}, {"ball", "../../../../ESCAPED"},
      {"\"ESCAPED\\tx\"", "gray_matter"},     {"\"ESCAPED\\nx\"", "gray_matter"},
      {"/tmp/ESCAPED", "gray_matter"},
  };
  for (const auto& [organ, tissue] : cases) {
    SCOPED_TRACE(organ + " / " + tissue);
    const fs::path scene = deep / "scene.yaml";
    write_text_file(scene, ball_scene(organ, tissue));
    const fs::path out = deep / "out";
    const CommandResult result = run_command({k_phantasm, "run", scene.string(), "-o", out.string(), "-q"});
    EXPECT_EQ(result.exit_code, 2) << result.err;
    EXPECT_TRUE(result.err.rfind(scene.string() + ":10:13: anatomy.organs[0].name: ", 0) == 0 ||
                result.err.rfind(scene.string() + ":11:15: anatomy.organs[0].tissue: ", 0) == 0)
        << result.err;
    EXPECT_NE(result.err.find("expected a name of 1 to 64 ASCII letters, digits, '_' or '-', found '"),
              std::string::npos)
        << result.err;
    EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
    EXPECT_FALSE(fs::exists(out));
    EXPECT_TRUE(paths_named(root, "ESCAPED").empty());
  }
}

TEST(HostileNames, OutputFileNeverLeavesTheFolder) {
  using phantasm::InputError;
  using phantasm::output_file;
  const fs::path folder = "/data/out";
  for (const std::string& name : {std::string("../x"), std::string(".."), std::string("."), std::string(""),
                                  std::string("a/b"), std::string("a\\b"), std::string("/etc/passwd"),
                                  std::string("a\tb"), std::string("a\nb"), std::string("a\0b", 3)}) {
    SCOPED_TRACE(name);
    EXPECT_THROW(output_file(folder, name), InputError);
  }
  EXPECT_EQ(output_file(folder, "sub-01_ses-ref_organ-left_lung_mesh.vtp"),
            folder / "sub-01_ses-ref_organ-left_lung_mesh.vtp");
  try {
    output_file(folder, "../../ESCAPED");
    ADD_FAILURE() << "no exception";
  } catch (const InputError& error) {
    EXPECT_EQ(
        std::string(error.what()),
        "/data/out: expected a file name that stays inside the output folder, found a path separator in "
        "'../../ESCAPED'");
  }
  EXPECT_NO_THROW(phantasm::require_inside(folder, folder / "derivatives" / "x.json"));
  EXPECT_THROW(phantasm::require_inside(folder, folder / "derivatives" / ".." / ".." / "x.json"), InputError);
}

TEST(HostileNames, EvalSubjectIsANameNotAPath) {
  const fs::path root = fresh_folder("hostile-subject");
  for (const std::string subject : {"../../../x", "01\t02", "/etc"}) {
    const CommandResult result =
        run_command({k_phantasm, "eval", root.string(), "--identity", "--subject", subject});
    EXPECT_EQ(result.exit_code, 2) << result.err;
    EXPECT_EQ(result.err.rfind("--subject: expected a name of 1 to 64 ASCII letters", 0), 0u) << result.err;
  }
}

TEST(HostileTargets, DeviceNodesAreNotReplaced) {
  const fs::path root = fresh_folder("hostile-device");
  const CommandResult eval =
      run_command({k_phantasm, "eval", root.string(), "--identity", "--json", "/dev/null"});
  EXPECT_EQ(eval.exit_code, 2);
  EXPECT_EQ(eval.err,
            "--json: /dev/null: expected a new file or a regular file to replace, found a device node\n");
  const CommandResult hdf5 = run_command({k_phantasm, "hdf5", root.string(), "-o", "/dev/null", "-q"});
  EXPECT_EQ(hdf5.exit_code, 2);
  EXPECT_EQ(hdf5.err,
            "--output: /dev/null: expected a new file or a regular file to replace, found a device node\n");
  struct stat info {};
  ASSERT_EQ(::stat("/dev/null", &info), 0);
  EXPECT_TRUE(S_ISCHR(info.st_mode));
}

TEST(DatasetIntegrity, ASecondRunIntoAFolderBeingWrittenIsRefused) {
  const fs::path root = fresh_folder("hostile-lock");
  const fs::path scene = root / "ball.yaml";
  write_text_file(scene, ball_scene("ball", "gray_matter", 1.0));
  const fs::path out = root / "out";
  BackgroundProcess first({k_phantasm, "run", scene.string(), "-o", out.string(), "--write-delay-ms", "5"});
  ASSERT_TRUE(wait_for([&] { return has_temporary_file(out); }));
  const CommandResult second =
      run_command({k_phantasm, "run", scene.string(), "-o", out.string(), "--force"});
  EXPECT_EQ(second.exit_code, 2) << second.err;
  EXPECT_EQ(
      second.err.rfind(
          out.string() +
              ": expected an output folder no other run writes into, found one "
              "being written by another phantasm process (a run or a batch); wait for it to finish or choose "
              "another folder\n",
          0),
      0u)
      << second.err;
  EXPECT_EQ(first.wait(), 0);
  EXPECT_TRUE(fs::exists(out / "derivatives" / "phantasm" / "sub-01" / "provenance.json"));
  // A batch is refused the same way while a run holds the folder, and a run while a batch does.
  BackgroundProcess third(
      {k_phantasm, "run", scene.string(), "-o", out.string(), "--force", "--write-delay-ms", "5"});
  ASSERT_TRUE(wait_for([&] { return has_temporary_file(out); }));
  const CommandResult batch = run_command(
      {k_phantasm, "batch", (k_source_dir / "tests" / "data" / "sweeps" / "three-subjects.yaml").string(),
       "-o", out.string(), "-q"});
  EXPECT_EQ(batch.exit_code, 2) << batch.err;
  EXPECT_NE(batch.err.find("being written by another phantasm process"), std::string::npos) << batch.err;
  EXPECT_EQ(third.wait(), 0);
}

TEST(DatasetIntegrity, ForceRemovesTheOldCompletionMarkerBeforeWritingAnything) {
  const fs::path root = fresh_folder("hostile-force");
  const fs::path scene = root / "ball.yaml";
  write_text_file(scene, ball_scene("ball", "gray_matter", 1.0));
  const fs::path out = root / "out";
  const fs::path provenance = out / "derivatives" / "phantasm" / "sub-01" / "provenance.json";
  ASSERT_EQ(run_command({k_phantasm, "run", scene.string(), "-o", out.string(), "-q"}).exit_code, 0);
  ASSERT_TRUE(fs::exists(provenance));
  BackgroundProcess rerun(
      {k_phantasm, "run", scene.string(), "-o", out.string(), "--force", "-q", "--write-delay-ms", "20"});
  // The first temporary file means writing has begun: the old marker must be gone by then.
  ASSERT_TRUE(wait_for([&] { return has_temporary_file(out); }));
  EXPECT_FALSE(fs::exists(provenance));
  rerun.send_signal(SIGKILL);
  rerun.wait();
  EXPECT_FALSE(fs::exists(provenance)) << "a killed --force run left a folder that claims to be complete";
  // Run to its end, the folder is complete again.
  ASSERT_EQ(run_command({k_phantasm, "run", scene.string(), "-o", out.string(), "--force", "-q"}).exit_code,
            0);
  EXPECT_TRUE(fs::exists(provenance));
}

TEST(DatasetIntegrity, BatchRefusesAFolderOfUnrelatedFiles) {
  const fs::path root = fresh_folder("hostile-batch-folder");
  write_text_file(root / "notes.txt", "mine\n");
  const CommandResult result = run_command(
      {k_phantasm, "batch", (k_source_dir / "tests" / "data" / "sweeps" / "three-subjects.yaml").string(),
       "-o", root.string(), "-q"});
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_EQ(result.err, root.string() +
                            ": expected an empty or new output folder, or a dataset an earlier batch wrote, "
                            "found 'notes.txt' in it (a file phantasm does not write)\n");
  EXPECT_EQ(folder_contents(root).size(), 1u);
}

TEST(HostileInputs, ImportedShapesWithAbsurdCoordinatesAreRefusedBeforeWork) {
  const fs::path root = fresh_folder("hostile-shapes");
  write_text_file(root / "huge.obj",
                  "v 1e30 0 0\nv 0 1e30 0\nv 0 0 1e30\nv 0 0 0\nf 1 2 3\nf 1 4 2\nf 2 4 3\nf 3 4 1\n");
  std::string scene = ball_scene("thing", "gray_matter");
  scene.replace(scene.find("{type: ellipsoid"), std::string::npos, "{type: mesh, file: huge.obj}\n");
  write_text_file(root / "mesh.yaml", scene);
  const CommandResult result =
      run_command({k_phantasm, "run", (root / "mesh.yaml").string(), "-o", (root / "out").string(), "-q"});
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_EQ(result.err, (root / "mesh.yaml").string() +
                            ":12:33: anatomy.organs[0].shape.file: " + (root / "huge.obj").string() +
                            ": vertex 0: expected coordinates "
                            "within +-100000 mm, found 1e+30\n");
}

TEST(HostileInputs, LabelVolumesWithANaNAffineAndFloatVolumesWithNaNAreRefused) {
  const fs::path root = fresh_folder("hostile-nifti");
  phantasm::ImageGrid grid;
  grid.dims = Eigen::Vector3i(8, 8, 8);
  grid.world_from_voxel(0, 3) = std::numeric_limits<double>::quiet_NaN();
  std::vector<std::int32_t> labels(512, 0);
  for (int v = 100; v < 300; ++v)
    labels[v] = 1;
  phantasm::write_nifti_labels(root / "nan-affine.nii.gz", grid, labels);
  std::string scene = ball_scene("thing", "gray_matter");
  scene.replace(scene.find("{type: ellipsoid"), std::string::npos,
                "{type: label_volume, file: nan-affine.nii.gz, label: 1}\n");
  write_text_file(root / "volume.yaml", scene);
  const CommandResult result =
      run_command({k_phantasm, "run", (root / "volume.yaml").string(), "-o", (root / "out").string(), "-q"});
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_NE(result.err.find(":12:41: anatomy.organs[0].shape.file: "), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("expected a finite voxel-to-world affine"), std::string::npos) << result.err;

  // libnifti turns NaN into 0 as it loads: an all-NaN field would read as no motion at all.
  grid.world_from_voxel(0, 3) = 0.0;
  phantasm::write_nifti(root / "nan.nii.gz", grid,
                        std::vector<float>(512, std::numeric_limits<float>::quiet_NaN()));
  try {
    phantasm::read_nifti(root / "nan.nii.gz");
    ADD_FAILURE() << "no exception";
  } catch (const phantasm::InputError& error) {
    EXPECT_EQ(std::string(error.what()),
              (root / "nan.nii.gz").string() +
                  ": expected finite values, found NaN at value 0 of 512 (i fastest, "
                  "then j, k, components)");
  }
}

TEST(HostileSweeps, DuplicateKeysSecondDocumentsAndBadNamesAreErrors) {
  const fs::path root = fresh_folder("hostile-sweeps");
  const std::string base = "base_scene: " + k_small_scene.string() + "\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"phantasm_sweep: 1\n" + base + "seed: 1\nseed: 2\n", ":4:1: seed: expected each key once"},
      {"phantasm_sweep: 1\n" + base + "vary:\n  seed: [1, 2]\n  seed: [3]\n",
       ":5:3: vary.seed: expected each key once"},
      {"phantasm_sweep: 1\n" + base + "---\nseed: 2\n", ":4:1: sweep: expected one YAML document, found 2"},
      {"phantasm_sweep: 1\nname: ../x\n" + base, ":2:7: name: expected a name of 1 to 64"},
      {"phantasm_sweep: 1\nname: [a]\n" + base, ":2:7: name: expected a single value"},
      {"phantasm_sweep: 1\n" + base + "vary:\n  seed: {random_integer: [0, 1e30]}\n",
       ":4:9: vary.seed.random_integer: expected two finite numbers"},
      {"phantasm_sweep: 1\n" + base + "vary:\n  deformation.loads[99999999999999999999].x: [1]\n",
       "vary.deformation.loads[99999999999999999999].x: expected a scene key path"},
  };
  int n = 0;
  for (const auto& [text, expected] : cases) {
    const fs::path sweep = root / ("sweep" + std::to_string(n++) + ".yaml");
    write_text_file(sweep, text);
    const CommandResult result = run_command({k_phantasm, "validate", sweep.string()});
    EXPECT_EQ(result.exit_code, 2) << text;
    EXPECT_EQ(result.err.rfind(sweep.string(), 0), 0u) << result.err;
    EXPECT_NE(result.err.find(expected), std::string::npos)
        << "expected " << expected << "\nfound " << result.err;
  }
}

TEST(HostileSweeps, AMillionSubjectsAreValidatedAndListedInSeconds) {
  const fs::path root = fresh_folder("hostile-million");
  const fs::path sweep = root / "million.yaml";
  write_text_file(sweep, "phantasm_sweep: 1\nbase_scene: " + k_small_scene.string() +
                             "\nrepeats: 100000\nvary:\n  seed: {random_integer: [1, 100000]}\n"
                             "  acquisition.noise_percent: [1, 2, 3, 4, 5, 6, 7, 8, 9, 10]\n");
  const auto start = std::chrono::steady_clock::now();
  const CommandResult validate = run_command({k_phantasm, "validate", sweep.string()});
  EXPECT_EQ(validate.exit_code, 0) << validate.err;
  EXPECT_EQ(validate.out.rfind(sweep.string() + ": valid sweep of 1000000 subjects (", 0), 0u)
      << validate.out;
  const CommandResult list = run_command({k_phantasm, "batch", "--list", sweep.string()});
  EXPECT_EQ(list.exit_code, 0) << list.err;
  EXPECT_EQ(std::count(list.out.begin(), list.out.end(), '\n'), 1000000);
  EXPECT_EQ(list.out.substr(0, 8), "0000001\n");
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_LT(seconds, 60.0);
  write_text_file(
      sweep,
      "phantasm_sweep: 1\nbase_scene: " + k_small_scene.string() +
          "\nrepeats: 100000\nvary:\n  acquisition.noise_percent: [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11]\n");
  const CommandResult too_many = run_command({k_phantasm, "batch", "--list", sweep.string()});
  EXPECT_EQ(too_many.exit_code, 2);
  EXPECT_NE(too_many.err.find("vary: expected at most 10^6 subjects, found more (1100000"), std::string::npos)
      << too_many.err;
}

TEST(HostileInputs, SettingsThatMakeNoSignalWarnAndProvenanceRecordsIt) {
  const fs::path root = fresh_folder("hostile-no-signal");
  write_text_file(root / "scene.yaml",
                  ball_scene("ball", "gray_matter") +
                      "tissues:\n  gray_matter: {T1_ms: 1.0e300}\nsequences:\n"
                      "  - {name: T1w, type: spoiled_gre, TR_ms: 20, TE_ms: 5, flip_deg: 30}\n"
                      "  - {name: T2w, type: spin_echo, TR_ms: 4000, TE_ms: 90}\n"
                      "outputs:\n  parameter_maps: false\n"); // a T1 map of 1e300 is refused (below)
  const fs::path out = root / "out";
  const CommandResult result =
      run_command({k_phantasm, "run", (root / "scene.yaml").string(), "-o", out.string(), "-q"});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.err.find("[mri] warning: tissue gray_matter: T1 of 1e+300 ms is beyond any tissue's"),
            std::string::npos)
      << result.err;
  std::string provenance = read_file(out / "derivatives" / "phantasm" / "sub-01" / "provenance.json");
  EXPECT_NE(provenance.find("T1 of 1e+300 ms"), std::string::npos);

  // A flip angle of 0 with a tissue's own T1: an image of zeros, with a warning.
  write_text_file(root / "flip.yaml",
                  ball_scene("ball", "gray_matter") +
                      "sequences:\n  - {name: T1w, type: spoiled_gre, TR_ms: 20, TE_ms: 5, flip_deg: 0}\n");
  const CommandResult flip =
      run_command({k_phantasm, "run", (root / "flip.yaml").string(), "-o", (root / "flip").string(), "-q"});
  ASSERT_EQ(flip.exit_code, 0) << flip.err;
  EXPECT_NE(flip.err.find("[mri] warning: sequence T1w: a flip angle of 0 deg makes no signal"),
            std::string::npos)
      << flip.err;
  provenance = read_file(root / "flip" / "derivatives" / "phantasm" / "sub-01" / "provenance.json");
  EXPECT_NE(provenance.find("a flip angle of 0 deg makes no signal"), std::string::npos);
}

// T1 of 1e300 ms with a flip angle of 0: the spoiled gradient echo's signal is 0/0. The run wrote
// images of NaN and exited 0 (#44 item 5); it now stops before any file, naming the file, the
// sequence and the tissue.
TEST(HostileInputs, ASignalThatIsNotANumberIsRefusedBeforeAnythingIsWritten) {
  const fs::path root = fresh_folder("hostile-nan-signal");
  const fs::path scene = root / "scene.yaml";
  write_text_file(scene, ball_scene("ball", "gray_matter") +
                             "tissues:\n  gray_matter: {T1_ms: 1.0e300}\nsequences:\n"
                             "  - {name: T2w, type: spin_echo, TR_ms: 4000, TE_ms: 90}\n"
                             "  - {name: T1w, type: spoiled_gre, TR_ms: 20, TE_ms: 5, flip_deg: 0}\n");
  const fs::path out = root / "out";
  const CommandResult result = run_command({k_phantasm, "run", scene.string(), "-o", out.string(), "-q"});
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(result.err.find(scene.string() +
                            ":17:23: sequences[1].type: sequence T1w, tissue gray_matter: expected "
                            "a finite signal, found NaN (T1 1e+300 ms"),
            std::string::npos)
      << result.err;
  EXPECT_EQ(raw_library_marker(result.err), "") << result.err;
  EXPECT_FALSE(fs::exists(out)) << "a refused run left files behind";

  // With a flip angle that excites, the signal is finite (0), but the T1 map would hold 1e300 ms,
  // beyond a float: infinity. Refused before the first file, naming the map and the tissue.
  const fs::path maps = root / "maps.yaml";
  write_text_file(maps, ball_scene("ball", "gray_matter") +
                            "tissues:\n  gray_matter: {T1_ms: 1.0e300}\nsequences:\n"
                            "  - {name: T1w, type: spoiled_gre, TR_ms: 20, TE_ms: 5, flip_deg: 30}\n");
  const CommandResult map = run_command({k_phantasm, "run", maps.string(), "-o", out.string(), "-q"});
  EXPECT_EQ(map.exit_code, 2) << map.err;
  EXPECT_NE(map.err.find(maps.string() + ": T1 map of the reference state: expected finite values before "
                                         "anything is written, found inf at voxel ("),
            std::string::npos)
      << map.err;
  EXPECT_NE(map.err.find("), tissue gray_matter\n"), std::string::npos) << map.err;
  EXPECT_FALSE(fs::exists(out)) << "a refused run left files behind";
}

// Two sweeps never mix in one dataset: while a batch of one sweep holds its mark in a folder, a
// batch of another is refused; shards of the same sweep share it; a mark left by a batch that
// ended is removed by the next batch (#20 item 2).
TEST(DatasetIntegrity, ASecondSweepIsRefusedWhileTheFirstWritesTheFolder) {
  const fs::path folder = fresh_folder("sweep-marks");
  {
    const phantasm::SweepMark first(folder, "aaaa");
    const phantasm::SweepMark shard(folder, "aaaa"); // the same sweep: accepted
    try {
      const phantasm::SweepMark other(folder, "bbbb");
      ADD_FAILURE() << "a second sweep was let in";
    } catch (const phantasm::InputError& error) {
      EXPECT_NE(std::string(error.what()).find("expected one sweep per dataset"), std::string::npos)
          << error.what();
    }
    EXPECT_TRUE(fs::exists(folder / ".phantasm-sweep-aaaa"));
  }
  // The first batch has ended: the next sweep may write, and its mark replaces the stale one.
  const phantasm::SweepMark later(folder, "bbbb");
  EXPECT_FALSE(fs::exists(folder / ".phantasm-sweep-aaaa"));
  EXPECT_TRUE(fs::exists(folder / ".phantasm-sweep-bbbb"));
}

namespace {

/// A command on a hostile input and what its one line of message must hold.
struct Refusal {
  std::vector<std::string> arguments; ///< after the program
  std::string file;                   ///< the file (or option) the message names
  std::string expected;               ///< a part of the message
};

const fs::path k_hostile = k_source_dir / "tests" / "data" / "hostile";

std::string hostile(const std::string& name) {
  return (k_hostile / name).string();
}

/// Runs each command and expects exit code 2 and one line naming the file, what was expected
/// and what was found, without a library's own words.
void expect_clear_refusals(const std::vector<Refusal>& cases) {
  for (const Refusal& c : cases) {
    std::vector<std::string> command{k_phantasm};
    command.insert(command.end(), c.arguments.begin(), c.arguments.end());
    std::string shown;
    for (const auto& argument : c.arguments)
      shown += " " + argument;
    SCOPED_TRACE("phantasm" + shown);
    const CommandResult result = run_command(command);
    EXPECT_EQ(result.exit_code, 2) << result.err;
    EXPECT_NE(result.err.find(c.file), std::string::npos)
        << "expected the file " << c.file << "\nfound " << result.err;
    EXPECT_NE(result.err.find(c.expected), std::string::npos)
        << "expected " << c.expected << "\nfound " << result.err;
    EXPECT_NE(result.err.find("expected"), std::string::npos) << result.err;
    EXPECT_NE(result.err.find("found"), std::string::npos) << result.err;
    EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
    EXPECT_EQ(raw_library_marker(result.err), "") << result.err;
  }
}

} // namespace

// No library's own words reach the user (#20 item 4): each input of tests/data/hostile, and a few
// made here, once got yaml-cpp's "bad conversion", "operator[] call on a scalar" or "bad file",
// nlohmann's "[json.exception....]", "stod", "<path>: Not a directory" with exit code 1, or (a
// device read as a scene) "out of memory". Each now gets exit code 2 and one line naming the
// file, what was expected and what was found. Sweeps and scenes here; datasets and output paths
// below.
TEST(HostileInputs, NoRawLibraryMessageReachesTheUser) {
  const fs::path bad_scenes = k_source_dir / "tests" / "data" / "bad-scenes";
  const auto sweep = [](const std::string& name) { return hostile(name); };
  const auto base = [](const std::string& name) { return hostile("base/" + name); };
  const std::string a_sweep = (k_source_dir / "tests" / "data" / "sweeps" / "small-sweep.yaml").string();
  expect_clear_refusals({
      {{"info", a_sweep},
       a_sweep + ":3:17: phantasm_sweep: ",
       "expected a scene (phantasm: 1, docs/scene-format.md), found a sweep; phantasm batch runs a sweep"},
      {{"batch", k_small_scene.string(), "--list"},
       k_small_scene.string() + ":3:11: phantasm: ",
       "expected a sweep (phantasm_sweep: 1, docs/batch.md), found a scene; phantasm run runs a scene"},
      {{"validate", sweep("sweep-random-range-name-is-a-list.yaml")},
       sweep("sweep-random-range-name-is-a-list.yaml") + ":5:9: vary.seed: ",
       "expected a list of values or a random range such as {uniform: [a, b]}, found {[uniform]: [1, 2]}"},
      {{"validate", sweep("sweep-sequence-name-is-a-list.yaml")},
       sweep("sweep-sequence-name-is-a-list.yaml") + ":5:14: vary.sequences: ",
       "expected lists of sequence names of the base scene, found [T2w] in [T1w, [T2w]]"},
      {{"validate", sweep("sweep-sequence-name-is-a-mapping.yaml")},
       sweep("sweep-sequence-name-is-a-mapping.yaml") + ":5:14: vary.sequences: ",
       "expected lists of sequence names of the base scene, found {name: T1w} in [{name: T1w}]"},
      {{"validate", sweep("sweep-base-sequence-is-not-a-mapping.yaml")},
       base("sequence-is-not-a-mapping.yaml") + ":54:5: sequences[1]: ",
       "expected a mapping with a name (vary.sequences picks sequences by name), found 'T2w'"},
      {{"validate", sweep("sweep-scaled-displacement-is-not-a-number.yaml")},
       base("displacement-is-not-a-number.yaml") + ":49:29: deformation.loads[0].displacement_mm[1]: ",
       "expected a number in mm (vary.deformation.scale multiplies it), found 'zero'"},
      {{"validate", sweep("sweep-scaled-load-type-is-a-list.yaml")},
       base("load-type-is-a-list.yaml") + ":47:13: deformation.loads[0].type: ",
       "expected one load type such as displacement, found [displacement]"},
      {{"validate", sweep("sweep-nested-too-deep.yaml")},
       sweep("sweep-nested-too-deep.yaml") + ":",
       "expected valid YAML, found lists or mappings nested 500 levels deep or more"},
      {{"validate", k_hostile.string()}, k_hostile.string() + ": ", "expected a scene file, found a folder"},
      {{"validate", "/dev/zero"}, "/dev/zero: ", "expected a scene file, found a device node"},
      {{"validate", (bad_scenes / "mesh-file-is-a-folder.yaml").string()},
       (bad_scenes / "mesh-file-is-a-folder.yaml").string() + ":14:33: anatomy.organs[0].shape.file: ",
       "expected an existing file, found a folder at '" + (bad_scenes / ".." / "meshes").string() + "'"},
      {{"validate", sweep("sweep-base-scene-is-a-device.yaml")},
       sweep("sweep-base-scene-is-a-device.yaml") + ":4:13: base_scene: ",
       "expected a scene file, found a device node: /dev/zero"},
  });
}

// The same for the files of a dataset (hdf5, eval) and for output paths that cannot be written.
TEST(HostileInputs, NoRawLibraryMessageReachesTheUserFromADatasetOrAnOutputPath) {
  const fs::path root = fresh_folder("hostile-raw");
  const fs::path a_file = k_hostile / "README.md"; // a file where a folder should be
  const fs::path no_templates = root / "no-templates";
  fs::create_directories(no_templates);
  const std::string landmarks = "derivatives/phantasm/sub-01/ses-ref/landmarks/sub-01_ses-ref_landmarks.csv";
  const std::string provenance = "derivatives/phantasm/sub-01/provenance.json";
  const auto dataset = [](const std::string& name) { return hostile("datasets/" + name); };
  expect_clear_refusals({
      {{"hdf5", dataset("provenance-cut-short"), "-o", (root / "x.h5").string(), "-q"},
       dataset("provenance-cut-short") + "/" + provenance + ":4:1: ",
       "expected the JSON phantasm writes in provenance.json, found the end of the file before the JSON "
       "ends"},
      {{"hdf5", dataset("provenance-not-utf8"), "-o", (root / "x.h5").string(), "-q"},
       dataset("provenance-not-utf8") + "/" + provenance + ":3:23: ",
       "expected the JSON phantasm writes in provenance.json, found byte 0xe9, which is not UTF-8 text"},
      {{"hdf5", dataset("provenance-without-files"), "-o", (root / "x.h5").string(), "-q"},
       dataset("provenance-without-files") + "/" + provenance + ": files: ",
       "expected the list of the subject's files (paths relative to the dataset), found no such key"},
      {{"hdf5", dataset("provenance-file-not-text"), "-o", (root / "x.h5").string(), "-q"},
       dataset("provenance-file-not-text") + "/" + provenance + ": files: ",
       "found a JSON array with an entry that is not text"},
      {{"hdf5", dataset("provenance-is-a-list"), "-o", (root / "x.h5").string(), "-q"},
       dataset("provenance-is-a-list") + "/" + provenance + ": files: ",
       "found a JSON array instead of an object"},
      {{"hdf5", dataset("landmark-not-a-number"), "-o", (root / "x.h5").string(), "-q"},
       dataset("landmark-not-a-number") + "/" + landmarks + ":3: ",
       "expected three finite numbers (mm) after the name and organ, found 'ball_top,ball,0.5,-1.25,twenty'"},
      {{"hdf5", dataset("landmark-out-of-range"), "-o", (root / "x.h5").string(), "-q"},
       dataset("landmark-out-of-range") + "/" + landmarks + ":3: ",
       "expected three finite numbers (mm) after the name and organ, found 'ball_top,ball,0.5,-1.25,1e400'"},
      {{"hdf5", dataset("landmark-out-of-range"), "-o", (a_file / "x.h5").string(), "-q"},
       "--output: " + (a_file / "x.h5").string() + ": ",
       "expected " + a_file.string() + " to be a folder (or not to exist), found a file"},
      {{"eval", dataset("landmark-out-of-range"), "--identity", "--json",
        (a_file / "out" / "x.json").string()},
       "--json: " + (a_file / "out" / "x.json").string() + ": ",
       "expected " + a_file.string() + " to be a folder (or not to exist), found a file"},
      {{"atlas", "colin27", "-o", (a_file / "x.nii.gz").string(), "--templates", no_templates.string(), "-q"},
       "--output: " + (a_file / "x.nii.gz").string() + ": ",
       "expected " + a_file.string() + " to be a folder (or not to exist), found a file"},
      {{"hdf5", dataset("label-table-is-a-folder"), "-o", (root / "x.h5").string(), "-q"},
       dataset("label-table-is-a-folder") + "/derivatives/phantasm/dseg.tsv: ",
       "expected a file phantasm writes, found a folder"},
      {{"run", k_small_scene.string(), "-o", (a_file / "out").string(), "-q"},
       (a_file / "out").string() + ": ",
       "expected " + a_file.string() + " to be a folder (or not to exist), found a file"},
      {{"run", k_small_scene.string(), "-o", (root / "out").string(), "--cache", (a_file / "cache").string(),
        "-q"},
       (a_file / "cache").string() + ": anatomy cache: ",
       "expected " + a_file.string() + " to be a folder (or not to exist), found a file"},
      {{"hdf5", dataset("landmark-out-of-range"), "-o", "", "-q"},
       "--output: ",
       "expected the path of a file to write, found an empty path"},
      {{"eval", dataset("landmark-out-of-range"), "--identity", "--json", (root / "new").string() + "/"},
       "--json: " + (root / "new").string() + "/: ",
       "expected the path of a file to write, found a folder's path (it ends in '/')"},
      {{"run", k_small_scene.string(), "-o", "", "-q"},
       "--output: ",
       "expected an output folder, found an empty path"},
      {{"eval", dataset("landmark-out-of-range"), "--identity", "--subject", "99"},
       dataset("landmark-out-of-range"),
       "--subject: expected a complete subject of " + dataset("landmark-out-of-range") + " (01), found 99"},
  });
  EXPECT_FALSE(fs::exists(root / "x.h5"));
}

// A folder the dataset writer makes where the output folder holds a file of that name (sub-01):
// run --force and a batch's subject said "phantasm: error: <path>: Not a directory" with exit
// code 1; both now name the file in the way, with exit code 2 (for the subject, in a batch).
TEST(HostileInputs, AFileWhereTheDatasetPutsAFolderIsNamed) {
  const fs::path root = fresh_folder("hostile-file-in-the-way");
  const fs::path ball = root / "ball.yaml";
  write_text_file(ball, ball_scene("ball", "gray_matter"));
  const fs::path taken = root / "taken";
  fs::create_directories(taken);
  write_text_file(taken / "sub-01", "notes\n");
  const std::string message = (taken / "sub-01").string() + "/ses-ref/anat: expected " +
                              (taken / "sub-01").string() +
                              " to be a folder (or not to exist), found a file\n";
  const CommandResult run =
      run_command({k_phantasm, "run", ball.string(), "-o", taken.string(), "--force", "-q"});
  EXPECT_EQ(run.exit_code, 2) << run.err;
  EXPECT_EQ(run.err, message);

  // A batch's subject fails the same way, with the subject named (the batch then exits 1 for the
  // subjects that failed).
  const fs::path sweep_file = root / "one-ball.yaml";
  write_text_file(sweep_file, "phantasm_sweep: 1\nbase_scene: ball.yaml\n");
  const CommandResult batch =
      run_command({k_phantasm, "batch", sweep_file.string(), "-o", taken.string(), "--no-cache", "-q"});
  EXPECT_EQ(batch.exit_code, 1) << batch.err;
  EXPECT_NE(batch.err.find("sub-01: " + message), std::string::npos) << batch.err;
  EXPECT_NE(batch.err.find("[batch] sub-01 failed (exit 2;"), std::string::npos) << batch.err;
  EXPECT_EQ(raw_library_marker(batch.err), "") << batch.err;
  EXPECT_EQ(read_file(taken / "sub-01"), "notes\n");
}

// Bytes that are not UTF-8: yaml-cpp keeps them, and nlohmann's dump() refused them when
// provenance.json was written, after the whole run ("[json.exception.type_error.316] invalid UTF-8
// byte", exit code 1). A scene must be UTF-8 text (the byte is named at its line); a path the
// file system gives, which need not be, is recorded with U+FFFD in its place.
TEST(HostileInputs, TextThatIsNotUtf8IsNamedAndPathsThatAreNotAreRecorded) {
  const fs::path root = fresh_folder("hostile-utf8");
  fs::copy_file(k_source_dir / "tests" / "data" / "meshes" / "tetrahedron-ascii.vtp", root / "x\xff.vtp");
  std::string scene = ball_scene("thing", "gray_matter");
  scene.replace(scene.find("{type: ellipsoid"), std::string::npos, "{type: mesh, file: x\xff.vtp}\n");
  write_text_file(root / "mesh.yaml", scene);
  const CommandResult validate = run_command({k_phantasm, "validate", (root / "mesh.yaml").string()});
  EXPECT_EQ(validate.exit_code, 2) << validate.err;
  EXPECT_EQ(validate.err, (root / "mesh.yaml").string() +
                              ":12:34: expected valid YAML, found a syntax error: byte 0xff, which is not "
                              "UTF-8 text\n");

  const fs::path named = root / "b\xff.yaml";
  write_text_file(named, ball_scene("ball", "gray_matter"));
  const fs::path out = root / "out";
  const CommandResult run = run_command({k_phantasm, "run", named.string(), "-o", out.string(), "-q"});
  EXPECT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(raw_library_marker(run.err), "") << run.err;
  const std::string provenance = read_file(out / "derivatives" / "phantasm" / "sub-01" / "provenance.json");
  EXPECT_NE(provenance.find("b\xef\xbf\xbd.yaml"), std::string::npos); // U+FFFD
}

// Input that was accepted without a word (#44 item 5): a key of vary that names no setting,
// obstacles that hold every organ at rest. Each is now refused with the file, the place, what
// was expected and what was found; a refused run leaves nothing behind.
TEST(HostileInputs, SilentNonsenseIsRefused) {
  expect_clear_refusals({
      {{"validate", hostile("sweep-empty-vary-key.yaml")},
       hostile("sweep-empty-vary-key.yaml") + ":5:7: vary.: ",
       "expected a scene key path such as acquisition.noise_percent or deformation.loads[1].displacement_mm, "
       "found an empty key"},
      {{"batch", "--list", hostile("sweep-empty-vary-key.yaml")},
       hostile("sweep-empty-vary-key.yaml") + ":5:7: vary.: ",
       "found an empty key"},
  });
  const fs::path root = fresh_folder("hostile-obstacles");
  const std::string scene = hostile("obstacle-encloses-every-organ.yaml");
  const CommandResult run = run_command({k_phantasm, "run", scene, "-o", (root / "out").string(), "-q"});
  EXPECT_EQ(run.exit_code, 2) << run.err;
  EXPECT_NE(run.err.find(scene +
                         ":19:5: deformation.obstacles[0]: expected obstacles beside the tissue at rest "
                         "(no simulated vertex may enter one), found organ 'ball' wholly inside the "
                         "obstacle\n"),
            std::string::npos)
      << run.err;
  EXPECT_EQ(raw_library_marker(run.err), "") << run.err;
  EXPECT_FALSE(fs::exists(root / "out"));
}

// A sweep saved with a UTF-8 byte-order mark before 'phantasm_sweep: 1' was taken for a scene
// ("expected a scene ..., found a sweep" from validate): it is a sweep.
TEST(HostileSweeps, ASweepWithAByteOrderMarkIsASweep) {
  const std::string sweep = hostile("sweep-with-byte-order-mark.yaml");
  ASSERT_EQ(read_file(sweep).rfind("\xef\xbb\xbfphantasm_sweep: 1\n", 0), 0u);
  const CommandResult validate = run_command({k_phantasm, "validate", sweep});
  EXPECT_EQ(validate.exit_code, 0) << validate.err;
  EXPECT_EQ(validate.out.rfind(sweep + ": valid sweep of 3 subjects", 0), 0u) << validate.out << validate.err;
  const CommandResult list = run_command({k_phantasm, "batch", "--list", sweep});
  EXPECT_EQ(list.exit_code, 0) << list.err;
  EXPECT_EQ(std::count(list.out.begin(), list.out.end(), '\n'), 3) << list.out;
}

// An exact mask changed after the run (#44 item 5): eval scored the registration where the truth
// is not exact. The dataset records the mask's values (ValuesSha256 in its sidecar); eval refuses
// another mask, naming the file, and scores the mask the run wrote.
TEST(DatasetIntegrity, EvalRefusesAnExactMaskChangedAfterTheRun) {
  const fs::path root = fresh_folder("hostile-tampered-mask");
  const fs::path scene = root / "push.yaml";
  write_text_file(scene, pushed_ball_scene(3.0));
  const fs::path out = root / "out";
  ASSERT_EQ(run_command({k_phantasm, "run", scene.string(), "-o", out.string(), "-q"}).exit_code, 0);
  const CommandResult untouched = run_command({k_phantasm, "eval", out.string(), "--identity"});
  ASSERT_EQ(untouched.exit_code, 0) << untouched.err;

  const fs::path mask =
      out / "derivatives" / "phantasm" / "sub-01" / "xfm" / "sub-01_from-def_to-ref_desc-exact_mask.nii.gz";
  ASSERT_TRUE(fs::exists(mask));
  EXPECT_NE(
      read_file(fs::path(mask).replace_extension("").replace_extension(".json")).find("\"ValuesSha256\""),
      std::string::npos);
  const phantasm::NiftiVolume original = phantasm::read_nifti(mask);
  std::vector<std::int32_t> tampered(original.values.begin(), original.values.end());
  long outside = 0;
  for (auto& value : tampered) {
    outside += value == 0;
    value = 1; // every voxel called exact, the smooth extension too
  }
  ASSERT_GT(outside, 0) << "the run left no voxel out of the mask: the test would prove nothing";
  phantasm::write_nifti_labels(mask, original.grid, tampered);
  const CommandResult eval = run_command({k_phantasm, "eval", out.string(), "--identity"});
  EXPECT_EQ(eval.exit_code, 2) << eval.err;
  EXPECT_EQ(eval.err.rfind(
                mask.string() + ": expected the exact mask the dataset wrote (SHA-256 of its values ", 0),
            0u)
      << eval.err;
  EXPECT_NE(eval.err.find("found other values ("), std::string::npos) << eval.err;
  EXPECT_NE(eval.err.find("the mask was changed after the run"), std::string::npos) << eval.err;
  EXPECT_EQ(std::count(eval.err.begin(), eval.err.end(), '\n'), 1) << eval.err;

  // The mask the run wrote, written back: accepted again.
  std::vector<std::int32_t> restored(original.values.begin(), original.values.end());
  phantasm::write_nifti_labels(mask, original.grid, restored);
  EXPECT_EQ(run_command({k_phantasm, "eval", out.string(), "--identity"}).exit_code, 0);
}

// Both fields checked alike (#44 item 4): a ball pushed 16 mm into itself. Any fold inside either
// field's exact mask is a warning with the count the written Jacobian and mask give and the organ
// of that grid's labels. Here no tet inverts (smallest det F about 0.49), so neither mask may hold
// a fold: a central difference across the mask's edge once reported the deformed grid folded.
TEST(DatasetIntegrity, AFoldInsideEitherExactMaskIsAWarningWithItsCount) {
  const fs::path root = fresh_folder("hostile-folds");
  const fs::path scene = root / "push.yaml";
  write_text_file(scene, pushed_ball_scene(-16.0));
  const fs::path out = root / "out";
  const CommandResult run = run_command({k_phantasm, "run", scene.string(), "-o", out.string(), "-q"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const fs::path xfm = out / "derivatives" / "phantasm" / "sub-01" / "xfm";
  const fs::path anat = out / "derivatives" / "phantasm" / "sub-01";
  for (const auto& [from, to, grid] :
       {std::tuple{"def", "ref", "the reference grid"}, std::tuple{"ref", "def", "the deformed grid"}}) {
    const std::string field = std::string("from-") + from + "_to-" + to;
    SCOPED_TRACE(field);
    const auto jacobian = phantasm::read_nifti(xfm / ("sub-01_" + field + "_jacobian.nii.gz")).values;
    const auto mask = phantasm::read_nifti(xfm / ("sub-01_" + field + "_desc-exact_mask.nii.gz")).values;
    const auto labels = phantasm::read_nifti(anat / (std::string("ses-") + to) / "anat" /
                                             ("sub-01_ses-" + std::string(to) + "_dseg.nii.gz"))
                            .values;
    ASSERT_EQ(jacobian.size(), mask.size());
    long folded = 0, in_ball = 0;
    for (std::size_t v = 0; v < mask.size(); ++v) {
      if (mask[v] > 0.5 && !(jacobian[v] > 0.0)) {
        ++folded;
        in_ball += labels[v] == 1.0;
      }
    }
    const std::string warning = "[voxelize] warning: " + std::to_string(folded) +
                                " voxels of the exact mask of " + field + " (" + grid +
                                ") have a Jacobian determinant <= 0";
    if (folded == 0) {
      EXPECT_EQ(run.err.find(field + " (" + grid + ")"), std::string::npos) << run.err;
      continue;
    }
    EXPECT_NE(run.err.find(warning), std::string::npos) << "expected " << warning << "\nfound " << run.err;
    if (in_ball > 0)
      EXPECT_NE(run.err.find(std::to_string(in_ball) + " in ball (" + std::to_string(in_ball) + ")"),
                std::string::npos)
          << run.err;
  }
  // No tet inverted, so the exact maps do not fold and neither field may warn.
  const auto record = nlohmann::json::parse(read_file(anat / "provenance.json"));
  for (const auto& body : record.at("bodies"))
    ASSERT_GT(body.at("smallest_det_F").get<double>(), 0.0) << body.dump();
  EXPECT_EQ(run.err.find("of the exact mask of"), std::string::npos) << run.err;
}

// An organ read from a file nested in a container smaller than itself (#44 item 5): validate
// cannot size a mesh, so the run refuses it once the anatomy is built, before any other stage,
// naming the organ's `inside` at its line; nothing is written.
TEST(HostileInputs, AMeshOrganLargerThanItsContainerIsRefused) {
  const fs::path root = fresh_folder("hostile-mesh-nesting");
  std::string cube;
  for (const char* vertex : {"-30 -30 -30", "30 -30 -30", "30 30 -30", "-30 30 -30", "-30 -30 30",
                             "30 -30 30", "30 30 30", "-30 30 30"})
    cube += std::string("v ") + vertex + "\n";
  cube +=
      "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\n"
      "f 4 5 8\n";
  write_text_file(root / "cube.obj", cube);
  const fs::path scene = root / "nest.yaml";
  write_text_file(scene, ball_scene("shell", "gray_matter", 4.0) +
                             "    - name: cube\n      tissue: white_matter\n      inside: shell\n"
                             "      shape: {type: mesh, file: cube.obj}\n");
  const CommandResult validate = run_command({k_phantasm, "validate", scene.string()});
  EXPECT_EQ(validate.exit_code, 0) << validate.err; // a mesh's size is known once it is read
  const CommandResult run =
      run_command({k_phantasm, "run", scene.string(), "-o", (root / "out").string(), "-q"});
  EXPECT_EQ(run.exit_code, 2) << run.err;
  EXPECT_EQ(run.err.rfind(scene.string() +
                              ":15:15: anatomy.organs[1].inside: expected a container at least as "
                              "large as the organ it holds, found 'shell' ",
                          0),
            0u)
      << run.err;
  EXPECT_NE(run.err.find(" and 'cube' 6"), std::string::npos) << run.err; // about 60 mm across
  EXPECT_FALSE(fs::exists(root / "out"));
}
