// The registry of the subject report's sections: one member per section
// (report/subject_sections/NAME.cpp), each the one place that knows its anchor, its title, what it
// shows and how it renders a subject's record. The registry's order is the page's order. Adding a
// section: docs/architecture.md, "Adding a variant".
#pragma once

#include <string>
#include <vector>

namespace phantasm {

struct SubjectRecord;

/// The sections of the subject report.
enum class ReportSectionKey { warnings, modelled, images, landmarks, volumes, convergence, timings, methods };

/// One section of the subject report.
struct ReportSection {
  ReportSectionKey key;
  const char* id;          ///< its HTML anchor, <h2 id="..."> ("warnings")
  const char* title;       ///< its heading (plain text)
  const char* description; ///< one line for the docs
  /// Its HTML below the heading, or "" to leave the section (heading and all) out of the page.
  /// @throws nlohmann::json::exception for provenance of another shape (subject_report_html names
  ///         the file)
  std::string (*html)(const SubjectRecord& record);
};

/// Every section, in the page's order.
const std::vector<const ReportSection*>& report_sections();

/// The member of a key (every key has one).
const ReportSection& report_section(ReportSectionKey key);

/// The section's heading: <h2 id="ID">TITLE</h2> and a line break.
std::string report_section_heading(const ReportSection& section);

} // namespace phantasm
