// Running a helper program (sbatch, squeue, scancel) and reading what it says: posix_spawnp with
// both output streams captured through pipes, bounded, and the exit status. No shell is involved, so
// nothing in an argument is interpreted.
#pragma once

#include <string>
#include <vector>

#include "aerotrack/rt/expected.hpp"

namespace aerotrack::app {

struct ProcessResult {
  int exit_status = 0;  ///< The exit code, or 128 + the signal that killed it.
  std::string out;      ///< stdout, at most max_output bytes.
  std::string err;      ///< stderr, at most max_output bytes.
};

/// Runs argv[0] (looked up on PATH) with argv and waits for it. Error only when it cannot be started:
/// "sbatch: not found on PATH" for a missing program.
rt::Expected<ProcessResult> runProcess(const std::vector<std::string>& argv, std::size_t max_output = 1 << 16);

/// The first non-empty line of a program's output, for one-line messages.
std::string firstLine(const std::string& text);

}  // namespace aerotrack::app
