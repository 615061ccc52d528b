// Config: defaults, nested sections, and errors that name the file, line and key.
#include <gtest/gtest.h>

#include <fstream>

#include "common/bus/system_config.h"
#include "common/config.h"
#include "tests/support/test_support.h"

using namespace slamaware;

namespace {

struct FilterOptions {
  double min_depth = 0.1;
  int iterations = 5;
  template <class V>
  void visit(V& v) {
    v("min_depth", min_depth, "m");
    v("iterations", iterations, "");
  }
};

struct ToyOptions {
  bool enabled = true;
  int count = 3;
  uint64_t seed = 42;
  double ratio = 0.5;
  std::string name = "toy";
  std::vector<double> weights = {1, 2};
  std::vector<std::string> tags = {"a"};
  FilterOptions filter;
  template <class V>
  void visit(V& v) {
    v("enabled", enabled, "switch");
    v("count", count, "how many");
    v("seed", seed, "random seed");
    v("ratio", ratio, "a ratio");
    v("name", name, "a name");
    v("weights", weights, "weights");
    v("tags", tags, "tags");
    v.section("filter", filter);
  }
};

std::string writeYaml(const std::string& name, const std::string& text) {
  // A folder per test: ctest runs the cases of this file in parallel.
  const std::string path =
      test::tempDir(std::string("config_") +
                    ::testing::UnitTest::GetInstance()->current_test_info()->name()) +
      "/" + name;
  std::ofstream(path) << text;
  return path;
}

std::string errorOf(const std::string& yaml, const std::string& section = "toy") {
  const std::string path = writeYaml("bad.yaml", yaml);
  try {
    loadConfig<ToyOptions>(path, section, false);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(Config, AMisspeltOrForeignSectionIsRefusedNotIgnored) {
  // `tracking:` where `toy:` was meant: the component must not run on its defaults silently.
  const std::string misspelt = errorOf("tracking:\n  count: 7\n");
  EXPECT_NE(misspelt.find("bad.yaml:1"), std::string::npos) << misspelt;
  EXPECT_NE(misspelt.find("unknown section 'tracking'"), std::string::npos) << misspelt;
  EXPECT_NE(misspelt.find("known: toy"), std::string::npos) << misspelt;
  // Beside the right section too.
  const std::string extra = errorOf("toy:\n  count: 7\nother: {anything: 1}\n");
  EXPECT_NE(extra.find("bad.yaml:3"), std::string::npos) << extra;
  EXPECT_NE(extra.find("unknown section 'other'"), std::string::npos) << extra;
}

TEST(Config, DefaultsWithoutFile) {
  const ToyOptions o = loadConfig<ToyOptions>("", "toy", false);
  EXPECT_EQ(o.count, 3);
  EXPECT_EQ(o.filter.iterations, 5);
}

TEST(Config, LoadsValuesAndNestedSections) {
  const std::string path =
      writeYaml("ok.yaml",
                "toy:\n  count: 7\n  seed: 18446744073709551615\n  ratio: 2\n  name: x\n"
                "  weights: [3.5, 4]\n  tags: [p, q]\n  filter:\n    min_depth: 0.25\n");
  const ToyOptions o = loadConfig<ToyOptions>(path, "toy", false);
  EXPECT_EQ(o.count, 7);
  EXPECT_EQ(o.seed, 18446744073709551615ull);
  EXPECT_DOUBLE_EQ(o.ratio, 2.0);
  EXPECT_EQ(o.name, "x");
  EXPECT_EQ(o.weights, (std::vector<double>{3.5, 4}));
  EXPECT_EQ(o.tags, (std::vector<std::string>{"p", "q"}));
  EXPECT_DOUBLE_EQ(o.filter.min_depth, 0.25);
  EXPECT_EQ(o.filter.iterations, 5) << "keys absent from the file keep their defaults";
}

TEST(Config, UnknownKeyNamesKeyFileAndLine) {
  const std::string e = errorOf("toy:\n  count: 1\n  cuont: 2\n");
  EXPECT_NE(e.find("unknown key 'cuont'"), std::string::npos) << e;
  EXPECT_NE(e.find("bad.yaml:3"), std::string::npos) << e;
  EXPECT_NE(e.find("count"), std::string::npos) << "lists the known keys: " << e;
}

TEST(Config, AKeyThatIsNotAPlainNameIsRefusedNamingTheFile) {
  // Found by fuzz_config (tests/fuzz/regressions/fuzz_config/scene-key-not-a-plain-name): a key
  // that is a list or a map escaped as a yaml-cpp exception without the file.
  for (const std::string yaml : {"toy:\n  ? [a, b]\n  : 1\n", "? {a: 1}\n: 2\n"}) {
    const std::string e = errorOf(yaml);
    EXPECT_NE(e.find("bad.yaml"), std::string::npos) << yaml << " -> " << e;
    EXPECT_NE(e.find("a key must be a plain name"), std::string::npos) << yaml << " -> " << e;
  }
}

TEST(Config, UnknownNestedKey) {
  const std::string e = errorOf("toy:\n  filter:\n    min_dpth: 1\n");
  EXPECT_NE(e.find("unknown key 'filter.min_dpth'"), std::string::npos) << e;
}

TEST(Config, IllTypedValues) {
  EXPECT_NE(errorOf("toy:\n  count: abc\n").find("key 'count': expected an integer, got 'abc'"),
            std::string::npos);
  EXPECT_NE(errorOf("toy:\n  count: 1.5\n").find("key 'count': expected an integer"),
            std::string::npos);
  EXPECT_NE(errorOf("toy:\n  enabled: maybe\n").find("key 'enabled': expected true or false"),
            std::string::npos);
  EXPECT_NE(errorOf("toy:\n  ratio: [1]\n").find("key 'ratio': expected a number, got a list"),
            std::string::npos);
  EXPECT_NE(errorOf("toy:\n  ratio: .nan\n").find("finite"), std::string::npos);
  EXPECT_NE(errorOf("toy:\n  weights: 3\n").find("key 'weights': expected a list"),
            std::string::npos);
  EXPECT_NE(errorOf("toy:\n  weights: [1, x]\n").find("key 'weights[1]'"), std::string::npos);
  EXPECT_NE(errorOf("toy:\n  filter: 3\n").find("key 'filter': expected a map"), std::string::npos);
  EXPECT_NE(errorOf("toy: 3\n").find("section 'toy': expected a map"), std::string::npos);
}

TEST(Config, SyntaxErrorAndMissingFile) {
  EXPECT_NE(errorOf("toy: [\n").find("YAML syntax error"), std::string::npos);
  try {
    loadConfig<ToyOptions>("/nonexistent/dir/x.yaml", "toy", false);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot open"), std::string::npos);
  }
}

TEST(Config, DescribeRoundTripsAndEquals) {
  ToyOptions a;
  a.count = 11;
  a.name = "with \"quotes\": and colon";
  a.filter.min_depth = 0.123456789012345;
  a.weights = {0.1, 1e-9};
  const std::string text = "toy:\n" + [&] {
    std::string d = describeOptions(optionListOf(a)), out;
    size_t start = 0;
    while (start < d.size()) {
      const size_t nl = d.find('\n', start);
      out += "  " + d.substr(start, nl - start + 1);
      start = nl + 1;
    }
    return out;
  }();
  const ToyOptions b = loadConfig<ToyOptions>(writeYaml("round.yaml", text), "toy", false);
  ToyOptions a2 = a, b2 = b;
  EXPECT_TRUE(optionsEqual(a2, b2)) << text;
  ToyOptions c;
  EXPECT_FALSE(optionsEqual(a2, c));
}

TEST(Config, SystemConfigRejectsUnknownSection) {
  const std::string path =
      writeYaml("system.yaml", "bus:\n  lockstep: true\nchanels:\n  camera: X\n");
  try {
    loadSystemConfig(path, false);
    FAIL() << "an unknown section must be refused";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown section 'chanels'"), std::string::npos)
        << e.what();
  }
}

TEST(Config, SchedulingNiceOutOfRangeIsRefused) {
  const std::string ok = writeYaml("system3.yaml",
                                   "scheduling:\n  recognizer_nice: 0\n  background_nice: 19\n"
                                   "  slam_mapping_nice: 1\n  slam_depth_nice: 3\n");
  const SystemConfig sys = loadSystemConfig(ok, false);
  EXPECT_EQ(sys.scheduling.recognizer_nice, 0);
  EXPECT_EQ(sys.scheduling.background_nice, 19);
  EXPECT_EQ(sys.scheduling.slam_mapping_nice, 1);
  EXPECT_EQ(sys.scheduling.slam_depth_nice, 3);
  for (const char* text :
       {"scheduling:\n  recognizer_nice: -5\n", "scheduling:\n  background_nice: 20\n",
        "scheduling:\n  slam_mapping_nice: -1\n", "scheduling:\n  slam_depth_nice: 20\n"}) {
    const std::string path = writeYaml("system4.yaml", text);
    try {
      loadSystemConfig(path, false);
      FAIL() << "must be refused: " << text;
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("_nice': a nice increment is 0..19"), std::string::npos)
          << e.what();
      EXPECT_NE(std::string(e.what()).find("system4.yaml"), std::string::npos) << e.what();
    }
  }
}

TEST(Config, LockstepWindowOutOfRangeIsRefused) {
  EXPECT_EQ(loadSystemConfig(writeYaml("system5.yaml", "bus:\n  lockstep_window: 1\n"), false)
                .bus.lockstep_window,
            1);
  for (const char* text : {"bus:\n  lockstep_window: 0\n", "bus:\n  lockstep_window: 1000\n"}) {
    const std::string path = writeYaml("system6.yaml", text);
    try {
      loadSystemConfig(path, false);
      FAIL() << "must be refused: " << text;
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("system6.yaml: key 'bus.lockstep_window'"),
                std::string::npos)
          << e.what();
    }
  }
}

TEST(Config, ChannelPrefixAndStatusNames) {
  const std::string path = writeYaml("system2.yaml", "channels:\n  prefix: R1_\n  camera: CAM\n");
  const SystemConfig sys = loadSystemConfig(path, false);
  EXPECT_EQ(sys.channels.camera, "R1_CAM");
  EXPECT_EQ(sys.channels.slam_pose, "R1_SLAM_POSE");
  EXPECT_EQ(sys.channels.statusOf("slam"), "R1_SLAM_STATUS");
}
