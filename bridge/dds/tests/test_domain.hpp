// A DDS domain that no other test on this host is using.
//
// ctest runs test processes in parallel, and every DDS test publishes on a domain of its own so
// that a reader counts only its own writer's samples. A random pick from 180 domains collided
// about once in a few hundred CI runs (two tests on domain 124: stepwatch saw the other test's
// node 9). So each domain is claimed with an flock() on a file named after it; the lock is held
// until the process exits, which the kernel does for us even after a crash.
#pragma once
#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cstdint>
#include <random>
#include <stdexcept>
#include <string>

namespace stepnode::bridge::dds::test {

// Domains 50..229: clear of 0 (the default a developer's own tools use) and below Fast DDS's
// limit of 232 for the default port mapping (7400 + 250 * domain must fit a UDP port).
inline constexpr uint32_t kFirstTestDomain = 50;
inline constexpr uint32_t kTestDomains = 180;

inline uint32_t unique_test_domain() {
  // Start at a random place so two processes do not race over the same first file.
  const uint32_t start = std::random_device{}() % kTestDomains;
  for (uint32_t i = 0; i < kTestDomains; ++i) {
    const uint32_t domain = kFirstTestDomain + (start + i) % kTestDomains;
    const std::string path = "/tmp/stepnode-test-dds-domain-" + std::to_string(domain) + ".lock";
    const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
    if (fd < 0) continue;
    if (::flock(fd, LOCK_EX | LOCK_NB) == 0) return domain;  // fd stays open: the claim
    ::close(fd);
  }
  throw std::runtime_error("every test DDS domain 50..229 is claimed by another process");
}

}  // namespace stepnode::bridge::dds::test
