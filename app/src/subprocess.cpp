// Running a helper program: see subprocess.hpp.
#include "subprocess.hpp"

#include <fcntl.h>
#include <poll.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>

extern char** environ;  // NOLINT(readability-redundant-declaration): POSIX names no header for it

namespace aerotrack::app {
namespace {

/// Closes a pipe's ends on every path out.
struct PipePair {
  std::array<int, 2> fd{-1, -1};
  PipePair() = default;
  PipePair(const PipePair&) = delete;
  PipePair& operator=(const PipePair&) = delete;
  ~PipePair() {
    for (const int f : fd)
      if (f >= 0) close(f);
  }
  void closeEnd(int i) {
    if (fd[static_cast<std::size_t>(i)] >= 0) close(fd[static_cast<std::size_t>(i)]);
    fd[static_cast<std::size_t>(i)] = -1;
  }
};

}  // namespace

rt::Expected<ProcessResult> runProcess(const std::vector<std::string>& argv, std::size_t max_output) {
  if (argv.empty()) return rt::Error{"runProcess: no program"};
  PipePair out_pipe, err_pipe;
  if (pipe2(out_pipe.fd.data(), O_CLOEXEC) != 0 || pipe2(err_pipe.fd.data(), O_CLOEXEC) != 0)
    return rt::Error{argv[0] + ": cannot create a pipe: " + std::strerror(errno)};
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, out_pipe.fd[1], STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, err_pipe.fd[1], STDERR_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  std::vector<std::string> args = argv;
  std::vector<char*> raw;
  raw.reserve(args.size() + 1);
  for (std::string& a : args) raw.push_back(a.data());
  raw.push_back(nullptr);
  pid_t pid = 0;
  const int spawned = posix_spawnp(&pid, argv[0].c_str(), &actions, nullptr, raw.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) {
    if (spawned == ENOENT) return rt::Error{argv[0] + ": not found on PATH"};
    return rt::Error{argv[0] + ": cannot start: " + std::strerror(spawned)};
  }
  out_pipe.closeEnd(1);
  err_pipe.closeEnd(1);
  ProcessResult result;
  std::array<pollfd, 2> fds{pollfd{out_pipe.fd[0], POLLIN, 0}, pollfd{err_pipe.fd[0], POLLIN, 0}};
  std::array<std::string*, 2> sinks{&result.out, &result.err};
  std::array<char, 4096> buffer{};
  int open_streams = 2;
  while (open_streams > 0) {
    if (poll(fds.data(), fds.size(), -1) < 0) {
      if (errno == EINTR) continue;
      break;
    }
    for (std::size_t i = 0; i < fds.size(); ++i) {
      if (fds[i].fd < 0 || fds[i].revents == 0) continue;
      const ssize_t n = read(fds[i].fd, buffer.data(), buffer.size());
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        fds[i].fd = -1;  // poll ignores negative descriptors; PipePair closes it
        --open_streams;
        continue;
      }
      // Read everything (a full pipe would block the child), keep the first max_output bytes.
      const std::size_t keep =
          std::min(static_cast<std::size_t>(n), max_output - std::min(max_output, sinks[i]->size()));
      sinks[i]->append(buffer.data(), keep);
    }
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return rt::Error{argv[0] + ": cannot wait for it: " + std::strerror(errno)};
  }
  result.exit_status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return result;
}

std::string firstLine(const std::string& text) {
  std::size_t start = 0;
  while (start < text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    std::string line = text.substr(start, end - start);
    if (line.find_first_not_of(" \t\r") != std::string::npos) return line;
    start = end + 1;
  }
  return "";
}

}  // namespace aerotrack::app
