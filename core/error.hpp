#pragma once

#include <stdexcept>
#include <string>

namespace phantasm {

/// A problem with what the user gave us (a scene, a mesh, a NIfTI file, a parameter): the
/// message names the file, the line or field, what was expected and what was found.
/// Command-line programs report it without a stack trace and exit with code 2.
class InputError : public std::runtime_error {
public:
  explicit InputError(const std::string& message) : std::runtime_error(message) {}
};

/// The run was asked to stop (SIGINT or SIGTERM) and stopped at a safe point.
class Cancelled : public std::runtime_error {
public:
  Cancelled() : std::runtime_error("cancelled") {}
};

} // namespace phantasm
