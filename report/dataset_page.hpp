// The page of a whole dataset (derivatives/phantasm/index.html): a row per subject with a
// thumbnail, the sweep's varied factors, its status and warnings and a link to its report, then
// plots of each subject's main figures against each varied factor. Written by `phantasm batch`
// when the sweep ends and by `phantasm report DATASET`; docs/report.md says how to read it.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace phantasm {

/// One figure of a subject, drawn against each factor: the plot it belongs to, and its series
/// there (an organ; empty when the plot has one series).
struct SubjectFigure {
  std::string plot, series;
  double value = 0.0;
};

/// A subject's row of the dataset page.
struct DatasetSubjectRow {
  enum class Status {
    written, ///< complete: provenance.json and every file it lists
    failed,  ///< the run failed or stopped: a subject folder without provenance.json, or its failed report
    missing, ///< in participants.tsv, not made (another shard, or the batch stopped before it)
  };
  std::string subject;
  Status status = Status::missing;
  std::string reason;                         ///< why it failed, as its run recorded it ("" when unknown)
  std::map<std::string, std::string> factors; ///< participants.tsv's column -> value
  std::vector<std::string> warnings;          ///< provenance.json's warnings
  std::string thumbnail_png;                  ///< middle slices of its first reference image; "" for none
  std::vector<SubjectFigure> figures;
};

/// What the dataset page shows.
struct DatasetPage {
  std::string name;                 ///< dataset_description.json's Name
  std::vector<std::string> factors; ///< participants.tsv's columns after participant_id, in its order
  std::vector<DatasetSubjectRow> rows;
};

/// derivatives/phantasm/index.html
std::filesystem::path dataset_page_path(const std::filesystem::path& dataset);

struct SubjectRecord; // report/subject_record.hpp

/// derivatives/phantasm/sub-<id>/page-summary.json: what the dataset page shows of a written
/// subject that only its volumes give (its thumbnail, each label's voxels in both states),
/// written with the subject's report from the record the report is made of, so that the page
/// reads one small file per subject instead of decompressing three volumes (half a second a
/// subject on the Colin head; every shard of a batch writes the page of all subjects so far). It
/// holds the SHA-256 of the provenance.json it was made with: a page reads it only while that
/// file is unchanged, and reads the volumes otherwise (the same row either way).
std::filesystem::path page_summary_path(const std::filesystem::path& dataset, const std::string& subject);

/// The page summary of a written subject (the text of page_summary_path) from `record`
/// (read_subject_record of the same dataset).
/// @throws InputError naming provenance.json when it cannot be read
std::string page_summary_text(const std::filesystem::path& dataset, const SubjectRecord& record);

/// Reads every subject of a dataset: those participants.tsv names and those with a folder or a
/// report in derivatives/phantasm, in participants.tsv's order, then by label.
/// @throws InputError when `dataset` is not a dataset phantasm wrote, or a complete subject's
///         provenance.json, timing.json, label table or volume is damaged (naming the file)
DatasetPage read_dataset_page(const std::filesystem::path& dataset);

/// The page's HTML (self-contained: thumbnails embedded as PNG, plots as SVG, no script). Plots
/// only when at least two subjects are written and the dataset varies a factor. Every text from
/// the dataset's files is HTML-escaped.
std::string dataset_page_html(const DatasetPage& page);

/// Reads the dataset and writes its page atomically.
/// @return the page's path
std::filesystem::path write_dataset_page(const std::filesystem::path& dataset);

} // namespace phantasm
