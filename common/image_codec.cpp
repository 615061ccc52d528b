#include "common/image_codec.h"

#include <algorithm>
#include <cctype>
#include <climits>
#include <csetjmp>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>

// jpeglib.h needs FILE and size_t declared before it.
#include <jpeglib.h>
// jerror.h after jpeglib.h: the warning codes.
#include <jerror.h>
#include <png.h>

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
/// than a non-empty `expected`, before any decoder allocates for it; returns its size.
cv::Size checkImageHeader(const uint8_t* data, size_t size, const std::string& what,
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
  return cv::Size(w, h);
}

// libjpeg and libpng report errors through a callback that must not return: it long-jumps back to
// the setjmp in the C-style functions below, whose frames hold only trivially destructible objects
// (a long jump over a C++ destructor would skip it). The callers turn a false return into an
// ImageError with the library's message.
struct JpegError {
  jpeg_error_mgr pub;
  jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

void onJpegError(j_common_ptr c) {
  auto* e = reinterpret_cast<JpegError*>(c->err);
  (*c->err->format_message)(c, e->message);
  std::longjmp(e->jump, 1);
}

/// libjpeg's warnings: the entropy-coded data ending before the image does (a marker or the end of
/// the bytes where rows should follow) is an error: libjpeg would fill the missing rows with grey
/// and decode on, at the cost of the whole image the header claims; other warnings and traces are
/// ignored (as OpenCV does: some cameras write extraneous bytes before markers).
void onJpegMessage(j_common_ptr c, int level) {
  if (level < 0 && (c->err->msg_code == JWRN_HIT_MARKER || c->err->msg_code == JWRN_JPEG_EOF))
    onJpegError(c);
}

/// Decodes a JPEG of width x height into `out` (rows of `step` bytes): 8-bit BGR, or grey if
/// `grey` (libjpeg's own colour conversion and upsampling, as OpenCV's decoder asks for them).
bool decodeJpegInto(const uint8_t* data, size_t size, bool grey, int width, int height,
                    uint8_t* out, size_t step, JpegError* err) {
  jpeg_decompress_struct cinfo;
  cinfo.err = jpeg_std_error(&err->pub);
  err->pub.error_exit = onJpegError;
  err->pub.emit_message = onJpegMessage;
  if (setjmp(err->jump)) {
    jpeg_destroy_decompress(&cinfo);
    return false;
  }
  jpeg_create_decompress(&cinfo);
  jpeg_mem_src(&cinfo, data, static_cast<unsigned long>(size));
  jpeg_read_header(&cinfo, TRUE);
  if (cinfo.num_components != 1 && cinfo.num_components != 3) {
    std::snprintf(err->message, sizeof err->message, "a JPEG of %d components (CMYK?) is not read",
                  cinfo.num_components);
    jpeg_destroy_decompress(&cinfo);
    return false;
  }
  cinfo.out_color_space = grey ? JCS_GRAYSCALE : JCS_EXT_BGR;
  jpeg_start_decompress(&cinfo);
  if (static_cast<int>(cinfo.output_width) != width ||
      static_cast<int>(cinfo.output_height) != height) {
    std::snprintf(err->message, sizeof err->message, "decoded size differs from the header");
    jpeg_destroy_decompress(&cinfo);
    return false;
  }
  while (cinfo.output_scanline < cinfo.output_height) {
    JSAMPROW row = out + step * cinfo.output_scanline;
    jpeg_read_scanlines(&cinfo, &row, 1);
  }
  jpeg_finish_decompress(&cinfo);
  jpeg_destroy_decompress(&cinfo);
  return true;
}

/// JPEG bytes of an 8-bit image of 1 or 3 (BGR) channels into `*out` (malloc'ed by libjpeg; the
/// caller frees it): libjpeg's defaults at `quality` with baseline tables, as OpenCV writes them.
bool encodeJpegTo(const uint8_t* pixels, size_t step, int width, int height, int channels,
                  int quality, unsigned char** out, unsigned long* out_size, JpegError* err) {
  jpeg_compress_struct cinfo;
  cinfo.err = jpeg_std_error(&err->pub);
  err->pub.error_exit = onJpegError;
  if (setjmp(err->jump)) {
    jpeg_destroy_compress(&cinfo);
    return false;
  }
  jpeg_create_compress(&cinfo);
  jpeg_mem_dest(&cinfo, out, out_size);
  cinfo.image_width = static_cast<JDIMENSION>(width);
  cinfo.image_height = static_cast<JDIMENSION>(height);
  cinfo.input_components = channels;
  cinfo.in_color_space = channels == 3 ? JCS_EXT_BGR : JCS_GRAYSCALE;
  jpeg_set_defaults(&cinfo);
  jpeg_set_quality(&cinfo, quality, TRUE);
  jpeg_start_compress(&cinfo, TRUE);
  while (cinfo.next_scanline < cinfo.image_height) {
    JSAMPROW row = const_cast<uint8_t*>(pixels + step * cinfo.next_scanline);
    jpeg_write_scanlines(&cinfo, &row, 1);
  }
  jpeg_finish_compress(&cinfo);
  jpeg_destroy_compress(&cinfo);
  return true;
}

struct PngError {
  jmp_buf jump;
  char message[256];
};

void onPngError(png_structp png, png_const_charp message) {
  auto* e = static_cast<PngError*>(png_get_error_ptr(png));
  std::snprintf(e->message, sizeof e->message, "%s", message);
  std::longjmp(e->jump, 1);
}

void ignorePngWarning(png_structp, png_const_charp) {}

struct PngInput {
  const uint8_t* data;
  size_t size, at;
};

void readPngBytes(png_structp png, png_bytep out, png_size_t n) {
  auto* in = static_cast<PngInput*>(png_get_io_ptr(png));
  if (n > in->size - in->at) png_error(png, "truncated PNG data");
  std::memcpy(out, in->data + in->at, n);
  in->at += n;
}

/// How a PNG is read: 8-bit BGR, 8-bit grey, or as stored (8 or 16 bits; grey, BGR or BGRA).
enum class PngRead { kColour, kGrey, kUnchanged };

/// The OpenCV type a PNG is read into (OpenCV's rules: a palette or RGB image with transparency,
/// or one with an alpha channel, has 4 channels when read unchanged).
int pngType(int bit_depth, int color_type, bool has_trns, PngRead mode) {
  if (mode == PngRead::kColour) return CV_8UC3;
  if (mode == PngRead::kGrey) return CV_8UC1;
  int channels = 1;
  if (color_type == PNG_COLOR_TYPE_RGB || color_type == PNG_COLOR_TYPE_PALETTE)
    channels = has_trns ? 4 : 3;
  else if (color_type == PNG_COLOR_TYPE_GRAY_ALPHA || color_type == PNG_COLOR_TYPE_RGB_ALPHA)
    channels = 4;
  return CV_MAKETYPE(bit_depth == 16 ? CV_16U : CV_8U, channels);
}

/// Decodes a PNG (its size checked by the caller) into `out`, of type pngType, with the transforms
/// OpenCV's decoder asks libpng for.
bool decodePngInto(PngInput* in, PngRead mode, cv::Mat* out, PngError* err) {
  png_structp png =
      png_create_read_struct(PNG_LIBPNG_VER_STRING, err, onPngError, ignorePngWarning);
  if (!png) return false;
  png_infop info = png_create_info_struct(png);
  if (!info || setjmp(err->jump)) {
    png_destroy_read_struct(&png, info ? &info : nullptr, nullptr);
    return false;
  }
  png_set_read_fn(png, in, readPngBytes);
  png_read_info(png, info);
  const int bit_depth = png_get_bit_depth(png, info), color_type = png_get_color_type(png, info);
  const bool has_trns = png_get_valid(png, info, PNG_INFO_tRNS) != 0;
  const int type = pngType(bit_depth, color_type, has_trns, mode);
  const int width = static_cast<int>(png_get_image_width(png, info));
  const int height = static_cast<int>(png_get_image_height(png, info));
  out->create(height, width, type);
  const bool colour = CV_MAT_CN(type) > 1;
  if (CV_MAT_DEPTH(type) == CV_8U && bit_depth == 16)
    png_set_strip_16(png);
  else if (bit_depth == 16)
    png_set_swap(png);  // little-endian memory
  if (CV_MAT_CN(type) < 4)
    png_set_strip_alpha(png);
  else
    png_set_tRNS_to_alpha(png);
  if (color_type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if ((color_type & PNG_COLOR_MASK_COLOR) == 0 && bit_depth < 8)
    png_set_expand_gray_1_2_4_to_8(png);
  if ((color_type & PNG_COLOR_MASK_COLOR) && colour)
    png_set_bgr(png);
  else if (colour)
    png_set_gray_to_rgb(png);
  else if (color_type & PNG_COLOR_MASK_COLOR)
    png_set_rgb_to_gray(png, 1, 0.299, 0.587);
  const int passes = png_set_interlace_handling(png);
  png_read_update_info(png, info);
  if (png_get_rowbytes(png, info) != out->cols * out->elemSize()) {
    std::snprintf(err->message, sizeof err->message, "unexpected row size");
    png_destroy_read_struct(&png, &info, nullptr);
    return false;
  }
  for (int pass = 0; pass < passes; ++pass)
    for (int y = 0; y < height; ++y) png_read_row(png, out->ptr<uint8_t>(y), nullptr);
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  return true;
}

void appendPngBytes(png_structp png, png_bytep data, png_size_t n) {
  auto* out = static_cast<std::vector<uint8_t>*>(png_get_io_ptr(png));
  out->insert(out->end(), data, data + n);
}

void flushNothing(png_structp) {}

/// PNG bytes of an 8- or 16-bit image of 1, 3 (BGR) or 4 (BGRA) channels, written as OpenCV writes
/// them when given a compression level.
bool encodePngTo(const cv::Mat& image, int compression, std::vector<uint8_t>* out, PngError* err) {
  png_structp png =
      png_create_write_struct(PNG_LIBPNG_VER_STRING, err, onPngError, ignorePngWarning);
  if (!png) return false;
  png_infop info = png_create_info_struct(png);
  if (!info || setjmp(err->jump)) {
    png_destroy_write_struct(&png, info ? &info : nullptr);
    return false;
  }
  png_set_write_fn(png, out, appendPngBytes, flushNothing);
  png_set_compression_level(png, compression);
  png_set_compression_strategy(png, 0);  // Z_DEFAULT_STRATEGY
  const int channels = image.channels();
  png_set_IHDR(png, info, static_cast<png_uint_32>(image.cols),
               static_cast<png_uint_32>(image.rows), image.depth() == CV_16U ? 16 : 8,
               channels == 1   ? PNG_COLOR_TYPE_GRAY
               : channels == 3 ? PNG_COLOR_TYPE_RGB
                               : PNG_COLOR_TYPE_RGBA,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  png_set_bgr(png);
  png_set_swap(png);  // little-endian memory (16-bit only)
  for (int y = 0; y < image.rows; ++y)
    png_write_row(png, const_cast<uint8_t*>(image.ptr<uint8_t>(y)));
  png_write_end(png, info);
  png_destroy_write_struct(&png, &info);
  return true;
}
}  // namespace

namespace {
/// The offset of a JPEG's frame header (SOFn marker), or 0 when there is none before the scan.
size_t jpegFrameHeader(const uint8_t* data, size_t size) {
  // Markers after SOI: FF xx, then (except for standalone markers) a 2-byte length that counts
  // itself. The frame header SOFn (C0-CF but C4 DHT, C8 JPG, CC DAC) holds precision (1), height
  // (2), width (2), components (1). Entropy-coded data (after SOS) comes only after the frame
  // header.
  size_t at = 2;
  while (at + 4 <= size) {
    if (data[at] != 0xFF) return 0;
    const uint8_t marker = data[at + 1];
    if (marker == 0xFF) {  // fill byte
      ++at;
      continue;
    }
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD8)) {  // standalone
      at += 2;
      continue;
    }
    if (marker == 0xD9 || marker == 0xDA) return 0;  // end of image / scan before any frame
    const size_t length = bigEndian(data + at + 2, 2);
    if (length < 2) return 0;
    if (marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC)
      return length >= 8 && at + 10 <= size ? at : 0;
    at += 2 + length;
  }
  return 0;
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
  const size_t sof = jpegFrameHeader(data, size);
  if (sof == 0) return false;
  *height = static_cast<int>(bigEndian(data + sof + 5, 2));
  *width = static_cast<int>(bigEndian(data + sof + 7, 2));
  return true;
}

std::vector<uint8_t> encodeJpeg(const cv::Mat& image, int quality) {
  if (image.empty() || image.depth() != CV_8U || (image.channels() != 3 && image.channels() != 1))
    throw ImageError("encodeJpeg: need a non-empty 8-bit BGR or grey image");
  JpegError err{};
  unsigned char* bytes = nullptr;
  unsigned long size = 0;
  const bool ok = encodeJpegTo(image.data, image.step, image.cols, image.rows, image.channels(),
                               std::clamp(quality, 1, 100), &bytes, &size, &err);
  std::vector<uint8_t> out;
  if (ok) out.assign(bytes, bytes + size);
  std::free(bytes);
  if (!ok) throw ImageError(std::string("encodeJpeg: ") + err.message);
  return out;
}

std::vector<uint8_t> encodePng(const cv::Mat& image, int compression) {
  if (image.empty()) throw ImageError("encodePng: empty image");
  if ((image.depth() != CV_8U && image.depth() != CV_16U) ||
      (image.channels() != 1 && image.channels() != 3 && image.channels() != 4))
    throw ImageError("encodePng: need an 8- or 16-bit image of 1, 3 or 4 channels");
  std::vector<uint8_t> out;
  PngError err{};
  if (!encodePngTo(image, std::clamp(compression, 0, 9), &out, &err))
    throw ImageError(std::string("encodePng: ") + err.message);
  return out;
}

namespace {
/// Decodes JPEG bytes (checked by the caller) into 8-bit BGR, or grey.
cv::Mat decodeJpeg(const uint8_t* data, size_t size, bool grey, int width, int height,
                   const std::string& what) {
  cv::Mat img(height, width, grey ? CV_8UC1 : CV_8UC3);
  JpegError err{};
  if (!decodeJpegInto(data, size, grey, width, height, img.data, img.step, &err))
    throw ImageError(what + ": corrupt image: " + err.message);
  return img;
}

/// Decodes PNG bytes (checked by the caller) as `mode` asks.
cv::Mat decodePng(const uint8_t* data, size_t size, PngRead mode, const std::string& what) {
  PngError err{};
  PngInput in{data, size, 0};
  cv::Mat img;
  if (!decodePngInto(&in, mode, &img, &err))
    throw ImageError(what + ": corrupt image: " + err.message);
  return img;
}

/// Refuses bytes that are not a whole JPEG or PNG (see decodeImage); returns the header's size.
cv::Size checkImageBytes(const uint8_t* data, size_t size, const std::string& what,
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
  return checkImageHeader(data, size, what, expected);
}
}  // namespace

cv::Mat decodeImage(const uint8_t* data, size_t size, const std::string& what, bool grey,
                    cv::Size expected) {
  const cv::Size s = checkImageBytes(data, size, what, expected);
  if (isJpeg(data, size)) return decodeJpeg(data, size, grey, s.width, s.height, what);
  return decodePng(data, size, grey ? PngRead::kGrey : PngRead::kColour, what);
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
  const cv::Size s = checkImageBytes(bytes.data(), bytes.size(), path, cv::Size());
  if (isPng(bytes.data(), bytes.size()))
    return decodePng(bytes.data(), bytes.size(), PngRead::kUnchanged, path);
  // A JPEG as stored: grey when it has one component, else BGR.
  const bool grey = bytes[jpegFrameHeader(bytes.data(), bytes.size()) + 9] == 1;
  return decodeJpeg(bytes.data(), bytes.size(), grey, s.width, s.height, path);
}

void writeImage(const std::string& path, const cv::Mat& image, int jpeg_quality) {
  std::string ext = path.substr(
      path.find_last_of('.') == std::string::npos ? path.size() : path.find_last_of('.'));
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  std::vector<uint8_t> bytes;
  try {
    if (ext == ".jpg" || ext == ".jpeg")
      bytes = encodeJpeg(image, jpeg_quality);
    else if (ext == ".png")
      bytes = encodePng(image, 3);
    else
      throw ImageError("not a .png or .jpg name");
  } catch (const ImageError& e) {
    throw ImageError(path + ": cannot write image: " + e.what());
  }
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
  if (!out.flush()) throw ImageError(path + ": cannot write image");
}

}  // namespace slamaware
