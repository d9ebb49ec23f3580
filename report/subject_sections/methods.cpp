// The subject report's methods paragraph: how the phantoms were generated, with its references
// (the solver's from its member of the solver registry).
#include "report/html_text.hpp"
#include "report/report_section.hpp"
#include "report/subject_record.hpp"
#include "report/subject_sections/section_html.hpp"
#include "sim/solver_type.hpp"

namespace phantasm {
namespace methods_section_member {

using namespace section_html;

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
    if (const SolverType* type = find_solver_type(solver); type && type->literature.reference) {
      citations.push_back(html_escape(type->literature.reference));
      text += " of " + html_escape(type->literature.method) + " [" + std::to_string(citations.size()) + "]";
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
  std::string html = "<p>" + text + "</p><ol>";
  for (const std::string& c : citations)
    html += "<li>" + c + "</li>";
  return html + "</ol><p>Every setting of the run is in provenance.json beside the subject's files.</p>\n";
}

} // namespace methods_section_member

const ReportSection& methods_report_section() {
  static const ReportSection section{ReportSectionKey::methods, "methods", "Methods",
                                     "a methods paragraph for a paper, with its references",
                                     methods_section_member::methods_section};
  return section;
}

} // namespace phantasm
