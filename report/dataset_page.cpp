#include "report/dataset_page.hpp"

#include "core/error.hpp"
#include "core/sha256.hpp"
#include "io/atomic_file.hpp"
#include "io/dataset_layout.hpp"
#include "io/dataset_tables.hpp"
#include "io/json_file.hpp"
#include "io/nifti_file.hpp"
#include "report/factor_plots.hpp"
#include "report/html_text.hpp"
#include "report/slice_pictures.hpp"
#include "report/subject_record.hpp"
#include "report/subject_report.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <set>
#include <sstream>

namespace phantasm {
namespace {

std::vector<std::string> tab_fields(const std::string& line) {
  std::vector<std::string> fields;
  std::istringstream in(line);
  for (std::string field; std::getline(in, field, '\t');)
    fields.push_back(!field.empty() && field.back() == '\r' ? field.substr(0, field.size() - 1) : field);
  return fields;
}

/// participants.tsv's factor columns, and each subject's values (participant_id without sub-).
void read_participants(const std::filesystem::path& file, DatasetPage& page,
                       std::map<std::string, std::map<std::string, std::string>>& values,
                       std::vector<std::string>& order) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(file, error)) return;
  std::istringstream in(read_dataset_text(file, "the sweep's participants table"));
  std::string line;
  if (!std::getline(in, line)) return;
  const std::vector<std::string> header = tab_fields(line);
  if (header.empty() || header.front() != "participant_id")
    throw InputError(file.string() + ":1: expected the header 'participant_id<TAB>...', found '" + line +
                     "'");
  page.factors.assign(header.begin() + 1, header.end());
  for (std::size_t n = 2; std::getline(in, line); ++n) {
    const std::vector<std::string> row = tab_fields(line);
    if (row.empty() || row.front().empty()) continue;
    if (row.front().rfind("sub-", 0) != 0)
      throw InputError(file.string() + ":" + std::to_string(n) +
                       ": expected a participant_id sub-<label>, found '" + row.front() + "'");
    const std::string subject = row.front().substr(4);
    order.push_back(subject);
    for (std::size_t c = 1; c < row.size() && c < header.size(); ++c)
      values[subject][header[c]] = row[c];
  }
}

/// The reason a failed subject's own report gives (its <pre class="reason">), "" when none.
std::string failure_reason(const std::filesystem::path& report) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(report, error)) return {};
  const std::string html = read_dataset_text(report, "the subject's report");
  const std::string open = "<pre class=\"reason\">";
  const std::size_t start = html.find(open);
  if (start == std::string::npos) return {};
  const std::size_t end = html.find("</pre>", start);
  return html_unescape(
      html.substr(start + open.size(), end == std::string::npos ? 0 : end - start - open.size()));
}

double number_at(const nlohmann::json& object, const char* key) {
  const auto found = object.find(key);
  return found != object.end() && found->is_number() ? found->get<double>() : std::nan("");
}

/// The figures provenance.json and timing.json record: displacement, Jacobian, solves, times.
void provenance_figures(const nlohmann::json& provenance, const std::vector<StageTiming>& timings,
                        DatasetSubjectRow& row) {
  for (const nlohmann::json& stage : provenance.value("stages", nlohmann::json::array())) {
    if (stage.value("stage", "") != "voxelize") continue;
    const nlohmann::json accuracy = stage.value("accuracy", nlohmann::json::object());
    row.figures.push_back({"largest displacement (mm)", "", number_at(accuracy, "largest displacement mm")});
    row.figures.push_back(
        {"smallest Jacobian determinant", "", number_at(accuracy, "smallest Jacobian determinant")});
  }
  const nlohmann::json solves = provenance.value("solves", nlohmann::json::array());
  if (!solves.empty()) {
    double iterations = 0.0, residual = 0.0;
    for (const nlohmann::json& s : solves) {
      iterations += number_at(s, "iterations");
      residual = std::max(residual, number_at(s, "relative_residual"));
    }
    row.figures.push_back({"solver iterations (all solves)", "", iterations});
    row.figures.push_back({"final relative residual (largest over the solves)", "", residual});
  }
  if (!timings.empty()) {
    double cpu = 0.0, wall = 0.0;
    for (const StageTiming& t : timings) {
      cpu += t.cpu_seconds;
      wall += t.wall_seconds;
    }
    row.figures.push_back({"processor time (s)", "", cpu});
    row.figures.push_back({"wall time (s)", "", wall});
  }
}

/// The figure of each organ's volume change from its dseg voxels in both states: every named
/// label but the background and the gap a moved organ leaves, in index order.
void volume_change_figures(const std::map<std::int32_t, std::string>& names,
                           const std::map<std::int32_t, std::array<std::int64_t, 2>>& voxels,
                           DatasetSubjectRow& row) {
  for (const auto& [index, name] : names) {
    const auto found = voxels.find(index);
    if (index <= 0 || name == "gap" || found == voxels.end() || found->second[0] <= 0) continue;
    row.figures.push_back({"volume change of each organ (%)", name,
                           100.0 * static_cast<double>(found->second[1] - found->second[0]) /
                               static_cast<double>(found->second[0])});
  }
}

/// Each organ's volume change (dseg voxels of both states) and the thumbnail (middle slices of
/// the first reference image, or of the reference labels when the run made no image).
void volume_figures_and_thumbnail(const DatasetLayout& layout, const std::set<std::string>& listed,
                                  DatasetSubjectRow& row) {
  const auto is_listed = [&](const std::filesystem::path& file) {
    return listed.count(std::filesystem::relative(file, layout.root()).generic_string()) > 0;
  };
  const std::string prefix = "sub-" + layout.subject() + "_ses-ref_";
  const std::filesystem::path anat = std::filesystem::path("sub-" + layout.subject()) / "ses-ref" / "anat";
  for (const std::string& file : listed) { // in name order
    const std::filesystem::path path(file);
    const std::string name = path.filename().string();
    if (path.parent_path() == anat && name.rfind(prefix, 0) == 0 && name.size() > 7 &&
        name.compare(name.size() - 7, 7, ".nii.gz") == 0) {
      const NiftiVolume image = read_nifti(layout.root() / path);
      row.thumbnail_png = grey_slices_png(SliceMontage(image.grid.dims), image.values);
      break;
    }
  }
  if (!is_listed(layout.dseg(PhantomState::reference))) return;
  std::map<std::int32_t, std::string> names;
  if (is_listed(layout.dseg_table())) names = read_label_names(layout.dseg_table());
  std::map<std::int32_t, std::array<std::int64_t, 2>> voxels; // reference, deformed
  ImageGrid grid;
  const std::vector<std::int32_t> reference = read_nifti_labels(layout.dseg(PhantomState::reference), &grid);
  if (row.thumbnail_png.empty())
    row.thumbnail_png =
        grey_slices_png(SliceMontage(grid.dims), std::vector<double>(reference.begin(), reference.end()));
  if (!is_listed(layout.dseg(PhantomState::deformed))) return;
  const std::vector<std::int32_t> deformed = read_nifti_labels(layout.dseg(PhantomState::deformed), &grid);
  for (const std::int32_t l : reference)
    ++voxels[l][0];
  for (const std::int32_t l : deformed)
    ++voxels[l][1];
  volume_change_figures(names, voxels, row);
}

/// The thumbnail and volume figures from the subject's page summary, when it was made with this
/// provenance.json; false (row unchanged) when there is none, it is stale or does not parse: a
/// kept copy, which the volumes can always make again.
bool figures_from_page_summary(const std::filesystem::path& dataset, const std::string& subject,
                               const std::string& provenance_text, DatasetSubjectRow& row) {
  const std::filesystem::path file = page_summary_path(dataset, subject);
  std::error_code error;
  if (!std::filesystem::is_regular_file(file, error)) return false;
  try {
    const nlohmann::json summary = nlohmann::json::parse(read_dataset_text(file, "the page summary"));
    if (summary.at("provenance_sha256").get<std::string>() != sha256_hex(provenance_text)) return false;
    const std::optional<std::string> png = base64_decode(summary.at("thumbnail_png").get<std::string>());
    if (!png) return false;
    std::map<std::int32_t, std::string> names;
    std::map<std::int32_t, std::array<std::int64_t, 2>> voxels;
    for (const nlohmann::json& label : summary.at("labels")) {
      const auto index = label.at("index").get<std::int32_t>();
      names[index] = label.at("name").get<std::string>();
      voxels[index] = {label.at("reference_voxels").get<std::int64_t>(),
                       label.at("deformed_voxels").get<std::int64_t>()};
    }
    row.thumbnail_png = *png;
    volume_change_figures(names, voxels, row);
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

DatasetSubjectRow read_written_subject(const std::filesystem::path& dataset, const std::string& subject) {
  const DatasetLayout layout(dataset, subject);
  DatasetSubjectRow row;
  row.subject = subject;
  row.status = DatasetSubjectRow::Status::written;
  const std::string provenance_text =
      read_dataset_text(layout.provenance(), "the provenance.json phantasm writes");
  const nlohmann::json provenance =
      parse_json_text(provenance_text, layout.provenance(), "the provenance.json phantasm writes");
  std::set<std::string> listed;
  try {
    for (const nlohmann::json& warning : provenance.value("warnings", nlohmann::json::array()))
      row.warnings.push_back(warning.get<std::string>());
    for (const nlohmann::json& file : provenance.at("files"))
      listed.insert(file.get<std::string>());
  } catch (const nlohmann::json::exception&) {
    throw InputError(
        layout.provenance().string() +
        ": expected the provenance phantasm writes ('files' and 'warnings' lists of text), found "
        "other values");
  }
  provenance_figures(provenance, read_stage_timings(dataset, subject), row);
  if (!figures_from_page_summary(dataset, subject, provenance_text, row))
    volume_figures_and_thumbnail(layout, listed, row);
  return row;
}

} // namespace

std::filesystem::path dataset_page_path(const std::filesystem::path& dataset) {
  return DatasetLayout(dataset, "").derivatives() / "index.html";
}

std::filesystem::path page_summary_path(const std::filesystem::path& dataset, const std::string& subject) {
  return DatasetLayout(dataset, subject).provenance().parent_path() / "page-summary.json";
}

std::string page_summary_text(const std::filesystem::path& dataset, const SubjectRecord& record) {
  const DatasetLayout layout(dataset, record.subject);
  // The labels' voxels count in both states only when the run wrote both (the page's figures).
  nlohmann::json labels = nlohmann::json::array();
  if (!record.reference_only)
    for (const auto& [index, label] : record.labels)
      labels.push_back({{"index", index},
                        {"name", label.name},
                        {"reference_voxels", label.voxels[0]},
                        {"deformed_voxels", label.voxels[1]}});
  const nlohmann::json summary = {
      {"provenance_sha256",
       sha256_hex(read_dataset_text(layout.provenance(), "the provenance.json phantasm writes"))},
      {"thumbnail_png",
       base64_encode(record.images.empty() ? std::string() : record.images.front().reference_png)},
      {"labels", labels}};
  return json_text(summary) + "\n";
}

DatasetPage read_dataset_page(const std::filesystem::path& dataset) {
  const DatasetLayout any(dataset, "");
  std::error_code error;
  for (const std::filesystem::path& needed : {any.dataset_description(), any.derivatives()})
    if (!std::filesystem::exists(needed, error))
      throw InputError(dataset.string() + ": expected a dataset phantasm wrote, found no " +
                       std::filesystem::relative(needed, dataset).generic_string() + " in it");
  DatasetPage page;
  const nlohmann::json description =
      parse_json_text(read_dataset_text(any.dataset_description(), "the dataset's description"),
                      any.dataset_description(), "the dataset's description");
  if (description.is_object() && description.contains("Name") && description["Name"].is_string())
    page.name = description["Name"].get<std::string>();
  std::map<std::string, std::map<std::string, std::string>> factors;
  std::vector<std::string> subjects;
  read_participants(dataset / "participants.tsv", page, factors, subjects);
  std::set<std::string> others; // subjects with a folder or a report of their own
  for (const auto& entry : std::filesystem::directory_iterator(any.derivatives(), error)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("sub-", 0) != 0) continue;
    if (entry.is_directory())
      others.insert(name.substr(4));
    else if (entry.path().extension() == ".html")
      others.insert(entry.path().stem().string().substr(4));
  }
  for (const std::string& s : others)
    if (std::find(subjects.begin(), subjects.end(), s) == subjects.end()) subjects.push_back(s);
  for (const std::string& subject : subjects) {
    const DatasetLayout layout(dataset, subject);
    DatasetSubjectRow row;
    if (std::filesystem::exists(layout.provenance(), error)) {
      row = read_written_subject(dataset, subject);
    } else if (others.count(subject)) {
      row.subject = subject;
      row.status = DatasetSubjectRow::Status::failed;
      row.reason = failure_reason(subject_report_path(dataset, subject));
    } else {
      row.subject = subject;
    }
    row.factors = factors[subject];
    page.rows.push_back(std::move(row));
  }
  return page;
}

namespace {

std::string status_cell(const DatasetSubjectRow& row) {
  switch (row.status) {
  case DatasetSubjectRow::Status::written:
    return row.warnings.empty() ? "<td class=\"ok\">written</td>" : "<td class=\"warn\">written, warned</td>";
  case DatasetSubjectRow::Status::failed:
    return "<td class=\"bad\">failed" +
           (row.reason.empty()
                ? std::string(" (no reason recorded: the run stopped, or the batch's log names it)")
                : "<pre>" + html_escape(row.reason) + "</pre>") +
           "</td>";
  case DatasetSubjectRow::Status::missing: break;
  }
  return "<td>not made (another shard, or the batch stopped before it)</td>";
}

std::string warnings_cell(const DatasetSubjectRow& row) {
  if (row.warnings.empty()) return "<td class=\"n\">0</td>";
  std::string html = "<td>" + std::to_string(row.warnings.size()) + ":<ul>";
  for (std::size_t k = 0; k < row.warnings.size() && k < 3; ++k)
    html += "<li>" + html_escape(row.warnings[k]) + "</li>";
  if (row.warnings.size() > 3) html += "<li>... (the subject's report lists them all)</li>";
  return html + "</ul></td>";
}

std::string subjects_table(const DatasetPage& page) {
  std::string html = "<table><tr><th>subject</th><th>middle slices</th>";
  for (const std::string& factor : page.factors)
    html += "<th class=\"factor\">" + html_escape(factor) + "</th>";
  html += "<th>status</th><th>warnings</th></tr>\n";
  for (const DatasetSubjectRow& row : page.rows) {
    const std::string label = "sub-" + html_escape(row.subject);
    html += "<tr><td>";
    html += row.status == DatasetSubjectRow::Status::missing
                ? label
                : "<a href=\"" + label + ".html\">" + label + "</a>";
    html += "</td><td>";
    if (!row.thumbnail_png.empty())
      html += "<img class=\"thumb\" alt=\"" + label + " middle slices\" src=\"" +
              png_data_url(row.thumbnail_png) + "\">";
    html += "</td>";
    for (const std::string& factor : page.factors) {
      const auto found = row.factors.find(factor);
      html +=
          "<td class=\"factor\">" + (found != row.factors.end() ? html_escape(found->second) : "") + "</td>";
    }
    html += status_cell(row) + warnings_cell(row) + "</tr>\n";
  }
  return html + "</table>\n";
}

/// Every plot of the page's figures (in order of first appearance) against `factor`.
std::string factor_section(const DatasetPage& page, const std::string& factor) {
  std::vector<std::string> plots;
  std::map<std::string, std::vector<PlotSeries>> series;
  for (const DatasetSubjectRow& row : page.rows) {
    const auto value = row.factors.find(factor);
    if (value == row.factors.end() || row.status != DatasetSubjectRow::Status::written) continue;
    for (const SubjectFigure& figure : row.figures) {
      if (std::find(plots.begin(), plots.end(), figure.plot) == plots.end()) plots.push_back(figure.plot);
      std::vector<PlotSeries>& lines = series[figure.plot];
      auto line = std::find_if(lines.begin(), lines.end(),
                               [&](const PlotSeries& s) { return s.name == figure.series; });
      if (line == lines.end()) line = lines.insert(lines.end(), PlotSeries{figure.series, {}});
      line->points.emplace_back(value->second, figure.value);
    }
  }
  std::string html = "<h3>Against " + html_escape(factor) + "</h3><div class=\"plots\">";
  for (const std::string& plot : plots)
    html += factor_plot_svg(factor, plot, series[plot]);
  return html + "</div>\n";
}

} // namespace

std::string dataset_page_html(const DatasetPage& page) {
  std::size_t written = 0, failed = 0, warned = 0;
  for (const DatasetSubjectRow& row : page.rows) {
    written += row.status == DatasetSubjectRow::Status::written ? 1 : 0;
    failed += row.status == DatasetSubjectRow::Status::failed ? 1 : 0;
    warned += row.warnings.empty() ? 0 : 1;
  }
  std::string body = "<p>" + std::to_string(page.rows.size()) + " subjects: " + std::to_string(written) +
                     " written (" + std::to_string(warned) + " with warnings), " + std::to_string(failed) +
                     " failed, " + std::to_string(page.rows.size() - written - failed) +
                     " not made. Each subject's label links to its own report.</p>\n";
  body += "<h2 id=\"subjects\">Subjects</h2>\n" + subjects_table(page);
  body += "<h2 id=\"plots\">Figures against the varied factors</h2>\n";
  if (page.factors.empty())
    body += "<p>The dataset varies no factor (it has no participants.tsv with factor columns).</p>\n";
  else if (written < 2)
    body += "<p>Fewer than two subjects are written: nothing to plot.</p>\n";
  else
    for (const std::string& factor : page.factors)
      body += factor_section(page, factor);
  body +=
      "<p>Each point is a subject, each line joins the means at each value of the factor. The figures come "
      "from each subject's provenance.json (largest displacement and smallest Jacobian determinant of the "
      "voxelized field, the solves), timing.json (processor and wall time of the run) and its dseg maps "
      "(the voxels of each organ in both states).</p>\n";
  return table_page_html("phantasm dataset: " + html_escape(page.name.empty() ? "(no name)" : page.name),
                         body);
}

std::filesystem::path write_dataset_page(const std::filesystem::path& dataset) {
  const std::string html = dataset_page_html(read_dataset_page(dataset));
  const std::filesystem::path path = dataset_page_path(dataset);
  write_file_atomically(path, html);
  return path;
}

} // namespace phantasm
