#include "io/vtk_xml_file.hpp"
#include "tests/apps/cli_fixtures.hpp"
#include "tests/support/subprocess.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include <algorithm>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

using namespace phantasm::testing;
namespace fs = std::filesystem;

namespace {

struct Expectation {
  std::string location; ///< "line:column"
  std::string key_path; ///< empty for problems without a key (syntax errors)
};

Expectation expectation_of(const fs::path& scene) {
  std::ifstream stream(scene);
  std::string first_line;
  std::getline(stream, first_line);
  std::smatch match;
  const std::regex pattern(R"(^# expect: (\d+:\d+) ?(\S*)$)");
  if (!std::regex_match(first_line, match, pattern)) {
    ADD_FAILURE() << scene << ": first line must be '# expect: LINE:COLUMN KEY.PATH', found '" << first_line
                  << "'";
    return {};
  }
  return {match[1], match[2]};
}

/// The subcommand names of the top-level help: the first word of each line indented by two
/// spaces in its "Subcommands:" section (deeper lines continue a description), sorted.
std::vector<std::string> subcommands_in_help(const std::string& help) {
  std::vector<std::string> names;
  std::istringstream lines(help);
  std::string line;
  bool in_section = false;
  const std::regex entry(R"(^  (\S+)( .*)?$)");
  while (std::getline(lines, line)) {
    if (line == "Subcommands:") {
      in_section = true;
    } else if (in_section && line.rfind("   ", 0) != 0) {
      std::smatch match;
      if (!std::regex_match(line, match, entry)) break; // the end of the section
      names.push_back(match[1]);
    }
  }
  std::sort(names.begin(), names.end());
  return names;
}

/// The names passed to CLI11's add_subcommand in the command's sources, sorted.
std::vector<std::string> subcommands_in_sources(const fs::path& folder) {
  std::vector<std::string> names;
  const std::regex call(R"re(add_subcommand\(\s*"([^"]+)")re");
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (entry.path().extension() != ".cpp") continue;
    const std::string source = read_file(entry.path());
    for (auto it = std::sregex_iterator(source.begin(), source.end(), call); it != std::sregex_iterator();
         ++it)
      names.push_back((*it)[1]);
  }
  std::sort(names.begin(), names.end());
  return names;
}

} // namespace

TEST(ValidateCommand, EveryMalformedSceneGetsOneMessageAtItsLocationAndExitCode2) {
  const fs::path folder = k_source_dir / "tests" / "data" / "bad-scenes";
  std::vector<fs::path> scenes;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (entry.path().extension() == ".yaml") scenes.push_back(entry.path());
  }
  std::sort(scenes.begin(), scenes.end());
  ASSERT_GE(scenes.size(), 12u);
  for (const auto& scene : scenes) {
    SCOPED_TRACE(scene.filename().string());
    const Expectation expected = expectation_of(scene);
    const CommandResult result = run_command({k_phantasm, "validate", scene.string()});
    EXPECT_EQ(result.exit_code, 2);
    EXPECT_TRUE(result.out.empty()) << result.out;
    std::string prefix = scene.string() + ":" + expected.location + ": ";
    if (!expected.key_path.empty()) prefix += expected.key_path + ": ";
    EXPECT_EQ(result.err.rfind(prefix, 0), 0u)
        << "expected a message starting with\n  " << prefix << "\nfound\n  " << result.err;
    EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
    EXPECT_NE(result.err.find("expected"), std::string::npos) << result.err;
    EXPECT_NE(result.err.find("found"), std::string::npos) << result.err;
    EXPECT_EQ(raw_library_marker(result.err), "") << result.err;
  }
}

// The scenes of data-synthetic/ and the registration study's scenes (scripts/registration_study/,
// run by scripts/registration_study.py, which no CI test runs in full for the Colin head).
TEST(ValidateCommand, ShippedScenesAreValid) {
  std::size_t study_scenes = 0;
  for (const fs::path& folder :
       {k_source_dir / "data-synthetic", k_source_dir / "scripts" / "registration_study"}) {
    for (const auto& entry : fs::directory_iterator(folder)) {
      if (entry.path().extension() != ".yaml") continue;
      const CommandResult result = run_command({k_phantasm, "validate", entry.path().string()});
      EXPECT_EQ(result.exit_code, 0) << entry.path() << "\n" << result.err;
      if (entry.path().filename() == "head-sweep.yaml") {
        EXPECT_NE(result.out.find("valid sweep of 20 subjects"), std::string::npos) << result.out;
      }
      if (folder.filename() == "registration_study") ++study_scenes;
    }
  }
  EXPECT_GE(study_scenes, 2u); // scene.yaml and colin-scene.yaml
}

// A scene given through a pipe (bash's <(...)) is read once: the sweep check and the scene check
// share its text.
TEST(ValidateCommand, ASceneFromAPipeIsChecked) {
  const std::string scene = (k_source_dir / "data-synthetic" / "head.yaml").string();
  const CommandResult result =
      run_command({"/bin/bash", "-c", "exec \"$0\" validate <(cat \"$1\")", k_phantasm, scene});
  EXPECT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.out.find(": valid\n"), std::string::npos) << result.out << result.err;
  // A sweep through a pipe is read as a sweep; its base scene, relative to the pipe's folder, is
  // not found there, and the message says so (not "an empty file").
  const std::string sweep = (k_source_dir / "data-synthetic" / "head-sweep.yaml").string();
  const CommandResult piped_sweep =
      run_command({"/bin/bash", "-c", "exec \"$0\" validate <(cat \"$1\")", k_phantasm, sweep});
  EXPECT_EQ(piped_sweep.exit_code, 2);
  EXPECT_NE(piped_sweep.err.find("base_scene: expected a scene file, found no such file"), std::string::npos)
      << piped_sweep.err;
}

TEST(ValidateCommand, AMissingSceneFileIsABadInput) {
  const CommandResult result = run_command({k_phantasm, "validate", "/no/such/scene.yaml"});
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_EQ(result.err, "/no/such/scene.yaml: expected a scene file, found no such file\n");
}

// The subcommands the top-level help lists must be every subcommand the sources add (CLI11 leaves
// a subcommand put in no group out of the list), and each must answer --help with its usage.
TEST(Cli, EverySubcommandHasHelp) {
  const CommandResult top = run_command({k_phantasm, "--help"});
  ASSERT_EQ(top.exit_code, 0);
  const std::vector<std::string> listed = subcommands_in_help(top.out);
  EXPECT_EQ(listed, subcommands_in_sources(k_source_dir / "apps" / "phantasm")) << top.out;
  EXPECT_GE(listed.size(), 6u) << top.out; // run, batch, hdf5, validate, info, eval at least
  for (const std::string& command : listed) {
    SCOPED_TRACE(command);
    const CommandResult result = run_command({k_phantasm, command, "--help"});
    EXPECT_EQ(result.exit_code, 0) << result.err;
    EXPECT_NE(result.out.find("Usage: phantasm " + command + " "), std::string::npos) << result.out;
  }
}

TEST(Cli, UnknownOptionsAreBadInput) {
  EXPECT_EQ(run_command({k_phantasm, "run", k_head_scene.string(), "--no-such-option"}).exit_code, 2);
  EXPECT_EQ(run_command({k_phantasm}).exit_code, 2);
}

// An unknown subcommand or option is named in the error, with what was expected (CLI11 alone
// says "A subcommand is required" for a misspelt subcommand).
TEST(Cli, UnknownWordsAreNamedInTheError) {
  const CommandResult subcommand = run_command({k_phantasm, "frobnicate"});
  EXPECT_EQ(subcommand.exit_code, 2);
  EXPECT_NE(subcommand.err.find("unknown subcommand 'frobnicate'"), std::string::npos) << subcommand.err;
  EXPECT_NE(subcommand.err.find("run, batch, hdf5"), std::string::npos) << subcommand.err;
  const CommandResult option = run_command({k_phantasm, "--frobnicate", "run"});
  EXPECT_EQ(option.exit_code, 2);
  EXPECT_NE(option.err.find("unknown option '--frobnicate'"), std::string::npos) << option.err;
  const CommandResult sub_option = run_command({k_phantasm, "info", k_head_scene.string(), "--frobnicate"});
  EXPECT_EQ(sub_option.exit_code, 2);
  EXPECT_NE(sub_option.err.find("--frobnicate"), std::string::npos) << sub_option.err;
  const CommandResult none = run_command({k_phantasm});
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_NE(none.err.find("a subcommand is required, one of: run"), std::string::npos) << none.err;
  EXPECT_EQ(run_command({k_phantasm, "--version"}).exit_code, 0);
}

// Every document the help texts, the sources and the docs point to is in the repository: each
// "docs/<name>.md" exists, each relative Markdown link of README.md and docs/ resolves, and none
// names the design notes that live outside it.
TEST(Cli, HelpTextsAndDocsPointIntoTheRepository) {
  std::vector<std::pair<std::string, std::string>> texts; // (where, text)
  const CommandResult top = run_command({k_phantasm, "--help"});
  texts.emplace_back("phantasm --help", top.out);
  for (const std::string& command : subcommands_in_help(top.out))
    texts.emplace_back("phantasm " + command + " --help", run_command({k_phantasm, command, "--help"}).out);
  std::vector<fs::path> markdown = {k_source_dir / "README.md"};
  for (const char* folder :
       {"anatomy", "apps", "atlas", "batch", "bench", "core", "docs", "evaluation", "geometry", "io", "mri",
        "pipeline", "python", "scene", "scripts", "sim", "voxelize", "data-synthetic"}) {
    for (const auto& entry : fs::recursive_directory_iterator(k_source_dir / folder)) {
      const std::string ext = entry.path().extension().string();
      if (!entry.is_regular_file() ||
          (ext != ".md" && ext != ".cpp" && ext != ".hpp" && ext != ".py" && ext != ".yaml" && ext != ".sh"))
        continue;
      texts.emplace_back(entry.path().lexically_relative(k_source_dir).string(), read_file(entry.path()));
      if (ext == ".md") markdown.push_back(entry.path());
    }
  }
  texts.emplace_back("README.md", read_file(k_source_dir / "README.md"));
  const std::vector<std::string> outside = {std::string("DESIGN") + ".md", std::string("METHOD") + ".md",
                                            std::string("../") + "shared"};
  const std::regex doc_reference(R"(docs/([A-Za-z0-9_-]+\.md))");
  for (const auto& [where, text] : texts) {
    for (const std::string& name : outside)
      EXPECT_EQ(text.find(name), std::string::npos) << where << " names " << name;
    for (auto it = std::sregex_iterator(text.begin(), text.end(), doc_reference);
         it != std::sregex_iterator(); ++it)
      EXPECT_TRUE(fs::exists(k_source_dir / "docs" / (*it)[1].str())) << where << " points to " << (*it)[0];
  }
  const std::regex link(R"(\]\(([^)#\s]+)(#[^)]*)?\))");
  for (const fs::path& file : markdown) {
    const std::string text = read_file(file);
    for (auto it = std::sregex_iterator(text.begin(), text.end(), link); it != std::sregex_iterator(); ++it) {
      const std::string target = (*it)[1];
      if (target.find("://") != std::string::npos || target.rfind("mailto:", 0) == 0) continue;
      EXPECT_TRUE(fs::exists(file.parent_path() / target)) << file << " links to " << target;
    }
  }
}

TEST(InfoCommand, ShowsTheGridAndEveryStagePlan) {
  const CommandResult result = run_command({k_phantasm, "info", k_head_scene.string()});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.out.find("grid 176 x 208 x 192"), std::string::npos) << result.out;
  for (const char* stage : {"anatomy:", "sim:", "voxelize:", "mri:"})
    EXPECT_NE(result.out.find(stage), std::string::npos);
  const CommandResult json = run_command({k_phantasm, "info", "--json", k_head_scene.string()});
  ASSERT_EQ(json.exit_code, 0);
  EXPECT_EQ(nlohmann::json::parse(json.out)["seed"], 1);
}

TEST(RunCommand, WritesSheetAndShellSurfacesAndTheSolvedBodyTetMesh) {
  const fs::path out = fresh_folder("small") / "out";
  ASSERT_EQ(run_command({k_phantasm, "run", k_small_scene.string(), "-o", out.string(), "-q"}).exit_code, 0);
  const fs::path derivatives = out / "derivatives" / "phantasm";
  const fs::path meshes = derivatives / "sub-01" / "ses-ref" / "meshes";
  EXPECT_TRUE(fs::exists(meshes / "sub-01_ses-ref_organ-scalp_mesh.vtp"));
  EXPECT_FALSE(fs::exists(meshes / "sub-01_ses-ref_organ-scalp_tetmesh.vtu")); // solid: false
  EXPECT_TRUE(fs::exists(meshes / "sub-01_ses-ref_organ-greyMatter_tetmesh.vtu"));

  // The scalp is held fixed: its deformed surface file is its reference one, byte for byte (a copy,
  // not a second tessellation); the grey matter moved, so its files differ.
  const fs::path def_meshes = out / "derivatives" / "phantasm" / "sub-01" / "ses-def" / "meshes";
  EXPECT_EQ(read_file(def_meshes / "sub-01_ses-def_organ-scalp_mesh.vtp"),
            read_file(meshes / "sub-01_ses-ref_organ-scalp_mesh.vtp"));
  const std::string grey_ref = read_file(meshes / "sub-01_ses-ref_organ-greyMatter_mesh.vtp");
  const std::string grey_def = read_file(def_meshes / "sub-01_ses-def_organ-greyMatter_mesh.vtp");
  EXPECT_GT(grey_def.size(), 1000u);
  EXPECT_NE(grey_def, grey_ref);

  // The grey matter is the simulated body (the white matter's sheet embedded in it): its tet mesh
  // in both states is the one solved, as many tets as the log says, each with the dseg label of
  // the organ whose material it took (as many per organ as the log says) and, deformed, the
  // det F of each tet, positive.
  std::map<std::string, int> label_of = phantasm::testing::dseg_table(derivatives / "dseg.tsv");
  const std::string log = read_file(derivatives / "sub-01" / "log.txt");
  std::smatch solved;
  ASSERT_TRUE(std::regex_search(log, solved,
                                std::regex(R"(grey_matter: solved as one body of (\d+) vertices and (\d+) )"
                                           R"(tets \(materials by tet:([^)]*)\))")))
      << log;
  const std::size_t tets = std::stoul(solved[2]);
  std::map<int, std::size_t> logged_per_label;
  {
    std::istringstream counts(solved[3].str());
    std::string organ;
    std::size_t count = 0;
    while (counts >> organ >> count) {
      ASSERT_TRUE(label_of.count(organ)) << organ;
      logged_per_label[label_of[organ]] = count;
    }
  }
  for (const char* state : {"ref", "def"}) {
    SCOPED_TRACE(state);
    const phantasm::VtuCells file =
        phantasm::read_vtu_cells(derivatives / "sub-01" / (std::string("ses-") + state) / "meshes" /
                                     (std::string("sub-01_ses-") + state + "_organ-greyMatter_tetmesh.vtu"),
                                 true);
    EXPECT_EQ(file.points.size() / 3, std::stoul(solved[1]));
    ASSERT_EQ(file.cells.size(), tets);
    ASSERT_EQ(file.cell_arrays.size(), state == std::string("ref") ? 1u : 2u);
    const phantasm::VtuCellArray& labels = file.cell_arrays[0];
    EXPECT_EQ(labels.name, "organ_label");
    ASSERT_EQ(labels.values.size(), tets);
    std::map<int, std::size_t> per_label;
    for (const double label : labels.values)
      ++per_label[static_cast<int>(label)];
    EXPECT_EQ(per_label, logged_per_label);
    if (state == std::string("def")) {
      const phantasm::VtuCellArray& det_F = file.cell_arrays[1];
      EXPECT_EQ(det_F.name, "det_F");
      ASSERT_EQ(det_F.values.size(), tets);
      EXPECT_GT(*std::min_element(det_F.values.begin(), det_F.values.end()), 0.0);
      EXPECT_LT(*std::min_element(det_F.values.begin(), det_F.values.end()), 1.0); // it was deformed
    }
  }

  // A preview per image: a PNG of the three middle slices side by side (48 + 48 + 56 wide,
  // max(56, 52) high for the 48 x 56 x 52 grid).
  for (const char* state : {"ref", "def"}) {
    const std::string png =
        read_file(out / "derivatives" / "phantasm" / "sub-01" / (std::string("ses-") + state) / "previews" /
                  (std::string("sub-01_ses-") + state + "_T1w.png"));
    ASSERT_GT(png.size(), 24u);
    EXPECT_EQ(png.substr(1, 3), "PNG");
    auto be32 = [&](std::size_t at) {
      return (static_cast<unsigned>(static_cast<unsigned char>(png[at])) << 24) |
             (static_cast<unsigned>(static_cast<unsigned char>(png[at + 1])) << 16) |
             (static_cast<unsigned>(static_cast<unsigned char>(png[at + 2])) << 8) |
             static_cast<unsigned>(static_cast<unsigned char>(png[at + 3]));
    };
    EXPECT_EQ(be32(16), 152u);
    EXPECT_EQ(be32(20), 56u);
  }
}

TEST(RunCommand, RefusesANonEmptyOutputFolderWithoutForceAndLeavesItUntouched) {
  const fs::path out = fresh_folder("refuse");
  std::ofstream(out / "precious.txt") << "user data";
  const CommandResult refused = run_command({k_phantasm, "run", k_small_scene.string(), "-o", out.string()});
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_NE(refused.err.find("--force"), std::string::npos) << refused.err;
  EXPECT_EQ(folder_contents(out).size(), 1u);
  const CommandResult forced =
      run_command({k_phantasm, "run", k_small_scene.string(), "-o", out.string(), "--force"});
  EXPECT_EQ(forced.exit_code, 0) << forced.err;
  EXPECT_EQ(read_file(out / "precious.txt"), "user data");
}

// The second run on one thread: the files are written in parallel (pipeline/dataset_writer.cpp)
// and every stage's loops split their work by thread count, none of which may show in a byte.
TEST(RunCommand, SameSceneTwiceGivesIdenticalBytes) {
  const fs::path root = fresh_folder("determinism");
  ASSERT_EQ(
      run_command({k_phantasm, "run", k_small_scene.string(), "-o", (root / "a").string(), "-q"}).exit_code,
      0);
  ASSERT_EQ(run_command({"/usr/bin/env", "OMP_NUM_THREADS=1", k_phantasm, "run", k_small_scene.string(), "-o",
                         (root / "b").string(), "-q"})
                .exit_code,
            0);
  const auto a = folder_contents(root / "a");
  EXPECT_GE(a.size(), 6u);
  EXPECT_EQ(a, folder_contents(root / "b"));
}

TEST(RunCommand, QuietPrintsNothingAndAPipeGetsPlainProgressLines) {
  const fs::path root = fresh_folder("verbosity");
  const CommandResult quiet =
      run_command({k_phantasm, "run", k_small_scene.string(), "-o", (root / "q").string(), "--quiet"});
  EXPECT_EQ(quiet.exit_code, 0);
  EXPECT_TRUE(quiet.err.empty()) << quiet.err;
  const CommandResult plain =
      run_command({k_phantasm, "run", k_small_scene.string(), "-o", (root / "p").string()});
  EXPECT_EQ(plain.exit_code, 0);
  EXPECT_NE(plain.err.find("writing 100% (82/82)"), std::string::npos) << plain.err;
  EXPECT_EQ(plain.err.find('\r'), std::string::npos);
  EXPECT_NE(plain.err.find("[voxelize] skipped: .vdb grids"), std::string::npos) << plain.err;
}

namespace {

/// Runs the small head with `outputs.vdb: true` into root/out (its scene in root/scene.yaml);
/// whether the run exited 0.
bool run_small_scene_with_vdb(const fs::path& root) {
  const std::string marker = "outputs:\n  subject: \"01\"\n";
  const fs::path scene = scene_variant(k_small_scene, root, marker, marker + "  vdb: true\n");
  return run_command({k_phantasm, "run", scene.string(), "-o", (root / "out").string(), "-q"}).exit_code == 0;
}

} // namespace

// outputs.vdb: each state's organ level sets and its label and fraction volumes in one .vdb file,
// which OpenVDB's Python module (Debian's python3-openvdb) reads whole (tests/apps/check_vdb.py).
TEST(RunCommand, VdbFilesHoldLevelSetsLabelsAndFractions) {
  const fs::path root = fresh_folder("vdb");
  ASSERT_TRUE(run_small_scene_with_vdb(root));
  openvdb::initialize();
  for (const char* state : {"ref", "def"}) {
    openvdb::io::File file(
        (root / "out" / "derivatives" / "phantasm" / "sub-01" / (std::string("ses-") + state) / "vdb" /
         (std::string("sub-01_ses-") + state + "_grids.vdb"))
            .string());
    file.open();
    auto sdf = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("white_matter_sdf"));
    auto labels = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("labels"));
    auto fraction = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("fraction_white_matter"));
    ASSERT_TRUE(sdf && labels && fraction);
    EXPECT_EQ(sdf->getGridClass(), openvdb::GRID_LEVEL_SET);
    // The grid centre (world origin) is deep in the white matter (dseg index 3).
    const openvdb::Coord centre = labels->transform().worldToIndexCellCentered(openvdb::Vec3d(0, 0, 0));
    EXPECT_EQ(labels->tree().getValue(centre), 3.0f);
    EXPECT_FLOAT_EQ(fraction->tree().getValue(centre), 1.0f);
    EXPECT_LT(sdf->tree().getValue(sdf->transform().worldToIndexCellCentered(openvdb::Vec3d(0, 0, 0))), 0.0f);
    EXPECT_EQ(
        labels->tree().getValue(labels->transform().worldToIndexCellCentered(openvdb::Vec3d(47, 55, 51))),
        0.0f);
    EXPECT_EQ(labels->metaValue<std::string>("units"), "label");
    file.close();
    const CommandResult python = run_command(
        {PHANTASM_PYTHON, (k_source_dir / "tests" / "apps" / "check_vdb.py").string(), file.filename()});
    EXPECT_EQ(python.exit_code, 0) << python.out << python.err;
    EXPECT_NE(python.out.find(" labels "), std::string::npos) << python.out;
  }
}

// The commands of docs/use-with-your-tools.md marked as tested (VTK, h5py, pyopenvdb) run on a
// small run with .vdb output (tests/apps/check_tool_docs.py).
TEST(Tools, DocumentedCommandsRunOnASmallRun) {
  const fs::path root = fresh_folder("tool-docs");
  ASSERT_TRUE(run_small_scene_with_vdb(root));
  const CommandResult check =
      run_command({PHANTASM_PYTHON, (k_source_dir / "tests" / "apps" / "check_tool_docs.py").string(),
                   (k_source_dir / "docs" / "use-with-your-tools.md").string(), root.string(),
                   fs::path(k_phantasm).parent_path().string()});
  EXPECT_EQ(check.exit_code, 0) << check.out << check.err;
  EXPECT_NE(check.out.find("ran 4 blocks, 0 failed"), std::string::npos) << check.out;
  EXPECT_NE(check.out.find("displacement_mm: RAS mm"), std::string::npos) << check.out;
  EXPECT_NE(check.out.find("label at the origin: 3"), std::string::npos) << check.out;
  EXPECT_NE(check.out.find("tets per organ: {'grey_matter': "), std::string::npos) << check.out;
}

// An inversion-recovery sidecar says which readout made the image; an MPRAGE sidecar also gives
// the echo train (spacing, length) and what TI is measured to, the timing the signal model assumes.
TEST(RunCommand, InversionRecoverySidecarsRecordTheReadoutAndTheTrainTiming) {
  const fs::path root = fresh_folder("ir-sidecars");
  std::string scene = read_file(k_small_scene);
  const std::string sequences = "  - {name: T1w, type: spoiled_gre, TR_ms: 20, TE_ms: 4, flip_deg: 25}\n"
                                "  - {name: T2w, type: spin_echo, TR_ms: 4000, TE_ms: 100}\n";
  ASSERT_NE(scene.find(sequences), std::string::npos);
  scene.replace(scene.find(sequences), sequences.size(),
                "  - {name: FLAIR, type: inversion_recovery, readout: spin_echo, TR_ms: 9000, TI_ms: 2500, "
                "TE_ms: 120}\n"
                "  - {name: IRT1, type: inversion_recovery, readout: gradient_echo, TR_ms: 3000, TI_ms: 800, "
                "TE_ms: 4}\n"
                "  - {name: T1w, type: mprage, TR_ms: 2300, TI_ms: 900, TE_ms: 2.98, flip_deg: 9, "
                "echo_spacing_ms: 7.1, turbo_factor: 64}\n");
  write_text_file(root / "scene.yaml", scene);
  const CommandResult run =
      run_command({k_phantasm, "run", (root / "scene.yaml").string(), "-o", (root / "out").string(), "-q"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const fs::path anat = root / "out" / "sub-01" / "ses-ref" / "anat";
  auto sidecar = [&](const std::string& suffix) {
    return nlohmann::json::parse(read_file(anat / ("sub-01_ses-ref_" + suffix + ".json")));
  };
  const nlohmann::json flair = sidecar("FLAIR"), ir = sidecar("IRT1"), mprage = sidecar("T1w");
  EXPECT_EQ(flair["InversionRecoveryReadout"], "spin_echo");
  EXPECT_DOUBLE_EQ(flair["InversionTime"].get<double>(), 2.5);
  EXPECT_EQ(ir["InversionRecoveryReadout"], "gradient_echo");
  EXPECT_EQ(mprage["InversionRecoveryReadout"], "gradient_echo");
  EXPECT_DOUBLE_EQ(mprage["EchoSpacing"].get<double>(), 0.0071);
  EXPECT_EQ(mprage["TurboFactor"], 64);
  EXPECT_DOUBLE_EQ(mprage["RepetitionTimePreparation"].get<double>(), 2.3);
  EXPECT_NE(mprage["InversionTimeMeasuredTo"].get<std::string>().find("centre echo"), std::string::npos);
  EXPECT_FALSE(sidecar("FLAIR").contains("EchoSpacing"));
}

TEST(RunCommand, AnInvalidSceneWritesNothing) {
  const fs::path out = fresh_folder("invalid") / "out";
  const fs::path scene = k_source_dir / "tests" / "data" / "bad-scenes" / "unknown-tissue.yaml";
  const CommandResult result = run_command({k_phantasm, "run", scene.string(), "-o", out.string()});
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_FALSE(fs::exists(out));
}

// Organ names become BIDS entity values in camelCase: two names that give the same value would
// name the same files, so the run stops before any stage with both names, and writes nothing.
TEST(RunCommand, OrganNamesThatGiveTheSameFileNamesAreRefused) {
  const fs::path folder = fresh_folder("entity-clash");
  const fs::path scene = folder / "scene.yaml";
  write_text_file(scene, R"(phantasm: 1
name: entity-clash
seed: 1
field_strength_T: 3.0
grid: {field_of_view_mm: [120, 80, 80], voxel_size_mm: 4.0}
anatomy:
  base_mesh_triangles: 80
  organs:
    - {name: ventricle_left, tissue: csf, shape: {type: ellipsoid, center_mm: [-21, 0, 0], radii_mm: [20, 20, 20]}}
    - {name: ventricleLeft, tissue: csf, shape: {type: ellipsoid, center_mm: [21, 0, 0], radii_mm: [20, 20, 20]}}
outputs:
  images: false
)");
  const CommandResult result =
      run_command({k_phantasm, "run", "--quiet", scene.string(), "-o", (folder / "out").string()});
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(result.err.find("organs 'ventricle_left' and 'ventricleLeft' would both be organ-ventricleLeft"),
            std::string::npos)
      << result.err;
  EXPECT_FALSE(fs::exists(folder / "out"));
}

// A setting the scene's validation accepts but a stage cannot carry out (here a collision with
// an organ that no load moves, so it is not simulated) stops the run with the stage's message at
// the file, line and column the setting was written at, with its key path.
TEST(RunCommand, AStageErrorIsReportedAtItsSceneLocation) {
  const fs::path folder = fresh_folder("stage-error");
  const fs::path scene = folder / "scene.yaml";
  write_text_file(scene, R"(phantasm: 1
name: stage-error
seed: 1
field_strength_T: 3.0
grid: {field_of_view_mm: [120, 80, 80], voxel_size_mm: 4.0}
materials:
  soft: {youngs_modulus_Pa: 5000, poisson_ratio: 0.45}
anatomy:
  base_mesh_triangles: 80
  organs:
    - {name: left, tissue: muscle_skeletal, material: soft,
       shape: {type: ellipsoid, center_mm: [-21, 0, 0], radii_mm: [20, 20, 20]}}
    - {name: right, tissue: muscle_skeletal, material: soft,
       shape: {type: ellipsoid, center_mm: [21, 0, 0], radii_mm: [20, 20, 20]}}
deformation:
  mode: quasi_static
  loads:
    - {type: displacement, organ: left, displacement_mm: [10, 0, 0], region: {center_mm: [-41, 0, 0], radius_mm: 10}}
  collisions:
    - {organs: [left, right]}
outputs:
  images: false
)");
  const CommandResult validated = run_command({k_phantasm, "validate", scene.string()});
  ASSERT_EQ(validated.exit_code, 0) << validated.err;
  const CommandResult result =
      run_command({k_phantasm, "run", "--quiet", scene.string(), "-o", (folder / "out").string()});
  EXPECT_EQ(result.exit_code, 2);
  const std::string expected =
      scene.string() + ":20:16: deformation.collisions[0].organs: expected organs simulated as bodies "
                       "of their own (loaded, not fixed, not inside another simulated organ), found "
                       "'right'\n";
  EXPECT_EQ(result.err, expected);
}

namespace {

/// The small head with `replace` swapped for `with` in its text (one occurrence).
fs::path small_scene_variant(const fs::path& folder, const std::string& replace, const std::string& with) {
  return scene_variant(k_small_scene, folder, replace, with);
}

nlohmann::json provenance_of(const fs::path& out) {
  return nlohmann::json::parse(read_file(out / "derivatives" / "phantasm" / "sub-01" / "provenance.json"));
}

} // namespace

// A solve cut off far from equilibrium says so (#16): converged false in provenance, a warning
// on stderr and in the log; with --strict, exit 1 and nothing of the subject written.
TEST(RunCommand, AnUnconvergedSolveWarnsAndStrictWritesNothing) {
  const fs::path root = fresh_folder("unconverged");
  const fs::path scene =
      small_scene_variant(root, "  fixed: [scalp]\n", "  fixed: [scalp]\n  solver: {max_iterations: 1}\n");
  const CommandResult run =
      run_command({k_phantasm, "run", scene.string(), "-o", (root / "out").string(), "-q"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.err.find("[sim] warning: 1 of 1 local_global solves did not converge"), std::string::npos)
      << run.err;
  const nlohmann::json provenance = provenance_of(root / "out");
  EXPECT_FALSE(provenance["converged"].get<bool>());
  EXPECT_FALSE(provenance["solves"][0]["converged"].get<bool>());
  EXPECT_GT(provenance["solves"][0]["relative_residual"].get<double>(), 1e-3);
  EXPECT_EQ(provenance["solves"][0]["stopped_by"], "max_iterations");
  EXPECT_NE(read_file(root / "out" / "derivatives" / "phantasm" / "sub-01" / "log.txt").find("warning"),
            std::string::npos);

  const fs::path strict_out = root / "strict";
  const CommandResult strict =
      run_command({k_phantasm, "run", scene.string(), "-o", strict_out.string(), "-q", "--strict"});
  EXPECT_EQ(strict.exit_code, 1) << strict.err;
  EXPECT_NE(strict.err.find("--strict"), std::string::npos) << strict.err;
  EXPECT_FALSE(fs::exists(strict_out / "derivatives" / "phantasm" / "sub-01"));
  EXPECT_FALSE(fs::exists(strict_out / "sub-01"));
  EXPECT_FALSE(fs::exists(strict_out / "dataset_description.json"));
}

// The default solve of the small head converges, and says so.
TEST(RunCommand, TheSmallHeadConvergesWithTheDefaults) {
  const fs::path out = fresh_folder("converged") / "out";
  const CommandResult run =
      run_command({k_phantasm, "run", k_small_scene.string(), "-o", out.string(), "-q", "--strict"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(run.err.find("warning"), std::string::npos) << run.err;
  const nlohmann::json provenance = provenance_of(out);
  EXPECT_TRUE(provenance["converged"].get<bool>());
  EXPECT_LE(provenance["solves"][0]["relative_residual"].get<double>(), 1e-3);
  for (const auto& body : provenance["bodies"])
    EXPECT_EQ(body["inverted_tets"].get<long>(), 0) << body.dump();
}

// A 1 Pa brain under gravity is crushed: its tets invert, and the run says which organ and
// under which load (#16).
TEST(RunCommand, InvertedTetsAreAWarningNamingTheOrgan) {
  const fs::path root = fresh_folder("inverted");
  fs::path scene =
      small_scene_variant(root, "brain: {youngs_modulus_Pa: 3000", "brain: {youngs_modulus_Pa: 1");
  std::string text = read_file(scene);
  text.replace(text.find("  loads:\n"), 9,
               "  loads:\n    - {type: gravity, acceleration_m_s2: [0, -9.81, 0]}\n");
  write_text_file(scene, text);
  const CommandResult run =
      run_command({k_phantasm, "run", scene.string(), "-o", (root / "out").string(), "-q"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.err.find("[sim] warning: grey_matter: "), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("inverted (det F <= 0"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("gravity"), std::string::npos) << run.err;
  const nlohmann::json provenance = provenance_of(root / "out");
  long inverted = 0;
  for (const auto& body : provenance["bodies"]) {
    inverted += body["inverted_tets"].get<long>();
    if (body["inverted_tets"].get<long>() > 0) {
      EXPECT_LE(body["smallest_det_F"].get<double>(), 0.0);
    }
  }
  EXPECT_GT(inverted, 0);
  const CommandResult strict =
      run_command({k_phantasm, "run", scene.string(), "-o", (root / "strict").string(), "-q", "--strict"});
  EXPECT_EQ(strict.exit_code, 1) << strict.err;
  EXPECT_FALSE(fs::exists(root / "strict" / "derivatives" / "phantasm" / "sub-01"));
}

// The command's malloc is tcmalloc's (apps/phantasm/CMakeLists.txt; docs/performance.md, Memory
// allocator), as the dynamic loader binds it: the command's own calls and those of the C++ library
// (operator new) go to libtcmalloc_minimal, none to glibc's. The sanitizer tree's command keeps the
// sanitizers' allocator, which tcmalloc would displace.
TEST(Cli, TheCommandAllocatesThroughTcmalloc) {
  const CommandResult result = run_command({"/usr/bin/env", "LD_DEBUG=bindings", k_phantasm, "--version"});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  std::vector<std::string> malloc_bindings;
  std::istringstream lines(result.err);
  for (std::string line; std::getline(lines, line);)
    if (line.find("symbol `malloc'") != std::string::npos) malloc_bindings.push_back(line);
  const auto binds_to = [&](const std::string& library) {
    return std::count_if(malloc_bindings.begin(), malloc_bindings.end(), [&](const std::string& line) {
      const std::size_t to = line.find(" to ");
      return to != std::string::npos && line.find(library, to) != std::string::npos;
    });
  };
  std::string all;
  for (const std::string& line : malloc_bindings)
    all += line + "\n";
  if (std::string(PHANTASM_COMMAND_ALLOCATOR) == "tcmalloc") {
    EXPECT_GE(binds_to("libtcmalloc_minimal.so"), 2) << all;
    EXPECT_EQ(binds_to("libc.so"), 0) << all;
  } else {
    EXPECT_EQ(std::string(PHANTASM_COMMAND_ALLOCATOR), "sanitizer");
    EXPECT_EQ(binds_to("libtcmalloc"), 0) << all;
  }
}
