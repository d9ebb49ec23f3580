// What lies at a path that should be a regular file, for the "found ..." of a message.
#pragma once

#include <filesystem>
#include <string>

namespace phantasm {

/// "no such file", "a folder", "a device node", "a FIFO", "a socket", or "a regular file" (for a
/// path that is one): a reader that wanted a file says what it found instead of "no such file".
inline std::string path_kind(const std::filesystem::path& path) {
  std::error_code error;
  const std::filesystem::file_status status = std::filesystem::status(path, error);
  if (!std::filesystem::exists(status)) return "no such file";
  if (std::filesystem::is_regular_file(status)) return "a regular file";
  if (std::filesystem::is_directory(status)) return "a folder";
  if (std::filesystem::is_character_file(status) || std::filesystem::is_block_file(status))
    return "a device node";
  if (std::filesystem::is_fifo(status)) return "a FIFO";
  if (std::filesystem::is_socket(status)) return "a socket";
  return "something that is not a file";
}

} // namespace phantasm
