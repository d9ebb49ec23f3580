// The dataset page and the benchmark page: their rows, factor columns, plots and escaping on
// pages built from known inputs, the dataset's subjects read back from a hand-made dataset, and
// (slow) a small sweep's pages written by phantasm batch, eval and report, opened in headless
// Chromium (check_report_in_browser.py).
#include "core/error.hpp"
#include "report/benchmark_page.hpp"
#include "report/dataset_page.hpp"
#include "report/factor_plots.hpp"
#include "report/html_text.hpp"
#include "report/subject_report.hpp"
#include "tests/apps/cli_fixtures.hpp"
#include "tests/support/subprocess.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <regex>
#include <string>

using namespace phantasm;
using namespace phantasm::testing;
namespace fs = std::filesystem;

namespace {

const std::string k_script = "<script>window.phantasmInjected = true</script>";

/// The rows of the first table of a page (header first), each as its cells' inner HTML.
std::vector<std::vector<std::string>> table_rows(const std::string& html) {
  const std::size_t start = html.find("<table>");
  const std::string table = html.substr(start, html.find("</table>", start) - start);
  std::vector<std::vector<std::string>> rows;
  static const std::regex row_pattern("<tr>(.*?)</tr>"), cell_pattern("<t[dh][^>]*>(.*?)</t[dh]>");
  for (std::sregex_iterator r(table.begin(), table.end(), row_pattern), end; r != end; ++r) {
    const std::string row = (*r)[1];
    std::vector<std::string> cells;
    for (std::sregex_iterator c(row.begin(), row.end(), cell_pattern); c != end; ++c)
      cells.push_back((*c)[1]);
    rows.push_back(cells);
  }
  return rows;
}

std::size_t count_of(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1))
    ++n;
  return n;
}

/// The cx (or cy) of each <circle> of an SVG, in order.
std::vector<double> circle_coordinates(const std::string& svg, bool y) {
  std::vector<double> values;
  static const std::regex pattern("<circle cx=\"([-0-9.e]+)\" cy=\"([-0-9.e]+)\"");
  for (std::sregex_iterator m(svg.begin(), svg.end(), pattern), end; m != end; ++m)
    values.push_back(std::stod((*m)[y ? 2 : 1]));
  return values;
}

std::vector<double> circle_xs(const std::string& svg) {
  return circle_coordinates(svg, false);
}
std::vector<double> circle_ys(const std::string& svg) {
  return circle_coordinates(svg, true);
}

DatasetSubjectRow written_row(const std::string& subject, const std::string& scale, double displacement) {
  DatasetSubjectRow row;
  row.subject = subject;
  row.status = DatasetSubjectRow::Status::written;
  row.factors = {{"deformation.scale", scale}, {"note", "plain"}};
  row.thumbnail_png = "\x89PNG not really a picture";
  row.figures = {{"largest displacement (mm)", "", displacement},
                 {"volume change of each organ (%)", "ventricles", -displacement},
                 {"volume change of each organ (%)", "brain", 0.1}};
  return row;
}

} // namespace

TEST(HtmlText, UnescapingGivesBackTheEscapedText) {
  const std::string text = "a <b>&amp;</b> \"c\" 'd' &nbsp;";
  EXPECT_EQ(html_unescape(html_escape(text)), text);
  EXPECT_EQ(html_unescape("&lt;script&gt; &amp;lt;"), "<script> &lt;");
}

TEST(FactorPlot, NumericFactorsAreSpacedByValueAndCategoriesEvenly) {
  const std::string numeric = factor_plot_svg("scale", "y", {{"", {{"0.5", 1.0}, {"1", 2.0}, {"2.5", 3.0}}}});
  const std::vector<double> x = circle_xs(numeric);
  ASSERT_EQ(x.size(), 3u);
  EXPECT_NEAR((x[1] - x[0]) / (x[2] - x[0]), 0.25, 1e-3); // (1 - 0.5) / (2.5 - 0.5)
  // Values given out of order are placed by value.
  const std::vector<double> shuffled =
      circle_xs(factor_plot_svg("scale", "y", {{"", {{"2.5", 3.0}, {"0.5", 1.0}, {"1", 2.0}}}}));
  EXPECT_NEAR(shuffled[0], x[2], 0.01);
  EXPECT_NEAR(shuffled[1], x[0], 0.01);

  EXPECT_FALSE(factor_is_numeric({"1", "2", "3T"}));
  EXPECT_TRUE(factor_is_numeric({"1", "-2.5", "1e3"}));
  const std::vector<double> c =
      circle_xs(factor_plot_svg("contrast", "y", {{"", {{"T1w", 1.0}, {"FLAIR", 2.0}, {"T2w", 3.0}}}}));
  ASSERT_EQ(c.size(), 3u);
  EXPECT_NEAR(c[1] - c[0], c[2] - c[1], 0.01);
  EXPECT_LT(c[0], c[1]); // in order of first appearance
}

TEST(FactorPlot, TheLineJoinsTheMeansAndNonFiniteValuesAreCounted) {
  const std::string svg =
      factor_plot_svg("scale", "y", {{"", {{"1", 1.0}, {"1", 3.0}, {"2", 2.0}, {"2", std::nan("")}}}});
  const std::vector<double> y = circle_ys(svg);
  ASSERT_EQ(y.size(), 3u); // the NaN is left out
  EXPECT_NE(svg.find("1 without a value"), std::string::npos);
  std::smatch line;
  ASSERT_TRUE(std::regex_search(svg, line, std::regex("<polyline[^>]*points=\"([-0-9.e]+),([-0-9.e]+) ")));
  EXPECT_NEAR(std::stod(line[2]), (y[0] + y[1]) / 2, 0.01); // the mean of 1 and 3 at x = 1
  EXPECT_NE(factor_plot_svg("f", "y", {{"", {{"1", std::nan("")}}}}).find("No value of y"),
            std::string::npos);
}

TEST(FactorPlot, TextsAreEscaped) {
  const std::string svg =
      factor_plot_svg(k_script, k_script, {{k_script, {{k_script, 1.0}}}, {"b", {{"x", 2.0}}}});
  EXPECT_EQ(svg.find("<script"), std::string::npos);
  EXPECT_NE(svg.find("&lt;script&gt;"), std::string::npos);
}

TEST(DatasetPage, ARowPerSubjectWithItsFactorsStatusWarningsAndLink) {
  DatasetPage page;
  page.name = "sweep " + k_script;
  page.factors = {"deformation.scale", "note"};
  page.rows.push_back(written_row("01", "0.5", 1.0));
  page.rows.back().warnings = {"solve 1 did not converge " + k_script, "b", "c", "d"};
  page.rows.back().factors["note"] = k_script;
  DatasetSubjectRow failed;
  failed.subject = "02";
  failed.status = DatasetSubjectRow::Status::failed;
  failed.reason = "the solve diverged " + k_script;
  failed.factors = {{"deformation.scale", "2.5"}};
  page.rows.push_back(failed);
  DatasetSubjectRow missing;
  missing.subject = "03";
  page.rows.push_back(missing);
  const std::string html = dataset_page_html(page);
  EXPECT_EQ(html.find("<script"), std::string::npos);

  const auto rows = table_rows(html);
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[0], (std::vector<std::string>{"subject", "middle slices", "deformation.scale", "note",
                                               "status", "warnings"}));
  for (const auto& row : rows)
    ASSERT_EQ(row.size(), 6u);
  EXPECT_EQ(rows[1][0], "<a href=\"sub-01.html\">sub-01</a>");
  EXPECT_NE(rows[1][1].find("src=\"data:image/png;base64,"), std::string::npos);
  EXPECT_EQ(rows[1][2], "0.5");
  EXPECT_EQ(rows[1][3], html_escape(k_script));
  EXPECT_EQ(rows[1][4], "written, warned");
  EXPECT_EQ(rows[1][5].rfind("4:", 0), 0u);
  EXPECT_NE(rows[1][5].find("did not converge " + html_escape(k_script)), std::string::npos);
  EXPECT_EQ(count_of(rows[1][5], "<li>"), 4u); // three warnings and a line saying there are more

  EXPECT_EQ(rows[2][0], "<a href=\"sub-02.html\">sub-02</a>");
  EXPECT_EQ(rows[2][1], ""); // no picture of a failed subject
  EXPECT_EQ(rows[2][2], "2.5");
  EXPECT_EQ(rows[2][3], "");
  EXPECT_NE(rows[2][4].find("failed<pre>the solve diverged " + html_escape(k_script)), std::string::npos);
  EXPECT_EQ(rows[3][0], "sub-03"); // no report to link to
  EXPECT_NE(rows[3][4].find("not made"), std::string::npos);
  EXPECT_NE(html.find("3 subjects: 1 written (1 with warnings), 1 failed, 1 not made"), std::string::npos);
}

TEST(DatasetPage, PlotsOfEachFigureAgainstEachFactorOnlyWithTwoWrittenSubjects) {
  DatasetPage page;
  page.factors = {"deformation.scale", "note"};
  page.rows.push_back(written_row("01", "0.5", 1.0));
  EXPECT_EQ(count_of(dataset_page_html(page), "<svg"), 0u); // one subject: its row, no plot
  page.rows.push_back(written_row("02", "2.5", 4.0));
  const std::string html = dataset_page_html(page);
  // Two plots (displacement; volume change with a line per organ) against each of two factors.
  EXPECT_EQ(count_of(html, "<svg"), 4u);
  EXPECT_EQ(count_of(html, "aria-label=\"largest displacement (mm) against deformation.scale\""), 1u);
  EXPECT_EQ(count_of(html, "aria-label=\"volume change of each organ (%) against note\""), 1u);
  EXPECT_EQ(count_of(html, "<circle"), 2u * (2 + 4));
  EXPECT_NE(html.find("&#9679; ventricles"), std::string::npos);
  page.factors.clear();
  EXPECT_EQ(count_of(dataset_page_html(page), "<svg"), 0u);
}

TEST(DatasetPage, SubjectsAreReadWithTheirStatusAndTheReasonTheirRunGave) {
  const fs::path dataset = fresh_folder("dataset-page-read");
  write_text_file(dataset / "dataset_description.json", "{\"Name\": \"three " + k_script + "\"}");
  write_text_file(dataset / "participants.tsv", "participant_id\tseed\tnote\nsub-01\t11\ta\nsub-02\t12\tb\n"
                                                "sub-03\t13\tc\n");
  const fs::path derivatives = dataset / "derivatives" / "phantasm";
  fs::create_directories(derivatives / "sub-02");
  write_text_file(derivatives / "sub-01.html",
                  failed_subject_report_html("01", "--strict: the run warned " + k_script, {"a log line"}));
  const DatasetPage page = read_dataset_page(dataset);
  EXPECT_EQ(page.name, "three " + k_script);
  EXPECT_EQ(page.factors, (std::vector<std::string>{"seed", "note"}));
  ASSERT_EQ(page.rows.size(), 3u);
  EXPECT_EQ(page.rows[0].status, DatasetSubjectRow::Status::failed);
  EXPECT_EQ(page.rows[0].reason, "--strict: the run warned " + k_script);
  EXPECT_EQ(page.rows[1].status, DatasetSubjectRow::Status::failed); // a folder without provenance.json
  EXPECT_EQ(page.rows[1].reason, "");
  EXPECT_EQ(page.rows[2].status, DatasetSubjectRow::Status::missing);
  EXPECT_EQ(page.rows[2].factors.at("seed"), "13");
  EXPECT_EQ(page.rows[2].factors.at("note"), "c");

  write_text_file(dataset / "participants.tsv", "subject\tseed\n");
  try {
    read_dataset_page(dataset);
    ADD_FAILURE() << "a participants.tsv without participant_id was read";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find((dataset / "participants.tsv").string() + ":1:"),
              std::string::npos)
        << error.what();
  }
  EXPECT_THROW(read_dataset_page(dataset / "none"), InputError);
}

namespace {

nlohmann::json pair_scores(int c, const std::string& scale, double dice_a, double dice_b,
                           nlohmann::json hd95_b, double tre) {
  return {{"case", c},
          {"subject", "0" + std::to_string(c)},
          {"result", "disp_" + std::to_string(c) + ".nii.gz"},
          {"factors", {{"deformation.scale", scale}}},
          {"labels",
           {{{"label", 1}, {"name", "brain"}, {"dice", dice_a}, {"hd95_mm", 1.0}},
            {{"label", 2}, {"name", "ventricles " + k_script}, {"dice", dice_b}, {"hd95_mm", hd95_b}}}},
          {"mean_dice", (dice_a + dice_b) / 2},
          {"mean_hd95_mm", 1.0},
          {"tre_mm", {{"mean", tre}}},
          {"dense_tre_mm", {{"mean", 2 * tre}}},
          {"endpoint_error_mm", {{"mean", tre / 2}, {"p95", tre}}},
          {"ndv", {{"percent", 0.0}}},
          {"jacobian_central_differences", {{"folding_fraction", 0.0}, {"log_jacobian_sd", 0.1}}},
          {"warnings", nlohmann::json::array()}};
}

nlohmann::json method_scores(const std::string& results, double shift) {
  return {
      {"task", "SMALL"},
      {"results", results},
      {"pairs",
       {pair_scores(1, "0.5", 0.9 - shift, 0.7 - shift, 2.0, 1.0 + shift),
        pair_scores(2, "2.5", 0.8 - shift, 0.5 - shift, nullptr, 3.0 + shift)}},
      {"summary",
       {{"pairs", 2},
        {"mean_dice", 0.725 - shift},
        {"dice_p30", 0.67 - shift},
        {"mean_dense_tre_mm", 4.0 + 2 * shift}}},
      {"warnings", {"disp_2.nii.gz: the result looks like the true field read the wrong way " + k_script}}};
}

} // namespace

TEST(BenchmarkPage, EachStructuresScoresAreItsMeansOverThePairs) {
  const std::vector<StructureScore> s = structure_scores(method_scores("/r/a", 0.0));
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].name, "brain");
  EXPECT_EQ(s[0].pairs, 2u);
  EXPECT_NEAR(s[0].mean_dice, 0.85, 1e-12);
  EXPECT_NEAR(s[0].lowest_dice, 0.8, 1e-12);
  EXPECT_NEAR(s[1].mean_dice, 0.6, 1e-12);
  EXPECT_NEAR(s[1].lowest_dice, 0.5, 1e-12);
  EXPECT_NEAR(s[1].mean_hd95_mm, 2.0, 1e-12); // the pair without an HD95 left out
}

TEST(BenchmarkPage, MethodsSideBySideWithTheirScoresAgainstEachFactor) {
  const std::vector<MethodScores> methods = {
      {method_name(method_scores("/r/elastix/", 0.0)), method_scores("/r/elastix/", 0.0)},
      {method_name(method_scores("/r/none", 0.2)), method_scores("/r/none", 0.2)}};
  EXPECT_EQ(methods[0].method, "elastix");
  const std::string html = benchmark_page_html(methods);
  EXPECT_EQ(html.find("<script"), std::string::npos);
  const auto summary = table_rows(html);
  ASSERT_EQ(summary.size(), 3u);
  EXPECT_EQ(summary[1][0], "elastix");
  EXPECT_EQ(summary[1][2], "0.725");
  EXPECT_EQ(summary[1][3], "0.67"); // the robustness figure
  EXPECT_EQ(summary[2][0], "none");
  EXPECT_EQ(summary[2][3], "0.47");
  EXPECT_EQ(summary[1][6], "4"); // the mean TRE on the dense landmarks
  // Seven figures against the one factor, each with a series per method.
  EXPECT_EQ(count_of(html, "<svg"), 7u);
  for (const char* figure : {"mean Dice", "mean HD95 (mm)", "mean TRE (mm)",
                             "mean TRE on the dense landmarks (mm)", "NDV (% of the cubes)"})
    EXPECT_EQ(count_of(html, "aria-label=\"" + std::string(figure) + " against deformation.scale\""), 1u)
        << figure;
  EXPECT_EQ(count_of(html, "&#9679; elastix"), 7u);
  EXPECT_EQ(count_of(html, "&#9679; none"), 7u);
  EXPECT_NE(html.find("ventricles " + html_escape(k_script)), std::string::npos);
  EXPECT_EQ(count_of(html, "read the wrong way " + html_escape(k_script)), 2u);
}

TEST(BenchmarkPage, ScoresOfAnotherTaskOrWithoutPairsAreRefusedNamingTheFile) {
  const fs::path folder = fresh_folder("benchmark-page-read");
  write_text_file(folder / "a.json", method_scores("/r/same", 0.0).dump());
  write_text_file(folder / "b.json", method_scores("/r/same", 0.1).dump());
  const std::vector<MethodScores> two = read_method_scores({folder / "a.json", folder / "b.json"});
  ASSERT_EQ(two.size(), 2u);
  EXPECT_NE(two[0].method, two[1].method); // two results folders of one name told apart

  nlohmann::json other = method_scores("/r/b", 0.0);
  other["task"] = "OTHER";
  write_text_file(folder / "other.json", other.dump());
  try {
    read_method_scores({folder / "a.json", folder / "other.json"});
    ADD_FAILURE() << "scores of two tasks were put on one page";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what())
                  .find((folder / "other.json").string() + ": expected scores of the task SMALL"),
              std::string::npos)
        << error.what();
  }
  write_text_file(folder / "bare.json", "{\"task\": \"SMALL\"}");
  EXPECT_THROW(read_method_scores({folder / "bare.json"}), InputError);
}

// A small sweep (four subjects varying the deformation scale and the noise): the page the batch
// writes, the benchmark page of its task scored with the ground truth as results, and two
// methods side by side, each opened in Chromium.
TEST(ReportInBrowser, TheDatasetAndBenchmarkPagesOfASmallSweepShowEveryRowAndPlot) {
  const fs::path root = fresh_folder("report-pages");
  const fs::path out = root / "out";
  const CommandResult batch = run_command(
      {k_phantasm, "batch", (k_source_dir / "tests" / "data" / "sweeps" / "small-sweep.yaml").string(), "-o",
       out.string(), "-q"});
  ASSERT_EQ(batch.exit_code, 0) << batch.err;
  const fs::path index = out / "derivatives" / "phantasm" / "index.html";
  ASSERT_TRUE(fs::exists(index));
  EXPECT_EQ(table_rows(read_file(index)).size(), 5u);
  const std::string checker = (k_source_dir / "tests" / "report" / "check_report_in_browser.py").string();
  // A value of participants.tsv holding a <script>, on the page that phantasm report writes again.
  std::string participants = read_file(out / "participants.tsv");
  participants.replace(participants.rfind("\t3\n"), 3, "\t3 " + k_script + "\n");
  write_text_file(out / "participants.tsv", participants);
  const CommandResult report = run_command({k_phantasm, "report", out.string(), "-q"});
  ASSERT_EQ(report.exit_code, 0) << report.err;
  // Three factors (seed, scale, noise) times seven figures.
  CommandResult browser =
      run_command({"/usr/bin/python3", checker, index.string(), "--kind", "dataset", "--root", out.string(),
                   "--min-plots", "21", "--expect-text", k_script});
  EXPECT_EQ(browser.exit_code, 0) << browser.out << browser.err;

  const CommandResult task =
      run_command({k_phantasm, "task", out.string(), "-o", (root / "task").string(), "-q"});
  ASSERT_EQ(task.exit_code, 0) << task.err;
  const nlohmann::json truth = nlohmann::json::parse(read_file(root / "task-truth" / "truth.json"));
  for (const char* method : {"truth", "truth-again"}) {
    fs::create_directories(root / method);
    for (const auto& pair : truth["pairs"])
      fs::copy_file(root / "task-truth" / pair["result"].get<std::string>(),
                    root / method / pair["result"].get<std::string>());
    const CommandResult eval =
        run_command({k_phantasm, "eval", (root / "task").string(), "--results", (root / method).string(),
                     "--json", (root / (std::string(method) + ".json")).string(), "--html",
                     (root / (std::string(method) + ".html")).string(), "-q"});
    ASSERT_EQ(eval.exit_code, 0) << eval.err;
  }
  const std::string page = read_file(root / "truth.html");
  EXPECT_EQ(table_rows(page).size(), 2u); // one method
  EXPECT_NE(page.find("aria-label=\"mean Dice against deformation.scale\""), std::string::npos);

  const CommandResult compare =
      run_command({k_phantasm, "report", "--scores", (root / "truth.json").string(), "--scores",
                   (root / "truth-again.json").string(), "-o", (root / "compare.html").string(), "-q"});
  ASSERT_EQ(compare.exit_code, 0) << compare.err;
  EXPECT_EQ(table_rows(read_file(root / "compare.html")).size(), 3u); // two methods
  browser = run_command({"/usr/bin/python3", checker, (root / "compare.html").string(), "--kind", "benchmark",
                         "--min-plots", "18"});
  EXPECT_EQ(browser.exit_code, 0) << browser.out << browser.err;
}

// The dataset page reads a subject's thumbnail and volume changes from the summary its run kept
// (page-summary.json) while provenance.json is the one it was made with, and from the volumes
// otherwise: the same page either way.
TEST(DatasetPage, ASubjectsKeptSummaryGivesTheRowItsVolumesGive) {
  const fs::path root = fresh_folder("dataset-page-summary");
  const fs::path out = root / "out";
  const CommandResult run =
      run_command({k_phantasm, "run", k_small_scene.string(), "-o", out.string(), "-q"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const fs::path summary = page_summary_path(out, "01");
  ASSERT_TRUE(fs::exists(summary));
  const std::string kept = read_file(summary);
  const DatasetPage from_summary = read_dataset_page(out);
  ASSERT_EQ(from_summary.rows.size(), 1u);
  const DatasetSubjectRow& row = from_summary.rows[0];
  EXPECT_EQ(row.thumbnail_png.substr(0, 4), "\x89PNG");
  EXPECT_TRUE(std::any_of(row.figures.begin(), row.figures.end(), [](const SubjectFigure& f) {
    return f.plot == "volume change of each organ (%)";
  }));
  fs::remove(summary);
  const DatasetPage from_volumes = read_dataset_page(out);
  EXPECT_EQ(dataset_page_html(from_summary), dataset_page_html(from_volumes));
  ASSERT_EQ(from_volumes.rows.size(), 1u);
  EXPECT_EQ(from_volumes.rows[0].thumbnail_png, row.thumbnail_png);
  ASSERT_EQ(from_volumes.rows[0].figures.size(), row.figures.size());
  for (std::size_t i = 0; i < row.figures.size(); ++i) {
    EXPECT_EQ(from_volumes.rows[0].figures[i].series, row.figures[i].series);
    EXPECT_EQ(from_volumes.rows[0].figures[i].value, row.figures[i].value) << row.figures[i].series;
  }

  // Read while it matches provenance.json (a thumbnail put in its place shows), not after.
  nlohmann::json changed = nlohmann::json::parse(kept);
  changed["thumbnail_png"] = base64_encode("another picture");
  write_text_file(summary, changed.dump());
  EXPECT_EQ(read_dataset_page(out).rows[0].thumbnail_png, "another picture");
  const fs::path provenance = out / "derivatives" / "phantasm" / "sub-01" / "provenance.json";
  const std::string provenance_text = read_file(provenance);
  write_text_file(provenance, provenance_text + "\n");
  EXPECT_EQ(read_dataset_page(out).rows[0].thumbnail_png, row.thumbnail_png);
  write_text_file(provenance, provenance_text);
  write_text_file(summary, "{\"provenance_sha256\": "); // damaged: the volumes answer
  EXPECT_EQ(dataset_page_html(read_dataset_page(out)), dataset_page_html(from_volumes));
  // phantasm report keeps it again, the run's bytes.
  const CommandResult report = run_command({k_phantasm, "report", out.string(), "-q"});
  ASSERT_EQ(report.exit_code, 0) << report.err;
  EXPECT_EQ(read_file(summary), kept);
}

// A single run: its dataset gets the page too, one row and no plot.
TEST(ReportCommand, ASingleSubjectDatasetGetsAPageOfOneRowWithoutPlots) {
  const fs::path root = fresh_folder("report-single-page");
  const CommandResult run =
      run_command({k_phantasm, "run", k_small_scene.string(), "-o", (root / "out").string(), "-q"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const CommandResult report = run_command({k_phantasm, "report", (root / "out").string(), "-q"});
  ASSERT_EQ(report.exit_code, 0) << report.err;
  const std::string html = read_file(root / "out" / "derivatives" / "phantasm" / "index.html");
  const auto rows = table_rows(html);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[1][0], "<a href=\"sub-01.html\">sub-01</a>");
  EXPECT_EQ(count_of(html, "<svg"), 0u);
  const CommandResult scores_without_output =
      run_command({k_phantasm, "report", "--scores", (root / "none.json").string()});
  EXPECT_EQ(scores_without_output.exit_code, 2);
  const CommandResult missing_scores = run_command(
      {k_phantasm, "report", "--scores", (root / "none.json").string(), "-o", (root / "page.html").string()});
  EXPECT_EQ(missing_scores.exit_code, 2);
  EXPECT_NE(missing_scores.err.find((root / "none.json").string()), std::string::npos) << missing_scores.err;
  EXPECT_FALSE(fs::exists(root / "page.html"));
}
