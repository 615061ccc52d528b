// Fuzz target: the object map's store (.ot trees + JSON table + checksums, map_store.h) and the
// engine's restore from it, as slamaware-objectmap loads its --map-dir at start.
// Input: one byte of flags, then parts cut by fuzz::kSeparator.
//   bit 0 clear: the parts are the files of generation 1 as they lie in the folder: the JSON,
//     then segment 0's .ot, segment 1's, ...
//   bit 0 set: the first part is the JSON content (the object table) and the others the .ot bytes
//     of its segments in order; the store writes them with correct headers and checksums, so that
//     the fuzzer reaches the content and OctoMap's reader behind the checksums.
// Checks beyond "no crash": a map the engine accepts snapshots, saves and loads again.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>

#include "procs/objectmap/json_number.h"
#include "procs/objectmap/map_store.h"
#include "procs/objectmap/object_map.h"
#include "tests/fuzz/fuzz_support.h"

namespace {

slamaware::objectmap::LoadReport loadInto(const std::string& dir,
                                          slamaware::objectmap::ObjectMapEngine* engine) {
  slamaware::objectmap::MapStore store(dir);
  return store.load([&](const slamaware::objectmap::MapSnapshot& s) { engine->restore(s); });
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace slamaware;
  using namespace slamaware::objectmap;
  if (size < 1) return 0;
  const std::vector<std::string> parts = fuzz::splitParts(data + 1, size - 1);
  const std::string root = fuzz::scratchDir();
  const std::string dir = root + "/map";
  if (data[0] & 1) {
    MapSnapshot snapshot;
    try {
      snapshot.content = nlohmann::json::parse(parts[0]);
      size_t next = 1;
      for (const auto& seg : snapshot.content.at("segments"))
        snapshot.segment_files[jsonInt<int32_t>(seg.at("id"))] =
            next < parts.size() ? parts[next++] : std::string();
      MapStore(dir).save(snapshot);
    } catch (const std::exception&) {
      return 0;  // not something the map could have saved
    }
  } else {
    fuzz::writeFile(dir + "/" + MapStore::jsonName(1), parts[0]);
    for (size_t i = 1; i < parts.size(); ++i)
      fuzz::writeFile(dir + "/" + MapStore::segmentName(1, static_cast<int32_t>(i - 1)), parts[i]);
  }
  ObjectMapEngine engine{ObjectMapOptions()};
  const LoadReport loaded = loadInto(dir, &engine);
  if (loaded.generation < 0) return 0;
  // What was accepted must survive the node's own save and load.
  const std::string again = root + "/again";
  MapStore(again).save(engine.snapshot());
  ObjectMapEngine reloaded{ObjectMapOptions()};
  const LoadReport second = loadInto(again, &reloaded);
  if (second.generation < 0) {
    std::fprintf(stderr, "fuzz_map_store: a restored map saves into one that does not load:\n");
    for (const auto& f : second.failures) std::fprintf(stderr, "  %s\n", f.c_str());
    std::abort();
  }
  return 0;
}
