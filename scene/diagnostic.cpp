#include "scene/diagnostic.hpp"

namespace phantasm {

std::string Diagnostic::format() const {
  std::string text = where.file;
  if (where.line > 0) text += ":" + std::to_string(where.line) + ":" + std::to_string(where.column);
  text += ": ";
  if (!key_path.empty()) text += key_path + ": ";
  return text + message;
}

std::string format_diagnostics(const std::vector<Diagnostic>& diagnostics) {
  std::string text;
  for (const auto& d : diagnostics)
    text += d.format() + "\n";
  return text;
}

} // namespace phantasm
