#include "io/output_path.hpp"

#include "core/error.hpp"
#include "core/path_kind.hpp"
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

std::filesystem::path file_in_the_way(const std::filesystem::path& path) {
  for (std::filesystem::path folder = path.parent_path(); !folder.empty() && folder != folder.parent_path();
       folder = folder.parent_path()) {
    struct stat info {};
    if (::stat(folder.c_str(), &info) != 0) continue;
    if (S_ISDIR(info.st_mode)) return {};
    return folder;
  }
  return {};
}

namespace {

/// "expected F to be a folder (or not to exist), found a file": F, found by file_in_the_way,
/// stands where a folder of the path belongs.
std::string expected_folder(const std::filesystem::path& in_the_way) {
  std::error_code ignored;
  return "expected " + in_the_way.string() + " to be a folder (or not to exist), found " +
         (std::filesystem::is_regular_file(in_the_way, ignored) ? "a file"
                                                                : "something that is not a folder");
}

} // namespace

std::string folder_creation_problem(const std::filesystem::path& folder, const std::error_code& error) {
  const std::filesystem::path in_the_way = file_in_the_way(folder);
  if (!in_the_way.empty()) return expected_folder(in_the_way);
  return "expected a folder phantasm can create, found: " + error.message();
}

std::string file_in_the_way_message(const std::filesystem::filesystem_error& error) {
  if (error.code() != std::errc::not_a_directory) return {};
  const std::filesystem::path in_the_way = file_in_the_way(error.path1());
  if (in_the_way.empty()) return {};
  return error.path1().string() + ": " + expected_folder(in_the_way);
}

void require_replaceable_file(const std::filesystem::path& path, std::string_view what) {
  // An empty path, or one ending in '/', names no file: its temporary file would be "..phantasm-
  // tmp-..." in the current folder, left there when the rename to "" fails.
  if (path.empty())
    throw InputError(std::string(what) + ": expected the path of a file to write, found an empty path");
  if (!path.has_filename()) {
    throw InputError(std::string(what) + ": " + path.string() +
                     ": expected the path of a file to write, found a folder's path (it ends in '/')");
  }
  struct stat info {};
  if (::stat(path.c_str(), &info) != 0) {
    if (errno != ENOTDIR) return; // missing (or unreadable: opening will say)
    const std::filesystem::path in_the_way = file_in_the_way(path);
    if (in_the_way.empty()) return;
    throw InputError(std::string(what) + ": " + path.string() + ": " + expected_folder(in_the_way));
  }
  if (S_ISREG(info.st_mode)) return;
  throw InputError(std::string(what) + ": " + path.string() +
                   ": expected a new file or a regular file to replace, found " + path_kind(path));
}

OutputFolderLock::OutputFolderLock(const std::filesystem::path& folder, FolderLockMode mode) {
  if (folder.empty()) throw InputError("--output: expected an output folder, found an empty path");
  std::error_code error;
  if (std::filesystem::exists(folder, error) && !std::filesystem::is_directory(folder, error))
    throw InputError(folder.string() + ": expected an output folder, found a file");
  std::filesystem::create_directories(folder, error);
  if (error) throw InputError(folder.string() + ": " + folder_creation_problem(folder, error));
  m_fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (m_fd < 0) {
    throw InputError(folder.string() +
                     ": expected an output folder phantasm can open, found: " + std::strerror(errno));
  }
  const int operation = (mode == FolderLockMode::exclusive ? LOCK_EX : LOCK_SH) | LOCK_NB;
  if (::flock(m_fd, operation) == 0) return;
  const int cause = errno;
  ::close(m_fd);
  m_fd = -1;
  if (cause == EWOULDBLOCK) {
    throw InputError(
        folder.string() +
        ": expected an output folder no other run writes into, found one being written by another "
        "phantasm process (" +
        (mode == FolderLockMode::exclusive ? "a run or a batch" : "a run") +
        "); wait for it to finish or choose another folder");
  }
  // A filesystem without flock() (some network mounts): the folder is used unlocked.
}

namespace {
constexpr const char* k_sweep_mark_prefix = ".phantasm-sweep-";
} // namespace

bool SweepMark::is_mark_name(const std::string& file_name) {
  return file_name.rfind(k_sweep_mark_prefix, 0) == 0;
}

SweepMark::SweepMark(const std::filesystem::path& folder, const std::string& sweep_id) {
  const std::string own = k_sweep_mark_prefix + sweep_id;
  const std::filesystem::path path = folder / own;
  m_fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (m_fd < 0) return; // a folder that takes no files fails at its first file, with its own message
  // Shared, waiting: another batch's probe below holds a mark exclusively for an instant only.
  if (::flock(m_fd, LOCK_SH) != 0) return; // no flock() on this filesystem: unchecked
  // Made and locked before looking at the others: of two sweeps starting at once, at least one
  // sees the other's mark held.
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(folder, error)) {
    const std::string name = entry.path().filename().string();
    if (!is_mark_name(name) || name == own) continue;
    const int other = ::open(entry.path().c_str(), O_RDONLY | O_CLOEXEC);
    if (other < 0) continue;
    const bool held = ::flock(other, LOCK_EX | LOCK_NB) != 0 && errno == EWOULDBLOCK;
    if (!held) std::filesystem::remove(entry.path(), error); // left by a batch that has ended
    ::close(other);
    if (held) {
      ::close(m_fd);
      m_fd = -1;
      throw InputError(folder.string() +
                       ": expected one sweep per dataset, found a batch of another sweep writing into it (" +
                       name + "); wait for it to finish or choose another folder");
    }
  }
}

SweepMark::~SweepMark() {
  if (m_fd >= 0) ::close(m_fd); // releases the lock; the mark stays for the next batch to check
}

OutputFolderLock::~OutputFolderLock() {
  if (m_fd >= 0) ::close(m_fd); // releases the lock
}

} // namespace phantasm
