#include "tools/synth/synth_options.h"

#include <algorithm>
#include <sstream>

#include "common/config.h"
#include "tools/synth/categories.h"

namespace slamaware::synth {

namespace {

[[noreturn]] void fail(const std::string& where, const std::string& key, const std::string& what) {
  throw ConfigError(where + ": key '" + key + "': " + what);
}

void oneOf(const std::string& where, const std::string& key, const std::string& value,
           const std::vector<std::string>& allowed) {
  if (std::find(allowed.begin(), allowed.end(), value) != allowed.end()) return;
  std::string list;
  for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
  fail(where, key, "'" + value + "' is not one of " + list);
}

void range(const std::string& where, const std::string& key, double v, double lo, double hi) {
  if (v >= lo && v <= hi) return;
  std::ostringstream s;
  s << v << " is outside [" << lo << ", " << hi << "]";
  fail(where, key, s.str());
}

void checkCamera(const CameraOptions& c, const std::string& where) {
  range(where, "camera.width", c.width, 16, 4096);
  range(where, "camera.height", c.height, 16, 4096);
  range(where, "camera.fx", c.fx, 1, 1e5);
  range(where, "camera.fy", c.fy, 1, 1e5);
  range(where, "camera.fps", c.fps, 0.1, 1000);
}

void checkSensor(const SensorOptions& s, const std::string& where) {
  range(where, "sensor.gain", s.gain, 0.01, 100);
  range(where, "sensor.read_noise", s.read_noise, 0, 50);
  range(where, "sensor.shot_noise", s.shot_noise, 0, 10);
  range(where, "sensor.psf_sigma_px", s.psf_sigma_px, 0, 1.5);
  range(where, "sensor.vignetting", s.vignetting, 0, 0.9);
  range(where, "sensor.shutter_s", s.shutter_s, 0, 0.1);
  range(where, "sensor.jpeg_quality", s.jpeg_quality, 1, 100);
}

void checkLight(const LightOptions& l, const std::string& where) {
  range(where, "light.elevation_deg", l.elevation_deg, 0, 90);
  range(where, "light.azimuth_deg", l.azimuth_deg, -1, 360);
  range(where, "light.sun", l.sun, 0, 5);
  range(where, "light.ambient", l.ambient, 0, 5);
  range(where, "light.warmth", l.warmth, -1, 1);
}

template <class Options>
Options load(const std::string& path) {
  Options o;
  OptionList list = optionListOf(o);
  ConfigFile(path).load("", list);
  if (o.name.empty())
    throw ConfigError(path + ": missing key 'name' (every config names its output)");
  if (o.seed < 0) throw ConfigError(path + ": missing key 'seed' (a non-negative integer)");
  return o;
}

}  // namespace

void validate(const SceneOptions& o, const std::string& where) {
  range(where, "frames", o.frames, 1, 100000);
  checkCamera(o.camera, where);
  checkSensor(o.sensor, where);
  checkLight(o.light, where);
  static const std::vector<std::string> floors{"random", "wood",     "parquet", "tiles",
                                               "carpet", "concrete", "linoleum"};
  static const std::vector<std::string> walls{"random", "wallpaper", "brick", "plaster",
                                              "panels", "stripes",   "tiles"};
  static const std::vector<std::string> tops{"random", "wood",    "laminate", "cloth",
                                             "marble", "checker", "stone"};
  oneOf(where, "room.floor", o.room.floor, floors);
  oneOf(where, "room.walls", o.room.walls, walls);
  if (o.room.size.size() != 2) fail(where, "room.size", "expected [x, y] in metres");
  range(where, "room.size[0]", o.room.size[0], 2.5, 12);
  range(where, "room.size[1]", o.room.size[1], 2.5, 12);
  range(where, "room.height", o.room.height, 2.0, 5);
  range(where, "room.pictures", o.room.pictures, 0, 30);
  range(where, "room.furniture", o.room.furniture, 0, 20);
  oneOf(where, "table.shape", o.table.shape, {"rect", "round"});
  oneOf(where, "table.top", o.table.top, tops);
  if (o.table.size.empty() || o.table.size.size() > 2)
    fail(where, "table.size", "expected [length, width] (or [diameter])");
  for (double s : o.table.size) range(where, "table.size", s, 0.4, 3.0);
  range(where, "table.height", o.table.height, 0.3, 1.2);
  range(where, "objects.count", o.objects.count, 1, 12);
  range(where, "objects.distractors", o.objects.distractors, 0, o.objects.count);
  for (const auto& c : o.objects.distractor_categories)
    if (!isCategory(c))
      fail(where, "objects.distractor_categories", "unknown category '" + c + "'");
  for (const auto& c : o.objects.classes)
    if (std::find(paperClasses().begin(), paperClasses().end(), c) == paperClasses().end())
      fail(where, "objects.classes", "'" + c + "' is not one of the five paper classes");
  range(where, "objects.min_gap", o.objects.min_gap, 0, 0.5);
  range(where, "objects.edge_margin", o.objects.edge_margin, 0, 0.5);
  range(where, "objects.spread", o.objects.spread, 0.2, 1);
  range(where, "objects.yaw_deg", o.objects.yaw_deg, -1, 360);
  const TrajectoryOptions& t = o.trajectory;
  range(where, "trajectory.radius_min", t.radius_min, 0.3, 3);
  range(where, "trajectory.radius_max", t.radius_max, t.radius_min, 3);
  range(where, "trajectory.height_min", t.height_min, 0.1, 1.5);
  range(where, "trajectory.height_max", t.height_max, t.height_min, 1.5);
  range(where, "trajectory.speed_variation", t.speed_variation, 0, 0.9);
  range(where, "trajectory.direction", t.direction, -1, 1);
  range(where, "trajectory.look_jitter", t.look_jitter, 0, 0.5);
  range(where, "trajectory.shake_deg", t.shake_deg, 0, 5);
  range(where, "trajectory.roll_deg", t.roll_deg, 0, 30);
  const double clear = t.radius_max + 0.45;
  if (o.room.size[0] < 2 * clear || o.room.size[1] < 2 * clear)
    fail(where, "room.size",
         "the room must be at least 2 x (trajectory.radius_max + 0.45) m wide in x and y");
}

void validate(const ObjectSetOptions& o, const std::string& where) {
  for (const auto& c : o.categories)
    if (c != "all" && !isCategory(c)) fail(where, "categories", "unknown category '" + c + "'");
  range(where, "instances", o.instances, 1, 1000);
  if (o.elevations_deg.empty()) fail(where, "elevations_deg", "expected at least one elevation");
  for (double e : o.elevations_deg) range(where, "elevations_deg", e, 5, 85);
  if (o.video_ids.size() != o.elevations_deg.size())
    fail(where, "video_ids", "expected one video number per elevation");
  range(where, "azimuth_step_deg", o.azimuth_step_deg, 0.5, 360);
  range(where, "distance_min", o.distance_min, 0.3, 3);
  range(where, "distance_max", o.distance_max, o.distance_min, 3);
  range(where, "crop_margin", o.crop_margin, 0, 1);
  range(where, "backgrounds", o.backgrounds, 1, 100);
  checkCamera(o.camera, where);
  checkSensor(o.sensor, where);
  checkLight(o.light, where);
}

SceneOptions loadSceneOptions(const std::string& path) {
  SceneOptions o = load<SceneOptions>(path);
  validate(o, path);
  return o;
}

ObjectSetOptions loadObjectSetOptions(const std::string& path) {
  ObjectSetOptions o = load<ObjectSetOptions>(path);
  validate(o, path);
  return o;
}

}  // namespace slamaware::synth
