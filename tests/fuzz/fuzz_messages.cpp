// Fuzz target: every message type through the bus layer's decode path (Bus::subscribe decodes with
// decodeMessage), and what the processes do with a decoded message before trusting it: the image
// decode of image_t, the camera of camera_info_t, the frame stamp lockstep reads, the summaries of
// slamaware-ctl and lcm-spy's helpers.
// Input: one byte choosing the type (its index in kDecoders, modulo their count), then the message.
// Checks beyond "no crash": a decoded message encodes to exactly getEncodedSize() bytes, and those
// bytes decode again to a message that encodes to the same bytes.
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "common/bus/bus.h"
#include "common/bus/frame_stamp.h"
#include "common/bus/image_msg.h"
#include "common/bus/type_registry.h"
#include "common/image_codec.h"
#include "slamaware/box_t.hpp"
#include "slamaware/camera_info_t.hpp"
#include "slamaware/detections_t.hpp"
#include "slamaware/image_t.hpp"
#include "slamaware/keyframe_t.hpp"
#include "slamaware/object_detections_t.hpp"
#include "slamaware/object_map_t.hpp"
#include "slamaware/object_query_reply_t.hpp"
#include "slamaware/object_query_t.hpp"
#include "slamaware/object_t.hpp"
#include "slamaware/point_cloud_t.hpp"
#include "slamaware/pose_t.hpp"
#include "slamaware/proc_command_t.hpp"
#include "slamaware/proc_info_t.hpp"
#include "slamaware/proc_status_t.hpp"
#include "slamaware/proposals_t.hpp"
#include "slamaware/status_t.hpp"

namespace slamaware {
namespace {

[[noreturn]] void fail(const char* what, const char* type) {
  std::fprintf(stderr, "fuzz_messages: %s: %s\n", type, what);
  std::abort();
}

template <class Msg>
std::vector<uint8_t> encodeExactly(const Msg& m) {
  const int n = m.getEncodedSize();
  if (n < 0) fail("negative encoded size", Msg::getTypeName());
  std::vector<uint8_t> out(static_cast<size_t>(n));
  if (m.encode(out.data(), 0, n) != n)
    fail("encode() wrote another size than getEncodedSize()", Msg::getTypeName());
  return out;
}

template <class Msg>
bool roundTrip(const uint8_t* data, size_t size, Msg* msg) {
  std::string why;
  if (!decodeMessage(data, size, msg, &why)) {
    if (why.empty()) fail("rejected without a reason", Msg::getTypeName());
    return false;
  }
  const std::vector<uint8_t> once = encodeExactly(*msg);
  Msg again{};
  if (!decodeMessage(once.data(), once.size(), &again, &why))
    fail("its own encoding does not decode", Msg::getTypeName());
  if (encodeExactly(again) != once)
    fail("decode(encode(m)) encodes differently", Msg::getTypeName());
  return true;
}

template <class Msg>
void decodeOnly(const uint8_t* data, size_t size) {
  Msg m{};
  roundTrip(data, size, &m);
}

void image(const uint8_t* data, size_t size) {
  image_t m{};
  if (!roundTrip(data, size, &m)) return;
  try {
    const cv::Mat bgr = decodeImageMessage(m, "CAMERA seq " + std::to_string(m.seq));
    if (bgr.cols != m.width || bgr.rows != m.height)
      fail("decoded image of another size", "image_t");
  } catch (const ImageError&) {
  }
}

void cameraInfo(const uint8_t* data, size_t size) {
  camera_info_t m{};
  if (!roundTrip(data, size, &m)) return;
  CameraModel camera;
  std::string why;
  if (!cameraFromMessage(m, &camera, &why) && why.empty())
    fail("refused without a reason", "camera_info_t");
}

using Decoder = void (*)(const uint8_t*, size_t);
constexpr Decoder kDecoders[] = {
    &decodeOnly<box_t>,          &cameraInfo,
    &decodeOnly<detections_t>,   &image,
    &decodeOnly<keyframe_t>,     &decodeOnly<object_detections_t>,
    &decodeOnly<object_map_t>,   &decodeOnly<object_query_reply_t>,
    &decodeOnly<object_query_t>, &decodeOnly<object_t>,
    &decodeOnly<point_cloud_t>,  &decodeOnly<pose_t>,
    &decodeOnly<proc_command_t>, &decodeOnly<proc_info_t>,
    &decodeOnly<proc_status_t>,  &decodeOnly<proposals_t>,
    &decodeOnly<status_t>,
};

}  // namespace
}  // namespace slamaware

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace slamaware;
  if (size < 1) return 0;
  const size_t n = sizeof(kDecoders) / sizeof(kDecoders[0]);
  kDecoders[data[0] % n](data + 1, size - 1);
  // Whatever the bytes, the tools that watch the whole bus name and summarise them without harm.
  typeNameOfMessage(data + 1, size - 1);
  summarizeMessage(data + 1, size - 1);
  peekFrameStamp(data + 1, size - 1);
  return 0;
}
