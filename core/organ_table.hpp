// The organ table every stage shares: each organ's name, tissue, container and nesting depth,
// built once by the scene parser from the anatomy section.
#pragma once

#include <string>
#include <vector>

namespace phantasm {

/// One organ as every stage sees it: what it is called, what it is made of and where it sits in
/// the nesting.
struct OrganEntry {
  std::string name;
  std::string tissue;
  int parent = -1; ///< index of the containing organ, -1 for an outermost organ
  int depth = 0;   ///< 0 for an outermost organ, 1 for an organ inside it, ...
};

/// An organ as the scene names it: its containing organ by name (empty for an outermost organ).
struct OrganNesting {
  std::string name;
  std::string tissue;
  std::string inside;
};

/// The organs of a scene in scene order, with their nesting resolved once (parents by index,
/// depths), shared by every stage.
class OrganTable {
public:
  OrganTable() = default;

  /// Resolves the nesting. A name under `inside` that no organ has counts as outermost; a cycle
  /// (which the scene's validation rejects) stops the depth at the number of organs.
  explicit OrganTable(const std::vector<OrganNesting>& organs);

  std::size_t size() const { return m_entries.size(); }
  bool empty() const { return m_entries.empty(); }
  const OrganEntry& operator[](std::size_t i) const { return m_entries[i]; }
  std::vector<OrganEntry>::const_iterator begin() const { return m_entries.begin(); }
  std::vector<OrganEntry>::const_iterator end() const { return m_entries.end(); }

  /// The index of the organ of this name, or -1.
  int index_of(const std::string& name) const;

  /// The tissues of the organs, each once, in order of first use.
  std::vector<std::string> tissues() const;

private:
  std::vector<OrganEntry> m_entries;
};

} // namespace phantasm
