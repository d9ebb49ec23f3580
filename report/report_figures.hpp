// The sections of the subject report that draw: the viewers of both states (slider, flicker,
// label contours, overlays with their colour bars) and the solver's convergence plots (SVG).
#pragma once

#include <nlohmann/json.hpp>

#include <string>

namespace phantasm {

struct SubjectRecord;

/// The script that drives every viewer of images_section() (plain JavaScript, no library).
extern const char* const k_viewer_script;

/// "Images of both states": the colour bars, then a viewer per image of the record.
std::string images_section(const SubjectRecord& record);

/// The relative residual against iteration, a line per solve (the solves' residuals_N over their
/// force scale), and, with several solves or none recorded per iteration, the value each ended at;
/// SVG on a log scale with the tolerance dashed.
/// @param solves provenance.json's "solves"
/// @param tolerance the relative residual a converged solve reaches
std::string residual_plots(const nlohmann::json& solves, double tolerance);

} // namespace phantasm
