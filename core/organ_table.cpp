#include "core/organ_table.hpp"

#include <algorithm>

namespace phantasm {

OrganTable::OrganTable(const std::vector<OrganNesting>& organs) {
  m_entries.reserve(organs.size());
  for (const OrganNesting& organ : organs)
    m_entries.push_back({organ.name, organ.tissue, -1, 0});
  for (std::size_t i = 0; i < organs.size(); ++i) {
    if (!organs[i].inside.empty()) m_entries[i].parent = index_of(organs[i].inside);
  }
  const int bound = static_cast<int>(m_entries.size());
  for (OrganEntry& entry : m_entries) {
    // Validation guarantees the nesting has no cycles; the bound is a second guard.
    for (int j = entry.parent; j >= 0 && entry.depth <= bound;
         j = m_entries[static_cast<std::size_t>(j)].parent)
      ++entry.depth;
  }
}

int OrganTable::index_of(const std::string& name) const {
  for (std::size_t i = 0; i < m_entries.size(); ++i) {
    if (m_entries[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

std::vector<std::string> OrganTable::tissues() const {
  std::vector<std::string> tissues;
  for (const OrganEntry& entry : m_entries) {
    if (std::find(tissues.begin(), tissues.end(), entry.tissue) == tissues.end())
      tissues.push_back(entry.tissue);
  }
  return tissues;
}

} // namespace phantasm
