// The HTML report of a subject (one self-contained file, pictures embedded as base64 PNG, plain
// inline JavaScript, no request outside the file), written at the end of every run and by
// `phantasm report DATASET` for a dataset written earlier. docs/report.md says how to read it.
#pragma once

#include "core/stage_report.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace phantasm {

struct SubjectRecord;

/// derivatives/phantasm/sub-<id>.html (where fMRIPrep puts its subject reports).
std::filesystem::path subject_report_path(const std::filesystem::path& dataset, const std::string& subject);

/// The report's HTML: its sections in the order of their registry (report/report_section.hpp),
/// warnings and errors first, then what was modelled, the images of both states with label
/// contours and the displacement and Jacobian overlays, landmarks, organ volumes, the solves'
/// convergence, stage times against the estimate, a methods paragraph. Every text taken from the
/// scene or a result file is HTML-escaped.
/// @throws InputError naming provenance.json when it is not of the shape phantasm writes
std::string subject_report_html(const SubjectRecord& record);

/// The report of a subject whose run failed: why, and the log so far.
/// @param reason the error the run ended with (shown as text)
std::string failed_subject_report_html(const std::string& subject, const std::string& reason,
                                       const std::vector<std::string>& log_lines);

/// Writes a complete subject's report (and, when given, the run's stage times beside its
/// provenance, which the report then shows against the cost estimate), atomically.
/// @throws InputError naming the subject's file that is missing or damaged (nothing written)
void write_subject_report(const std::filesystem::path& dataset, const std::string& subject,
                          const std::vector<StageTiming>& timings = {});

/// Writes the report of a subject whose run failed (failed_subject_report_html), atomically.
void write_failed_subject_report(const std::filesystem::path& dataset, const std::string& subject,
                                 const std::string& reason, const std::vector<std::string>& log_lines);

/// What `phantasm report` wrote.
struct DatasetReportSummary {
  std::vector<std::filesystem::path> written; ///< the reports, in subject order
  std::vector<std::string> failed;            ///< subjects without provenance.json (reported as failed)
};

/// Writes the report of every subject of a dataset written earlier (or of `subject` only):
/// complete subjects from their files; a subject folder without provenance.json (its run failed
/// or was stopped) gets a report saying so, unless the run left one. Every report is made
/// before any is written.
/// @throws InputError when `dataset` is not a dataset phantasm wrote, names no such subject, or
///         a subject's file is missing or damaged (nothing written)
DatasetReportSummary write_dataset_reports(const std::filesystem::path& dataset,
                                           const std::string& subject = {});

} // namespace phantasm
