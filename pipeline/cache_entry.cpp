#include "pipeline/cache_entry.hpp"

#include "core/cancellation.hpp"
#include "core/error.hpp"

#include <cerrno>
#include <chrono>
#include <cstring>
#include <fcntl.h>
#include <fstream>
#include <sstream>
#include <sys/file.h>
#include <thread>
#include <unistd.h>

namespace phantasm {

CacheKeyLock::CacheKeyLock(const std::filesystem::path& path, const std::string& what) {
  m_fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (m_fd < 0)
    throw InputError(path.string() + ": cannot open the " + what + "'s lock file: " + std::strerror(errno));
  while (::flock(m_fd, LOCK_EX | LOCK_NB) != 0) {
    if (errno != EWOULDBLOCK && errno != EINTR) break; // no flock on this filesystem: unlocked
    try {
      throw_if_cancelled();
    } catch (...) {
      ::close(m_fd);
      throw;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
}

CacheKeyLock::~CacheKeyLock() {
  if (m_fd >= 0) ::close(m_fd);
}

std::string read_cache_entry(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::error_code error;
  const auto size = std::filesystem::file_size(path, error);
  if (!in || error) return {};
  std::string bytes(static_cast<std::size_t>(size), '\0');
  in.read(bytes.data(), static_cast<std::streamsize>(size));
  bytes.resize(static_cast<std::size_t>(in.gcount()));
  return bytes;
}

} // namespace phantasm
