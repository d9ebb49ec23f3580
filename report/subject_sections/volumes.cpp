// The subject report's section of organ volumes: each label's voxels in both states times the
// voxel volume, and the change.
#include "report/html_text.hpp"
#include "report/report_section.hpp"
#include "report/subject_record.hpp"
#include "report/subject_sections/section_html.hpp"

namespace phantasm {
namespace volumes_section_member {

using namespace section_html;

std::string volumes_section(const SubjectRecord& r) {
  std::string html;
  if (r.labels.empty() || r.reference_contours_png.empty()) return html + "<p>The run wrote no labels.</p>\n";
  const double voxel_ml = r.spacing_mm.prod() / 1000.0;
  html += "<p>Voxels of each label of the dseg maps times the voxel volume (" + significant(voxel_ml) +
          " ml); the partial-volume maps are finer.</p><table><tr><th>label</th><th>name</th><th>tissue</th>"
          "<th>reference (ml)</th><th>deformed (ml)</th><th>change (%)</th></tr>";
  for (const auto& [index, label] : r.labels) {
    const double ref = static_cast<double>(label.voxels[0]) * voxel_ml;
    const double def = static_cast<double>(label.voxels[1]) * voxel_ml;
    html += "<tr>" + cell(std::to_string(index), true) + cell(html_escape(label.name)) +
            cell(html_escape(label.tissue)) + cell(significant(ref, 5), true) +
            cell(significant(def, 5), true) +
            cell(ref > 0.0 ? significant(100.0 * (def - ref) / ref, 3) : "", true) + "</tr>";
  }
  return html + "</table>\n";
}

} // namespace volumes_section_member

const ReportSection& volumes_report_section() {
  static const ReportSection section{ReportSectionKey::volumes, "volumes", "Organ volumes",
                                     "each label's volume in both states and its change",
                                     volumes_section_member::volumes_section};
  return section;
}

} // namespace phantasm
