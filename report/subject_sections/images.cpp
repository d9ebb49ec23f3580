// The subject report's images of both states: the overlays' colour bars, then a viewer per image
// (slider and flicker between the states, label contours, overlays), driven by k_viewer_script
// (report/report_figures.hpp).
#include "report/html_text.hpp"
#include "report/report_section.hpp"
#include "report/slice_pictures.hpp"
#include "report/subject_record.hpp"

#include <algorithm>

namespace phantasm {
namespace images_section_member {

std::string img(const std::string& png, const std::string& cls, const std::string& alt,
                const std::string& extra = {}) {
  return "<img class=\"" + cls + "\" alt=\"" + html_escape(alt) + "\"" + extra + " src=\"" +
         png_data_url(png) + "\">";
}

std::string colour_bars(const SubjectRecord& r) {
  std::string html;
  if (r.displacement)
    html += "<p>Displacement |u| (mm), from-def_to-ref on the reference grid: 0 " +
            img(colour_bar_png(r.displacement->scale), "bar", "colour bar of the displacement") + " " +
            significant(r.displacement->scale.high) + " mm (largest " +
            significant(r.largest_displacement_mm) + " mm; transparent below 2 % of it).</p>";
  if (r.jacobian)
    html += "<p>Jacobian determinant det(I + grad u) (volume ratio, no unit; log scale): " +
            significant(r.jacobian->scale.low) + " " +
            img(colour_bar_png(r.jacobian->scale), "bar", "colour bar of the Jacobian determinant") + " " +
            significant(r.jacobian->scale.high) +
            " (blue: tissue compressed, red: expanded, transparent within 1 % of 1, magenta: 0 or below; "
            "smallest " +
            significant(r.smallest_jacobian) + ").</p>";
  return html;
}

std::string viewer(const SubjectRecord& r, const ImagePictures& image, int width) {
  std::string html =
      "<figure class=\"viewer\"><div class=\"stack\" style=\"width:" + std::to_string(width) + "px\">";
  html += img(image.reference_png, "base", image.name + " reference");
  if (!r.reference_contours_png.empty())
    html += img(r.reference_contours_png, "ref-c", "label contours, reference");
  html += img(image.deformed_png, "def", image.name + " deformed");
  if (!r.deformed_contours_png.empty())
    html += img(r.deformed_contours_png, "def-c", "label contours, deformed");
  if (r.displacement)
    html += img(r.displacement->png, "ov", "displacement magnitude", " data-overlay=\"displacement\"");
  if (r.jacobian) html += img(r.jacobian->png, "ov", "Jacobian determinant", " data-overlay=\"jacobian\"");
  html += "</div><div class=\"controls\">reference <input type=\"range\" class=\"mix\" min=\"0\" max=\"100\" "
          "value=\"0\"> deformed <label><input type=\"checkbox\" class=\"flicker\"> flicker</label> "
          "<label><input type=\"checkbox\" class=\"contours\" checked> label contours</label> "
          "<select class=\"overlay\"><option value=\"\">no overlay</option>";
  if (r.displacement) html += "<option value=\"displacement\">displacement |u| (mm)</option>";
  if (r.jacobian) html += "<option value=\"jacobian\">Jacobian determinant</option>";
  html +=
      "</select></div><figcaption><b>" + html_escape(image.name) +
      "</b>: middle slices, axial (anterior up), coronal and sagittal (superior up); the subject's right on "
      "the right of the axial and coronal slices.</figcaption></figure>\n";
  return html;
}

std::string images_section(const SubjectRecord& r) {
  std::string html;
  if (r.images.empty()) return html + "<p>The run wrote neither images nor labels.</p>\n";
  if (r.reference_only)
    html +=
        "<p>Nothing deforms in this scene: the run wrote the reference state only, shown on both sides.</p>";
  if (r.images.front().name == "dseg") html += "<p>The run made no MR images: the label maps are shown.</p>";
  html += colour_bars(r);
  const int montage_width = r.dims.x() * 2 + r.dims.y();
  const int width = montage_width * std::max(1, 1100 / std::max(1, montage_width));
  for (const ImagePictures& image : r.images)
    html += viewer(r, image, std::min(width, 1100));
  return html;
}

} // namespace images_section_member

const ReportSection& images_report_section() {
  static const ReportSection section{
      ReportSectionKey::images, "images", "Images of both states",
      "middle slices of each image in both states, with label contours and the displacement and Jacobian "
      "overlays",
      images_section_member::images_section};
  return section;
}

} // namespace phantasm
