#include "report/factor_plots.hpp"

#include "report/html_text.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <map>
#include <sstream>

namespace phantasm {
namespace {

const char* const k_colours[] = {"#236", "#c33", "#393", "#c80", "#83a", "#088", "#a52", "#555"};

bool parse_number(const std::string& text, double& value) {
  if (text.empty()) return false;
  char* end = nullptr;
  value = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size() && std::isfinite(value);
}

/// Where each factor value lies along the x axis, from 0 (left) to 1 (right), and its order.
struct FactorAxis {
  std::vector<std::string> values; ///< left to right
  std::map<std::string, double> position;
};

FactorAxis factor_axis(const std::vector<PlotSeries>& series) {
  FactorAxis axis;
  for (const PlotSeries& s : series)
    for (const auto& [x, y] : s.points)
      if (std::isfinite(y) && std::find(axis.values.begin(), axis.values.end(), x) == axis.values.end())
        axis.values.push_back(x);
  if (axis.values.empty()) return axis;
  if (factor_is_numeric(axis.values)) {
    std::map<std::string, double> number;
    for (const std::string& v : axis.values)
      parse_number(v, number[v]);
    std::sort(axis.values.begin(), axis.values.end(),
              [&](const std::string& a, const std::string& b) { return number[a] < number[b]; });
    const double low = number[axis.values.front()], high = number[axis.values.back()];
    for (const std::string& v : axis.values)
      axis.position[v] = high > low ? (number[v] - low) / (high - low) : 0.5;
  } else {
    for (std::size_t k = 0; k < axis.values.size(); ++k)
      axis.position[axis.values[k]] =
          axis.values.size() > 1 ? static_cast<double>(k) / static_cast<double>(axis.values.size() - 1) : 0.5;
  }
  return axis;
}

} // namespace

bool factor_is_numeric(const std::vector<std::string>& values) {
  double number = 0.0;
  return std::all_of(values.begin(), values.end(),
                     [&](const std::string& v) { return parse_number(v, number); });
}

std::string factor_plot_svg(const std::string& factor, const std::string& y_label,
                            const std::vector<PlotSeries>& series) {
  const FactorAxis axis = factor_axis(series);
  double low = INFINITY, high = -INFINITY;
  std::size_t left_out = 0;
  for (const PlotSeries& s : series)
    for (const auto& [x, y] : s.points) {
      if (!std::isfinite(y)) {
        ++left_out;
        continue;
      }
      low = std::min(low, y);
      high = std::max(high, y);
    }
  if (axis.values.empty()) return "<p>No value of " + html_escape(y_label) + " was recorded.</p>";
  const double pad = high > low ? 0.08 * (high - low) : std::max(std::abs(high) * 0.1, 1e-6);
  low -= pad;
  high += pad;
  const std::size_t legend_rows = series.size() > 1 ? (series.size() + 2) / 3 : 0;
  const double w = 360, left = 62, right = 14, top = 12,
               bottom = 58 + 12.0 * static_cast<double>(legend_rows);
  const double h = top + 160 + bottom;
  const auto x_of = [&](const std::string& x) {
    return left + 10 + (w - left - right - 20) * axis.position.at(x);
  };
  const auto y_of = [&](double y) { return top + (h - top - bottom) * (high - y) / (high - low); };
  std::ostringstream svg;
  svg << "<svg class=\"plot\" role=\"img\" aria-label=\"" << html_escape(y_label) << " against "
      << html_escape(factor) << "\" width=\"" << w << "\" height=\"" << h
      << "\" style=\"background:#fff;border:1px solid #ccc\">";
  for (const double y : {low + pad, (low + high) / 2, high - pad})
    svg << "<line x1=\"" << left << "\" x2=\"" << w - right << "\" y1=\"" << y_of(y) << "\" y2=\"" << y_of(y)
        << "\" stroke=\"#eee\"/><text x=\"4\" y=\"" << y_of(y) + 4 << "\" font-size=\"11\">" << significant(y)
        << "</text>";
  // The values along x, each at least 44 pixels from the one drawn before it.
  double last_label = -INFINITY;
  for (const std::string& x : axis.values) {
    if (x_of(x) - last_label < 44) continue;
    last_label = x_of(x);
    svg << "<text x=\"" << x_of(x) << "\" y=\"" << h - bottom + 14
        << "\" font-size=\"11\" text-anchor=\"middle\">" << html_escape(x.substr(0, 8)) << "</text>";
  }
  for (std::size_t s = 0; s < series.size(); ++s) {
    const char* colour = k_colours[s % (sizeof k_colours / sizeof *k_colours)];
    std::map<std::string, std::pair<double, int>> sums;
    for (const auto& [x, y] : series[s].points) {
      if (!std::isfinite(y)) continue;
      sums[x].first += y;
      ++sums[x].second;
      svg << "<circle cx=\"" << x_of(x) << "\" cy=\"" << y_of(y) << "\" r=\"3\" fill=\"" << colour
          << "\" fill-opacity=\"0.75\"><title>" << html_escape(series[s].name) << " " << html_escape(x)
          << ": " << significant(y, 4) << "</title></circle>";
    }
    svg << "<polyline fill=\"none\" stroke=\"" << colour << "\" points=\"";
    for (const std::string& x : axis.values)
      if (const auto found = sums.find(x); found != sums.end())
        svg << x_of(x) << "," << y_of(found->second.first / found->second.second) << " ";
    svg << "\"/>";
    if (series.size() > 1)
      svg << "<text x=\"" << left + 4 + static_cast<double>(s % 3) * 98 << "\" y=\""
          << h - bottom + 56 + static_cast<double>(s / 3) * 12 << "\" font-size=\"11\" fill=\"" << colour
          << "\">&#9679; " << html_escape(series[s].name.substr(0, 16)) << "</text>";
  }
  svg << "<text x=\"" << left << "\" y=\"" << h - bottom + 30 << "\" font-size=\"11\">"
      << html_escape(y_label) << "</text><text x=\"" << left << "\" y=\"" << h - bottom + 42
      << "\" font-size=\"11\">against " << html_escape(factor)
      << (left_out ? "; " + std::to_string(left_out) + " without a value" : "") << "</text></svg>";
  return svg.str();
}

} // namespace phantasm
