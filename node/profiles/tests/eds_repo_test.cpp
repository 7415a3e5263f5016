// The EDS committed at the repository root (stepnode.eds) is the one the dictionary table
// generates for the default DeviceInfo{}. When the object map changes, regenerate it:
//   STEPNODE_WRITE_EDS=1 build/node/device_objects_tests --gtest_filter='*Eds*Repo*'
// and commit the file.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "node/profiles/tests/stepnode_device.hpp"
#include "od/eds.hpp"

#ifndef STEPNODE_SOURCE_DIR
#error "device_objects_tests needs STEPNODE_SOURCE_DIR (see node/CMakeLists.txt)"
#endif

namespace stepnode::od {
namespace {

std::string generated_eds() {
  Dictionary od;
  DeviceInfo info;
  info.description = node::DeviceLayout{}.description();  // as the node describes itself
  build_stepnode_device(od, info);
  return write_eds(od, info);
}

std::string first_difference(const std::string& a, const std::string& b) {
  std::istringstream x(a), y(b);
  std::string lx, ly;
  for (int line = 1;; ++line) {
    bool gx = static_cast<bool>(std::getline(x, lx)), gy = static_cast<bool>(std::getline(y, ly));
    if (!gx && !gy) return "none";
    if (!gx || !gy || lx != ly)
      return "line " + std::to_string(line) + ": file has '" + (gx ? lx : "<end>") +
             "', generator has '" + (gy ? ly : "<end>") + "'";
  }
}

TEST(EdsRepo, StepnodeEdsEqualsTheGenerator) {
  const std::string path = std::string(STEPNODE_SOURCE_DIR) + "/stepnode.eds";
  const std::string generated = generated_eds();
  if (const char* w = std::getenv("STEPNODE_WRITE_EDS"); w && *w && std::string(w) != "0") {
    std::ofstream(path, std::ios::binary | std::ios::trunc) << generated;
  }
  std::ifstream in(path, std::ios::binary);
  ASSERT_TRUE(in)
      << path << " is missing. Generate it with:\n"
      << "  STEPNODE_WRITE_EDS=1 build/node/device_objects_tests --gtest_filter='*Eds*Repo*'";
  std::stringstream file;
  file << in.rdbuf();
  EXPECT_TRUE(file.str() == generated)
      << path << " differs from the dictionary (first difference: "
      << first_difference(file.str(), generated) << ").\n"
      << "Regenerate it and commit it:\n"
      << "  STEPNODE_WRITE_EDS=1 build/node/device_objects_tests --gtest_filter='*Eds*Repo*'";
}

TEST(EdsRepo, StepnodeEdsIsAValidEdsOfTheDevice) {
  std::ifstream in(std::string(STEPNODE_SOURCE_DIR) + "/stepnode.eds", std::ios::binary);
  ASSERT_TRUE(in);
  std::stringstream file;
  file << in.rdbuf();
  EdsFile eds = parse_eds(file.str());
  EXPECT_EQ(eds.sections["fileinfo"]["filename"], "stepnode.eds");
  Dictionary od;
  build_stepnode_device(od, DeviceInfo{});
  size_t entries = 0;
  for (const auto& [index, obj] : od.objects()) entries += obj.entries.size();
  EXPECT_EQ(eds.entries.size(), entries);
  ASSERT_NE(eds.find(0x1018, 2), nullptr);
  EXPECT_EQ(eds.find(0x1018, 2)->name, "Identity object / Product code");
}

}  // namespace
}  // namespace stepnode::od
