// What the subject report draws: the script of the viewers of both states (slider, flicker,
// label contours, overlays; report/subject_sections/images.cpp) and the solver's convergence plots
// (SVG).
#pragma once

#include <nlohmann/json.hpp>

#include <string>

namespace phantasm {

/// The script that drives every viewer of the section "Images of both states" (plain JavaScript,
/// no library).
extern const char* const k_viewer_script;

/// The relative residual against iteration, a line per solve (the solves' residuals_N over their
/// force scale), and, with several solves or none recorded per iteration, the value each ended at;
/// SVG on a log scale with the tolerance dashed.
/// @param solves provenance.json's "solves"
/// @param tolerance the relative residual a converged solve reaches
std::string residual_plots(const nlohmann::json& solves, double tolerance);

} // namespace phantasm
