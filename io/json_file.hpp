// Writing a JSON file atomically with sorted keys and fixed indentation, so the same content
// always gives the same bytes (sidecars, provenance.json, evaluation reports); reading one back
// with a message that names the file and the line and column of a syntax error.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <string_view>

namespace phantasm {

/// JSON text with two-space indentation (or `indent`), keys in sorted order. Text that is not
/// UTF-8 (a path as the file system gave it, "b\xff.yaml") is written with U+FFFD in place of the
/// bytes that are not, where nlohmann's dump() would throw after a whole run.
std::string json_text(const nlohmann::json& value, int indent = 2);

/// Writes JSON with two-space indentation and a final newline, atomically. Keys come out in
/// sorted order, so the same content always gives the same bytes.
void write_json_file(const std::filesystem::path& path, const nlohmann::json& value);

/// Parses the JSON text of a file.
/// @param text the file's bytes
/// @param file named in the message
/// @param expected what the file should hold, e.g. "the JSON phantasm writes in provenance.json"
/// @throws InputError "<file>:<line>:<column>: expected <expected>, found ..." for text that is
/// not JSON (a syntax error, a file cut short, bytes that are not UTF-8)
nlohmann::json parse_json_text(const std::string& text, const std::filesystem::path& file,
                               std::string_view expected);

/// Reads a JSON file and parses it as parse_json_text does.
/// @throws InputError naming the file when it cannot be read, or as parse_json_text
nlohmann::json read_json_file(const std::filesystem::path& path, std::string_view expected);

} // namespace phantasm
