// slamaware-synth-logcheck: checks a recording of a synthetic scene (the bundled sample): every
// frame present exactly once and in order (seq = frame index, utime = index / fps), the intrinsics
// on CAMERA_INFO, and, given the sequence folder it was streamed from, the same JPEG bytes.
// Exit code 0 when the log is complete and faithful, 1 otherwise (with the reason on stderr).
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>

#include "common/bus/log_reader.h"
#include "common/dataset.h"
#include "slamaware/camera_info_t.hpp"
#include "slamaware/image_t.hpp"

using namespace slamaware;

int main(int argc, char** argv) {
  CLI::App app{
      "slamaware-synth-logcheck: is a recorded synthetic scene complete and byte-faithful?"};
  std::string log, sequence, camera = "CAMERA", camera_info = "CAMERA_INFO";
  int frames = -1;
  app.add_option("log", log, "LCM log")->required()->check(CLI::ExistingFile);
  app.add_option("--frames", frames, "expected number of frames")->required();
  app.add_option("--sequence", sequence,
                 "the sequence folder that was streamed (compares the JPEG bytes)");
  app.add_option("--camera", camera, "frame channel");
  app.add_option("--camera-info", camera_info, "intrinsics channel");
  CLI11_PARSE(app, argc, argv);

  auto fail = [](const std::string& why) {
    std::fprintf(stderr, "logcheck: %s\n", why.c_str());
    return 1;
  };
  try {
    SequenceFolder seq;
    const bool compare = !sequence.empty();
    if (compare) seq = SequenceFolder::open(sequence);
    const double fps = compare ? seq.info().fps : 30.0;
    int next = 0, infos = 0;
    for (const LogRecord& r : LogReader::readAll(log)) {
      if (r.channel == camera_info) {
        camera_info_t info;
        if (info.decode(r.data.data(), 0, static_cast<int>(r.data.size())) < 0)
          return fail("undecodable CAMERA_INFO");
        if (compare && (info.width != seq.info().camera.width() ||
                        std::fabs(info.fx - seq.info().camera.fx()) > 1e-9))
          return fail("CAMERA_INFO does not match sequence.yaml");
        ++infos;
        continue;
      }
      if (r.channel != camera) continue;
      image_t img;
      if (img.decode(r.data.data(), 0, static_cast<int>(r.data.size())) < 0)
        return fail("undecodable CAMERA message");
      if (img.seq != next)
        return fail("expected seq " + std::to_string(next) + ", got " + std::to_string(img.seq));
      if (img.utime != static_cast<int64_t>(std::llround(next * 1e6 / fps)))
        return fail("frame " + std::to_string(next) + ": utime " + std::to_string(img.utime) +
                    " is not index / fps");
      if (compare) {
        std::ifstream in(seq.framePath(static_cast<size_t>(next)), std::ios::binary);
        const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), {});
        if (img.pixel_format != image_t::PIXEL_FORMAT_JPEG || img.data != bytes)
          return fail("frame " + std::to_string(next) + " differs from " +
                      seq.framePath(static_cast<size_t>(next)));
      }
      ++next;
    }
    if (next != frames)
      return fail("found " + std::to_string(next) + " frames, expected " + std::to_string(frames));
    if (infos == 0) return fail("no CAMERA_INFO");
    std::printf("logcheck: %s: %d frames in order, %d CAMERA_INFO%s\n", log.c_str(), next, infos,
                compare ? ", frames identical to the sequence" : "");
    return 0;
  } catch (const std::exception& e) {
    return fail(e.what());
  }
}
