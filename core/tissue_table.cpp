#include "core/tissue_table.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace phantasm {
namespace detail {
extern const char* const tissue_table_csv;
}

namespace {

/// Splits CSV text into rows of fields (RFC 4180 quoting: "a, b" and "" for a quote).
std::vector<std::vector<std::string>> split_csv(std::string_view text, const std::string& source) {
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> row;
  std::string field;
  bool quoted = false;
  int line = 1;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (quoted) {
      if (c == '"' && i + 1 < text.size() && text[i + 1] == '"') {
        field += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        if (c == '\n') ++line;
        field += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      row.push_back(std::move(field));
      field.clear();
    } else if (c == '\n' || c == '\r') {
      if (c == '\r' && i + 1 < text.size() && text[i + 1] == '\n') ++i;
      row.push_back(std::move(field));
      field.clear();
      if (!(row.size() == 1 && row[0].empty())) rows.push_back(std::move(row));
      row.clear();
      ++line;
    } else {
      field += c;
    }
  }
  if (quoted) throw InputError(source + ":" + std::to_string(line) + ": unterminated quoted field");
  if (!field.empty() || !row.empty()) {
    row.push_back(std::move(field));
    rows.push_back(std::move(row));
  }
  return rows;
}

std::optional<double> parse_value(const std::string& text, const std::string& where,
                                  const std::string& column) {
  if (text.empty()) return std::nullopt;
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0' || !std::isfinite(value) || value < 0.0) {
    throw InputError(where + ": column " + column +
                     ": expected a non-negative number or an empty "
                     "field, found '" +
                     text + "'");
  }
  return value;
}

} // namespace

const TissueTable& TissueTable::builtin() {
  static const TissueTable table = parse_csv(detail::tissue_table_csv, "core/data/tissues.csv");
  return table;
}

TissueTable TissueTable::parse_csv(std::string_view text, const std::string& source_name) {
  const auto rows = split_csv(text, source_name);
  const std::vector<std::string> expected = {"tissue",        "field_T",   "T1_ms",     "T2_ms",
                                             "T2star_ms",     "PD_rel",    "T1_source", "T2_source",
                                             "T2star_source", "PD_source", "status",    "notes"};
  if (rows.empty() || rows[0] != expected) {
    throw InputError(source_name + ":1: expected the header tissue,field_T,T1_ms,T2_ms,T2star_ms,"
                                   "PD_rel,T1_source,T2_source,T2star_source,PD_source,status,notes");
  }
  TissueTable table;
  for (std::size_t r = 1; r < rows.size(); ++r) {
    const auto& row = rows[r];
    const std::string where = source_name + ": row " + std::to_string(r + 1);
    if (row.size() != expected.size()) {
      throw InputError(where + ": expected " + std::to_string(expected.size()) + " fields, found " +
                       std::to_string(row.size()));
    }
    TissueRecord record;
    record.tissue = row[0];
    if (record.tissue.empty()) throw InputError(where + ": column tissue: expected a name, found ''");
    const auto field = parse_value(row[1], where, "field_T");
    if (!field || *field <= 0.0) throw InputError(where + ": column field_T: expected a positive field");
    record.field_T = *field;
    record.T1_ms = parse_value(row[2], where, "T1_ms");
    record.T2_ms = parse_value(row[3], where, "T2_ms");
    record.T2star_ms = parse_value(row[4], where, "T2star_ms");
    record.PD = parse_value(row[5], where, "PD_rel");
    record.T1_source = row[6];
    record.T2_source = row[7];
    record.T2star_source = row[8];
    record.PD_source = row[9];
    record.status = row[10];
    record.notes = row[11];
    if (table.find(record.tissue, record.field_T) != nullptr) {
      throw InputError(where + ": tissue " + record.tissue + " at " + row[1] + " T appears twice");
    }
    table.m_records.push_back(std::move(record));
  }
  return table;
}

std::vector<std::string> TissueTable::tissue_names() const {
  std::vector<std::string> names;
  for (const auto& record : m_records) {
    if (std::find(names.begin(), names.end(), record.tissue) == names.end()) {
      names.push_back(record.tissue);
    }
  }
  return names;
}

bool TissueTable::has_tissue(const std::string& tissue) const {
  for (const auto& record : m_records) {
    if (record.tissue == tissue) return true;
  }
  return false;
}

const TissueRecord* TissueTable::find(const std::string& tissue, double field_T) const {
  for (const auto& record : m_records) {
    if (record.tissue == tissue && std::abs(record.field_T - field_T) < 1e-6) return &record;
  }
  return nullptr;
}

std::vector<double> TissueTable::field_strengths(const std::string& tissue) const {
  std::vector<double> fields;
  for (const auto& record : m_records) {
    if (record.tissue == tissue) fields.push_back(record.field_T);
  }
  return fields;
}

} // namespace phantasm
