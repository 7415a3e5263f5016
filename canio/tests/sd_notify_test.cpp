// ServiceNotifier against a listener of our own: a datagram socket bound in a temporary
// directory (or in the abstract namespace) plays the service manager.
#include "canio/sd_notify.hpp"

#include <gtest/gtest.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string>

namespace stepnode::canio {
namespace {

// A bound AF_UNIX datagram socket: `name` is a path, or "@name" for the abstract namespace.
class Listener {
 public:
  explicit Listener(const std::string& name)
      : fd_(::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0)) {
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    std::memcpy(a.sun_path, name.data(), name.size());
    socklen_t len = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + name.size());
    if (name[0] == '@') a.sun_path[0] = '\0';
    else ++len;
    if (::bind(fd_, reinterpret_cast<sockaddr*>(&a), len) != 0)
      ADD_FAILURE() << "bind " << name << ": " << std::strerror(errno);
  }
  ~Listener() { ::close(fd_); }
  // The next datagram within timeout_ms, or nothing.
  std::optional<std::string> receive(int timeout_ms = 1000) {
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, timeout_ms) != 1) return std::nullopt;
    char buf[512];
    ssize_t n = ::recv(fd_, buf, sizeof buf, 0);
    if (n < 0) return std::nullopt;
    return std::string(buf, static_cast<size_t>(n));
  }

 private:
  int fd_;
};

class TempDir {
 public:
  TempDir() {
    char templ[] = "/tmp/sd_notify_test.XXXXXX";
    path_ = ::mkdtemp(templ);
  }
  ~TempDir() { std::filesystem::remove_all(path_); }
  std::string path(const char* leaf) const { return path_ + "/" + leaf; }

 private:
  std::string path_;
};

// Sets or clears the three variables for one test and puts them back after it.
class Environment {
 public:
  Environment(const char* socket, const char* usec, const char* pid) {
    set("NOTIFY_SOCKET", socket);
    set("WATCHDOG_USEC", usec);
    set("WATCHDOG_PID", pid);
  }
  ~Environment() {
    ::unsetenv("NOTIFY_SOCKET");
    ::unsetenv("WATCHDOG_USEC");
    ::unsetenv("WATCHDOG_PID");
  }

 private:
  static void set(const char* name, const char* value) {
    if (value) ::setenv(name, value, 1);
    else ::unsetenv(name);
  }
};

TEST(SdNotify, SendsEachMessageAsOneDatagramToThePathInNotifySocket) {
  TempDir dir;
  std::string path = dir.path("notify");
  Listener manager(path);
  ServiceNotifier n(ServiceNotifier::Settings{path, 0});
  ASSERT_TRUE(n.enabled());
  EXPECT_TRUE(n.ready());
  EXPECT_TRUE(n.status("node 5 on can0"));
  EXPECT_TRUE(n.watchdog());
  EXPECT_TRUE(n.stopping());
  EXPECT_EQ(manager.receive(), "READY=1");
  EXPECT_EQ(manager.receive(), "STATUS=node 5 on can0");
  EXPECT_EQ(manager.receive(), "WATCHDOG=1");
  EXPECT_EQ(manager.receive(), "STOPPING=1");
  EXPECT_EQ(manager.receive(50), std::nullopt);
}

TEST(SdNotify, AnAtSignNamesTheAbstractNamespace) {
  std::string name = "@stepnode-sd-notify-test-" + std::to_string(::getpid());
  Listener manager(name);
  ServiceNotifier n(ServiceNotifier::Settings{name, 0});
  ASSERT_TRUE(n.enabled());
  EXPECT_TRUE(n.ready());
  EXPECT_EQ(manager.receive(), "READY=1");
}

TEST(SdNotify, WithoutNotifySocketEveryCallIsANoOp) {
  Environment env(nullptr, "1000000", nullptr);
  ServiceNotifier n;
  EXPECT_FALSE(n.enabled());
  EXPECT_EQ(n.watchdog_period_us(), 0u);  // nobody to pet, whatever WATCHDOG_USEC says
  EXPECT_TRUE(n.ready());
  EXPECT_TRUE(n.watchdog());
}

TEST(SdNotify, ANameThatIsNeitherAnAbsolutePathNorAbstractTurnsNotifyingOff) {
  EXPECT_FALSE(ServiceNotifier(ServiceNotifier::Settings{"relative/notify", 0}).enabled());
  EXPECT_FALSE(
      ServiceNotifier(ServiceNotifier::Settings{"/" + std::string(200, 'x'), 0}).enabled());
}

TEST(SdNotify, AManagerThatIsGoneIsAFailedSendNotACrashOrABlock) {
  TempDir dir;
  ServiceNotifier n(ServiceNotifier::Settings{dir.path("nobody"), 0});
  ASSERT_TRUE(n.enabled());
  EXPECT_FALSE(n.ready());
}

TEST(SdNotify, TheWatchdogPeriodIsHalfOfWatchdogUsec) {
  TempDir dir;
  std::string path = dir.path("notify");
  Environment env(path.c_str(), "400000", nullptr);
  ServiceNotifier n;
  ASSERT_TRUE(n.enabled());
  EXPECT_EQ(n.watchdog_period_us(), 200000u);
}

TEST(SdNotify, TheWatchdogIsOnlyForTheProcessWatchdogPidNames) {
  TempDir dir;
  std::string path = dir.path("notify");
  std::string self = std::to_string(::getpid());
  std::string other = std::to_string(::getpid() + 1);
  {
    Environment env(path.c_str(), "400000", self.c_str());
    EXPECT_EQ(ServiceNotifier::settings_from_environment(::getpid()).watchdog_usec, 400000u);
  }
  {
    Environment env(path.c_str(), "400000", other.c_str());
    auto s = ServiceNotifier::settings_from_environment(::getpid());
    EXPECT_EQ(s.watchdog_usec, 0u);
    EXPECT_EQ(s.socket, path);  // READY and STOPPING still go out
  }
}

TEST(SdNotify, AWatchdogUsecThatIsNotAPositiveNumberLeavesTheWatchdogOff) {
  for (const char* bad : {"", "0", "-5", "12abc", " 100", "99999999999999999999999"}) {
    Environment env("/run/notify", bad, nullptr);
    EXPECT_EQ(ServiceNotifier::settings_from_environment(::getpid()).watchdog_usec, 0u)
        << "'" << bad << "'";
  }
}

}  // namespace
}  // namespace stepnode::canio
