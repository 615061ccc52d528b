// config/slam.yaml loads with the node's loader and equals the built-in defaults (running without
// --config means the same); a misspelt key is refused with its name.
#include <gtest/gtest.h>

#include <fstream>

#include "common/config.h"
#include "procs/slam/slam_options.h"
#include "tests/support/test_support.h"

using namespace slamaware;
using namespace slamaware::slam;

TEST(SlamConfig, ShippedFileEqualsTheDefaults) {
  SlamOptions file = loadConfig<SlamOptions>(test::sourcePath("config/slam.yaml"), "slam", false);
  SlamOptions defaults;
  EXPECT_TRUE(optionsEqual(file, defaults)) << describeOptions(optionListOf(file));
  EXPECT_EQ(test::readTextFile(test::sourcePath("config/slam.yaml")),
            defaultConfigFileText<SlamOptions>("slam"))
      << "config/slam.yaml is generated from the built-in defaults: make configs";
}

TEST(SlamConfig, AMisspeltKeyIsRefused) {
  const std::string path = test::tempDir("slam_config") + "/bad.yaml";
  std::ofstream(path) << "slam:\n  depth:\n    max_seed_per_keyframe: 10\n";
  try {
    loadConfig<SlamOptions>(path, "slam", false);
    FAIL() << "accepted an unknown key";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("max_seed_per_keyframe"), std::string::npos) << e.what();
  }
}
