// Fuzz target: the LCM log reader (LogReader over lcm::LogFile), as slamaware-replay, the camera's
// log source and the evaluator read recordings. Input: the bytes of a log file. Every event it
// returns is also summarised and stamped like the tools do.
// Checks beyond "no crash": events come in file order, each starting where the previous ended,
// and a damaged log is reported with an offset inside the file.
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "common/bus/frame_stamp.h"
#include "common/bus/log_reader.h"
#include "common/bus/type_registry.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace slamaware;
  const std::string path = fuzz::scratchDir() + "/session.lcm";
  fuzz::writeFile(path, data, size);
  try {
    LogReader reader(path);
    int64_t previous_end = 0;
    while (auto record = reader.next()) {
      if (record->offset != previous_end) {
        std::fprintf(stderr, "fuzz_log_reader: event at %lld, previous ended at %lld\n",
                     static_cast<long long>(record->offset), static_cast<long long>(previous_end));
        std::abort();
      }
      previous_end = record->offset + 4 + 8 + 8 + 4 + 4 +
                     static_cast<int64_t>(record->channel.size()) +
                     static_cast<int64_t>(record->data.size());
      if (previous_end > static_cast<int64_t>(size)) {
        std::fprintf(stderr, "fuzz_log_reader: an event ends after the end of the file\n");
        std::abort();
      }
      summarizeMessage(record->data.data(), record->data.size());
      peekFrameStamp(record->data.data(), record->data.size());
    }
  } catch (const LogError& e) {
    if (e.offset() < -1 || e.offset() > static_cast<int64_t>(size)) {
      std::fprintf(stderr, "fuzz_log_reader: damage reported at %lld in a file of %zu bytes\n",
                   static_cast<long long>(e.offset()), size);
      std::abort();
    }
  }
  return 0;
}
