// The stepwatch executable against an in-process bridge publisher on a domain of its own:
// --once --json gets the TRANSIENT_LOCAL state of every node and axis; bad input exits 2.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "bridge/dds/publisher.hpp"
#include "bridge/dds/tests/test_domain.hpp"

namespace stepnode::stepwatch {
namespace {

struct Result {
  int status = -1;
  std::string out;
};

Result run(const std::string& args) {
  std::string command = std::string(STEPWATCH_EXE) + " " + args + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  Result r;
  char buf[4096];
  while (fgets(buf, sizeof buf, pipe)) r.out += buf;
  int raw = pclose(pipe);
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  return r;
}

TEST(StepwatchCli, OnceJsonPrintsEveryNodeAndAxisOfALateJoin) {
  uint32_t domain = bridge::dds::test::unique_test_domain();
  bridge::dds::PublisherOptions options;
  options.participant.domain = domain;
  bridge::dds::DdsPublisher publisher(options);
  bridge::NodeHealthSample h;
  h.node = 5;
  h.state = bridge::NodeState::Operational;
  h.device_name = "stepnode";
  h.axes = 2;
  publisher.node_health(h);
  for (uint8_t axis : {1, 2}) {
    bridge::AxisStatusSample s;
    s.node = 5;
    s.axis = axis;
    s.status_bits = axis == 1 ? 0x1100 : 0x8100;
    publisher.axis_status(s);
  }
  Result r = run("--once --json --wait-ms 10000 --domain " + std::to_string(domain));
  ASSERT_EQ(r.status, 0) << r.out;
  std::vector<nlohmann::json> lines;
  size_t start = 0;
  while (start < r.out.size()) {
    size_t end = r.out.find('\n', start);
    lines.push_back(nlohmann::json::parse(r.out.substr(start, end - start)));
    start = end + 1;
  }
  ASSERT_EQ(lines.size(), 3u) << r.out;
  EXPECT_EQ(lines[0]["type"], "node");
  EXPECT_EQ(lines[0]["state"], "OPERATIONAL");
  EXPECT_EQ(lines[1]["axis"], 1);
  EXPECT_EQ(lines[1]["status"]["at_home"], true);
  EXPECT_EQ(lines[2]["axis"], 2);
  EXPECT_EQ(lines[2]["status"]["moving"], true);
}

TEST(StepwatchCli, OnceWithNoBridgeExits1) {
  Result r = run("--once --wait-ms 300 --domain " +
                 std::to_string(bridge::dds::test::unique_test_domain()));
  EXPECT_EQ(r.status, 1) << r.out;
  EXPECT_NE(r.out.find("no samples on DDS domain"), std::string::npos) << r.out;
}

TEST(StepwatchCli, LiveJsonStreamsSamples) {
  uint32_t domain = bridge::dds::test::unique_test_domain();
  bridge::dds::PublisherOptions options;
  options.participant.domain = domain;
  bridge::dds::DdsPublisher publisher(options);
  std::atomic<bool> done{false};
  std::thread writer([&] {
    bridge::AxisPositionSample p;
    p.node = 9;
    p.axis = 1;
    for (int i = 0; !done; ++i) {
      p.motor_position = i;
      publisher.axis_position(p);
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });
  Result r = run("--json --count 3 --duration-ms 15000 --domain " + std::to_string(domain));
  done = true;
  writer.join();
  ASSERT_EQ(r.status, 0) << r.out;
  auto first = nlohmann::json::parse(r.out.substr(0, r.out.find('\n')));
  EXPECT_EQ(first["type"], "axis_position");
  EXPECT_EQ(first["node"], 9);
  EXPECT_GT(first["recv_time_ns"].get<uint64_t>(), first["publish_time_ns"].get<uint64_t>() - 1);
}

TEST(StepwatchCli, BadArgumentsExit2WithOneLine) {
  for (const char* args :
       {"--domain 300", "--ros2-prefix x", "--wait-ms 5", "--bogus", "--ros2 --ros2-prefix a//b",
        "--once --count 3", "--once --profiles /nonexistent/stepwatch.xml"}) {
    Result r = run(args);
    EXPECT_EQ(r.status, 2) << args << ": " << r.out;
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << args << ": " << r.out;
    EXPECT_EQ(r.out.rfind("stepwatch: ", 0), 0u) << args << ": " << r.out;
  }
}

}  // namespace
}  // namespace stepnode::stepwatch
