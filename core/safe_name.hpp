// The one rule for every name a scene or sweep gives that can reach a file name (organ, tissue,
// material, subject, sequence, scene and sweep names): ASCII letters, digits, '_' and '-', 1 to
// 64 characters. What may become part of a path is decided here, in one place (docs/scene-format.md,
// names); io/output_path.hpp joins such names to the output folder.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace phantasm {

/// The longest name a scene may give (a file name holds several of them plus a prefix).
inline constexpr std::size_t k_max_name_length = 64;

/// What a name may hold, for messages: "a name of 1 to 64 letters, digits, '_' or '-'".
inline constexpr const char* k_safe_name_rule = "a name of 1 to 64 ASCII letters, digits, '_' or '-'";

/// True when `text` obeys the name rule (see k_safe_name_rule).
inline bool is_safe_name(std::string_view text) {
  if (text.empty() || text.size() > k_max_name_length) return false;
  for (const char c : text) {
    const bool letter = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z');
    const bool digit = c >= '0' && c <= '9';
    if (!letter && !digit && c != '_' && c != '-') return false;
  }
  return true;
}

/// A name quoted for a message with control characters and non-ASCII bytes shown as \xNN, so a
/// tab, a newline or a NUL in a name is visible and cannot break the one-line message.
inline std::string quote_name(std::string_view text) {
  static const char* hex = "0123456789abcdef";
  std::string out = "'";
  std::size_t shown = 0;
  for (const char c : text) {
    if (++shown > 200) {
      out += "...";
      break;
    }
    const auto byte = static_cast<unsigned char>(c);
    if (byte < 0x20 || byte >= 0x7f || c == '\'' || c == '\\') {
      out += "\\x";
      out += hex[byte >> 4];
      out += hex[byte & 15];
    } else {
      out += c;
    }
  }
  return out + "'";
}

} // namespace phantasm
