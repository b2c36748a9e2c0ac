// The systemd service protocol (issue 11 item 5: Type=notify with the watchdog), without libsystemd:
// a datagram of "KEY=VALUE" lines to the unix socket systemd names in $NOTIFY_SOCKET (a path, or an
// abstract address written with a leading '@'). READY=1 when every task runs, WATCHDOG=1 while they
// keep running, STOPPING=1 on the way out, STATUS=... a line for `systemctl status`. Outside systemd
// (no $NOTIFY_SOCKET) the notifier is disabled and every call is a no-op.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "aerotrack/rt/expected.hpp"
#include "aerotrack/rt/time.hpp"

namespace aerotrack::app {

class SystemdNotifier {
 public:
  /// From systemd's variables: NOTIFY_SOCKET, WATCHDOG_USEC, WATCHDOG_PID (the watchdog is ours only if
  /// the pid is ours or unset). Null arguments: that variable is unset.
  static SystemdNotifier fromEnvironment(const char* notify_socket, const char* watchdog_usec, const char* watchdog_pid,
                                         long own_pid);
  SystemdNotifier() = default;
  SystemdNotifier(std::string socket_address, rt::DurationNs watchdog_timeout_ns)
      : address_(std::move(socket_address)), watchdog_timeout_ns_(watchdog_timeout_ns) {}

  bool enabled() const { return !address_.empty(); }
  /// The service's watchdog timeout (WatchdogSec=), 0 if none: ping at half of it.
  rt::DurationNs watchdogTimeoutNs() const { return watchdog_timeout_ns_; }
  /// Sends one state datagram. Error naming the socket if it cannot be sent; ok when disabled.
  rt::Status notify(const std::string& state) const;

 private:
  std::string address_;
  rt::DurationNs watchdog_timeout_ns_ = 0;
};

/// Whether every periodic task has run since the last call (the watchdog's question: is the process
/// still doing its job, not merely alive). counts: each periodic task's step count, in a fixed order.
class TaskLiveness {
 public:
  bool allAdvanced(const std::vector<std::uint64_t>& counts);

 private:
  std::vector<std::uint64_t> last_;
};

}  // namespace aerotrack::app
