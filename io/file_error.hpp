// The InputError of a file the io readers refuse.
#pragma once

#include "core/error.hpp"

#include <filesystem>
#include <string>

namespace phantasm {

/// Throws the InputError of a file: "<file>: <message>", the message saying what was expected
/// and what was found.
[[noreturn]] inline void throw_file_error(const std::filesystem::path& file, const std::string& message) {
  throw InputError(file.string() + ": " + message);
}

} // namespace phantasm
