// Fuzz target: the recognizer model loader (loadModel), as slamaware-recognizer reads its --model.
// Input: one byte of flags, then the bytes. Flag bit 0 clear: the bytes are the whole file.
// Set: they are the payload, given a correct header and checksums here, so that the fuzzer reaches
// the field parser behind the checksum. Checks beyond "no crash": a model that loads passes
// check() and saves and loads again to the same classes and dimensions.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "procs/recognizer/model.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace slamaware;
  using namespace slamaware::recognizer;
  if (size < 1) return 0;
  const std::vector<uint8_t> bytes(data + 1, data + size);
  const std::vector<uint8_t> file = (data[0] & 1) ? modelFileBytes(bytes) : bytes;
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
  if (again.classifier.classes != model.classifier.classes ||
      again.params.encodedDims() != model.params.encodedDims() ||
      again.provenance != model.provenance) {
    std::fprintf(stderr, "fuzz_model: a saved model loads differently\n");
    std::abort();
  }
  return 0;
}
