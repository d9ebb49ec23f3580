// Writing a JSON file atomically with sorted keys and fixed indentation, so the same content
// always gives the same bytes (sidecars, provenance.json, evaluation reports).
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>

namespace phantasm {

/// Writes JSON with two-space indentation and a final newline, atomically. Keys come out in
/// sorted order, so the same content always gives the same bytes.
void write_json_file(const std::filesystem::path& path, const nlohmann::json& value);

} // namespace phantasm
