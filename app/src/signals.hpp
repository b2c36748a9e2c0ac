// SIGINT/SIGTERM without a global flag: the signals are blocked in every thread (the mask is set
// before any thread starts and inherited), and one watcher thread takes them with sigtimedwait
// and sets the stop flag it was given. Construct it first thing in main.
#pragma once

#include <atomic>
#include <csignal>
#include <thread>

namespace aerotrack::app {

class SignalWatcher {
 public:
  explicit SignalWatcher(std::atomic<bool>& stop);
  ~SignalWatcher();
  SignalWatcher(const SignalWatcher&) = delete;
  SignalWatcher& operator=(const SignalWatcher&) = delete;

  /// The signal that stopped us, or 0.
  int received() const { return received_.load(); }
  /// The exit status of a command stopped by a signal, after its clean shutdown: the shell's
  /// convention, 128 + the signal (130 for SIGINT, 143 for SIGTERM) -- the same for every command.
  int stoppedStatus() const { return 128 + (received() != 0 ? received() : 2); }

 private:
  std::atomic<bool>& stop_;
  std::atomic<bool> quit_{false};
  std::atomic<int> received_{0};
  sigset_t previous_mask_{};
  std::thread thread_;
};

}  // namespace aerotrack::app
