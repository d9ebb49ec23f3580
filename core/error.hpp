// The exceptions phantasm throws on purpose: InputError for a fault in what the user gave (exit
// code 2) and Cancelled for a run asked to stop.
#pragma once

#include <stdexcept>
#include <string>
#include <utility>

namespace phantasm {

/// A problem with what the user gave us (a scene, a mesh, a NIfTI file, a parameter): the
/// message names the file, the line or field, what was expected and what was found.
/// Command-line programs report it without a stack trace and exit with code 2.
class InputError : public std::runtime_error {
public:
  explicit InputError(const std::string& message) : std::runtime_error(message) {}
};

/// A setting a stage cannot carry out, named by its key path in the scene ("deformation.loads[1].organ").
/// Stages know settings, not files: the pipeline, which holds the scene, turns the key path into
/// the file, line and column the user wrote it at (Scene::location_of).
class SettingError : public InputError {
public:
  /// @param key_path the setting's path in the scene, e.g. "deformation.collisions[0].organs"
  /// @param message what was expected and what was found, without the key path
  SettingError(std::string key_path, std::string message)
      : InputError(key_path + ": " + message), m_key_path(std::move(key_path)),
        m_message(std::move(message)) {}

  const std::string& key_path() const { return m_key_path; }
  const std::string& message() const { return m_message; }

private:
  std::string m_key_path;
  std::string m_message;
};

/// The run was asked to stop (SIGINT or SIGTERM) and stopped at a safe point.
class Cancelled : public std::runtime_error {
public:
  Cancelled() : std::runtime_error("cancelled") {}
};

} // namespace phantasm
