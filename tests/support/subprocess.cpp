#include "tests/support/subprocess.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <thread>

extern char** environ;

namespace phantasm::testing {
namespace {

std::vector<char*> c_arguments(const std::vector<std::string>& argv) {
  std::vector<char*> args;
  for (const auto& a : argv)
    args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  return args;
}

int decode_status(int status) {
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return -1;
}

std::string read_all(int fd) {
  std::string text;
  char buffer[4096];
  ssize_t n = 0;
  while ((n = ::read(fd, buffer, sizeof buffer)) > 0)
    text.append(buffer, static_cast<std::size_t>(n));
  return text;
}

} // namespace

CommandResult run_command(const std::vector<std::string>& argv) {
  int out_pipe[2], err_pipe[2];
  if (::pipe(out_pipe) != 0 || ::pipe(err_pipe) != 0) throw std::runtime_error("pipe failed");
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, out_pipe[1], 1);
  posix_spawn_file_actions_adddup2(&actions, err_pipe[1], 2);
  posix_spawn_file_actions_addclose(&actions, out_pipe[0]);
  posix_spawn_file_actions_addclose(&actions, err_pipe[0]);
  auto args = c_arguments(argv);
  pid_t pid = 0;
  const int spawned = ::posix_spawn(&pid, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(out_pipe[1]);
  ::close(err_pipe[1]);
  if (spawned != 0) throw std::runtime_error("cannot start " + argv[0]);
  CommandResult result;
  // Read stderr on a thread so that neither pipe can fill up and block the child.
  std::thread err_reader([&] { result.err = read_all(err_pipe[0]); });
  result.out = read_all(out_pipe[0]);
  err_reader.join();
  ::close(out_pipe[0]);
  ::close(err_pipe[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);
  result.exit_code = decode_status(status);
  return result;
}

BackgroundProcess::BackgroundProcess(const std::vector<std::string>& argv, const std::string& stderr_path) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, stderr_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  auto args = c_arguments(argv);
  pid_t pid = 0;
  const int spawned = ::posix_spawn(&pid, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) throw std::runtime_error("cannot start " + argv[0]);
  m_pid = pid;
}

BackgroundProcess::~BackgroundProcess() {
  if (!m_waited && m_pid > 0) {
    ::kill(m_pid, SIGKILL);
    wait();
  }
}

void BackgroundProcess::send_signal(int signal_number) {
  ::kill(m_pid, signal_number);
}

bool BackgroundProcess::ended() {
  if (m_waited) return true;
  if (::waitpid(m_pid, &m_status, WNOHANG) != m_pid) return false;
  m_waited = true;
  return true;
}

bool BackgroundProcess::has_open(const std::string& path) const {
  std::error_code error;
  const std::filesystem::path wanted = std::filesystem::weakly_canonical(path, error);
  const std::filesystem::path fds = "/proc/" + std::to_string(m_pid) + "/fd";
  for (const auto& entry : std::filesystem::directory_iterator(fds, error)) {
    std::error_code link_error;
    if (std::filesystem::read_symlink(entry.path(), link_error) == wanted) return true;
  }
  return false;
}

std::vector<int> BackgroundProcess::children() const {
  std::ifstream in("/proc/" + std::to_string(m_pid) + "/task/" + std::to_string(m_pid) + "/children");
  std::vector<int> pids;
  for (int pid = 0; in >> pid;)
    pids.push_back(pid);
  return pids;
}

int BackgroundProcess::wait() {
  if (!m_waited) {
    ::waitpid(m_pid, &m_status, 0);
    m_waited = true;
  }
  return decode_status(m_status);
}

} // namespace phantasm::testing
