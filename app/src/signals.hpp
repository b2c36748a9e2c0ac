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

 private:
  std::atomic<bool>& stop_;
  std::atomic<bool> quit_{false};
  std::atomic<int> received_{0};
  sigset_t previous_mask_{};
  std::thread thread_;
};

}  // namespace aerotrack::app
