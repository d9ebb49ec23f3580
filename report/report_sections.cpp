#include "report/report_section.hpp"

#include "core/registry.hpp"
#include "report/html_text.hpp"

namespace phantasm {

// The members, one per file of report/subject_sections/.
const ReportSection& warnings_report_section();
const ReportSection& modelled_report_section();
const ReportSection& images_report_section();
const ReportSection& landmarks_report_section();
const ReportSection& volumes_report_section();
const ReportSection& convergence_report_section();
const ReportSection& timings_report_section();
const ReportSection& methods_report_section();

namespace {

const Registry<ReportSection, ReportSectionKey>& report_section_registry() {
  // The registrations, in the page's order: a new section adds its line here and its declaration
  // above (docs/architecture.md, Adding a variant).
  static const Registry<ReportSection, ReportSectionKey> sections(
      "report section", &ReportSection::key,
      {&warnings_report_section(), &modelled_report_section(), &images_report_section(),
       &landmarks_report_section(), &volumes_report_section(), &convergence_report_section(),
       &timings_report_section(), &methods_report_section()});
  return sections;
}

} // namespace

const std::vector<const ReportSection*>& report_sections() {
  return report_section_registry().members();
}

const ReportSection& report_section(ReportSectionKey key) {
  return report_section_registry().at(key);
}

std::string report_section_heading(const ReportSection& section) {
  return std::string("<h2 id=\"") + section.id + "\">" + html_escape(section.title) + "</h2>\n";
}

} // namespace phantasm
