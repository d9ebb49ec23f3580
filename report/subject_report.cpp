#include "report/subject_report.hpp"

#include "core/error.hpp"
#include "core/version.hpp"
#include "io/atomic_file.hpp"
#include "io/dataset_layout.hpp"
#include "io/json_file.hpp"
#include "report/html_text.hpp"
#include "report/report_figures.hpp"
#include "report/subject_record.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

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

/// A JSON value as text: strings as they are, anything else as compact JSON.
std::string text_of(const nlohmann::json& value) {
  return value.is_string() ? value.get<std::string>()
         : value.is_null() ? std::string()
                           : json_text(value, -1);
}

std::string e(const nlohmann::json& value) {
  return html_escape(text_of(value));
}

std::string cell(const std::string& html, bool number = false) {
  return std::string(number ? "<td class=\"n\">" : "<td>") + html + "</td>";
}

std::string list_html(const nlohmann::json& lines) {
  std::string html = "<ul>";
  for (const nlohmann::json& line : lines)
    html += "<li>" + e(line) + "</li>";
  return html + "</ul>";
}

std::string warnings_section(const SubjectRecord& r) {
  std::string html = "<h2 id=\"warnings\">Warnings and errors</h2>\n";
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

std::string organs_table(const nlohmann::json& settings) {
  std::string html = "<table><tr><th>organ</th><th>tissue</th><th>material</th><th>solid</th><th>inside</th>"
                     "<th>shape</th></tr>";
  for (const nlohmann::json& organ : settings.at("anatomy").at("organs")) {
    const nlohmann::json shape = organ.value("shape", nlohmann::json::object());
    html += "<tr>" + cell(e(organ.value("name", ""))) + cell(e(organ.value("tissue", ""))) +
            cell(e(organ.value("material", ""))) + cell(organ.value("solid", false) ? "yes" : "no") +
            cell(e(organ.value("inside", ""))) + cell(e(shape.value("type", nlohmann::json()))) + "</tr>";
  }
  return html + "</table>";
}

std::string materials_table(const nlohmann::json& settings) {
  const nlohmann::json materials = settings.value("materials", nlohmann::json::object());
  if (materials.empty()) return "<p>No materials (nothing deforms).</p>";
  std::string html = "<table><tr><th>material</th><th>Young's modulus (Pa)</th><th>Poisson ratio</th>"
                     "<th>density (kg/m&sup3;)</th></tr>";
  for (const auto& [name, m] : materials.items())
    html += "<tr>" + cell(html_escape(name)) + cell(e(m.value("youngs_modulus_Pa", nlohmann::json())), true) +
            cell(e(m.value("poisson_ratio", nlohmann::json())), true) +
            cell(e(m.value("density_kg_m3", nlohmann::json())), true) + "</tr>";
  return html + "</table>";
}

/// Rows of JSON objects: each key a column (the union of the keys, in order of first use).
std::string objects_table(const nlohmann::json& rows, const char* empty) {
  if (!rows.is_array() || rows.empty()) return std::string("<p>") + empty + "</p>";
  std::vector<std::string> columns;
  for (const nlohmann::json& row : rows)
    for (const auto& [key, value] : row.items())
      if (std::find(columns.begin(), columns.end(), key) == columns.end()) columns.push_back(key);
  std::string html = "<table><tr>";
  for (const std::string& c : columns)
    html += "<th>" + html_escape(c) + "</th>";
  html += "</tr>";
  for (const nlohmann::json& row : rows) {
    html += "<tr>";
    for (const std::string& c : columns)
      html += cell(row.contains(c) ? e(row.at(c)) : "");
    html += "</tr>";
  }
  return html + "</table>";
}

std::string modelled_section(const SubjectRecord& r) {
  const nlohmann::json& settings = r.provenance.at("settings");
  const nlohmann::json grid = settings.value("grid", nlohmann::json::object());
  std::string html = "<h2 id=\"modelled\">What was modelled</h2>\n";
  html += "<p>Scene <b>" + e(settings.value("name", "")) + "</b>, seed " + e(r.provenance.value("seed", 0)) +
          ". Grid: " + std::to_string(r.dims.x()) + " x " + std::to_string(r.dims.y()) + " x " +
          std::to_string(r.dims.z()) + " voxels of " + e(grid.value("voxel_size_mm", nlohmann::json())) +
          " mm, field of view " + e(grid.value("field_of_view_mm", nlohmann::json())) + " mm centred at " +
          e(grid.value("center_mm", nlohmann::json())) + " mm, " + e(grid.value("orientation", "")) +
          "; field strength " + e(settings.value("field_strength_T", nlohmann::json())) + " T.</p>\n";
  html += "<h3>Organs</h3>" + organs_table(settings);
  html += "<h3>Materials</h3>" + materials_table(settings);
  const nlohmann::json deformation = settings.value("deformation", nlohmann::json::object());
  html += "<h3>Loads</h3><p>Deformation mode " + e(deformation.value("mode", "")) + ", solver " +
          e(deformation.value("solver", nlohmann::json::object()).value("method", "")) + ".</p>" +
          objects_table(deformation.value("loads", nlohmann::json::array()), "No loads.");
  html += "<h3>Sequences</h3>" + objects_table(settings.value("sequences", nlohmann::json::array()),
                                               "No sequences: the run made no MR images.");
  html += "<h3>Each stage: modelled and skipped</h3>";
  for (const nlohmann::json& stage : r.provenance.at("stages")) {
    html += "<h4>" + e(stage.value("stage", "")) + " (" + e(stage.value("status", "")) + ")</h4>" +
            list_html(stage.value("modelled", nlohmann::json::array()));
    if (const nlohmann::json skipped = stage.value("skipped", nlohmann::json::array()); !skipped.empty())
      html += "<p>Skipped:</p>" + list_html(skipped);
  }
  if (!r.scene_text.empty())
    html += "<details><summary>The scene file as run</summary><pre>" + html_escape(r.scene_text) +
            "</pre></details>";
  return html + "\n";
}

std::string landmarks_section(const SubjectRecord& r) {
  std::string html = "<h2 id=\"landmarks\">Landmarks</h2>\n";
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

std::string volumes_section(const SubjectRecord& r) {
  std::string html = "<h2 id=\"volumes\">Organ volumes</h2>\n";
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

std::string convergence_section(const SubjectRecord& r) {
  std::string html = "<h2 id=\"convergence\">Solver convergence</h2>\n";
  const nlohmann::json solves = r.provenance.value("solves", nlohmann::json::array());
  if (solves.empty()) return html + "<p>Nothing was simulated.</p>\n";
  const double tolerance = r.provenance.at("settings")
                               .value("deformation", nlohmann::json::object())
                               .value("solver", nlohmann::json::object())
                               .value("relative_residual_tolerance", 1e-3);
  std::size_t converged = 0;
  long iterations = 0;
  for (const nlohmann::json& s : solves) {
    converged += s.value("converged", false) ? 1 : 0;
    iterations += s.value("iterations", 0L);
  }
  html +=
      std::string(converged == solves.size() ? "<p class=\"ok\">" : "<p class=\"bad\">") +
      std::to_string(converged) + " of " + std::to_string(solves.size()) +
      " solves converged (relative residual " + "at most " + significant(tolerance) + "), " +
      std::to_string(iterations) +
      " iterations in all. The relative residual is the largest force on a free vertex over the loads' force "
      "per vertex.</p>";
  html += residual_plots(solves, tolerance);
  html += "<table><tr><th>solve</th><th>solver</th><th>iterations</th><th>stopped by</th><th>relative "
          "residual</th>"
          "<th>residual (N)</th><th>converged</th></tr>";
  for (std::size_t k = 0; k < solves.size(); ++k) {
    const nlohmann::json& s = solves[k];
    html += "<tr>" + cell(std::to_string(k + 1), true) + cell(e(s.value("solver", ""))) +
            cell(e(s.value("iterations", 0)), true) + cell(e(s.value("stopped_by", ""))) +
            cell(significant(s.value("relative_residual", 0.0)), true) +
            cell(significant(s.value("residual_N", 0.0)), true) +
            cell(s.value("converged", false) ? "yes" : "<b>no</b>") + "</tr>";
  }
  html += "</table>";
  if (const nlohmann::json bodies = r.provenance.value("bodies", nlohmann::json::array()); !bodies.empty())
    html += "<p>Bodies at the result:</p>" + objects_table(bodies, "");
  return html + "\n";
}

std::string timings_section(const SubjectRecord& r) {
  std::string html = "<h2 id=\"timings\">Stage times against the cost estimate</h2>\n";
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

std::string joined(const std::vector<std::string>& parts) {
  std::string text;
  for (std::size_t k = 0; k < parts.size(); ++k)
    text += (k == 0 ? "" : k + 1 == parts.size() ? " and " : ", ") + parts[k];
  return text;
}

std::string methods_section(const SubjectRecord& r) {
  const nlohmann::json& settings = r.provenance.at("settings");
  const nlohmann::json deformation = settings.value("deformation", nlohmann::json::object());
  const std::string solver = deformation.value("solver", nlohmann::json::object()).value("method", "");
  std::vector<std::string> organs, sequences,
      citations = {
          "S. I. Vyatkin, B. S. Dolgovesov, Combined method of deformation and animation of objects based on "
          "positional modeling and continuum mechanics using free-form patches, Software &amp; Systems "
          "38(3), 2025, "
          "pp. 438-447."};
  for (const nlohmann::json& organ : settings.at("anatomy").at("organs"))
    organs.push_back(e(organ.value("name", "")) + " (" + e(organ.value("tissue", "")) + ")");
  for (const nlohmann::json& s : settings.value("sequences", nlohmann::json::array())) {
    std::string text = e(s.value("name", "")) + " (" + e(s.value("type", ""));
    for (const char* key : {"TR_ms", "TE_ms", "TI_ms", "flip_deg"})
      if (s.contains(key)) text += ", " + std::string(key) + " " + e(s.at(key));
    sequences.push_back(text + ")");
  }
  std::string text = "Phantoms were generated with phantasm " +
                     e(r.provenance.value("phantasm_version", "")) + " from the scene " +
                     e(settings.value("name", "")) + " (scene file SHA-256 " +
                     e(r.provenance.value("scene", nlohmann::json::object()).value("sha256", "")) +
                     ", seed " + e(r.provenance.value("seed", 0)) + "). The anatomy comprised " +
                     joined(organs) + ", each a free-form patch surface [1]";
  const std::string mode = deformation.value("mode", "none");
  if (mode != "none") {
    text += "; it was deformed " + html_escape(mode == "dynamic" ? "dynamically" : "quasi-statically") +
            " by the " + html_escape(solver) + " solver";
    if (solver == "local_global") {
      text += " of Projective Dynamics [2]";
      citations.push_back(
          "S. Bouaziz, S. Martin, T. Liu, L. Kavan, M. Pauly, Projective Dynamics: Fusing Constraint "
          "Projections for Fast Simulation, ACM Transactions on Graphics 33(4), 2014.");
    }
    text += " to a relative residual of " + e(deformation.value("solver", nlohmann::json::object())
                                                  .value("relative_residual_tolerance", nlohmann::json()));
  }
  const nlohmann::json vox = settings.value("voxelization", nlohmann::json::object());
  text +=
      ". Labels, partial-volume fractions (" + e(vox.value("supersampling", nlohmann::json())) +
      "<sup>3</sup> samples per voxel), displacement fields both ways and their Jacobian determinants were "
      "computed on a grid of " +
      std::to_string(r.dims.x()) + " x " + std::to_string(r.dims.y()) + " x " + std::to_string(r.dims.z()) +
      " voxels of " +
      e(settings.value("grid", nlohmann::json::object()).value("voxel_size_mm", nlohmann::json())) + " mm";
  if (!sequences.empty())
    text += "; MR images " + joined(sequences) + " were synthesized at " +
            e(settings.value("field_strength_T", 0.0)) + " T";
  text += ".";
  for (const nlohmann::json& stage : r.provenance.at("stages"))
    for (const nlohmann::json& line : stage.value("modelled", nlohmann::json::array()))
      if (const std::string s = text_of(line);
          s.find("source") != std::string::npos && s.find(" et al") != std::string::npos)
        citations.push_back(html_escape(s));
  std::string html = "<h2 id=\"methods\">Methods</h2>\n<p>" + text + "</p><ol>";
  for (const std::string& c : citations)
    html += "<li>" + c + "</li>";
  return html + "</ol><p>Every setting of the run is in provenance.json beside the subject's files.</p>\n";
}

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
                              e(record.provenance.at("settings").value("name", ""));
    return page(title, warnings_section(record) + modelled_section(record) + images_section(record) +
                           landmarks_section(record) + volumes_section(record) + convergence_section(record) +
                           timings_section(record) + methods_section(record));
  } catch (const nlohmann::json::exception& error) {
    throw InputError(DatasetLayout("", record.subject).provenance().string() +
                     ": expected the provenance phantasm writes, found a value of another kind (" +
                     error.what() + ")");
  }
}

std::string failed_subject_report_html(const std::string& subject, const std::string& reason,
                                       const std::vector<std::string>& log_lines) {
  std::string body =
      "<h2 id=\"warnings\">Warnings and errors</h2>\n<div class=\"bad\"><p>The run of this subject "
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
  const std::string html = subject_report_html(read_subject_record(dataset, subject));
  write_file_atomically(subject_report_path(dataset, subject), html);
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
                       (subjects.empty() ? std::string("none") : "sub-" + joined(subjects)));
    subjects = {subject};
  }
  if (subjects.empty())
    throw InputError(any.derivatives().string() + ": expected subject folders sub-<id>, found none");
  // Every page is made before any is written: a damaged subject leaves the dataset as it was.
  std::vector<std::pair<std::filesystem::path, std::string>> pages;
  DatasetReportSummary summary;
  for (const std::string& s : subjects) {
    const DatasetLayout layout(dataset, s);
    if (std::filesystem::exists(layout.provenance(), error)) {
      pages.emplace_back(subject_report_path(dataset, s),
                         subject_report_html(read_subject_record(dataset, s)));
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
  return summary;
}

} // namespace phantasm
