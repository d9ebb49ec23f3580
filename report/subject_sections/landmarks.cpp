// The subject report's section of landmarks: named material points in both states, largest move
// first.
#include "report/html_text.hpp"
#include "report/report_section.hpp"
#include "report/subject_record.hpp"
#include "report/subject_sections/section_html.hpp"

#include <algorithm>

namespace phantasm {
namespace landmarks_section_member {

using namespace section_html;

std::string landmarks_section(const SubjectRecord& r) {
  std::string html;
  if (r.reference_only) return html + "<p>Nothing deforms: the landmarks stay where they are.</p>\n";
  if (r.landmarks.empty()) return html + "<p>The run wrote no landmarks.</p>\n";
  html += "<p>Named material points, the same points in both states (world RAS mm), largest move first.</p>"
          "<table><tr><th>landmark</th><th>organ</th><th>reference (mm)</th><th>deformed (mm)</th>"
          "<th>moved (mm)</th></tr>";
  std::vector<const LandmarkMove*> order;
  for (const LandmarkMove& l : r.landmarks)
    order.push_back(&l);
  std::stable_sort(order.begin(), order.end(), [](const LandmarkMove* a, const LandmarkMove* b) {
    return (a->deformed_mm - a->reference_mm).norm() > (b->deformed_mm - b->reference_mm).norm();
  });
  const auto point = [](const Eigen::Vector3d& p) {
    return significant(p.x(), 4) + ", " + significant(p.y(), 4) + ", " + significant(p.z(), 4);
  };
  for (const LandmarkMove* l : order)
    html += "<tr>" + cell(html_escape(l->name)) + cell(html_escape(l->organ)) +
            cell(point(l->reference_mm), true) + cell(point(l->deformed_mm), true) +
            cell(significant((l->deformed_mm - l->reference_mm).norm()), true) + "</tr>";
  return html + "</table>\n";
}

} // namespace landmarks_section_member

const ReportSection& landmarks_report_section() {
  static const ReportSection section{
      ReportSectionKey::landmarks, "landmarks", "Landmarks",
      "named material points in both states (world RAS mm), largest move first",
      landmarks_section_member::landmarks_section};
  return section;
}

} // namespace phantasm
