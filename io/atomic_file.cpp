#include "io/atomic_file.hpp"

#include "core/cancellation.hpp"
#include "io/output_path.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <stdexcept>
#include <thread>

namespace phantasm {
namespace {

constexpr const char* k_temporary_marker = ".phantasm-tmp-";
constexpr std::size_t k_chunk_bytes = std::size_t{1} << 20;
constexpr std::size_t k_slow_chunk_bytes = 4096; // with a test delay: small chunks, many pauses
std::atomic<int> g_write_delay_ms{0};
std::atomic<unsigned> g_temporary_counter{0};

/// This machine's name as it appears in temporary file names: on a file system that several
/// machines share (a cluster's), a process id says nothing about another machine's processes.
const std::string& host_name() {
  static const std::string name = [] {
    char buffer[256] = {};
    if (::gethostname(buffer, sizeof buffer - 1) != 0 || buffer[0] == '\0') return std::string("localhost");
    std::string text(buffer);
    for (char& c : text) {
      if (c == '/' || c == '-' || static_cast<unsigned char>(c) < 0x21) c = '_';
    }
    return text;
  }();
  return name;
}

std::runtime_error io_error(const std::string& what, const std::filesystem::path& path) {
  return std::runtime_error(what + " '" + path.string() + "': " + std::strerror(errno));
}

void fsync_folder(const std::filesystem::path& folder) {
  const int fd = ::open(folder.empty() ? "." : folder.c_str(), O_RDONLY | O_DIRECTORY);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}

} // namespace

AtomicFileWriter::AtomicFileWriter(std::filesystem::path final_path) : m_final_path(std::move(final_path)) {
  // The rename of commit() would replace a device node or a FIFO with a regular file.
  require_replaceable_file(m_final_path, "output file");
  const std::filesystem::path folder = m_final_path.parent_path();
  if (!folder.empty()) std::filesystem::create_directories(folder);
  const std::string name = "." + m_final_path.filename().string() + k_temporary_marker +
                           std::to_string(::getpid()) + "-" + std::to_string(g_temporary_counter++) + "-" +
                           host_name();
  m_temporary_path = folder / name;
  m_registration.emplace(m_temporary_path);
  m_fd = ::open(m_temporary_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (m_fd < 0) throw io_error("cannot create", m_temporary_path);
}

AtomicFileWriter::~AtomicFileWriter() {
  if (m_fd >= 0) ::close(m_fd);
  if (!m_committed) ::unlink(m_temporary_path.c_str());
}

void AtomicFileWriter::write(const void* data, std::size_t size) {
  const auto* bytes = static_cast<const char*>(data);
  while (size > 0) {
    throw_if_cancelled();
    if (const int delay = g_write_delay_ms.load(); delay > 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(delay));
      throw_if_cancelled();
    }
    const std::size_t chunk =
        std::min(size, g_write_delay_ms.load() > 0 ? k_slow_chunk_bytes : k_chunk_bytes);
    const ssize_t written = ::write(m_fd, bytes, chunk);
    if (written < 0) {
      if (errno == EINTR) continue;
      throw io_error("cannot write", m_temporary_path);
    }
    bytes += written;
    size -= static_cast<std::size_t>(written);
  }
}

void AtomicFileWriter::commit() {
  throw_if_cancelled();
  if (::fsync(m_fd) != 0) throw io_error("cannot flush", m_temporary_path);
  if (::close(m_fd) != 0) {
    m_fd = -1;
    throw io_error("cannot close", m_temporary_path);
  }
  m_fd = -1;
  // A test's pause: a signal can then land between the last byte and the rename.
  if (const int delay = g_write_delay_ms.load(); delay > 0)
    std::this_thread::sleep_for(std::chrono::milliseconds(delay));
  if (const int error = m_registration->rename_to(m_final_path); error != 0) {
    errno = error;
    throw io_error("cannot rename to " + m_final_path.string() + " from", m_temporary_path);
  }
  m_committed = true;
  fsync_folder(m_final_path.parent_path());
}

void write_file_atomically(const std::filesystem::path& path, std::string_view bytes) {
  AtomicFileWriter writer(path);
  writer.write(bytes);
  writer.commit();
}

bool is_temporary_file_name(const std::filesystem::path& path) {
  const std::string name = path.filename().string();
  return !name.empty() && name[0] == '.' && name.find(k_temporary_marker) != std::string::npos;
}

namespace {

/// True when the process that made a temporary file (the pid and host in its name) may still run:
/// another run writing into the same dataset, e.g. a parallel batch job, on this machine or, on
/// a shared file system, on another (whose processes this one cannot see: they count as alive).
/// Names without a host (written before hosts were named) count as this machine's. Unknown
/// owners count as gone.
bool owner_is_alive(const std::filesystem::path& temporary) {
  const std::string name = temporary.filename().string();
  const std::size_t at = name.find(k_temporary_marker);
  if (at == std::string::npos) return false;
  const std::string rest = name.substr(at + std::string(k_temporary_marker).size());
  const std::size_t dash = rest.find('-');
  if (dash == 0 || dash == std::string::npos) return false;
  const std::size_t host_dash = rest.find('-', dash + 1);
  if (host_dash != std::string::npos && rest.substr(host_dash + 1) != host_name()) return true;
  long pid = 0;
  try {
    pid = std::stol(rest.substr(0, dash));
  } catch (const std::exception&) {
    return false;
  }
  if (pid <= 0) return false;
  return ::kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM;
}

} // namespace

std::size_t remove_stale_temporaries(const std::filesystem::path& root) {
  std::size_t removed = 0;
  std::error_code error;
  if (!std::filesystem::is_directory(root, error)) return 0;
  for (auto it = std::filesystem::recursive_directory_iterator(root, error);
       it != std::filesystem::recursive_directory_iterator(); it.increment(error)) {
    if (error) break;
    if (it->is_regular_file(error) && is_temporary_file_name(it->path()) && !owner_is_alive(it->path())) {
      if (std::filesystem::remove(it->path(), error)) ++removed;
    }
  }
  return removed;
}

void set_write_delay_for_testing(int milliseconds_per_chunk) {
  g_write_delay_ms = milliseconds_per_chunk;
}

int write_delay_for_testing() {
  return g_write_delay_ms.load();
}

} // namespace phantasm
