#pragma once
// Options of the synthetic generator: a scene config (config/scenes/*.yaml) and an object-set
// config (config/objects/*.yaml). Every key has a default here; a config file only lists what it
// changes, except the keys marked required (name, seed), which every file must give.
#include <cstdint>
#include <string>
#include <vector>

#include "tools/synth/sensor.h"

namespace slamaware::synth {

struct CameraOptions {
  int width = 640, height = 480;
  double fx = 525, fy = 525, cx = 319.5, cy = 239.5;
  double fps = 30;

  template <class V>
  void visit(V& v) {
    v("width", width, "px");
    v("height", height, "px");
    v("fx", fx, "px, focal length");
    v("fy", fy, "px");
    v("cx", cx, "px, principal point (centre of the top-left pixel = 0)");
    v("cy", cy, "px");
    v("fps", fps, "frames per second");
  }
};

struct RoomOptions {
  std::string floor = "random";  ///< wood, parquet, tiles, carpet, concrete, linoleum or random
  std::string walls =
      "random";  ///< wallpaper, brick, plaster, panels, stripes, tiles or random (per wall)
  std::vector<double> size = {5.0, 4.2};  ///< m, floor extent along x and y
  double height = 2.6;                    ///< m, ceiling height
  int pictures = 6;                       ///< posters, paintings, calendars on the walls
  int furniture = 4;                      ///< shelves, cabinets, boxes, plants along the walls

  template <class V>
  void visit(V& v) {
    v("floor", floor, "wood, parquet, tiles, carpet, concrete, linoleum or random");
    v("walls", walls,
      "wallpaper, brick, plaster, panels, stripes, tiles or random (each wall drawn)");
    v("size", size, "m, [x, y] extent of the room");
    v("height", height, "m, ceiling height");
    v("pictures", pictures, "posters and paintings on the walls");
    v("furniture", furniture, "shelves, cabinets, boxes and plants along the walls");
  }
};

struct TableOptions {
  std::string shape = "rect";  ///< rect or round
  std::string top = "random";  ///< wood, laminate, cloth, marble, checker, stone or random
  std::vector<double> size = {1.2, 0.8};  ///< m, [length, width]; round: [diameter]
  double height = 0.74;                   ///< m, floor to table top

  template <class V>
  void visit(V& v) {
    v("shape", shape, "rect or round");
    v("top", top, "wood, laminate, cloth, marble, checker, stone or random");
    v("size", size, "m, [length, width] (round: [diameter])");
    v("height", height, "m, floor to the table top");
  }
};

struct ObjectOptions {
  int count = 5;                                   ///< objects on the table (3-8)
  int distractors = 1;                             ///< of which from the other 46 categories
  std::vector<std::string> distractor_categories;  ///< allowed distractors (empty: all others)
  std::vector<std::string> classes;                ///< paper classes to draw from (empty: all five)
  double min_gap = 0.05;                           ///< m, free space between objects
  double edge_margin = 0.05;                       ///< m, free space to the table edge
  double spread = 1.0;  ///< fraction of the table top the objects may use (around the centre)
  double yaw_deg = -1;  ///< rotation of every object about z (-1: random per object)

  template <class V>
  void visit(V& v) {
    v("count", count, "objects on the table (3-8)");
    v("distractors", distractors, "how many of them come from the 46 non-paper categories");
    v("distractor_categories", distractor_categories,
      "allowed distractor categories (empty: all 46)");
    v("classes", classes, "paper classes to draw from (empty: all five)");
    v("min_gap", min_gap, "m, free space between two objects");
    v("edge_margin", edge_margin, "m, free space between an object and the table edge");
    v("spread", spread, "fraction of the table top (around its centre) the objects may use");
    v("yaw_deg", yaw_deg, "deg, rotation of every object about z (-1: random per object)");
  }
};

struct TrajectoryOptions {
  double radius_min = 0.75, radius_max = 1.25;  ///< m, horizontal distance to the table centre
  double height_min = 0.35, height_max = 0.7;   ///< m, camera height above the table top
  double arc_deg = 360;                         ///< total angle travelled around the table
  int direction = 0;                            ///< +1 counter-clockwise, -1 clockwise, 0 random
  double speed_variation = 0.4;                 ///< relative variation of the angular speed (< 0.9)
  double look_jitter = 0.06;                    ///< m, slow wander of the look-at point
  double shake_deg = 0.25;                      ///< deg, hand tremor (1-3 Hz)
  double roll_deg = 3;                          ///< deg, slow roll

  template <class V>
  void visit(V& v) {
    v("radius_min", radius_min, "m, smallest horizontal distance from the table centre");
    v("radius_max", radius_max, "m, largest horizontal distance from the table centre");
    v("height_min", height_min, "m, lowest camera height above the table top");
    v("height_max", height_max, "m, highest camera height above the table top");
    v("arc_deg", arc_deg, "deg, angle travelled around the table over the sequence");
    v("direction", direction, "+1 counter-clockwise, -1 clockwise, 0 random");
    v("speed_variation", speed_variation, "relative variation of the angular speed (0-0.9)");
    v("look_jitter", look_jitter, "m, slow wander of the point looked at");
    v("shake_deg", shake_deg, "deg, amplitude of the hand tremor (1-3 Hz)");
    v("roll_deg", roll_deg, "deg, amplitude of the slow roll");
  }
};

struct LightOptions {
  double elevation_deg = 0;  ///< of the directional light (0: random 50-75)
  double azimuth_deg = -1;   ///< (-1: random)
  double sun = 0.7;          ///< directional light intensity
  double ambient = 0.5;      ///< hemisphere (ambient) intensity
  double warmth = 0.0;       ///< -1 cool (daylight) .. +1 warm (tungsten)

  template <class V>
  void visit(V& v) {
    v("elevation_deg", elevation_deg, "deg, elevation of the directional light (0: random 50-75)");
    v("azimuth_deg", azimuth_deg, "deg, azimuth of the directional light (-1: random)");
    v("sun", sun, "directional light intensity");
    v("ambient", ambient, "ambient (sky/ground hemisphere) intensity");
    v("warmth", warmth, "colour of the light: -1 cool .. +1 warm");
  }
};

struct SceneOptions {
  std::string name;         ///< required: the sequence name
  int64_t seed = -1;        ///< required: the scene seed (--seed overrides)
  int frames = 450;         ///< frames of the sequence (its camera path); --frames renders fewer
  bool write_depth = true;  ///< depth/ 16-bit PNG in millimetres
  CameraOptions camera;
  RoomOptions room;
  TableOptions table;
  ObjectOptions objects;
  TrajectoryOptions trajectory;
  LightOptions light;
  SensorOptions sensor;
  std::string notes;

  template <class V>
  void visit(V& v) {
    v("name", name, "sequence name (required)");
    v("seed", seed, "scene seed (required; --seed overrides)");
    v("frames", frames,
      "frames of the sequence (the camera path spans them; --frames renders the first N)");
    v("write_depth", write_depth, "write depth/ (16-bit PNG, mm)");
    v("notes", notes, "free text copied into sequence.yaml");
    v.section("camera", camera);
    v.section("room", room);
    v.section("table", table);
    v.section("objects", objects);
    v.section("trajectory", trajectory);
    v.section("light", light);
    v.section("sensor", sensor);
  }
};

struct ObjectSetOptions {
  std::string name;                     ///< required
  int64_t seed = -1;                    ///< required (--seed overrides)
  std::vector<std::string> categories;  ///< categories (empty or ["all"]: all 51)
  int instances = 3;                    ///< instances per category
  std::vector<double> elevations_deg = {30, 45, 60};
  std::vector<int> video_ids = {1, 2, 4};  ///< the UW dataset numbers its elevations 1, 2, 4
  double azimuth_step_deg = 5;
  double distance_min = 0.75, distance_max = 1.0;  ///< m, camera to object
  double crop_margin = 0.12;                       ///< of the object's box size, on each side
  int backgrounds = 6;  ///< different rooms / tables the turntable stands in
  CameraOptions camera;
  SensorOptions sensor;
  LightOptions light;

  template <class V>
  void visit(V& v) {
    v("name", name, "object set name (required)");
    v("seed", seed, "object set seed (required; --seed overrides)");
    v("categories", categories, "categories in the set (empty or [all]: all 51)");
    v("instances", instances, "instances per category");
    v("elevations_deg", elevations_deg, "deg, camera elevations of the turntable videos");
    v("video_ids", video_ids, "video number of each elevation in the file names");
    v("azimuth_step_deg", azimuth_step_deg, "deg, turntable rotation between two views");
    v("distance_min", distance_min, "m, smallest camera-object distance");
    v("distance_max", distance_max, "m, largest camera-object distance");
    v("crop_margin", crop_margin, "margin around the object's box, fraction of its size per side");
    v("backgrounds", backgrounds, "number of different rooms the turntable stands in");
    v.section("camera", camera);
    v.section("sensor", sensor);
    v.section("light", light);
  }
};

/// Loads and checks a scene config; throws ConfigError naming the file and the key at fault.
SceneOptions loadSceneOptions(const std::string& path);
/// Loads and checks an object-set config; throws ConfigError naming the file and the key.
ObjectSetOptions loadObjectSetOptions(const std::string& path);
/// Checks values (ranges, known styles and categories); `where` names the file in errors.
void validate(const SceneOptions& o, const std::string& where);
void validate(const ObjectSetOptions& o, const std::string& where);

}  // namespace slamaware::synth
