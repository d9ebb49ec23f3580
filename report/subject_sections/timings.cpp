// The subject report's section of stage times: each stage's processor and wall time against the
// cost estimate's, and the estimated peak memory.
#include "report/html_text.hpp"
#include "report/report_section.hpp"
#include "report/subject_record.hpp"
#include "report/subject_sections/section_html.hpp"

#include <algorithm>
#include <set>

namespace phantasm {
namespace timings_section_member {

using namespace section_html;

std::string timings_section(const SubjectRecord& r) {
  std::string html;
  const nlohmann::json estimate = r.provenance.value("estimate", nlohmann::json::object());
  const nlohmann::json estimated = estimate.value("stage_cpu_seconds", nlohmann::json::object());
  if (r.timings.empty())
    html += "<p>This subject's stage times were not recorded (its run kept no timing.json); the estimate "
            "alone:</p>";
  html += "<table><tr><th>stage</th><th>estimated processor time (s)</th><th>measured processor time (s)</th>"
          "<th>measured wall time (s)</th><th>measured / estimated</th></tr>";
  std::set<std::string> stages;
  for (const auto& [stage, seconds] : estimated.items())
    stages.insert(stage);
  for (const StageTiming& t : r.timings)
    stages.insert(t.stage);
  for (const std::string& stage : stages) {
    const auto found = std::find_if(r.timings.begin(), r.timings.end(),
                                    [&](const StageTiming& t) { return t.stage == stage; });
    const double guess = estimated.value(stage, -1.0);
    html += "<tr>" + cell(html_escape(stage)) + cell(guess >= 0 ? significant(guess) : "", true);
    if (found != r.timings.end())
      html += cell(significant(found->cpu_seconds), true) + cell(significant(found->wall_seconds), true) +
              cell(guess > 0 ? significant(found->cpu_seconds / guess, 2) : "", true);
    else
      html += cell("") + cell("") + cell("");
    html += "</tr>";
  }
  html += "</table><p>Estimated peak memory " + significant(estimate.value("peak_memory_bytes", 0.0) / 1e6) +
          " MB (driven by " + e(estimate.value("memory_driver", "")) +
          "). The rates behind the estimate: docs/architecture.md, Cost estimate.</p>";
  return html + "\n";
}

} // namespace timings_section_member

const ReportSection& timings_report_section() {
  static const ReportSection section{
      ReportSectionKey::timings, "timings", "Stage times against the cost estimate",
      "each stage's measured processor and wall time against the cost estimate",
      timings_section_member::timings_section};
  return section;
}

} // namespace phantasm
