// The log reader tells a corrupt log from its end, and says where.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>

#include "common/bus/log_reader.h"
#include "tests/support/test_support.h"

using namespace slamaware;

namespace {

// Writes a log of n events with lcm::LogFile; returns the byte offsets of the events.
std::vector<int64_t> writeLog(const std::string& path, int n) {
  lcm::LogFile log(path, "w");
  std::vector<int64_t> offsets;
  for (int i = 0; i < n; ++i) {
    std::string payload(100 + i, static_cast<char>('a' + i % 26));
    lcm::LogEvent ev;
    ev.eventnum = i;
    ev.timestamp = 1000 + i;
    ev.channel = "CHANNEL_" + std::to_string(i % 3);
    ev.datalen = static_cast<int32_t>(payload.size());
    ev.data = payload.data();
    offsets.push_back(std::ftell(log.getFilePtr()));
    log.writeEvent(&ev);
  }
  return offsets;
}

std::vector<uint8_t> readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(in), {});
}
void writeBytes(const std::string& path, const std::vector<uint8_t>& b) {
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(b.data()), b.size());
}

// Reads a log with only `spare` bytes of address space left; 0 when it stops at `damaged` after
// the events before it.
int readWithSpareAddressSpace(const std::string& path, long spare, int64_t damaged) {
  long pages = 0;
  std::ifstream("/proc/self/statm") >> pages;
  const rlim_t limit = static_cast<rlim_t>(pages * sysconf(_SC_PAGESIZE) + spare);
  const rlimit rl{limit, limit};
  setrlimit(RLIMIT_AS, &rl);
  int n = 0;
  try {
    LogReader reader(path);
    while (reader.next()) ++n;
  } catch (const LogError& e) {
    return n == 3 && e.offset() == damaged ? 0 : 2;
  }
  return 3;
}

}  // namespace

TEST(LogReader, ReadsAWholeLog) {
  const std::string path = test::tempDir("log_ok") + "/ok.lcm";
  writeLog(path, 10);
  const auto events = LogReader::readAll(path);
  ASSERT_EQ(events.size(), 10u);
  EXPECT_EQ(events[3].channel, "CHANNEL_0");
  EXPECT_EQ(events[3].timestamp, 1003);
  EXPECT_EQ(events[9].data.size(), 109u);
}

TEST(LogReader, EmptyLogIsACleanEnd) {
  const std::string path = test::tempDir("log_empty") + "/empty.lcm";
  writeBytes(path, {});
  EXPECT_TRUE(LogReader::readAll(path).empty());
}

TEST(LogReader, TruncatedLogIsAnErrorWithOffset) {
  const std::string path = test::tempDir("log_trunc") + "/t.lcm";
  const auto offsets = writeLog(path, 10);
  auto bytes = readBytes(path);
  bytes.resize(offsets[7] + 30);  // cut inside event 7
  writeBytes(path, bytes);
  LogReader reader(path);
  int n = 0;
  try {
    while (reader.next()) ++n;
    FAIL() << "a truncated log must not end silently";
  } catch (const LogError& e) {
    EXPECT_EQ(n, 7);
    EXPECT_EQ(e.offset(), offsets[7]);
    EXPECT_NE(std::string(e.what()).find("byte offset " + std::to_string(offsets[7])),
              std::string::npos)
        << e.what();
  }
}

TEST(LogReader, DamagedHeaderIsAnErrorWithOffset) {
  const std::string path = test::tempDir("log_hdr") + "/h.lcm";
  const auto offsets = writeLog(path, 10);
  for (int damaged : {0, 4}) {
    auto bytes = readBytes(path);
    bytes[offsets[damaged]] ^= 0xFF;  // break the sync word of one event
    const std::string bad = path + std::to_string(damaged);
    writeBytes(bad, bytes);
    try {
      LogReader::readAll(bad);
      FAIL() << "a damaged header must not be skipped silently";
    } catch (const LogError& e) {
      EXPECT_EQ(e.offset(), offsets[damaged]) << e.what();
    }
  }
}

TEST(LogReader, GarbageBetweenEventsIsAnError) {
  const std::string path = test::tempDir("log_garbage") + "/g.lcm";
  const auto offsets = writeLog(path, 5);
  auto bytes = readBytes(path);
  bytes.insert(bytes.begin() + offsets[2], {0x01, 0x02, 0x03});
  writeBytes(path, bytes);
  try {
    LogReader::readAll(path);
    FAIL();
  } catch (const LogError& e) {
    EXPECT_EQ(e.offset(), offsets[2]);
  }
}

TEST(LogReader, DamagedLengthFieldIsAnError) {
  const std::string path = test::tempDir("log_len") + "/l.lcm";
  const auto offsets = writeLog(path, 5);
  auto bytes = readBytes(path);
  // data length field of event 3: sync(4) eventnum(8) timestamp(8) channellen(4) -> datalen
  bytes[offsets[3] + 24] = 0x7f;
  writeBytes(path, bytes);
  EXPECT_THROW(LogReader::readAll(path), LogError);
}

// A header claiming 2 GB is refused before anything is allocated: with 256 MB of address space to
// spare, LCM's reader (which allocates the claimed length unchecked) would write through NULL.
TEST(LogReader, AHugeClaimedLengthIsRefusedBeforeAllocation) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "an address-space limit and AddressSanitizer's shadow memory do not mix";
#else
  const std::string path = test::tempDir("log_huge") + "/l.lcm";
  const auto offsets = writeLog(path, 5);
  auto bytes = readBytes(path);
  bytes[offsets[3] + 24] = 0x7f;
  bytes[offsets[3] + 25] = 0xff;
  bytes[offsets[3] + 26] = 0xff;
  bytes[offsets[3] + 27] = 0x00;
  writeBytes(path, bytes);
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(std::exit(readWithSpareAddressSpace(path, 256 << 20, offsets[3])),
              ::testing::ExitedWithCode(0), "");
#endif
}

TEST(LogReader, MissingFile) { EXPECT_THROW(LogReader("/nonexistent/x.lcm"), LogError); }
