#include "tools/stepcalc/png_export.hpp"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstring>
#include <fstream>
#include <stdexcept>

// environ: declared by <unistd.h> (glibc, _GNU_SOURCE as g++ defines it).

namespace stepnode::tools {

void write_png(const std::string& svg, const std::string& png_path) {
  int fds[2];
  if (pipe(fds) != 0) throw std::runtime_error(std::string("pipe: ") + std::strerror(errno));
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[0], STDIN_FILENO);
  posix_spawn_file_actions_addclose(&actions, fds[1]);
  std::string out = png_path;
  char prog[] = "rsvg-convert", format[] = "--format=png", dash_o[] = "-o";
  char* argv[] = {prog, format, dash_o, out.data(), nullptr};
  pid_t pid = 0;
  int rc = posix_spawnp(&pid, prog, &actions, nullptr, argv, environ);
  posix_spawn_file_actions_destroy(&actions);
  close(fds[0]);
  if (rc != 0) {
    close(fds[1]);
    if (rc == ENOENT)
      throw std::runtime_error(
          "a .png plot needs rsvg-convert, which is not installed (Debian package librsvg2-bin; "
          "tools/setup installs it), or plot to FILE.svg");
    throw std::runtime_error(std::string("cannot run rsvg-convert: ") + std::strerror(rc));
  }
  // rsvg-convert reads the whole SVG before it writes; a closed pipe means it failed.
  struct sigaction ignore {
  }, old{};
  ignore.sa_handler = SIG_IGN;
  sigaction(SIGPIPE, &ignore, &old);
  size_t done = 0;
  while (done < svg.size()) {
    ssize_t n = write(fds[1], svg.data() + done, svg.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    done += static_cast<size_t>(n);
  }
  close(fds[1]);
  sigaction(SIGPIPE, &old, nullptr);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || done < svg.size())
    throw std::runtime_error("rsvg-convert could not write " + png_path);
}

namespace {
bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() > suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}
}  // namespace

bool plot_path_ok(const std::string& path) {
  return ends_with(path, ".svg") || ends_with(path, ".png");
}

void write_plot(const std::string& svg, const std::string& path) {
  if (ends_with(path, ".png")) return write_png(svg, path);
  std::ofstream out(path, std::ios::binary);
  out << svg;
  out.close();
  if (!out) throw std::runtime_error("cannot write " + path);
}

}  // namespace stepnode::tools
