// The MR parameters of every tissue a scene uses at its field strength, scene values first and
// then the built-in tissue table, each with where it came from.
#pragma once

#include "core/organ_table.hpp"
#include "mri/mri_settings.hpp"
#include "mri/sequence_type.hpp"

#include <map>
#include <optional>
#include <string>

namespace phantasm {

/// The MR parameters of one tissue as used for a scene, with where each value came from.
struct TissueParameters {
  std::string tissue;
  std::optional<double> T1_ms, T2_ms, T2star_ms, PD;
  std::string T1_source, T2_source, T2star_source, PD_source; ///< "scene" or the table's source
};

/// The parameters of every tissue the organs and the tissue regions use, at the settings' field
/// strength: the scene's
/// tissue values first, then the built-in table. Values neither provides stay empty (the scene's
/// validation has already made sure that its sequences need none of those).
/// @param settings field strength and the scene's tissue values
/// @param organs the organ table (its tissues)
std::map<std::string, TissueParameters> resolve_tissue_parameters(const MriSettings& settings,
                                                                  const OrganTable& organs);

/// A tissue's relaxation for the signal equations. The scene's validation made sure every value a
/// sequence needs is there; the others, empty, read PD 0, T1 1 ms, T2 0 and T2* as T2.
Relaxation relaxation_of(const TissueParameters& parameters);

} // namespace phantasm
