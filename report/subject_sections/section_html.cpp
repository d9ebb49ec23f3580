#include "report/subject_sections/section_html.hpp"

#include "io/json_file.hpp"
#include "report/html_text.hpp"

#include <algorithm>

namespace phantasm::section_html {

std::string text_of(const nlohmann::json& value) {
  return value.is_string() ? value.get<std::string>()
         : value.is_null() ? std::string()
                           : json_text(value, -1);
}

std::string e(const nlohmann::json& value) {
  return html_escape(text_of(value));
}

std::string cell(const std::string& html, bool number) {
  return std::string(number ? "<td class=\"n\">" : "<td>") + html + "</td>";
}

std::string list_html(const nlohmann::json& lines) {
  std::string html = "<ul>";
  for (const nlohmann::json& line : lines)
    html += "<li>" + e(line) + "</li>";
  return html + "</ul>";
}

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

std::string joined(const std::vector<std::string>& parts) {
  std::string text;
  for (std::size_t k = 0; k < parts.size(); ++k)
    text += (k == 0 ? "" : k + 1 == parts.size() ? " and " : ", ") + parts[k];
  return text;
}

} // namespace phantasm::section_html
