// Diagnostics of input files: where a problem is (file, line, column), what it is, and their
// formatting for the user.
#pragma once

#include <string>
#include <vector>

namespace phantasm {

/// Where something is in a text file; line and column count from 1 (0 means unknown).
struct SourceLocation {
  std::string file;
  int line = 0;
  int column = 0;
};

/// One problem found in an input file.
struct Diagnostic {
  SourceLocation where;
  std::string key_path; ///< e.g. "sequences[1].TE_ms"; empty for syntax errors
  std::string message;  ///< "expected ..., found ..."

  /// "file:line:column: key.path: expected ..., found ...", the format compilers use, so editors
  /// jump to the place.
  std::string format() const;
};

/// Joins the formatted diagnostics, one per line.
std::string format_diagnostics(const std::vector<Diagnostic>& diagnostics);

} // namespace phantasm
