// slamaware-bench-synth: frames per second of the synthetic renderer on one core (640x480, the
// default scene: rasterisation, shading, sensor model), median over a run of frames. Frames are
// timed in CPU time of the rendering thread, so that other processes sharing the machine do not
// count; the wall-clock rate is printed beside it. Writes {"synth_fps": <median>} to --out.
#include <time.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <vector>

#include "tools/synth/scene.h"

using namespace slamaware::synth;

int main(int argc, char** argv) {
  CLI::App app{
      "slamaware-bench-synth: median frames/s of the synthetic renderer at 640x480 on one core"};
  std::string out;
  int frames = 90;
  int64_t seed = 7;
  app.add_option("--out", out, "JSON file to write")->required();
  app.add_option("--frames", frames, "frames to time")->check(CLI::PositiveNumber);
  app.add_option("--seed", seed, "scene seed");
  CLI11_PARSE(app, argc, argv);

  SceneOptions o;  // the defaults: a 5 x 4.2 m room, a 1.2 x 0.8 m table, 5 objects
  o.name = "bench";
  o.seed = seed;
  o.frames = std::max(frames, 2);
  o.objects.count = 6;
  o.objects.distractors = 2;
  SyntheticScene scene(o);
  FrameBuffers fb;
  scene.render(0, &fb);  // warm-up (allocations)
  auto cpuSeconds = [] {
    timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
  };
  std::vector<double> fps, wall_fps;
  for (int i = 0; i < frames; ++i) {
    const auto w0 = std::chrono::steady_clock::now();
    const double c0 = cpuSeconds();
    const cv::Mat img = scene.render(i, &fb);
    const double s = cpuSeconds() - c0;
    const double ws = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
    fps.push_back(1.0 / std::max(s, 1e-9));
    wall_fps.push_back(1.0 / std::max(ws, 1e-9));
  }
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  const double cpu_median = median(fps), wall_median = median(wall_fps);
  std::ofstream f(out);
  f << "{\"synth_fps\": " << cpu_median << "}\n";
  if (!f) {
    std::fprintf(stderr, "slamaware-bench-synth: cannot write %s\n", out.c_str());
    return 1;
  }
  std::printf(
      "synth_fps %.1f (median of %d frames, 640x480, CPU time of one core; wall clock %.1f)\n",
      cpu_median, frames, wall_median);
  return 0;
}
