// Fuzz target: the image codec (JPEG and PNG through OpenCV) as every reader of image files and
// JPEG camera frames uses it. Input: one byte of flags (bit 0: decode as grey), then the file.
// Checks beyond "no crash": a decoded image is non-empty, 8-bit, of 3 channels (1 when grey),
// within the size limit, and PNG-encodes again.
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "common/image_codec.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace slamaware;
  if (size < 1) return 0;
  const bool grey = data[0] & 1;
  try {
    const cv::Mat img = decodeImage(data + 1, size - 1, "fuzz input", grey);
    if (img.empty() || img.depth() != CV_8U || img.channels() != (grey ? 1 : 3) ||
        static_cast<int64_t>(img.cols) * img.rows > kMaxImagePixels) {
      std::fprintf(stderr, "fuzz_image: decoded %dx%d, %d channels, depth %d\n", img.cols, img.rows,
                   img.channels(), img.depth());
      std::abort();
    }
    encodePng(img, 1);
  } catch (const ImageError&) {
  }
  return 0;
}
