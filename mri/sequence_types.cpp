#include "mri/sequence_type.hpp"

#include "core/registry.hpp"

namespace phantasm {

// The members, one per file of mri/sequences/.
const SequenceType& spin_echo_sequence();
const SequenceType& spoiled_gre_sequence();
const SequenceType& inversion_recovery_sequence();
const SequenceType& bssfp_sequence();
const SequenceType& mprage_sequence();

namespace {

const Registry<SequenceType, SequenceKind>& sequence_registry() {
  // The registrations: a new sequence adds its line here and its declaration above
  // (docs/architecture.md, Adding a variant).
  static const Registry<SequenceType, SequenceKind> types("sequence", &SequenceType::kind,
                                                          {&spin_echo_sequence(), &spoiled_gre_sequence(),
                                                           &inversion_recovery_sequence(), &bssfp_sequence(),
                                                           &mprage_sequence()});
  return types;
}

} // namespace

const std::vector<const SequenceType*>& sequence_types() {
  return sequence_registry().members();
}

const SequenceType& sequence_type(SequenceKind kind) {
  return sequence_registry().at(kind);
}

const SequenceType* find_sequence_type(const std::string& name) {
  return sequence_registry().find(name);
}

std::vector<std::string> sequence_type_names() {
  return sequence_registry().names();
}

const char* to_string(SequenceKind kind) {
  return sequence_type(kind).name;
}

} // namespace phantasm
