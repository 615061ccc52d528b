#include "tools/synth/random_scene.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "common/config.h"
#include "tools/synth/rng.h"

namespace slamaware::synth {

namespace {

/// Rounds to `step` so that the written config is readable (0.83, not 0.8314159...).
double q(double v, double step = 0.01) {
  const double per_unit = std::round(1.0 / step);  // 100 for 0.01: divide, do not multiply
  return std::round(v * per_unit) / per_unit;
}

}  // namespace

// The ranges, one line each. They span the tables and cameras a robot meets indoors, wider than
// the fixed suite in every direction; tools/synth/README.md lists them for users.
SceneOptions randomSceneOptions(uint64_t seed, int frames) {
  Rng rng(hashCombine(seed, hashString("random scene")));
  SceneOptions o;
  o.name = "random_" + std::to_string(seed);
  o.seed = static_cast<int64_t>(seed % (uint64_t{1} << 53));
  o.frames = frames;
  o.notes = "random scene " + std::to_string(seed) + " (slamaware-synth scene --random)";

  // Table: shape, size 0.6-1.8 m, height 0.45-1.05 m, any top (cloth included).
  TableOptions& t = o.table;
  t.shape = rng.chance(0.4) ? "round" : "rect";
  t.top =
      rng.pick(std::vector<std::string>{"wood", "laminate", "cloth", "marble", "checker", "stone"});
  if (t.shape == "round") {
    t.size = {q(rng.uniform(0.6, 1.4))};
  } else {
    const double length = q(rng.uniform(0.6, 1.8));
    t.size = {length, q(std::max(0.6, length * rng.uniform(0.45, 1.0)))};
  }
  t.height = q(rng.uniform(0.45, 1.05));
  const double half_extent = 0.5 * t.size[0];  // the larger half-size (length >= width)

  // Objects: 2-9 of the five classes and 0-4 distractors (at most 12 in all), packed densely or
  // loosely; buildRandomScene removes what does not fit.
  ObjectOptions& ob = o.objects;
  const int paper = rng.range(2, 9);
  ob.distractors = std::min(rng.range(0, 4), 12 - paper);
  ob.count = paper + ob.distractors;
  ob.min_gap = q(rng.uniform(0.02, 0.12));
  ob.edge_margin = q(rng.uniform(0.02, 0.10));
  ob.spread = q(rng.uniform(0.6, 1.0));

  // Camera: 0.25-0.7 m beyond the table's edge, 0.2-0.85 m above its top, 120-420 degrees around
  // it, tremor and roll from steady to hand-held.
  TrajectoryOptions& c = o.trajectory;
  c.radius_min = q(half_extent + rng.uniform(0.25, 0.55));
  c.radius_max = q(c.radius_min + rng.uniform(0.05, 0.45));
  c.height_min = q(rng.uniform(0.2, 0.55));
  c.height_max = q(c.height_min + rng.uniform(0.05, 0.35));
  c.arc_deg = q(rng.uniform(120, 420), 1);
  c.direction = rng.chance(0.5) ? 1 : -1;
  c.speed_variation = q(rng.uniform(0.0, 0.6));
  c.look_jitter = q(rng.uniform(0.0, 0.12));
  c.shake_deg = q(rng.uniform(0.0, 0.8));
  c.roll_deg = q(rng.uniform(0.0, 6.0));

  // Room: large enough for the camera path, any floor and walls, sparse to busy.
  RoomOptions& r = o.room;
  const double clear = 2 * (c.radius_max + 0.45);
  r.size = {q(std::max(clear, rng.uniform(3.5, 7.0))), q(std::max(clear, rng.uniform(3.5, 7.0)))};
  r.height = q(rng.uniform(2.4, 3.2));
  r.pictures = rng.range(0, 10);
  r.furniture = rng.range(0, 8);

  // Light: direction, strength of sun and sky, colour from daylight to tungsten.
  LightOptions& l = o.light;
  l.elevation_deg = q(rng.uniform(30, 80), 1);
  l.azimuth_deg = q(rng.uniform(0, 360), 1);
  l.sun = q(rng.uniform(0.3, 1.2));
  l.ambient = q(rng.uniform(0.3, 0.8));
  l.warmth = q(rng.uniform(-0.8, 0.8));

  // Sensor: exposure, noise, lens blur, vignetting, motion blur and JPEG of webcams to good
  // cameras.
  SensorOptions& s = o.sensor;
  s.gain = q(rng.uniform(0.7, 1.4));
  s.read_noise = q(rng.uniform(0.5, 4.0));
  s.shot_noise = q(rng.uniform(0.02, 0.2), 0.005);
  s.psf_sigma_px = q(rng.uniform(0.3, 1.0));
  s.vignetting = q(rng.uniform(0.0, 0.4));
  s.shutter_s = q(rng.chance(0.5) ? rng.uniform(0.0, 0.012) : 0.0, 0.001);
  s.jpeg_quality = rng.range(70, 97);
  validate(o, o.name);
  return o;
}

std::unique_ptr<SyntheticScene> buildRandomScene(uint64_t seed, int frames, int render_frames,
                                                 SceneOptions* options) {
  SceneOptions o = randomSceneOptions(seed, frames);
  for (;;) {
    try {
      auto scene = std::make_unique<SyntheticScene>(o, -1, render_frames);
      if (options) *options = o;
      return scene;
    } catch (const std::invalid_argument&) {
      // Too many objects for this table: one fewer (a distractor first), keeping at least one.
      if (o.objects.count <= 1) throw;
      if (o.objects.distractors > 0) --o.objects.distractors;
      --o.objects.count;
    }
  }
}

std::string sceneConfigYaml(SceneOptions options) {
  return "# A random scene (slamaware-synth scene --random): every option that built it.\n"
         "# Reproduce it with: slamaware-synth scene --config THIS_FILE --out DIR\n" +
         describeOptions(optionListOf(options));
}

}  // namespace slamaware::synth
