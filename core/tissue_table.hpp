// The tissue parameter table: relaxation times and proton density per tissue and field
// strength, each with its source; the scene's checks and the MR stage read it.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace phantasm {

/// Relaxation and proton-density values of one tissue at one field strength, with the source of
/// each value. A value the literature did not provide is empty; a scene must then supply it.
struct TissueRecord {
  std::string tissue;              ///< e.g. "white_matter"
  double field_T = 0.0;            ///< main field strength in tesla
  std::optional<double> T1_ms;     ///< longitudinal relaxation time in ms
  std::optional<double> T2_ms;     ///< transverse relaxation time in ms
  std::optional<double> T2star_ms; ///< effective transverse relaxation time in ms
  std::optional<double> PD;        ///< proton density relative to CSF (= 1)
  std::string T1_source, T2_source, T2star_source, PD_source;
  std::string status; ///< how the sources were checked (read / secondary / simulator / proxy)
  std::string notes;
};

/// The tissue parameter table: one record per tissue and field strength.
class TissueTable {
public:
  /// The table shipped with phantasm (core/data/tissues.csv).
  static const TissueTable& builtin();

  /// Parses a table in the CSV layout of core/data/tissues.csv.
  /// @param source_name file name used in error messages
  /// @throws InputError naming the line and column of a malformed row
  static TissueTable parse_csv(std::string_view text, const std::string& source_name);

  /// Every distinct tissue name, in table order.
  std::vector<std::string> tissue_names() const;
  bool has_tissue(const std::string& tissue) const;
  /// The record for a tissue at a field strength (matched within 1e-6 T), or nullptr.
  const TissueRecord* find(const std::string& tissue, double field_T) const;
  /// The field strengths (T) for which the table has a record of this tissue.
  std::vector<double> field_strengths(const std::string& tissue) const;
  const std::vector<TissueRecord>& records() const { return m_records; }

private:
  std::vector<TissueRecord> m_records;
};

} // namespace phantasm
