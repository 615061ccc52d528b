#include "common/image_codec.h"

#include <algorithm>
#include <climits>
#include <cstring>
#include <fstream>
#include <iterator>
#include <opencv2/imgcodecs.hpp>

namespace slamaware {

namespace {
bool isJpeg(const uint8_t* d, size_t n) { return n >= 4 && d[0] == 0xFF && d[1] == 0xD8; }
bool isPng(const uint8_t* d, size_t n) {
  static const uint8_t sig[8] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
  return n >= 8 && std::equal(sig, sig + 8, d);
}
uint32_t bigEndian(const uint8_t* p, int n) {
  uint32_t v = 0;
  for (int i = 0; i < n; ++i) v = (v << 8) | p[i];
  return v;
}

/// Refuses an image whose header is missing, asks for more than kMaxImagePixels or for another size
/// than a non-empty `expected`, before any decoder allocates for it.
void checkImageHeader(const uint8_t* data, size_t size, const std::string& what,
                      cv::Size expected = cv::Size()) {
  int w = 0, h = 0;
  if (!peekImageSize(data, size, &w, &h))
    throw ImageError(what + ": no image header (JPEG frame header or PNG IHDR) found");
  if (!expected.empty() && (w != expected.width || h != expected.height))
    throw ImageError(what + ": the image header says " + std::to_string(w) + "x" +
                     std::to_string(h) + " but the message says " + std::to_string(expected.width) +
                     "x" + std::to_string(expected.height));
  if (w <= 0 || h <= 0 || static_cast<int64_t>(w) * h > kMaxImagePixels)
    throw ImageError(what + ": the header says " + std::to_string(w) + "x" + std::to_string(h) +
                     " pixels (at most " + std::to_string(kMaxImagePixels / 1000000) +
                     " megapixels are decoded)");
}
}  // namespace

bool peekImageSize(const uint8_t* data, size_t size, int* width, int* height) {
  if (isPng(data, size)) {
    // Signature, then the first chunk must be IHDR: length (4), type (4), width (4), height (4).
    if (size < 24 || std::memcmp(data + 12, "IHDR", 4) != 0) return false;
    const uint32_t w = bigEndian(data + 16, 4), h = bigEndian(data + 20, 4);
    if (w > INT32_MAX || h > INT32_MAX) return false;
    *width = static_cast<int>(w);
    *height = static_cast<int>(h);
    return true;
  }
  if (!isJpeg(data, size)) return false;
  // Markers after SOI: FF xx, then (except for standalone markers) a 2-byte length that counts
  // itself. The frame header SOFn (C0-CF but C4 DHT, C8 JPG, CC DAC) holds precision (1), height
  // (2), width (2). Entropy-coded data (after SOS) comes only after the frame header.
  size_t at = 2;
  while (at + 4 <= size) {
    if (data[at] != 0xFF) return false;
    const uint8_t marker = data[at + 1];
    if (marker == 0xFF) {  // fill byte
      ++at;
      continue;
    }
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD8)) {  // standalone
      at += 2;
      continue;
    }
    if (marker == 0xD9 || marker == 0xDA) return false;  // end of image / scan before any frame
    const size_t length = bigEndian(data + at + 2, 2);
    if (length < 2) return false;
    if (marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC) {
      if (length < 7 || at + 9 > size) return false;
      *height = static_cast<int>(bigEndian(data + at + 5, 2));
      *width = static_cast<int>(bigEndian(data + at + 7, 2));
      return true;
    }
    at += 2 + length;
  }
  return false;
}

std::vector<uint8_t> encodeJpeg(const cv::Mat& image, int quality) {
  if (image.empty() || image.depth() != CV_8U || (image.channels() != 3 && image.channels() != 1))
    throw ImageError("encodeJpeg: need a non-empty 8-bit BGR or grey image");
  std::vector<uint8_t> out;
  if (!cv::imencode(".jpg", image, out, {cv::IMWRITE_JPEG_QUALITY, std::clamp(quality, 1, 100)}))
    throw ImageError("encodeJpeg: OpenCV could not encode the image");
  return out;
}

std::vector<uint8_t> encodePng(const cv::Mat& image, int compression) {
  if (image.empty()) throw ImageError("encodePng: empty image");
  std::vector<uint8_t> out;
  if (!cv::imencode(".png", image, out,
                    {cv::IMWRITE_PNG_COMPRESSION, std::clamp(compression, 0, 9)}))
    throw ImageError("encodePng: OpenCV could not encode the image");
  return out;
}

cv::Mat decodeImage(const uint8_t* data, size_t size, const std::string& what, bool grey,
                    cv::Size expected) {
  if (size == 0) throw ImageError(what + ": empty image data");
  if (!isJpeg(data, size) && !isPng(data, size))
    throw ImageError(what + ": not a JPEG or PNG image (" + std::to_string(size) + " bytes)");
  // A JPEG must end with the EOI marker; libjpeg fills a truncated image with grey and only warns.
  if (isJpeg(data, size)) {
    size_t end = size;
    while (end > 2 && data[end - 1] == 0) --end;  // some encoders pad
    if (end < 4 || data[end - 2] != 0xFF || data[end - 1] != 0xD9)
      throw ImageError(what + ": truncated JPEG (no end-of-image marker)");
  }
  if (isPng(data, size)) {
    static const uint8_t iend[8] = {'I', 'E', 'N', 'D', 0xAE, 0x42, 0x60, 0x82};
    if (size < 20 || !std::equal(iend, iend + 8, data + size - 8))
      throw ImageError(what + ": truncated PNG (no IEND chunk)");
  }
  checkImageHeader(data, size, what, expected);
  if (size > static_cast<size_t>(INT32_MAX)) throw ImageError(what + ": image file over 2 GB");
  cv::Mat img;
  try {
    img = cv::imdecode(cv::Mat(1, static_cast<int>(size), CV_8U, const_cast<uint8_t*>(data)),
                       grey ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR);
  } catch (const cv::Exception& e) {
    throw ImageError(what + ": corrupt image: " + e.what());
  }
  if (img.empty()) throw ImageError(what + ": corrupt image (decoder failed)");
  return img;
}

namespace {
std::vector<uint8_t> readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ImageError(path + ": cannot open image file");
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(in), {});
}
}  // namespace

cv::Mat readImage(const std::string& path, bool grey) {
  const std::vector<uint8_t> bytes = readFile(path);
  return decodeImage(bytes.data(), bytes.size(), path, grey);
}

cv::Mat readImageUnchanged(const std::string& path) {
  const std::vector<uint8_t> bytes = readFile(path);
  if (bytes.empty()) throw ImageError(path + ": empty image file");
  checkImageHeader(bytes.data(), bytes.size(), path);
  cv::Mat img;
  try {
    img = cv::imdecode(bytes, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    throw ImageError(path + ": corrupt image: " + e.what());
  }
  if (img.empty()) throw ImageError(path + ": corrupt image");
  return img;
}

void writeImage(const std::string& path, const cv::Mat& image, int jpeg_quality) {
  bool ok = false;
  try {
    ok = cv::imwrite(path, image, {cv::IMWRITE_JPEG_QUALITY, jpeg_quality});
  } catch (const cv::Exception& e) {
    throw ImageError(path + ": cannot write image: " + e.what());
  }
  if (!ok) throw ImageError(path + ": cannot write image");
}

}  // namespace slamaware
