#include "io/output_path.hpp"

#include "core/error.hpp"
#include "core/safe_name.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <string>

namespace phantasm {

std::filesystem::path output_file(const std::filesystem::path& folder, std::string_view name) {
  const char* problem = nullptr;
  if (name.empty()) {
    problem = "an empty name";
  } else if (name == "." || name == "..") {
    problem = "a name that is '.' or '..'";
  } else if (name.front() == '/') {
    problem = "an absolute path";
  } else {
    for (const char c : name) {
      const auto byte = static_cast<unsigned char>(c);
      if (c == '/' || c == '\\') {
        problem = "a path separator";
        break;
      }
      if (byte < 0x20 || byte == 0x7f) {
        problem = "a control character (tab, newline, NUL, ...)";
        break;
      }
    }
  }
  if (problem) {
    throw InputError(folder.string() + ": expected a file name that stays inside the output folder, found " +
                     problem + " in " + quote_name(name));
  }
  return folder / std::string(name);
}

void require_inside(const std::filesystem::path& root, const std::filesystem::path& path) {
  const std::filesystem::path base = root.lexically_normal();
  const std::filesystem::path relative = path.lexically_normal().lexically_relative(base);
  const bool inside = !relative.empty() && *relative.begin() != "..";
  if (!inside || path.lexically_normal().is_absolute() != base.is_absolute()) {
    throw InputError(path.string() + ": expected a path inside the output folder " + root.string() +
                     ", found one outside it");
  }
}

void require_replaceable_file(const std::filesystem::path& path, std::string_view what) {
  struct stat info {};
  if (::stat(path.c_str(), &info) != 0) return; // missing (or unreadable: opening will say)
  if (S_ISREG(info.st_mode)) return;
  const char* kind = S_ISDIR(info.st_mode)                            ? "a folder"
                     : S_ISCHR(info.st_mode) || S_ISBLK(info.st_mode) ? "a device node"
                     : S_ISFIFO(info.st_mode)                         ? "a FIFO"
                     : S_ISSOCK(info.st_mode)                         ? "a socket"
                                                                      : "something that is not a file";
  throw InputError(std::string(what) + ": " + path.string() +
                   ": expected a new file or a regular file to replace, found " + kind);
}

OutputFolderLock::OutputFolderLock(const std::filesystem::path& folder) {
  std::error_code error;
  if (std::filesystem::exists(folder, error) && !std::filesystem::is_directory(folder, error))
    throw InputError(folder.string() + ": expected an output folder, found a file");
  std::filesystem::create_directories(folder, error);
  if (error) throw InputError(folder.string() + ": cannot create the output folder: " + error.message());
  m_path = folder / k_output_lock_name;
  // The holder removes the lock file when it ends: a lock taken on a file already unlinked (or
  // replaced) meanwhile is no lock, so take it again on the file now under the name.
  for (int attempt = 0; attempt < 100; ++attempt) {
    if (try_lock(folder)) return;
  }
  throw InputError(folder.string() + ": cannot lock the output folder: its lock file keeps changing");
}

bool OutputFolderLock::try_lock(const std::filesystem::path& folder) {
  const std::filesystem::path& lock = m_path;
  m_fd = ::open(lock.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (m_fd < 0) {
    throw InputError(folder.string() + ": cannot create the lock file " + lock.filename().string() + ": " +
                     std::strerror(errno));
  }
  if (::flock(m_fd, LOCK_EX | LOCK_NB) != 0) {
    const int cause = errno;
    std::string holder;
    char text[32] = {};
    if (::pread(m_fd, text, sizeof(text) - 1, 0) > 0) holder = std::string(" (pid ") + text + ")";
    while (!holder.empty() && (holder.back() == '\n' || holder.back() == ')'))
      holder.pop_back();
    if (!holder.empty()) holder += ")";
    ::close(m_fd);
    m_fd = -1;
    if (cause == EWOULDBLOCK) {
      throw InputError(folder.string() +
                       ": expected an output folder no other run writes into, found one "
                       "being written by another phantasm process" +
                       holder + "; wait for it to finish or choose another folder");
    }
    throw InputError(folder.string() + ": cannot lock the output folder: " + std::strerror(cause));
  }
  struct stat held {
  }, named{};
  if (::fstat(m_fd, &held) != 0 || ::stat(lock.c_str(), &named) != 0 || held.st_ino != named.st_ino ||
      held.st_dev != named.st_dev) {
    ::close(m_fd);
    m_fd = -1;
    return false;
  }
  // Who holds the lock, for the message a second writer gets.
  const std::string pid = std::to_string(::getpid()) + "\n";
  if (::ftruncate(m_fd, 0) == 0) {
    [[maybe_unused]] const ssize_t written = ::pwrite(m_fd, pid.data(), pid.size(), 0);
  }
  return true;
}

OutputFolderLock::~OutputFolderLock() {
  if (m_fd < 0) return;
  // Unlinked while held, so the folder is left as the run made it; a process that opened the
  // old file meanwhile sees it is gone once it gets the lock, and retries (try_lock).
  ::unlink(m_path.c_str());
  ::close(m_fd); // releases the lock
}

} // namespace phantasm
