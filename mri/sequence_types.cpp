#include "mri/sequence_type.hpp"

#include <stdexcept>

namespace phantasm {

// The members, one per file of mri/sequences/.
const SequenceType& spin_echo_sequence();
const SequenceType& spoiled_gre_sequence();
const SequenceType& inversion_recovery_sequence();
const SequenceType& bssfp_sequence();
const SequenceType& mprage_sequence();

const std::vector<const SequenceType*>& sequence_types() {
  // The registrations: a new sequence adds its line here and its declaration above
  // (docs/architecture.md, Adding a variant).
  static const std::vector<const SequenceType*> types{&spin_echo_sequence(), &spoiled_gre_sequence(),
                                                      &inversion_recovery_sequence(), &bssfp_sequence(),
                                                      &mprage_sequence()};
  return types;
}

const SequenceType& sequence_type(SequenceKind kind) {
  for (const SequenceType* type : sequence_types())
    if (type->kind == kind) return *type;
  throw std::logic_error("a sequence kind without a member of the sequence registry");
}

const SequenceType* find_sequence_type(const std::string& name) {
  for (const SequenceType* type : sequence_types())
    if (name == type->name) return type;
  return nullptr;
}

std::vector<std::string> sequence_type_names() {
  std::vector<std::string> names;
  for (const SequenceType* type : sequence_types())
    names.emplace_back(type->name);
  return names;
}

const char* to_string(SequenceKind kind) {
  return sequence_type(kind).name;
}

} // namespace phantasm
