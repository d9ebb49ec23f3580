// What several sections of the subject report share: JSON values as escaped text, table cells,
// lists, a table of JSON objects, a reader's list. Internal to the report.
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace phantasm::section_html {

/// A JSON value as text: strings as they are, null as "", anything else as compact JSON.
std::string text_of(const nlohmann::json& value);

/// text_of(value), HTML-escaped.
std::string e(const nlohmann::json& value);

/// A table cell of HTML, right-aligned in tabular figures when `number`.
std::string cell(const std::string& html, bool number = false);

/// A bulleted list of the lines (each escaped).
std::string list_html(const nlohmann::json& lines);

/// Rows of JSON objects: each key a column (the union of the keys, in order of first use); the
/// paragraph `empty` when there are none.
std::string objects_table(const nlohmann::json& rows, const char* empty);

/// Parts as a reader's list: "a", "a and b", "a, b and c".
std::string joined(const std::vector<std::string>& parts);

} // namespace phantasm::section_html
