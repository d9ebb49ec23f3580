// A registry of the members of a family of variants (MR sequences, organ shape sources, field
// conventions, solvers): each member is a struct of its own file with a `name` and a key of an
// enum, and the registry is the one list of them. It finds a member by its key or by its name,
// lists the names for help and for "expected one of ..." messages, and refuses two members of
// one name or key when it is built. Adding a member: docs/architecture.md, "Adding a variant".
#pragma once

#include <initializer_list>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace phantasm {

/// The members of one family, in the order of its docs' table.
/// @tparam Member a struct with a key member (an enum) named on construction and, for lookups by
/// name, `const char* name` (the second half of a family, as the shape builds, may go without)
/// @tparam Key the type of that key
template <typename Member, typename Key>
class Registry {
public:
  /// @param family what the members are, for the messages of a broken registry ("sequence")
  /// @param key the member's key (&SequenceType::kind)
  /// @param members one per key and name
  /// @throws std::logic_error for two members of one name or of one key
  Registry(const char* family, Key Member::*key, std::initializer_list<const Member*> members)
      : m_family(family), m_key(key), m_members(members) {
    for (std::size_t i = 0; i < m_members.size(); ++i) {
      for (std::size_t j = 0; j < i; ++j) {
        if constexpr (k_named) {
          if (std::string(m_members[i]->name) == m_members[j]->name)
            throw std::logic_error(std::string("two members of the ") + family + " registry named " +
                                   m_members[i]->name);
        }
        if (m_members[i]->*key == m_members[j]->*key)
          throw std::logic_error(std::string("two members of the ") + family +
                                 " registry of one kind: " + label(j) + " and " + label(i));
      }
    }
  }

  /// Every member, in order.
  const std::vector<const Member*>& members() const { return m_members; }

  /// The member of `key`.
  /// @throws std::logic_error when no member has it (a key added without its member)
  const Member& at(Key key) const {
    for (const Member* member : m_members)
      if (member->*m_key == key) return *member;
    throw std::logic_error(std::string("a ") + m_family + " kind without a member of the " + m_family +
                           " registry");
  }

  /// The member named `name`, or null.
  const Member* find(const std::string& name) const {
    for (const Member* member : m_members)
      if (name == member->name) return member;
    return nullptr;
  }

  /// The members' names, in order.
  std::vector<std::string> names() const {
    std::vector<std::string> names;
    for (const Member* member : m_members)
      names.emplace_back(member->name);
    return names;
  }

  /// The names of the members that `keep` accepts, as a reader's list: "a, b or c" (`last` " or "),
  /// or "a, b, c" (`last` ", ").
  template <typename Keep>
  std::string names_text(Keep&& keep, const char* last = " or ") const {
    std::vector<std::string> kept;
    for (const Member* member : m_members)
      if (keep(*member)) kept.emplace_back(member->name);
    std::string text;
    for (std::size_t i = 0; i < kept.size(); ++i)
      text += (i == 0 ? "" : i + 1 == kept.size() ? last : ", ") + kept[i];
    return text;
  }

  /// Every member's name, as a reader's list (see names_text).
  std::string all_names_text(const char* last = " or ") const {
    return names_text([](const Member&) { return true; }, last);
  }

private:
  template <typename M, typename = void>
  struct named : std::false_type {};
  template <typename M>
  struct named<M, std::void_t<decltype(std::declval<const M&>().name)>> : std::true_type {};
  static constexpr bool k_named = named<Member>::value;

  /// The member at `index` for a message: its name, or its place.
  std::string label(std::size_t index) const {
    if constexpr (k_named)
      return m_members[index]->name;
    else
      return "member " + std::to_string(index + 1);
  }

  const char* m_family;
  Key Member::*m_key;
  std::vector<const Member*> m_members;
};

} // namespace phantasm
