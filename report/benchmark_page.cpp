#include "report/benchmark_page.hpp"

#include "core/error.hpp"
#include "io/json_file.hpp"
#include "report/factor_plots.hpp"
#include "report/html_text.hpp"
#include "report/subject_record.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

namespace phantasm {
namespace {

/// A number of the scores (a member path like {"tre_mm", "mean"}); NaN when null or absent.
double score(const nlohmann::json& object, const std::vector<const char*>& path) {
  const nlohmann::json* at = &object;
  for (const char* key : path) {
    if (!at->is_object() || !at->contains(key)) return std::nan("");
    at = &(*at)[key];
  }
  return at->is_number() ? at->get<double>() : std::nan("");
}

std::string number_cell(double value, int digits = 3) {
  return "<td class=\"n\">" + (std::isfinite(value) ? significant(value, digits) : std::string("&ndash;")) +
         "</td>";
}

std::string json_as_text(const nlohmann::json& value) {
  return value.is_string() ? value.get<std::string>()
         : value.is_null() ? std::string()
                           : json_text(value, -1);
}

/// A figure of a pair, as the page plots it against each factor.
/// A figure of each pair plotted against the factors: its label and its member path in the scores.
struct PairFigure {
  const char* label;
  std::vector<const char*> path;
};

const std::vector<PairFigure>& pair_figures() {
  static const std::vector<PairFigure> figures = {
      {"mean Dice", {"mean_dice"}},
      {"mean HD95 (mm)", {"mean_hd95_mm"}},
      {"mean TRE (mm)", {"tre_mm", "mean"}},
      {"mean TRE on the dense landmarks (mm)", {"dense_tre_mm", "mean"}},
      {"mean endpoint error (mm)", {"endpoint_error_mm", "mean"}},
      {"NDV (% of the cubes)", {"ndv", "percent"}},
      {"folding fraction (central differences)", {"jacobian_central_differences", "folding_fraction"}},
  };
  return figures;
}

std::string summary_table(const std::vector<MethodScores>& methods) {
  std::string html = "<table><tr><th>method</th><th>pairs</th><th>mean Dice</th><th>Dice, 30th percentile "
                     "(robustness)</th><th>mean HD95 (mm)</th><th>mean TRE (mm)</th><th>mean dense TRE "
                     "(mm)</th><th>mean endpoint error (mm)</th><th>mean NDV (%)</th><th>mean SD of log det "
                     "J</th><th>warnings</th></tr>\n";
  for (const MethodScores& m : methods) {
    const nlohmann::json& s = m.scores.at("summary");
    html += "<tr><td>" + html_escape(m.method) + "</td>" + number_cell(score(s, {"pairs"}), 6) +
            number_cell(score(s, {"mean_dice"}), 4) + number_cell(score(s, {"dice_p30"}), 4) +
            number_cell(score(s, {"mean_hd95_mm"})) + number_cell(score(s, {"mean_tre_mm"})) +
            number_cell(score(s, {"mean_dense_tre_mm"})) + number_cell(score(s, {"mean_endpoint_error_mm"})) +
            number_cell(score(s, {"mean_ndv_percent"})) + number_cell(score(s, {"mean_log_jacobian_sd"})) +
            "<td class=\"n\">" + std::to_string(m.scores.value("warnings", nlohmann::json::array()).size()) +
            "</td></tr>\n";
  }
  return html + "</table>\n";
}

std::string scores_warnings_section(const std::vector<MethodScores>& methods) {
  std::string html = "<h2 id=\"warnings\">Warnings</h2>\n";
  std::string items;
  for (const MethodScores& m : methods)
    for (const nlohmann::json& w : m.scores.value("warnings", nlohmann::json::array()))
      items += "<li><b>" + html_escape(m.method) + "</b>: " + html_escape(json_as_text(w)) + "</li>";
  if (items.empty()) return html + "<p class=\"ok\">No result looks like a field read the wrong way.</p>\n";
  return html + "<div class=\"warn\"><ul>" + items + "</ul></div>\n";
}

/// The varied factors of every method's pairs, in order of first appearance.
std::vector<std::string> factors_of(const std::vector<MethodScores>& methods) {
  std::vector<std::string> factors;
  for (const MethodScores& m : methods)
    for (const nlohmann::json& pair : m.scores.at("pairs")) {
      const nlohmann::json pair_factors = pair.value("factors", nlohmann::json::object());
      for (const auto& [factor, value] : pair_factors.items())
        if (std::find(factors.begin(), factors.end(), factor) == factors.end()) factors.push_back(factor);
    }
  return factors;
}

std::string factor_plots(const std::vector<MethodScores>& methods) {
  std::string html = "<h2 id=\"factors\">Scores against the varied factors</h2>\n";
  const std::vector<std::string> factors = factors_of(methods);
  if (factors.empty()) return html + "<p>The task's dataset varies no factor.</p>\n";
  for (const std::string& factor : factors) {
    html += "<h3>Against " + html_escape(factor) + "</h3><div class=\"plots\">";
    for (const PairFigure& figure : pair_figures()) {
      std::vector<PlotSeries> series;
      for (const MethodScores& m : methods) {
        PlotSeries line{m.method, {}};
        for (const nlohmann::json& pair : m.scores.at("pairs")) {
          const nlohmann::json factors_of_pair = pair.value("factors", nlohmann::json::object());
          if (factors_of_pair.contains(factor))
            line.points.emplace_back(json_as_text(factors_of_pair[factor]), score(pair, figure.path));
        }
        series.push_back(std::move(line));
      }
      html += factor_plot_svg(factor, figure.label, series);
    }
    html += "</div>\n";
  }
  return html +
         "<p>Each point is a pair, each line joins a method's means at each value of the factor.</p>\n";
}

std::string structures_table(const std::vector<MethodScores>& methods) {
  std::vector<std::vector<StructureScore>> per_method;
  std::vector<std::string> names;
  for (const MethodScores& m : methods) {
    per_method.push_back(structure_scores(m.scores));
    for (const StructureScore& s : per_method.back())
      if (std::find(names.begin(), names.end(), s.name) == names.end()) names.push_back(s.name);
  }
  std::string html = "<h2 id=\"structures\">Per structure</h2>\n<table><tr><th>structure</th>";
  for (const MethodScores& m : methods)
    html += "<th>" + html_escape(m.method) + ": mean Dice</th><th>lowest Dice</th><th>mean HD95 (mm)</th>";
  html += "</tr>\n";
  for (const std::string& name : names) {
    html += "<tr><td>" + html_escape(name) + "</td>";
    for (const std::vector<StructureScore>& scores : per_method) {
      const auto found =
          std::find_if(scores.begin(), scores.end(), [&](const StructureScore& s) { return s.name == name; });
      if (found == scores.end())
        html += "<td></td><td></td><td></td>";
      else
        html += number_cell(found->mean_dice, 4) + number_cell(found->lowest_dice, 4) +
                number_cell(found->mean_hd95_mm);
    }
    html += "</tr>\n";
  }
  return html + "</table>\n";
}

std::string pairs_table(const MethodScores& m, const std::vector<std::string>& factors) {
  std::string html =
      "<h3>" + html_escape(m.method) + "</h3><table><tr><th>case</th><th>subject</th><th>result</th>";
  for (const std::string& factor : factors)
    html += "<th>" + html_escape(factor) + "</th>";
  html += "<th>mean Dice</th><th>mean HD95 (mm)</th><th>TRE (mm)</th><th>dense TRE (mm)</th><th>endpoint "
          "error (mm)</th><th>endpoint "
          "error p95 (mm)</th><th>NDV (%)</th><th>folding fraction</th><th>SD of log det "
          "J</th><th>warnings</th></tr>\n";
  for (const nlohmann::json& p : m.scores.at("pairs")) {
    const nlohmann::json pair_factors = p.value("factors", nlohmann::json::object());
    html += "<tr><td class=\"n\">" + html_escape(json_as_text(p.value("case", nlohmann::json()))) +
            "</td><td>" + html_escape(json_as_text(p.value("subject", nlohmann::json()))) + "</td><td>" +
            html_escape(json_as_text(p.value("result", nlohmann::json()))) + "</td>";
    for (const std::string& factor : factors)
      html += "<td>" +
              (pair_factors.contains(factor) ? html_escape(json_as_text(pair_factors[factor])) : "") +
              "</td>";
    html += number_cell(score(p, {"mean_dice"}), 4) + number_cell(score(p, {"mean_hd95_mm"})) +
            number_cell(score(p, {"tre_mm", "mean"})) + number_cell(score(p, {"dense_tre_mm", "mean"})) +
            number_cell(score(p, {"endpoint_error_mm", "mean"})) +
            number_cell(score(p, {"endpoint_error_mm", "p95"})) + number_cell(score(p, {"ndv", "percent"})) +
            number_cell(score(p, {"jacobian_central_differences", "folding_fraction"})) +
            number_cell(score(p, {"jacobian_central_differences", "log_jacobian_sd"})) + "<td class=\"n\">" +
            std::to_string(p.value("warnings", nlohmann::json::array()).size()) + "</td></tr>\n";
  }
  return html + "</table>\n";
}

/// Refuses scores without what `phantasm eval` writes.
void require_scores(const MethodScores& m, const std::string& where) {
  const nlohmann::json& s = m.scores;
  if (!s.is_object() || !s.contains("pairs") || !s["pairs"].is_array() || !s.contains("summary") ||
      !s["summary"].is_object() || !s.contains("task") || !s["task"].is_string())
    throw InputError(where +
                     ": expected the scores phantasm eval TASK --results DIR writes ('task', 'pairs', "
                     "'summary'), found " +
                     (s.is_object() ? std::string("an object without them") : "no object"));
  for (const nlohmann::json& pair : s["pairs"])
    if (!pair.is_object())
      throw InputError(where + ": expected each of 'pairs' an object, found " +
                       json_text(pair, -1).substr(0, 60));
}

} // namespace

std::string method_name(const nlohmann::json& scores) {
  std::filesystem::path results(scores.is_object() ? scores.value("results", "") : "");
  while (!results.empty() && results.filename().empty())
    results = results.parent_path();
  return results.empty() ? "results" : results.filename().string();
}

std::vector<StructureScore> structure_scores(const nlohmann::json& scores) {
  std::vector<StructureScore> out;
  std::map<std::string, std::array<double, 3>> sums; // Dice sum, HD95 sum, HD95 count
  for (const nlohmann::json& pair : scores.at("pairs"))
    for (const nlohmann::json& label : pair.value("labels", nlohmann::json::array())) {
      const std::string name = json_as_text(label.value("name", nlohmann::json()));
      auto found =
          std::find_if(out.begin(), out.end(), [&](const StructureScore& s) { return s.name == name; });
      if (found == out.end()) found = out.insert(out.end(), StructureScore{name, 0, 0.0, INFINITY, 0.0});
      const double dice = score(label, {"dice"}), hd95 = score(label, {"hd95_mm"});
      ++found->pairs;
      sums[name][0] += std::isfinite(dice) ? dice : 0.0;
      found->lowest_dice = std::min(found->lowest_dice, std::isfinite(dice) ? dice : INFINITY);
      if (std::isfinite(hd95)) {
        sums[name][1] += hd95;
        sums[name][2] += 1.0;
      }
    }
  for (StructureScore& s : out) {
    s.mean_dice = sums[s.name][0] / static_cast<double>(s.pairs);
    s.mean_hd95_mm = sums[s.name][2] > 0 ? sums[s.name][1] / sums[s.name][2] : std::nan("");
    if (!std::isfinite(s.lowest_dice)) s.lowest_dice = std::nan("");
  }
  return out;
}

std::string benchmark_page_html(const std::vector<MethodScores>& methods) {
  if (methods.empty())
    throw InputError("the benchmark page: expected the scores of one method at least, found none");
  for (const MethodScores& m : methods)
    require_scores(m, "the scores of " + m.method);
  const std::string task = methods.front().scores["task"].get<std::string>();
  std::string body =
      "<p>Task <b>" + html_escape(task) + "</b>, " + std::to_string(methods.size()) +
      (methods.size() == 1 ? " method" : " methods") +
      ", each scored by <code>phantasm eval TASK --results DIR</code> against the exact ground "
      "truth.</p>\n";
  body += "<h2 id=\"summary\">Summary</h2>\n" + summary_table(methods) +
          "<p>The robustness figure is the 30th percentile of the pairs' mean Dice, as LUMIR reports it: the "
          "Dice that 70 % of the pairs reach.</p>\n";
  body += scores_warnings_section(methods) + factor_plots(methods) + structures_table(methods);
  body += "<h2 id=\"pairs\">Per pair</h2>\n";
  const std::vector<std::string> factors = factors_of(methods);
  for (const MethodScores& m : methods)
    body += pairs_table(m, factors);
  if (const nlohmann::json conventions =
          methods.front().scores.value("conventions", nlohmann::json::object());
      conventions.is_object() && !conventions.empty()) {
    body += "<h2 id=\"conventions\">What each score means</h2><ul>";
    for (const auto& [name, text] : conventions.items())
      body += "<li><b>" + html_escape(name) + "</b>: " + html_escape(json_as_text(text)) + "</li>";
    body += "</ul>\n";
  }
  return table_page_html("phantasm benchmark: " + html_escape(task), body);
}

std::vector<MethodScores> read_method_scores(const std::vector<std::filesystem::path>& files) {
  std::vector<MethodScores> methods;
  for (const std::filesystem::path& file : files) {
    MethodScores m;
    m.scores = parse_json_text(read_dataset_text(file, "the scores phantasm eval writes"), file,
                               "the scores phantasm eval writes");
    require_scores(m, file.string());
    m.method = method_name(m.scores);
    const std::string task = m.scores["task"].get<std::string>();
    if (!methods.empty() && task != methods.front().scores["task"].get<std::string>())
      throw InputError(file.string() + ": expected scores of the task " +
                       methods.front().scores["task"].get<std::string>() + " (as " + files.front().string() +
                       "), found the task " + task);
    // Two results folders of the same name: told apart by their scores file.
    for (const MethodScores& other : methods)
      if (other.method == m.method) m.method += " (" + file.filename().string() + ")";
    methods.push_back(std::move(m));
  }
  return methods;
}

} // namespace phantasm
