// What the fuzz targets share: a private scratch folder for the files the readers take by path,
// and the rule for exceptions. A reader may refuse an input only with the project's own error
// (InputError, which the command turns into a message and exit code 2); any other exception is a
// finding, as are crashes, sanitizer reports, hangs and runaway memory, which libFuzzer reports.
#pragma once

#include "core/error.hpp"

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <string>
#include <typeinfo>

namespace phantasm::fuzz {

/// A folder of this process's own under the system's temporary folder, made on first use and
/// removed at exit (libFuzzer's workers are processes, so each has its own).
const std::filesystem::path& scratch_folder();

/// Writes bytes to a file of the scratch folder (replacing it) and returns its path.
std::filesystem::path write_scratch_file(const std::string& name, const std::uint8_t* data, std::size_t size);

/// Reports an exception other than InputError as a finding: prints what threw and aborts, so
/// that libFuzzer saves the input.
[[noreturn]] void unexpected_exception(const char* what_ran, const std::exception* error);

/// Runs `body`, accepting InputError only.
template <typename Body>
void expect_input_errors_only(const char* what_ran, Body&& body) {
  try {
    body();
  } catch (const InputError&) {
    // A refused input, with a message: what the readers are for.
  } catch (const std::exception& error) {
    unexpected_exception(what_ran, &error);
  } catch (...) {
    unexpected_exception(what_ran, nullptr);
  }
}

/// Aborts with a message when a condition the target checks does not hold.
[[noreturn]] void finding(const std::string& message);

} // namespace phantasm::fuzz
