// The layout rule of docs/architecture.md §1: a stage's algorithm library (slamaware_<stage>, the
// sources its CMakeLists.txt lists, and the headers of its own folder they include, followed
// transitively) includes no LCM header (generated slamaware/*.hpp, <lcm/...>, common/bus/) and no
// header of another folder of procs/ or tools/. The checker is first shown to catch both on a
// made-up stage.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>

#include "tests/support/test_support.h"

namespace fs = std::filesystem;

namespace {

// The .cpp files of `add_library(slamaware_<stage> STATIC ...)` in <folder>/CMakeLists.txt.
std::vector<std::string> librarySources(const fs::path& root, const std::string& folder,
                                        const std::string& stage) {
  const std::string cmake =
      slamaware::test::readTextFile((root / folder / "CMakeLists.txt").string());
  const std::regex lib("add_library\\(slamaware_" + stage + " STATIC([^)]*)\\)");
  std::smatch m;
  if (!std::regex_search(cmake, m, lib)) return {};
  std::vector<std::string> files;
  std::istringstream words(m[1].str());
  for (std::string w; words >> w;)
    if (w.size() > 4 && w.substr(w.size() - 4) == ".cpp") files.push_back(folder + "/" + w);
  return files;
}

struct Violation {
  std::string file, include;
};

// Every forbidden include reachable from the sources of the library slamaware_<stage> in
// `folder` (procs/<stage>, or tools/synth for the generator); `scanned` counts the files.
std::vector<Violation> forbiddenIncludes(const fs::path& root, const std::string& folder,
                                         const std::string& stage, int* scanned) {
  const std::string own = folder + "/";
  std::vector<std::string> todo = librarySources(root, folder, stage);
  std::set<std::string> seen(todo.begin(), todo.end());
  std::vector<Violation> bad;
  const std::regex include_re("^\\s*#\\s*include\\s*[<\"]([^>\"]+)[>\"]");
  *scanned = 0;
  while (!todo.empty()) {
    const std::string file = todo.back();
    todo.pop_back();
    std::ifstream in(root / file);
    if (!in) continue;
    ++*scanned;
    for (std::string line; std::getline(in, line);) {
      std::smatch m;
      if (!std::regex_search(line, m, include_re)) continue;
      const std::string inc = m[1].str();
      const bool lcm = inc.rfind("slamaware/", 0) == 0 || inc.rfind("lcm/", 0) == 0 ||
                       inc.rfind("common/bus/", 0) == 0;
      const bool other_stage =
          (inc.rfind("procs/", 0) == 0 || inc.rfind("tools/", 0) == 0) && inc.rfind(own, 0) != 0;
      if (lcm || other_stage) bad.push_back({file, inc});
      if (inc.rfind(own, 0) == 0 && seen.insert(inc).second) todo.push_back(inc);
    }
  }
  return bad;
}

std::string describe(const std::vector<Violation>& v) {
  std::string s;
  for (const Violation& x : v) s += "  " + x.file + " includes " + x.include + "\n";
  return s;
}

TEST(Layout, TheCheckerFindsLcmAndOtherStagesInAMadeUpStage) {
  const fs::path root = slamaware::test::tempDir("layout_check");
  fs::create_directories(root / "procs/demo");
  std::ofstream(root / "procs/demo/CMakeLists.txt")
      << "add_library(slamaware_demo STATIC a.cpp\n  b.cpp)\n"
      << "add_executable(demo main.cpp)\n";
  std::ofstream(root / "procs/demo/a.cpp") << "#include \"procs/demo/a.h\"\n#include <vector>\n";
  std::ofstream(root / "procs/demo/a.h") << "#pragma once\n#include \"slamaware/pose_t.hpp\"\n";
  std::ofstream(root / "procs/demo/b.cpp")
      << "#include \"procs/slam/map/map.h\"\n#include \"common/geometry.h\"\n";
  std::ofstream(root / "procs/demo/main.cpp")
      << "#include \"common/bus/node.h\"\n";  // the node may
  int scanned = 0;
  const std::vector<Violation> bad = forbiddenIncludes(root, "procs/demo", "demo", &scanned);
  EXPECT_EQ(scanned, 3);  // a.cpp, a.h (through a.cpp), b.cpp; not the node
  ASSERT_EQ(bad.size(), 2u) << describe(bad);
  EXPECT_EQ(bad[0].include + " " + bad[1].include, "procs/slam/map/map.h slamaware/pose_t.hpp");
}

TEST(Layout, StageLibrariesIncludeNoLcmAndNoOtherStage) {
  const fs::path root = slamaware::test::sourcePath("");
  for (const std::string stage : {"slam", "proposals", "recognizer", "objectmap", "synth"}) {
    const std::string folder = (stage == "synth" ? "tools/" : "procs/") + stage;
    int scanned = 0;
    const std::vector<Violation> bad = forbiddenIncludes(root, folder, stage, &scanned);
    EXPECT_GE(scanned, 5) << stage
                          << ": the library's sources were not found in its CMakeLists.txt";
    EXPECT_TRUE(bad.empty()) << "slamaware_" << stage << " must not include LCM or another stage:\n"
                             << describe(bad);
  }
}

}  // namespace
