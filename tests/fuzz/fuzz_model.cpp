// Fuzz target: the recognizer model loader (loadModel), as slamaware-recognizer reads its --model.
// Input: one byte of flags, then the bytes. Flag bit 0 clear: the bytes are the whole file.
// Set: they are the payload, given a correct header and checksums here, so that the fuzzer reaches
// the field parser behind the checksum. Checks beyond "no crash": a model that loads passes
// check() and saves and loads again to the same classes and dimensions.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "common/atomic_file.h"
#include "procs/recognizer/model.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace slamaware;
  if (size < 1) return 0;
  std::vector<uint8_t> file;
  if (data[0] & 1) {
    // The layout of model.h: magic, version, header CRC, payload size, payload CRC, payload.
    file.assign(28, 0);
    std::memcpy(file.data(), "SLMRECOG", 8);
    const uint32_t version = kModelFormatVersion;
    const uint64_t payload = size - 1;
    const uint32_t payload_crc = crc32(data + 1, size - 1);
    std::memcpy(file.data() + 8, &version, 4);
    std::memcpy(file.data() + 16, &payload, 8);
    std::memcpy(file.data() + 24, &payload_crc, 4);
    const uint32_t header_crc = crc32(file.data() + 16, 12, crc32(file.data(), 12));
    std::memcpy(file.data() + 12, &header_crc, 4);
    file.insert(file.end(), data + 1, data + size);
  } else {
    file.assign(data + 1, data + size);
  }
  const std::string dir = fuzz::scratchDir();
  fuzz::writeFile(dir + "/recognizer.model", file.data(), file.size());
  RecognizerModel model;
  try {
    model = loadModel(dir + "/recognizer.model");
  } catch (const ModelError&) {
    return 0;
  }
  model.check("loaded model");
  saveModel(model, dir + "/again.model");
  const RecognizerModel again = loadModel(dir + "/again.model");
  if (again.classifier.classes != model.classifier.classes || again.params.vladDims() != model.params.vladDims() ||
      again.provenance != model.provenance) {
    std::fprintf(stderr, "fuzz_model: a saved model loads differently\n");
    std::abort();
  }
  return 0;
}
