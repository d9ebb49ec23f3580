#include "report/report_figures.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace phantasm {

// Each viewer: a slider from the reference (0) to the deformed state (100), a flicker between
// them, label contours of the state shown, and one colour overlay at a time.
const char* const k_viewer_script = R"(
document.querySelectorAll('figure.viewer').forEach(function (f) {
  var q = function (c) { return f.querySelector(c); };
  var mix = q('.mix'), flicker = q('.flicker'), contours = q('.contours'), overlay = q('.overlay'), timer = null;
  function show() {
    var t = mix.value / 100, c = contours.checked;
    f.querySelectorAll('.def').forEach(function (e) { e.style.opacity = t; });
    f.querySelectorAll('.ref-c').forEach(function (e) { e.style.opacity = c ? 1 - t : 0; });
    f.querySelectorAll('.def-c').forEach(function (e) { e.style.opacity = c ? t : 0; });
    f.querySelectorAll('.ov').forEach(function (e) { e.style.display = e.dataset.overlay === overlay.value ? 'block' : 'none'; });
  }
  mix.oninput = show; contours.onchange = show; overlay.onchange = show;
  flicker.onchange = function () {
    clearInterval(timer);
    if (flicker.checked) timer = setInterval(function () { mix.value = mix.value > 50 ? 0 : 100; show(); }, 700);
  };
  show();
});
)";

namespace {

/// Lines of relative residuals (each a series, drawn against its index) on a log scale, with
/// the tolerance dashed; a point per value when `points` (red where `failed`).
std::string residual_plot(const std::vector<std::vector<double>>& series, double tolerance,
                          const std::string& x_label, int first, bool points,
                          const std::vector<bool>& failed = {}) {
  const auto log_of = [](double v) { return std::log10(std::max(v, 1e-16)); };
  double lo = log_of(tolerance), hi = lo;
  std::size_t longest = 1;
  for (const std::vector<double>& line : series) {
    longest = std::max(longest, line.size());
    for (const double v : line) {
      lo = std::min(lo, log_of(v));
      hi = std::max(hi, log_of(v));
    }
  }
  lo = std::floor(lo - 0.5);
  hi = std::ceil(hi + 0.5);
  const double w = 640, h = 220, left = 60, bottom = 30;
  const auto x_of = [&](std::size_t k) {
    return left + (longest > 1 ? (w - left - 10) * static_cast<double>(k) / static_cast<double>(longest - 1)
                               : (w - left) / 2);
  };
  const auto y_of = [&](double log_value) { return 10 + (h - bottom - 10) * (hi - log_value) / (hi - lo); };
  std::ostringstream svg;
  svg << "<svg role=\"img\" aria-label=\"relative residual against " << x_label << "\" width=\"" << w
      << "\" height=\"" << h << "\" style=\"background:#fff;border:1px solid #ccc\">";
  for (double decade = lo; decade <= hi; decade += 1.0)
    svg << "<line x1=\"" << left << "\" x2=\"" << w - 10 << "\" y1=\"" << y_of(decade) << "\" y2=\""
        << y_of(decade) << "\" stroke=\"#eee\"/><text x=\"4\" y=\"" << y_of(decade) + 4
        << "\" font-size=\"11\">1e" << decade << "</text>";
  svg << "<line x1=\"" << left << "\" x2=\"" << w - 10 << "\" y1=\"" << y_of(log_of(tolerance)) << "\" y2=\""
      << y_of(log_of(tolerance)) << "\" stroke=\"#c33\" stroke-dasharray=\"4 3\"/>";
  for (const std::vector<double>& line : series) {
    svg << "<polyline fill=\"none\" stroke=\"#236\" stroke-opacity=\"0.7\" points=\"";
    for (std::size_t k = 0; k < line.size(); ++k)
      svg << x_of(k) << "," << y_of(log_of(line[k])) << " ";
    svg << "\"/>";
    for (std::size_t k = 0; points && k < line.size(); ++k)
      svg << "<circle cx=\"" << x_of(k) << "\" cy=\"" << y_of(log_of(line[k])) << "\" r=\"3\" fill=\""
          << (k < failed.size() && failed[k] ? "#c33" : "#236") << "\"/>";
  }
  svg << "<text x=\"" << left << "\" y=\"" << h - 8 << "\" font-size=\"11\">" << x_label << " " << first
      << " .. " << longest - 1 + first << "; dashed: the tolerance</text></svg>";
  return svg.str();
}

/// Each solve's relative residual per iteration (local/global records it), and at the end of
/// each solve when there are several (or no iterations were recorded).
} // namespace

std::string residual_plots(const nlohmann::json& solves, double tolerance) {
  std::vector<std::vector<double>> iterations;
  std::vector<double> ends;
  std::vector<bool> failed;
  for (const nlohmann::json& s : solves) {
    const double scale = s.value("force_scale_N", 0.0);
    if (s.contains("residuals_N") && scale > 0.0) {
      std::vector<double> line;
      for (const nlohmann::json& r : s.at("residuals_N"))
        line.push_back(r.get<double>() / scale);
      iterations.push_back(std::move(line));
    }
    ends.push_back(s.value("relative_residual", 0.0));
    failed.push_back(!s.value("converged", false));
  }
  std::string html;
  if (!iterations.empty())
    html += "<p>Relative residual against iteration, a line per solve (its local/global iterations; a "
            "Newton step that finishes a solve shows in its end value):</p>" +
            residual_plot(iterations, tolerance, "iteration", 0, false);
  if (solves.size() > 1 || iterations.empty())
    html += "<p>Relative residual at the end of each solve (red: not converged):</p>" +
            residual_plot({ends}, tolerance, "solve", 1, true, failed);
  return html;
}

} // namespace phantasm
