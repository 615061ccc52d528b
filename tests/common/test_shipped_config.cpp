// The files in config/ load with the loaders of the processes that read them, and the
// built-in defaults equal what the files say (so running without --config means the same).
#include <gtest/gtest.h>

#include "common/bus/system_config.h"
#include "common/config.h"
#include "procs/camera/camera_options.h"
#include "tests/support/test_support.h"

using namespace slamaware;

TEST(ShippedConfig, SystemYamlEqualsDefaults) {
  SystemConfig file = loadSystemConfig(test::sourcePath("config/system.yaml"), false);
  SystemConfig defaults = loadSystemConfig("", false);
  EXPECT_TRUE(optionsEqual(file.bus, defaults.bus));
  EXPECT_TRUE(optionsEqual(file.scheduling, defaults.scheduling));
  EXPECT_TRUE(optionsEqual(file.channels, defaults.channels));
}

TEST(ShippedConfig, CameraYamlEqualsDefaults) {
  camera::CameraOptions file =
      loadConfig<camera::CameraOptions>(test::sourcePath("config/camera.yaml"), "camera", false);
  camera::CameraOptions defaults;
  EXPECT_TRUE(optionsEqual(file, defaults)) << describeOptions(optionListOf(file));
  EXPECT_EQ(test::readTextFile(test::sourcePath("config/camera.yaml")),
            defaultConfigFileText<camera::CameraOptions>("camera"))
      << "config/camera.yaml is generated from the built-in defaults: make configs";
}
