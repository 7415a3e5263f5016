// The service manager's notification protocol (systemd's sd_notify(3)), written here so the
// binaries need no libsystemd: one datagram per message to the AF_UNIX socket named by
// $NOTIFY_SOCKET (a path, or an abstract name when it starts with '@').
//
// Without NOTIFY_SOCKET every call is a no-op, so the processes behave the same when
// started by hand. The watchdog is armed only when WATCHDOG_USEC is set and WATCHDOG_PID is
// unset or names this process (systemd sets both for the main process of a unit).
#pragma once
#include <sys/socket.h>
#include <sys/types.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstdint>
#include <string>
#include <string_view>

namespace stepnode::canio {

class ServiceNotifier {
 public:
  // What the environment says, for `self` (this process' id).
  struct Settings {
    std::string socket;          // $NOTIFY_SOCKET; empty: notifications off
    uint64_t watchdog_usec = 0;  // $WATCHDOG_USEC; 0: no watchdog
  };
  // Reads NOTIFY_SOCKET, WATCHDOG_USEC and WATCHDOG_PID. A WATCHDOG_USEC that is not a
  // positive number, or a WATCHDOG_PID of another process, leaves the watchdog off.
  static Settings settings_from_environment(pid_t self);

  ServiceNotifier() : ServiceNotifier(settings_from_environment(::getpid())) {}
  explicit ServiceNotifier(const Settings& settings);
  ~ServiceNotifier();
  ServiceNotifier(const ServiceNotifier&) = delete;
  ServiceNotifier& operator=(const ServiceNotifier&) = delete;

  bool enabled() const { return fd_ >= 0; }
  // How often to send WATCHDOG=1: half the manager's timeout (its own advice), 0 when off.
  uint64_t watchdog_period_us() const { return enabled() ? watchdog_usec_ / 2 : 0; }

  // Each sends one message and returns whether the datagram went out (true when off: there
  // is nobody to tell). Never blocks: a manager that does not read must not stop the loop.
  bool ready() { return send("READY=1"); }
  bool watchdog() { return send("WATCHDOG=1"); }
  bool stopping() { return send("STOPPING=1"); }
  bool status(std::string_view text);
  bool send(std::string_view message);

 private:
  int fd_ = -1;
  sockaddr_un address_{};
  socklen_t address_length_ = 0;
  uint64_t watchdog_usec_ = 0;
};

}  // namespace stepnode::canio
