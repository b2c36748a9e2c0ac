// Signal watcher: see signals.hpp.
#include "signals.hpp"

#include <pthread.h>

#include <ctime>

namespace aerotrack::app {

SignalWatcher::SignalWatcher(std::atomic<bool>& stop) : stop_(stop) {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &set, &previous_mask_);
  thread_ = std::thread([this, set] {
    const timespec poll{0, 100'000'000};  // re-check quit_ ten times a second
    while (!quit_.load()) {
      const int sig = sigtimedwait(&set, nullptr, &poll);
      if (sig > 0) {
        received_.store(sig);
        stop_.store(true, std::memory_order_release);
      }
    }
  });
}

SignalWatcher::~SignalWatcher() {
  quit_.store(true);
  thread_.join();
  pthread_sigmask(SIG_SETMASK, &previous_mask_, nullptr);
}

}  // namespace aerotrack::app
