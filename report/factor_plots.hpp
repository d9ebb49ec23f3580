// Plots of a figure against a varied factor of a sweep (SVG), for the dataset page and the
// benchmark page: a point per subject or pair, the mean at each value of the factor joined by a
// line, a colour per series (an organ, a method) with its legend.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace phantasm {

/// The points of one series: the factor's value as participants.tsv writes it, and the figure.
struct PlotSeries {
  std::string name; ///< shown in the legend when a plot has several series
  std::vector<std::pair<std::string, double>> points;
};

/// True when every value of the factor reads as a number: the axis is then numeric (spaced by
/// value); otherwise its values are evenly spaced categories in order of first appearance.
bool factor_is_numeric(const std::vector<std::string>& values);

/// A plot of `y_label` against `factor`: the finite points of every series (non-finite values
/// are left out and counted in the caption), the mean per factor value of each series joined by a
/// line. Every text is HTML-escaped.
/// @return the <svg>, or a paragraph saying that no value was recorded when no point is finite
std::string factor_plot_svg(const std::string& factor, const std::string& y_label,
                            const std::vector<PlotSeries>& series);

} // namespace phantasm
