#pragma once
// Image file codecs (JPEG through libjpeg, PNG through libpng, with the settings OpenCV uses),
// with errors that say what was wrong. (Not OpenCV's imgcodecs: it brings some 120 shared
// libraries that every process would load at each start.)
// Colour images are 8-bit BGR (OpenCV's order) in memory.
#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <stdexcept>
#include <string>
#include <vector>

namespace slamaware {

class ImageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The largest image any reader decodes (width x height, 64 megapixels): a header asking for more
/// is refused before the decoder allocates (a 50-byte PNG can claim 4 gigapixels).
constexpr int64_t kMaxImagePixels = int64_t{8192} * 8192;

/// Width and height from a JPEG's frame header (SOF) or a PNG's IHDR, without decoding; false when
/// the bytes hold neither.
bool peekImageSize(const uint8_t* data, size_t size, int* width, int* height);

/// JPEG bytes of an 8-bit BGR or grey image; quality 1-100.
std::vector<uint8_t> encodeJpeg(const cv::Mat& image, int quality);
/// PNG bytes of an 8- or 16-bit image (BGR, BGRA or grey); compression 0-9.
std::vector<uint8_t> encodePng(const cv::Mat& image, int compression = 3);
/// Decodes JPEG or PNG bytes into 8-bit BGR (or grey if `grey`). Throws ImageError for bytes that
/// are not a complete image, or (before decoding) whose header asks for more than kMaxImagePixels
/// or for another size than a non-empty `expected`; `what` names the source in the message.
cv::Mat decodeImage(const uint8_t* data, size_t size, const std::string& what, bool grey = false,
                    cv::Size expected = cv::Size());
/// Reads an image file as 8-bit BGR; throws ImageError naming the file when it is missing or
/// corrupt.
cv::Mat readImage(const std::string& path, bool grey = false);
/// Reads an image file without conversion (e.g. 16-bit depth PNG).
cv::Mat readImageUnchanged(const std::string& path);
/// Writes an image file (format from the extension); throws ImageError on failure.
void writeImage(const std::string& path, const cv::Mat& image, int jpeg_quality = 95);

}  // namespace slamaware
