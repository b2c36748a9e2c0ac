// The systemd notification protocol against a real unix datagram socket standing in for systemd
// (a path, and an abstract address), the environment's parsing, and the watchdog's liveness rule.
#include "systemd_notify.hpp"

#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstddef>
#include <cstring>
#include <filesystem>
#include <string>

namespace aerotrack::app {
namespace {

/// A datagram socket bound where systemd would listen.
class FakeSystemd {
 public:
  explicit FakeSystemd(const std::string& address) {
    fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    std::memcpy(a.sun_path, address.data(), address.size());
    if (address[0] == '@') a.sun_path[0] = '\0';
    bound_ = ::bind(fd_, reinterpret_cast<const sockaddr*>(&a),
                    static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + address.size())) == 0;
  }
  ~FakeSystemd() { ::close(fd_); }
  FakeSystemd(const FakeSystemd&) = delete;
  FakeSystemd& operator=(const FakeSystemd&) = delete;
  bool bound() const { return bound_; }
  std::string receive() const {
    char buffer[256];
    const ssize_t n = ::recv(fd_, buffer, sizeof(buffer), MSG_DONTWAIT);
    return n > 0 ? std::string(buffer, static_cast<std::size_t>(n)) : std::string();
  }

 private:
  int fd_ = -1;
  bool bound_ = false;
};

TEST(SystemdNotifier, SendsStatesToASocketPath) {
  const std::string path =
      (std::filesystem::temp_directory_path() / ("aerotrack_notify_" + std::to_string(::getpid()))).string();
  std::filesystem::remove(path);
  const FakeSystemd systemd(path);
  ASSERT_TRUE(systemd.bound());
  const SystemdNotifier notifier = SystemdNotifier::fromEnvironment(path.c_str(), nullptr, nullptr, ::getpid());
  ASSERT_TRUE(notifier.enabled());
  ASSERT_TRUE(notifier.notify("READY=1\nSTATUS=tasks running"));
  EXPECT_EQ(systemd.receive(), "READY=1\nSTATUS=tasks running");
  ASSERT_TRUE(notifier.notify("WATCHDOG=1"));
  EXPECT_EQ(systemd.receive(), "WATCHDOG=1");
  std::filesystem::remove(path);
}

TEST(SystemdNotifier, SendsToAnAbstractAddress) {
  const std::string address = "@aerotrack_notify_test_" + std::to_string(::getpid());
  const FakeSystemd systemd(address);
  ASSERT_TRUE(systemd.bound());
  const SystemdNotifier notifier(address, 0);
  ASSERT_TRUE(notifier.notify("STOPPING=1"));
  EXPECT_EQ(systemd.receive(), "STOPPING=1");
}

TEST(SystemdNotifier, OutsideSystemdEverythingIsANoOp) {
  const SystemdNotifier notifier = SystemdNotifier::fromEnvironment(nullptr, "2000000", nullptr, 1);
  EXPECT_FALSE(notifier.enabled());
  EXPECT_EQ(notifier.watchdogTimeoutNs(), 0);
  EXPECT_TRUE(notifier.notify("READY=1"));
}

TEST(SystemdNotifier, ReadsTheWatchdogTimeoutOnlyWhenItIsOurs) {
  EXPECT_EQ(SystemdNotifier::fromEnvironment("/run/x", "2000000", nullptr, 42).watchdogTimeoutNs(), 2'000'000'000);
  EXPECT_EQ(SystemdNotifier::fromEnvironment("/run/x", "2000000", "42", 42).watchdogTimeoutNs(), 2'000'000'000);
  EXPECT_EQ(SystemdNotifier::fromEnvironment("/run/x", "2000000", "43", 42).watchdogTimeoutNs(), 0);
  EXPECT_EQ(SystemdNotifier::fromEnvironment("/run/x", "2s", nullptr, 42).watchdogTimeoutNs(), 0);
  EXPECT_EQ(SystemdNotifier::fromEnvironment("/run/x", "0", nullptr, 42).watchdogTimeoutNs(), 0);
}

TEST(SystemdNotifier, AMissingSocketIsOneLineNamingIt) {
  const SystemdNotifier notifier("/nonexistent/aerotrack/notify", 0);
  const rt::Status s = notifier.notify("READY=1");
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("/nonexistent/aerotrack/notify"), std::string::npos) << s.error().message;
  EXPECT_EQ(s.error().message.find('\n'), std::string::npos);
}

TEST(TaskLiveness, EveryTaskMustHaveSteppedSinceTheLastCheck) {
  TaskLiveness liveness;
  EXPECT_FALSE(liveness.allAdvanced({10, 20})) << "the first call only sets the baseline";
  EXPECT_TRUE(liveness.allAdvanced({11, 25}));
  EXPECT_FALSE(liveness.allAdvanced({12, 25})) << "the second task is stuck";
  EXPECT_TRUE(liveness.allAdvanced({13, 26}));
  EXPECT_FALSE(liveness.allAdvanced({14})) << "a changed task list is not evidence of progress";
}

}  // namespace
}  // namespace aerotrack::app
