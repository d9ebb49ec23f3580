// The subject report's first section: the run's warnings, unconverged solves and folded voxels,
// or that it had none.
#include "report/report_section.hpp"
#include "report/subject_record.hpp"
#include "report/subject_sections/section_html.hpp"

namespace phantasm {
namespace warnings_section_member {

using namespace section_html;

std::string warnings_section(const SubjectRecord& r) {
  std::string html;
  const nlohmann::json warnings = r.provenance.value("warnings", nlohmann::json::array());
  const bool converged = r.provenance.value("converged", true);
  if (warnings.empty() && converged && r.nonpositive_jacobian_voxels == 0)
    return html + "<p class=\"ok\">The run finished without a warning: every solve converged.</p>\n";
  html += "<div class=\"warn\"><p>The run finished with results it cannot vouch for (<code>--strict</code> "
          "would have refused them):</p>";
  html += list_html(warnings);
  if (!converged) html += "<p>Not every solve converged (see Solver convergence).</p>";
  if (r.nonpositive_jacobian_voxels > 0)
    html += "<p>" + std::to_string(r.nonpositive_jacobian_voxels) +
            " voxels of the reference grid have a Jacobian determinant of 0 or below (folded motion; magenta "
            "in the Jacobian overlay; inside or outside the exact mask).</p>";
  return html + "</div>\n";
}

} // namespace warnings_section_member

const ReportSection& warnings_report_section() {
  static const ReportSection section{
      ReportSectionKey::warnings, "warnings", "Warnings and errors",
      "the run's warnings, unconverged solves and folded voxels, or that there were none",
      warnings_section_member::warnings_section};
  return section;
}

} // namespace phantasm
