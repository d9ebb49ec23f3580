#include "sim/load_type.hpp"

#include "core/registry.hpp"

namespace phantasm {

// The members, one per file of sim/load_types/.
const LoadType& gravity_load_type();
const LoadType& displacement_load_type();
const LoadType& growth_load_type();

namespace {

const Registry<LoadType, LoadKind>& load_registry() {
  // The registrations: a new load type adds its line here and its declaration above, and how it
  // acts on the model in sim/loads.cpp (docs/architecture.md, Adding a variant).
  static const Registry<LoadType, LoadKind> types(
      "load", &LoadType::kind, {&gravity_load_type(), &displacement_load_type(), &growth_load_type()});
  return types;
}

} // namespace

const std::vector<const LoadType*>& load_types() {
  return load_registry().members();
}

const LoadType& load_type(LoadKind kind) {
  return load_registry().at(kind);
}

const LoadType* find_load_type(const std::string& name) {
  return load_registry().find(name);
}

std::vector<std::string> load_type_names() {
  return load_registry().names();
}

const char* to_string(LoadKind kind) {
  return load_type(kind).name;
}

} // namespace phantasm
