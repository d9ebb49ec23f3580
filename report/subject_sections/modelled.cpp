// The subject report's section of what was modelled: the grid, organs, materials, loads,
// sequences, what each stage modelled and skipped, and the scene file as run.
#include "report/html_text.hpp"
#include "report/report_section.hpp"
#include "report/subject_record.hpp"
#include "report/subject_sections/section_html.hpp"

namespace phantasm {
namespace modelled_section_member {

using namespace section_html;

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

std::string modelled_section(const SubjectRecord& r) {
  const nlohmann::json& settings = r.provenance.at("settings");
  const nlohmann::json grid = settings.value("grid", nlohmann::json::object());
  std::string html;
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

} // namespace modelled_section_member

const ReportSection& modelled_report_section() {
  static const ReportSection section{ReportSectionKey::modelled, "modelled", "What was modelled",
                                     "the grid, organs, materials, loads and sequences, what each stage "
                                     "modelled and skipped, the scene file",
                                     modelled_section_member::modelled_section};
  return section;
}

} // namespace phantasm
