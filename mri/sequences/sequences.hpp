// The members of the sequence registry, one per file of this folder; mri/sequence_types.cpp
// lists them. Internal to the registry.
#pragma once

#include "mri/sequence_type.hpp"

namespace phantasm {

const SequenceType& spin_echo_sequence();
const SequenceType& spoiled_gre_sequence();
const SequenceType& inversion_recovery_sequence();
const SequenceType& bssfp_sequence();
const SequenceType& mprage_sequence();

} // namespace phantasm
