#include "canio/sd_notify.hpp"

#include <spdlog/spdlog.h>

#include <cerrno>
#include <charconv>
#include <cstddef>
#include <cstdlib>
#include <cstring>

namespace stepnode::canio {

namespace {

// A decimal number that is all of `text`, else nothing (no sign, no spaces, no suffix).
bool parse_decimal(const char* text, uint64_t& out) {
  if (!text || !*text) return false;
  const char* end = text + std::strlen(text);
  auto [ptr, ec] = std::from_chars(text, end, out);
  return ec == std::errc() && ptr == end;
}

}  // namespace

ServiceNotifier::Settings ServiceNotifier::settings_from_environment(pid_t self) {
  Settings s;
  if (const char* socket = std::getenv("NOTIFY_SOCKET")) s.socket = socket;
  uint64_t usec = 0;
  if (!parse_decimal(std::getenv("WATCHDOG_USEC"), usec) || usec == 0) return s;
  // systemd names the process the watchdog is for; a child that inherited the variables
  // (none here, but a shell wrapper could be one) must not pet on its parent's behalf.
  if (const char* pid_text = std::getenv("WATCHDOG_PID")) {
    uint64_t pid = 0;
    if (!parse_decimal(pid_text, pid) || pid != static_cast<uint64_t>(self)) return s;
  }
  s.watchdog_usec = usec;
  return s;
}

ServiceNotifier::ServiceNotifier(const Settings& settings) {
  const std::string& name = settings.socket;
  if (name.empty()) return;
  // A path needs room for its terminating NUL; an abstract name ('@' becomes NUL) is
  // exactly its bytes, and its length is part of the name.
  bool abstract = name[0] == '@';
  if ((name[0] != '/' && !abstract) ||
      name.size() + (abstract ? 0 : 1) > sizeof address_.sun_path) {
    spdlog::warn(
        "NOTIFY_SOCKET '{}' is not an absolute path or an @abstract name that fits: not notifying",
        name);
    return;
  }
  address_.sun_family = AF_UNIX;
  std::memcpy(address_.sun_path, name.data(), name.size());
  if (abstract) address_.sun_path[0] = '\0';
  address_length_ =
      static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + name.size() + (abstract ? 0 : 1));
  fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  if (fd_ < 0) {
    spdlog::warn("NOTIFY_SOCKET: socket: {}: not notifying", std::strerror(errno));
    return;
  }
  watchdog_usec_ = settings.watchdog_usec;
}

ServiceNotifier::~ServiceNotifier() {
  if (fd_ >= 0) ::close(fd_);
}

bool ServiceNotifier::status(std::string_view text) {
  std::string message = "STATUS=";
  message += text;
  return send(message);
}

bool ServiceNotifier::send(std::string_view message) {
  if (fd_ < 0) return true;
  ssize_t n = ::sendto(fd_, message.data(), message.size(), MSG_NOSIGNAL | MSG_DONTWAIT,
                       reinterpret_cast<const sockaddr*>(&address_), address_length_);
  if (n == static_cast<ssize_t>(message.size())) return true;
  // Logged at debug only: a watchdog message that cannot go out every few seconds would
  // otherwise fill the journal, and the manager notices the silence by itself.
  spdlog::debug("NOTIFY_SOCKET: sending '{}': {}", message,
                n < 0 ? std::strerror(errno) : "short write");
  return false;
}

}  // namespace stepnode::canio
