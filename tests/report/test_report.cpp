// The subject report: its text and picture helpers on known inputs, and the report of a small run
// read back by `phantasm report` and opened in headless Chromium (check_report_in_browser.py).
#include "io/nifti_file.hpp"
#include "report/html_text.hpp"
#include "report/slice_pictures.hpp"
#include "tests/apps/cli_fixtures.hpp"
#include "tests/support/subprocess.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

using namespace phantasm;
using namespace phantasm::testing;
namespace fs = std::filesystem;

TEST(HtmlText, EscapingLeavesNoMarkupInText) {
  EXPECT_EQ(html_escape("<script>alert('x') & \"y\"</script>"),
            "&lt;script&gt;alert(&#39;x&#39;) &amp; &quot;y&quot;&lt;/script&gt;");
  EXPECT_EQ(html_escape("plain text, 1 < 2"), "plain text, 1 &lt; 2");
  const std::string escaped = html_escape("<>&\"'");
  EXPECT_EQ(escaped.find_first_of("<>\"'"), std::string::npos);
}

TEST(HtmlText, Base64MatchesTheRfc4648Vectors) {
  const std::pair<const char*, const char*> vectors[] = {{"", ""},
                                                         {"f", "Zg=="},
                                                         {"fo", "Zm8="},
                                                         {"foo", "Zm9v"},
                                                         {"foob", "Zm9vYg=="},
                                                         {"fooba", "Zm9vYmE="},
                                                         {"foobar", "Zm9vYmFy"}};
  for (const auto& [text, encoded] : vectors)
    EXPECT_EQ(base64_encode(text), encoded) << text;
  EXPECT_EQ(base64_encode(std::string("\xff\x00\x80", 3)), "/wCA");
  for (const auto& [text, encoded] : vectors)
    EXPECT_EQ(base64_decode(encoded), std::optional<std::string>(text)) << encoded;
  EXPECT_EQ(base64_decode("/wCA"), std::optional<std::string>(std::string("\xff\x00\x80", 3)));
  for (const char* bad : {"Zg=", "Zg", "Z===", "Zm=v", "Zm9v\n", "Zm!v", "=Zm9"})
    EXPECT_EQ(base64_decode(bad), std::nullopt) << bad;
}

TEST(SlicePictures, PanelsShowTheMiddleSlicesWithRightAnteriorAndSuperiorUpOrRight) {
  const Eigen::Vector3i dims(4, 5, 6);
  const SliceMontage montage(dims);
  const auto index = [&](int i, int j, int k) { return i + dims.x() * (j + dims.y() * k); };
  EXPECT_EQ(montage.width(), 4 + 4 + 5);
  EXPECT_EQ(montage.height(), 6);
  EXPECT_EQ(montage.voxel(1, 2), index(1, 2, 3));     // axial, k = nz/2
  EXPECT_EQ(montage.voxel(4 + 1, 3), index(1, 2, 3)); // coronal, j = ny/2, k up
  EXPECT_EQ(montage.voxel(8 + 2, 4), index(2, 2, 4)); // sagittal, i = nx/2, j across
  EXPECT_EQ(montage.voxel(0, 5), -1);                 // above the axial panel (ny = 5 rows)
  EXPECT_EQ(montage.panel(3), 0);
  EXPECT_EQ(montage.panel(4), 1);
  EXPECT_EQ(montage.panel(8), 2);
}

TEST(SlicePictures, ColourScalesHideNoChangeAndMarkFolds) {
  const ColourScale ratio{ColourScale::Kind::jacobian, 0.5, 2.0};
  EXPECT_EQ(ratio.colour(1.0)[3], 0);   // no volume change: transparent
  EXPECT_EQ(ratio.colour(0.0)[0], 255); // folded: magenta, opaque
  EXPECT_EQ(ratio.colour(-1.0)[3], 255);
  EXPECT_GT(ratio.colour(0.5)[2], ratio.colour(0.5)[0]); // compressed: blue
  EXPECT_GT(ratio.colour(2.0)[0], ratio.colour(2.0)[2]); // expanded: red
  const ColourScale length{ColourScale::Kind::magnitude, 0.0, 10.0};
  EXPECT_EQ(length.colour(0.1)[3], 0);
  EXPECT_GT(length.colour(10.0)[0], length.colour(0.5)[0]); // brighter as it grows (to yellow)
  EXPECT_GT(length.colour(10.0)[1], length.colour(0.5)[1]);
}

TEST(SlicePictures, PicturesArePngsOfTheMontageSize) {
  const Eigen::Vector3i dims(6, 7, 8);
  const SliceMontage montage(dims);
  std::vector<double> values(6 * 7 * 8);
  for (std::size_t v = 0; v < values.size(); ++v)
    values[v] = static_cast<double>(v % 13);
  for (const std::string& png : {grey_slices_png(montage, values),
                                 colour_slices_png(montage, values, {ColourScale::Kind::magnitude, 0, 12})}) {
    ASSERT_GT(png.size(), 33u);
    EXPECT_EQ(png.substr(1, 3), "PNG");
    const auto be32 = [&](std::size_t at) {
      return static_cast<unsigned>(static_cast<unsigned char>(png[at])) << 24 |
             static_cast<unsigned>(static_cast<unsigned char>(png[at + 1])) << 16 |
             static_cast<unsigned>(static_cast<unsigned char>(png[at + 2])) << 8 |
             static_cast<unsigned>(static_cast<unsigned char>(png[at + 3]));
    };
    EXPECT_EQ(be32(16), static_cast<unsigned>(montage.width()));
    EXPECT_EQ(be32(20), static_cast<unsigned>(montage.height()));
  }
}

namespace {

const fs::path k_checker = k_source_dir / "tests" / "report" / "check_report_in_browser.py";
const std::string k_injected = "<script>window.phantasmInjected = true</script>";

/// The small head with a <script> in a comment and one solver iteration (so the run warns),
/// run once; its dataset folder.
const fs::path& warned_run() {
  static const fs::path out = [] {
    const fs::path root = fresh_folder("report-warned");
    const std::string marker = "deformation:\n  mode: quasi_static\n";
    const fs::path scene =
        scene_variant(k_small_scene, root, marker, marker + "  solver: {max_iterations: 1}\n");
    write_text_file(scene, "# " + k_injected + " a scene description in a comment\n" + read_file(scene));
    const CommandResult run =
        run_command({k_phantasm, "run", scene.string(), "-o", (root / "out").string(), "-q"});
    EXPECT_EQ(run.exit_code, 0) << run.err;
    EXPECT_NE(run.err.find("did not converge"), std::string::npos) << run.err;
    return root / "out";
  }();
  return out;
}

fs::path report_of(const fs::path& dataset) {
  return dataset / "derivatives" / "phantasm" / "sub-01.html";
}

/// A copy of the warned run's dataset to damage.
fs::path copy_of_warned_run(const std::string& name) {
  const fs::path copy = fresh_folder(name) / "out";
  fs::copy(warned_run(), copy, fs::copy_options::recursive);
  return copy;
}

} // namespace

TEST(ReportInBrowser, TheReportOfARunThatWarnedShowsItFirstWithEveryImageAndNoScriptOfTheScene) {
  const fs::path report = report_of(warned_run());
  ASSERT_TRUE(fs::exists(report));
  const CommandResult browser = run_command({"/usr/bin/python3", k_checker.string(), report.string(),
                                             "--expect-warnings", "--expect-text", k_injected});
  EXPECT_EQ(browser.exit_code, 0) << browser.out << browser.err;
  EXPECT_NE(browser.out.find("0 failed checks"), std::string::npos) << browser.out;
  const std::string html = read_file(report);
  EXPECT_NE(html.find("&lt;script&gt;window.phantasmInjected"), std::string::npos);
  EXPECT_EQ(html.find(k_injected), std::string::npos);
  EXPECT_LT(html.find("id=\"warnings\""), html.find("id=\"modelled\""));
  EXPECT_NE(html.find("aria-label=\"relative residual against iteration\""), std::string::npos);
}

TEST(ReportCommand, AStrictRunThatWarnedWritesNoSubjectButAReportSayingWhy) {
  const fs::path root = fresh_folder("report-strict");
  fs::copy_file(warned_run().parent_path() / "scene.yaml", root / "scene.yaml");
  const CommandResult run = run_command(
      {k_phantasm, "run", (root / "scene.yaml").string(), "-o", (root / "out").string(), "-q", "--strict"});
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_FALSE(fs::exists(root / "out" / "derivatives" / "phantasm" / "sub-01"));
  const std::string html = read_file(report_of(root / "out"));
  EXPECT_NE(html.find("--strict: the run warned, no subject written"), std::string::npos);
  EXPECT_NE(html.find("did not converge"), std::string::npos);
  EXPECT_EQ(html.find(k_injected), std::string::npos);
}

TEST(ReportCommand, ReportingADatasetAgainGivesTheRunsOwnReport) {
  const fs::path copy = copy_of_warned_run("report-again");
  const std::string original = read_file(report_of(copy));
  fs::remove(report_of(copy));
  const CommandResult again = run_command({k_phantasm, "report", copy.string(), "-q"});
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_EQ(read_file(report_of(copy)), original); // the stage times come from timing.json
}

TEST(ReportCommand, AFolderThatIsNotADatasetIsBadInputAndNothingIsWritten) {
  const fs::path folder = fresh_folder("report-not-a-dataset");
  write_text_file(folder / "notes.txt", "mine\n");
  const CommandResult result = run_command({k_phantasm, "report", folder.string()});
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_NE(result.err.find(folder.string() +
                            ": expected a dataset phantasm wrote, found no dataset_description.json"),
            std::string::npos)
      << result.err;
  EXPECT_EQ(folder_contents(folder).size(), 1u);
  const CommandResult missing = run_command({k_phantasm, "report", (folder / "none").string()});
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_FALSE(fs::exists(folder / "none"));
}

TEST(ReportCommand, AMissingOrDamagedFileIsNamedAndNoReportIsWritten) {
  const fs::path copy = copy_of_warned_run("report-damaged");
  fs::remove(report_of(copy));
  const fs::path image = copy / "sub-01" / "ses-def" / "anat" / "sub-01_ses-def_T2w.nii.gz";
  const std::string bytes = read_file(image);
  fs::remove(image);
  const CommandResult missing = run_command({k_phantasm, "report", copy.string()});
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.err.find(image.string()), std::string::npos) << missing.err;
  EXPECT_FALSE(fs::exists(report_of(copy)));

  write_text_file(image, bytes.substr(0, bytes.size() / 2)); // cut short
  const CommandResult damaged = run_command({k_phantasm, "report", copy.string()});
  EXPECT_EQ(damaged.exit_code, 2);
  EXPECT_NE(damaged.err.find(image.string()), std::string::npos) << damaged.err;
  EXPECT_FALSE(fs::exists(report_of(copy)));

  write_text_file(image, bytes);
  const fs::path landmarks =
      copy / "derivatives" / "phantasm" / "sub-01" / "ses-def" / "landmarks" / "sub-01_ses-def_landmarks.csv";
  std::string csv = read_file(landmarks);
  std::size_t at = csv.find('\n') + 1; // the first row's y_mm, after three commas
  for (int comma = 0; comma < 3; ++comma)
    at = csv.find(',', at) + 1;
  csv.replace(at, csv.find(',', at) - at, "two");
  write_text_file(landmarks, csv);
  const CommandResult table = run_command({k_phantasm, "report", copy.string()});
  EXPECT_EQ(table.exit_code, 2);
  EXPECT_NE(table.err.find(landmarks.string() + ":2: expected three numbers, found"), std::string::npos)
      << table.err;
  EXPECT_FALSE(fs::exists(report_of(copy)));
}

// The report reads each image's two states side by side; what it names when files are bad is
// still the first bad file in the order of the subject's files, and a volume on another grid is
// named against the subject's grid.
TEST(ReportCommand, TheFirstBadFileInTheSubjectsOrderIsNamed) {
  const fs::path copy = copy_of_warned_run("report-first-bad");
  fs::remove(report_of(copy));
  const fs::path reference = copy / "sub-01" / "ses-ref" / "anat" / "sub-01_ses-ref_T2w.nii.gz";
  const fs::path deformed = copy / "sub-01" / "ses-def" / "anat" / "sub-01_ses-def_T2w.nii.gz";
  const std::string reference_bytes = read_file(reference);
  const std::string deformed_bytes = read_file(deformed);
  write_text_file(reference, reference_bytes.substr(0, reference_bytes.size() / 2));
  write_text_file(deformed, deformed_bytes.substr(0, deformed_bytes.size() / 3));
  for (int attempt = 0; attempt < 3; ++attempt) { // the same file named however the threads run
    const CommandResult both = run_command({k_phantasm, "report", copy.string()});
    EXPECT_EQ(both.exit_code, 2);
    EXPECT_NE(both.err.find(reference.string()), std::string::npos) << both.err;
    EXPECT_EQ(both.err.find(deformed.string()), std::string::npos) << both.err;
  }
  EXPECT_FALSE(fs::exists(report_of(copy)));

  write_text_file(reference, reference_bytes);
  ImageGrid other;
  other.dims = {4, 5, 6};
  write_nifti(deformed, other, std::vector<float>(120, 1.0f));
  const CommandResult grid = run_command({k_phantasm, "report", copy.string()});
  EXPECT_EQ(grid.exit_code, 2);
  EXPECT_NE(grid.err.find(deformed.string() + ": expected a volume of "), std::string::npos) << grid.err;
  EXPECT_NE(grid.err.find("voxels like the subject's other volumes, found 4 x 5 x 6"), std::string::npos)
      << grid.err;
  EXPECT_FALSE(fs::exists(report_of(copy)));
}

TEST(ReportCommand, ASubjectWhoseRunDidNotFinishGetsAReportSayingSo) {
  const fs::path copy = copy_of_warned_run("report-failed");
  fs::remove(report_of(copy));
  fs::remove(copy / "derivatives" / "phantasm" / "sub-01" / "provenance.json");
  const CommandResult result = run_command({k_phantasm, "report", copy.string()});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.err.find("sub-01: the run did not finish"), std::string::npos) << result.err;
  const std::string html = read_file(report_of(copy));
  EXPECT_NE(html.find("failed"), std::string::npos);
  EXPECT_NE(html.find("provenance.json is missing"), std::string::npos);
  EXPECT_LT(html.find("id=\"warnings\""), html.find("The run's log"));
}

// A scene in which nothing deforms: the run writes the reference state only (no ses-def images,
// labels or landmarks), and its report shows that state on both sides and says why.
TEST(ReportCommand, ARunInWhichNothingDeformsGetsAReportOfItsOneState) {
  const fs::path root = fresh_folder("report-reference-only");
  write_text_file(root / "scene.yaml", "phantasm: 1\nname: ball\nseed: 1\nfield_strength_T: 3.0\n"
                                       "grid: {field_of_view_mm: 48, voxel_size_mm: 3}\n"
                                       "anatomy:\n  organs:\n    - {name: ball, tissue: gray_matter, shape: "
                                       "{type: ellipsoid, center_mm: [0, 0, 0], radii_mm: 15}}\n"
                                       "sequences:\n  - {name: T1w, type: spoiled_gre, TR_ms: 20, TE_ms: 5, "
                                       "flip_deg: 30}\n");
  const CommandResult run =
      run_command({k_phantasm, "run", (root / "scene.yaml").string(), "-o", (root / "out").string(), "-q"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_FALSE(fs::exists(root / "out" / "sub-01" / "ses-def" / "anat" / "sub-01_ses-def_T1w.nii.gz"));
  const std::string html = read_file(report_of(root / "out"));
  EXPECT_NE(html.find("Nothing deforms in this scene"), std::string::npos);
  EXPECT_NE(html.find("the landmarks stay where they are"), std::string::npos);
}
