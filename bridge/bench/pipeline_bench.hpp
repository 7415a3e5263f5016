// pipeline_bench (bridge/bench/pipeline_bench.cpp): what its two processes share. The
// subscriber process is bridge/bench/pipeline_subscriber.cpp.
#pragma once
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/topic/Topic.hpp>

#include <sys/types.h>
#include <time.h>

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace stepnode::bench {

// CPU time of this process (user + system), in seconds.
double process_cpu_s();
// The time of `clock` (CLOCK_THREAD_CPUTIME_ID, a thread's CPU clock, ...), in seconds.
double clock_s(clockid_t clock);
// A "VmRSS:"-style line of /proc/self/status, in kB (0 when it is missing).
long status_kb(const char* key);
// The value at fraction `p` (0..1) of sorted values (0 when there are none).
int64_t percentile(const std::vector<int64_t>& sorted, double p);
// Registers the AxisPosition type as the bridge names it and creates its topic. Throws
// std::runtime_error when Fast DDS refuses either.
eprosima::fastdds::dds::Topic* register_axis_position(
    eprosima::fastdds::dds::DomainParticipant* participant);

// The subscriber process (pipeline_bench --subscriber): answers commands on stdin, see
// pipeline_subscriber.cpp. Throws std::runtime_error when Fast DDS refuses its set-up.
int run_subscriber(uint32_t domain, const std::string& profiles, int32_t depth,
                   uint32_t port_queue);

// The publishing process's end of the subscriber process: starts it (this program again,
// `exe` --subscriber), announces each run and reads its report.
class SubscriberProcess {
 public:
  SubscriberProcess(const std::string& exe, uint32_t domain, const std::string& profiles,
                    int32_t depth, uint32_t port_queue);
  ~SubscriberProcess();
  SubscriberProcess(const SubscriberProcess&) = delete;
  SubscriberProcess& operator=(const SubscriberProcess&) = delete;

  void begin(int32_t first, int32_t end);
  struct Result {
    uint64_t received = 0, duplicates = 0;
    int64_t p50 = 0, p99 = 0, max = 0;
    double cpu_s = 0;
  };
  Result report();

 private:
  std::string expect_line();
  pid_t pid_ = 0;
  FILE* out_ = nullptr;
  FILE* in_ = nullptr;
};

}  // namespace stepnode::bench
