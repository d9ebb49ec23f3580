#include "io/json_file.hpp"

#include "core/error.hpp"
#include "core/format.hpp"
#include "io/atomic_file.hpp"

#include <algorithm>
#include <fstream>
#include <sstream>

namespace phantasm {

std::string json_text(const nlohmann::json& value, int indent) {
  return value.dump(indent, ' ', false, nlohmann::json::error_handler_t::replace);
}

void write_json_file(const std::filesystem::path& path, const nlohmann::json& value) {
  write_file_atomically(path, json_text(value) + "\n");
}

nlohmann::json parse_json_text(const std::string& text, const std::filesystem::path& file,
                               std::string_view expected) {
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& error) {
    // The library's message ("[json.exception.parse_error.101] parse error at line 2, column 1:
    // syntax error while parsing value - ...") names neither the file nor what belongs there.
    // error.byte is the 1-based offset of the byte it stopped at.
    std::size_t at = std::min<std::size_t>(error.byte == 0 ? 0 : error.byte - 1, text.size());
    // A multi-byte character cut short is found at the byte after it: name its first byte.
    const auto byte_at = [&](std::size_t b) { return static_cast<unsigned char>(text[b]); };
    if (at < text.size() && byte_at(at) < 0x80) {
      std::size_t lead = at;
      while (lead > 0 && byte_at(lead - 1) >= 0x80 && byte_at(lead - 1) < 0xc0 && at - lead < 3)
        --lead;
      if (lead > 0 && byte_at(lead - 1) >= 0xc0) at = lead - 1;
    }
    std::size_t line = 1, column = 1;
    for (std::size_t b = 0; b < at; ++b) {
      if (text[b] == '\n') {
        ++line;
        column = 1;
      } else {
        ++column;
      }
    }
    std::string found;
    if (text.find_first_not_of(" \t\r\n") == std::string::npos) {
      found = "an empty file";
    } else if (at >= text.size()) {
      found = "the end of the file before the JSON ends (a file cut short?)";
    } else {
      const auto byte = static_cast<unsigned char>(text[at]);
      std::string shown;
      if (byte >= 0x20 && byte < 0x7f) {
        shown = "'" + std::string(1, text[at]) + "'";
      } else {
        shown = format_byte(byte);
      }
      found = shown + (byte >= 0x80 ? ", which is not UTF-8 text" : ", which cannot stand there in JSON");
    }
    throw InputError(file.string() + ":" + std::to_string(line) + ":" + std::to_string(column) +
                     ": expected " + std::string(expected) + ", found " + found);
  }
}

nlohmann::json read_json_file(const std::filesystem::path& path, std::string_view expected) {
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw InputError(path.string() + ": expected " + std::string(expected) + ", found no readable file");
  std::ostringstream text;
  text << in.rdbuf();
  return parse_json_text(text.str(), path, expected);
}

} // namespace phantasm
