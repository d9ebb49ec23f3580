// The subject report's section of the solves: how many converged, the residual plots, each solve's
// iterations and residuals, and the bodies at the result.
#include "report/html_text.hpp"
#include "report/report_figures.hpp"
#include "report/report_section.hpp"
#include "report/subject_record.hpp"
#include "report/subject_sections/section_html.hpp"

namespace phantasm {
namespace convergence_section_member {

using namespace section_html;

std::string convergence_section(const SubjectRecord& r) {
  std::string html;
  const nlohmann::json solves = r.provenance.value("solves", nlohmann::json::array());
  if (solves.empty()) return html + "<p>Nothing was simulated.</p>\n";
  const double tolerance = r.provenance.at("settings")
                               .value("deformation", nlohmann::json::object())
                               .value("solver", nlohmann::json::object())
                               .value("relative_residual_tolerance", 1e-3);
  std::size_t converged = 0;
  long iterations = 0;
  for (const nlohmann::json& s : solves) {
    converged += s.value("converged", false) ? 1 : 0;
    iterations += s.value("iterations", 0L);
  }
  html +=
      std::string(converged == solves.size() ? "<p class=\"ok\">" : "<p class=\"bad\">") +
      std::to_string(converged) + " of " + std::to_string(solves.size()) +
      " solves converged (relative residual " + "at most " + significant(tolerance) + "), " +
      std::to_string(iterations) +
      " iterations in all. The relative residual is the largest force on a free vertex over the loads' force "
      "per vertex.</p>";
  html += residual_plots(solves, tolerance);
  html += "<table><tr><th>solve</th><th>solver</th><th>iterations</th><th>stopped by</th><th>relative "
          "residual</th>"
          "<th>residual (N)</th><th>converged</th></tr>";
  for (std::size_t k = 0; k < solves.size(); ++k) {
    const nlohmann::json& s = solves[k];
    html += "<tr>" + cell(std::to_string(k + 1), true) + cell(e(s.value("solver", ""))) +
            cell(e(s.value("iterations", 0)), true) + cell(e(s.value("stopped_by", ""))) +
            cell(significant(s.value("relative_residual", 0.0)), true) +
            cell(significant(s.value("residual_N", 0.0)), true) +
            cell(s.value("converged", false) ? "yes" : "<b>no</b>") + "</tr>";
  }
  html += "</table>";
  if (const nlohmann::json bodies = r.provenance.value("bodies", nlohmann::json::array()); !bodies.empty())
    html += "<p>Bodies at the result:</p>" + objects_table(bodies, "");
  return html + "\n";
}

} // namespace convergence_section_member

const ReportSection& convergence_report_section() {
  static const ReportSection section{
      ReportSectionKey::convergence, "convergence", "Solver convergence",
      "each solve's iterations, residual and convergence, with plots of the relative residual",
      convergence_section_member::convergence_section};
  return section;
}

} // namespace phantasm
