#include "report/subject_report.hpp"

#include "core/error.hpp"
#include "core/version.hpp"
#include "io/atomic_file.hpp"
#include "io/dataset_layout.hpp"
#include "report/dataset_page.hpp"
#include "report/html_text.hpp"
#include "report/report_figures.hpp"
#include "report/report_section.hpp"
#include "report/subject_record.hpp"
#include "report/subject_sections/section_html.hpp"

#include <algorithm>
#include <fstream>

namespace phantasm {
namespace {

const char* const k_style = R"(
body{font-family:sans-serif;max-width:1200px;margin:1em auto;padding:0 1em;color:#222}
h1{font-size:1.5em}h2{border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:1.6em}
table{border-collapse:collapse;margin:.5em 0;display:block;max-width:100%;overflow-x:auto}td,th{border:1px solid #ccc;padding:.2em .5em;text-align:left;vertical-align:top}
td.n{text-align:right;font-variant-numeric:tabular-nums}
.ok{background:#e6f4e6;border:1px solid #7b7;padding:.5em}.bad{background:#fde8e8;border:1px solid #d66;padding:.5em}
.warn{background:#fff4d6;border:1px solid #db4;padding:.5em}
pre{background:#f6f6f6;padding:.5em;overflow:auto;max-height:30em;white-space:pre-wrap}
.stack{position:relative;background:#000}.stack img{position:absolute;left:0;top:0;width:100%;image-rendering:pixelated}
.stack img.base{position:static;display:block}
figure.viewer{margin:1em 0}.controls{margin:.3em 0}.bar{vertical-align:middle;height:14px;width:256px}
)";

std::string page(const std::string& title, const std::string& body) {
  return "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>" + title +
         "</title><style>" + k_style + "</style></head><body>\n<h1>" + title + "</h1>\n" + body + "<script>" +
         k_viewer_script + "</script></body></html>\n";
}

} // namespace

std::filesystem::path subject_report_path(const std::filesystem::path& dataset, const std::string& subject) {
  return DatasetLayout(dataset, subject).derivatives() / ("sub-" + subject + ".html");
}

std::string subject_report_html(const SubjectRecord& record) {
  try {
    const std::string title = "phantasm report: sub-" + html_escape(record.subject) + ", scene " +
                              section_html::e(record.provenance.at("settings").value("name", ""));
    std::string body;
    for (const ReportSection* section : report_sections())
      if (const std::string html = section->html(record); !html.empty())
        body += report_section_heading(*section) + html;
    return page(title, body);
  } catch (const nlohmann::json::exception& error) {
    throw InputError(DatasetLayout("", record.subject).provenance().string() +
                     ": expected the provenance phantasm writes, found a value of another kind (" +
                     error.what() + ")");
  }
}

std::string failed_subject_report_html(const std::string& subject, const std::string& reason,
                                       const std::vector<std::string>& log_lines) {
  std::string body = report_section_heading(report_section(ReportSectionKey::warnings)) +
                     "<div class=\"bad\"><p>The run of this subject "
                     "failed; nothing of it can be vouched for.</p><pre class=\"reason\">" +
                     html_escape(reason) + "</pre></div>\n";
  if (!log_lines.empty()) {
    body += "<h2>The run's log until then</h2><pre>";
    for (const std::string& line : log_lines)
      body += html_escape(line) + "\n";
    body += "</pre>\n";
  }
  return page("phantasm report: sub-" + html_escape(subject) + " failed", body);
}

void write_subject_report(const std::filesystem::path& dataset, const std::string& subject,
                          const std::vector<StageTiming>& timings) {
  if (!timings.empty()) write_timings(dataset, subject, timings);
  const SubjectRecord record = read_subject_record(dataset, subject);
  const std::string html = subject_report_html(record);
  const std::string summary = page_summary_text(dataset, record);
  write_file_atomically(subject_report_path(dataset, subject), html);
  write_file_atomically(page_summary_path(dataset, subject), summary);
}

void write_failed_subject_report(const std::filesystem::path& dataset, const std::string& subject,
                                 const std::string& reason, const std::vector<std::string>& log_lines) {
  write_file_atomically(subject_report_path(dataset, subject),
                        failed_subject_report_html(subject, reason, log_lines));
}

DatasetReportSummary write_dataset_reports(const std::filesystem::path& dataset, const std::string& subject) {
  const DatasetLayout any(dataset, "");
  std::error_code error;
  if (!std::filesystem::is_directory(dataset, error))
    throw InputError(dataset.string() + ": expected a dataset folder phantasm wrote, found " +
                     (std::filesystem::exists(dataset, error) ? "a file" : "nothing"));
  for (const std::filesystem::path& needed : {any.dataset_description(), any.derivatives()})
    if (!std::filesystem::exists(needed, error))
      throw InputError(dataset.string() + ": expected a dataset phantasm wrote, found no " +
                       std::filesystem::relative(needed, dataset).generic_string() + " in it");
  std::vector<std::string> subjects;
  for (const auto& entry : std::filesystem::directory_iterator(any.derivatives(), error)) {
    const std::string name = entry.path().filename().string();
    if (entry.is_directory() && name.rfind("sub-", 0) == 0) subjects.push_back(name.substr(4));
  }
  std::sort(subjects.begin(), subjects.end());
  if (!subject.empty()) {
    if (std::find(subjects.begin(), subjects.end(), subject) == subjects.end())
      throw InputError("--subject " + subject + ": expected a subject of " + dataset.string() + ", found " +
                       (subjects.empty() ? std::string("none") : "sub-" + section_html::joined(subjects)));
    subjects = {subject};
  }
  if (subjects.empty())
    throw InputError(any.derivatives().string() + ": expected subject folders sub-<id>, found none");
  // Every page is made before any is written: a damaged subject leaves the dataset as it was.
  std::vector<std::pair<std::filesystem::path, std::string>> pages, page_summaries;
  DatasetReportSummary summary;
  for (const std::string& s : subjects) {
    const DatasetLayout layout(dataset, s);
    if (std::filesystem::exists(layout.provenance(), error)) {
      const SubjectRecord record = read_subject_record(dataset, s);
      pages.emplace_back(subject_report_path(dataset, s), subject_report_html(record));
      page_summaries.emplace_back(page_summary_path(dataset, s), page_summary_text(dataset, record));
      continue;
    }
    summary.failed.push_back(s);
    if (std::filesystem::exists(subject_report_path(dataset, s), error))
      continue; // the run's own, with its reason
    std::vector<std::string> log;
    if (std::ifstream in(layout.log()); in)
      for (std::string line; std::getline(in, line);)
        log.push_back(line);
    pages.emplace_back(
        subject_report_path(dataset, s),
        failed_subject_report_html(s,
                                   layout.provenance().string() +
                                       " is missing: the run of this subject failed or was stopped "
                                       "before its end, and left no record of why (a batch's log "
                                       "names the exit status)",
                                   log));
  }
  for (const auto& [path, html] : pages) {
    write_file_atomically(path, html);
    summary.written.push_back(path);
  }
  for (const auto& [path, text] : page_summaries)
    write_file_atomically(path, text);
  return summary;
}

} // namespace phantasm
