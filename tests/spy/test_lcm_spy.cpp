// lcm-spy sees our types: every type loads from the generated jar through lcm-spy's own type
// database, and its Java fingerprint equals the C++ one. Headless (no window is opened).
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include "slamaware/box_t.hpp"
#include "slamaware/camera_info_t.hpp"
#include "slamaware/detections_t.hpp"
#include "slamaware/image_t.hpp"
#include "slamaware/keyframe_t.hpp"
#include "slamaware/object_detections_t.hpp"
#include "slamaware/object_map_t.hpp"
#include "slamaware/object_query_reply_t.hpp"
#include "slamaware/object_query_t.hpp"
#include "slamaware/object_t.hpp"
#include "slamaware/point_cloud_t.hpp"
#include "slamaware/pose_t.hpp"
#include "slamaware/proc_command_t.hpp"
#include "slamaware/proc_info_t.hpp"
#include "slamaware/proc_status_t.hpp"
#include "slamaware/proposals_t.hpp"
#include "slamaware/status_t.hpp"
#include "tests/support/test_support.h"

using namespace slamaware;

namespace {
std::string run(const std::string& cmd, int* rc = nullptr) {
  FILE* p = popen((cmd + " 2>&1").c_str(), "r");
  if (!p) return "";
  std::string out;
  char buf[256];
  while (fgets(buf, sizeof(buf), p)) out += buf;
  const int status = pclose(p);
  if (rc) *rc = status;
  return out;
}

// name=fingerprint=file, the file holding a C++-encoded default message of the type.
const std::string& messageDir() {
  static const std::string dir = test::tempDir("lcm_spy");
  return dir;
}

template <class T>
std::string arg(const char* name) {
  const std::string& dir = messageDir();
  const T msg{};
  std::vector<uint8_t> bytes(msg.getEncodedSize());
  msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  const std::string path = dir + "/" + name + ".bin";
  FILE* f = std::fopen(path.c_str(), "wb");
  std::fwrite(bytes.data(), 1, bytes.size(), f);
  std::fclose(f);
  return std::string(name) + "=" + std::to_string(T::getHash()) + "=" + path;
}
}  // namespace

TEST(LcmSpy, EveryTypeLoadsFromTheJarWithTheCppFingerprint) {
  const std::string jar = std::string(SLAMAWARE_BIN_DIR) + "/../lcmtypes/slamaware_lcmtypes.jar";
  ASSERT_TRUE(std::filesystem::exists(jar)) << jar;
  const std::vector<std::string> types = {arg<box_t>("box_t"),
                                          arg<camera_info_t>("camera_info_t"),
                                          arg<detections_t>("detections_t"),
                                          arg<image_t>("image_t"),
                                          arg<keyframe_t>("keyframe_t"),
                                          arg<object_detections_t>("object_detections_t"),
                                          arg<object_map_t>("object_map_t"),
                                          arg<object_query_reply_t>("object_query_reply_t"),
                                          arg<object_query_t>("object_query_t"),
                                          arg<object_t>("object_t"),
                                          arg<point_cloud_t>("point_cloud_t"),
                                          arg<pose_t>("pose_t"),
                                          arg<proc_command_t>("proc_command_t"),
                                          arg<proc_info_t>("proc_info_t"),
                                          arg<proc_status_t>("proc_status_t"),
                                          arg<proposals_t>("proposals_t"),
                                          arg<status_t>("status_t")};
  // The class path of our lcm-spy wrapper, so that this tests what users run.
  const std::string classpath = run("BUILD=" + std::string(SLAMAWARE_BIN_DIR) + "/.. " +
                                    test::sourcePath("scripts/lcm-spy") + " --classpath");
  ASSERT_NE(classpath.find("slamaware_lcmtypes.jar"), std::string::npos) << classpath;
  std::string cmd = "java -Djava.awt.headless=true -cp " +
                    classpath.substr(0, classpath.find('\n')) + ":" + SLAMAWARE_SPY_CLASSES +
                    " CheckTypes";
  for (const auto& t : types) cmd += " " + t;
  int rc = 0;
  const std::string out = run(cmd, &rc);
  EXPECT_EQ(rc, 0) << out;
  for (const auto& t : types) {
    const std::string name = t.substr(0, t.find('='));
    EXPECT_NE(out.find("OK " + name + "\n"), std::string::npos) << name << "\n" << out;
  }
  EXPECT_EQ(types.size(), 17u);
}

TEST(LcmSpy, WrapperScriptAvoidsRemovedJvmFlags) {
  // Debian's lcm-spy passes -Xincgc, which JDK 17 refuses; ours must not, and must put jchart2d
  // and our jar on the class path.
  FILE* f = std::fopen(test::sourcePath("scripts/lcm-spy").c_str(), "r");
  ASSERT_NE(f, nullptr);
  std::string text;
  char buf[512];
  while (fgets(buf, sizeof(buf), f))
    if (buf[0] != '#') text += buf;  // the commands, not the comments
  std::fclose(f);
  EXPECT_EQ(text.find("-Xincgc"), std::string::npos);
  EXPECT_NE(text.find("jchart2d.jar"), std::string::npos);
  EXPECT_NE(text.find("slamaware_lcmtypes.jar"), std::string::npos);
  // The JVM that runs lcm-spy must accept the flags the script uses.
  EXPECT_EQ(
      std::system("java -Djava.net.preferIPv4Stack=true -Xmx256m -ea "
                  "--add-exports java.desktop/sun.swing=ALL-UNNAMED -version > /dev/null 2>&1"),
      0);
}
