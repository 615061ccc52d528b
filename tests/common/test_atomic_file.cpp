// common/atomic_file: the CRC-32 is the standard one (zlib/PNG check value), chains over pieces,
// and the atomic writer leaves the complete new content and no temporary file behind, or throws
// naming the file.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>

#include "common/atomic_file.h"
#include "tests/support/test_support.h"

using namespace slamaware;
namespace fs = std::filesystem;

namespace {

std::string readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

}  // namespace

TEST(AtomicFile, Crc32IsTheStandardCheckValue) {
  const std::string s = "123456789";
  EXPECT_EQ(crc32(s.data(), s.size()), 0xCBF43926u);
  EXPECT_EQ(crc32(s.data(), 0), 0u);
  // Continuing over a second piece gives the CRC of the whole.
  EXPECT_EQ(crc32(s.data() + 4, 5, crc32(s.data(), 4)), 0xCBF43926u);
  // One flipped bit changes it.
  std::string t = s;
  t[3] ^= 0x10;
  EXPECT_NE(crc32(t.data(), t.size()), 0xCBF43926u);
}

TEST(AtomicFile, WritesReplacesAndLeavesNoTemporary) {
  const std::string dir = test::tempDir("atomic_file");
  const std::string path = dir + "/sub/folder/file.bin";  // parent folders are created
  const std::string first(100000, 'a');
  writeFileAtomic(path, first.data(), first.size());
  EXPECT_EQ(readAll(path), first);
  const std::string second = "short";
  writeFileAtomic(path, second.data(), second.size());
  EXPECT_EQ(readAll(path), second);
  writeFileAtomic(dir + "/empty", nullptr, 0);
  EXPECT_EQ(fs::file_size(dir + "/empty"), 0u);
  for (const auto& e : fs::recursive_directory_iterator(dir))
    EXPECT_EQ(e.path().filename().string().find(".tmp."), std::string::npos) << e.path();
}

TEST(AtomicFile, FailureNamesTheFile) {
  const std::string dir = test::tempDir("atomic_file_fail");
  const std::string blocker = dir + "/not_a_folder";
  writeFileAtomic(blocker, "x", 1);
  const std::string path = blocker + "/file.bin";  // its parent is a regular file
  try {
    writeFileAtomic(path, "y", 1);
    FAIL() << "expected an exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}
