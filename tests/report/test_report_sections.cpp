// The registry of the subject report's sections: every member has its own anchor and title, the
// page shows them in the registry's order, and the methods paragraph cites a solver's literature
// from the solver's member.
#include "report/html_text.hpp"
#include "report/report_section.hpp"
#include "report/subject_record.hpp"
#include "report/subject_report.hpp"
#include "sim/solver_type.hpp"

#include <gtest/gtest.h>

#include <set>
#include <string>

using namespace phantasm;

namespace {

/// The record of a small quasi-static run with one organ, one sequence and one solve by `solver`,
/// built by hand (no files, no pictures).
SubjectRecord record_solved_by(const std::string& solver) {
  SubjectRecord record;
  record.subject = "01";
  record.dims = Eigen::Vector3i(8, 8, 8);
  record.spacing_mm = Eigen::Vector3d::Constant(2.0);
  record.provenance = {
      {"phantasm_version", "0.0.0"},
      {"seed", 3},
      {"scene", {{"sha256", "abc"}}},
      {"settings",
       {{"name", "ball"},
        {"field_strength_T", 3.0},
        {"grid", {{"voxel_size_mm", 2.0}, {"field_of_view_mm", 16}}},
        {"anatomy", {{"organs", {{{"name", "ball"}, {"tissue", "gray_matter"}, {"solid", true}}}}}},
        {"deformation",
         {{"mode", "quasi_static"},
          {"solver", {{"method", solver}, {"relative_residual_tolerance", 1e-3}}},
          {"loads", {{{"type", "gravity"}}}}}},
        {"sequences", {{{"name", "T1w"}, {"type", "spoiled_gre"}, {"TR_ms", 20}}}}}},
      {"stages", {{{"stage", "anatomy"}, {"status", "ran"}, {"modelled", {"ball"}}}}},
      {"solves",
       {{{"solver", solver}, {"iterations", 5}, {"relative_residual", 1e-4}, {"converged", true}}}}};
  record.landmarks = {{"apex", "ball", Eigen::Vector3d(0, 0, 10), Eigen::Vector3d(0, 0, 9)}};
  return record;
}

} // namespace

TEST(ReportSections, EverySectionHasItsOwnAnchorTitleAndDescription) {
  std::set<std::string> ids, titles;
  for (const ReportSection* section : report_sections()) {
    EXPECT_TRUE(ids.insert(section->id).second) << section->id;
    EXPECT_TRUE(titles.insert(section->title).second) << section->title;
    EXPECT_NE(std::string(section->description), "") << section->id;
    EXPECT_EQ(&report_section(section->key), section) << section->id;
    EXPECT_EQ(report_section_heading(*section),
              std::string("<h2 id=\"") + section->id + "\">" + section->title + "</h2>\n");
  }
  EXPECT_EQ(report_sections().front()->key, ReportSectionKey::warnings); // what the run warned, first
}

TEST(ReportSections, ThePageShowsEverySectionInTheRegistrysOrder) {
  const std::string html = subject_report_html(record_solved_by("local_global"));
  std::size_t previous = 0;
  for (const ReportSection* section : report_sections()) {
    const std::size_t at = html.find(report_section_heading(*section));
    ASSERT_NE(at, std::string::npos) << section->id;
    EXPECT_GT(at, previous) << section->id;
    previous = at;
  }
}

TEST(ReportSections, TheMethodsSectionCitesTheSolversLiteratureFromItsMember) {
  const ReportSection& methods = report_section(ReportSectionKey::methods);
  bool cited = false;
  for (const SolverType* solver : solver_types()) {
    const std::string html = methods.html(record_solved_by(solver->name));
    const std::string by = std::string(" by the ") + solver->name + " solver";
    ASSERT_NE(html.find(by), std::string::npos) << html;
    if (solver->literature.reference == nullptr) {
      EXPECT_EQ(html.find(by + " of "), std::string::npos) << html;
      EXPECT_EQ(html.find("<li>", html.find("<li>") + 1), std::string::npos) << html; // [1] only
      continue;
    }
    cited = true;
    EXPECT_NE(html.find(by + " of " + html_escape(solver->literature.method) + " [2]"), std::string::npos)
        << html;
    EXPECT_NE(html.find("<li>" + html_escape(solver->literature.reference) + "</li>"), std::string::npos)
        << html;
  }
  EXPECT_TRUE(cited) << "no solver names its literature";
}
