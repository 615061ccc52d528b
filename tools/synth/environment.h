#pragma once
// The surroundings of the objects: a room (textured floor, walls, ceiling, skirting, a door,
// pictures, furniture along the walls), a table in the middle (world origin under its centre)
// and the light. Also bakes shadows and ambient occlusion into the light maps of the two
// horizontal receivers (the table top and the floor).
//
// World frame: metres, z up, origin on the floor under the centre of the table; the table's
// long side runs along x.
#include <vector>

#include "tools/synth/render_scene.h"
#include "tools/synth/rng.h"
#include "tools/synth/synth_options.h"

namespace slamaware::synth {

/// A horizontal surface with light maps: world rectangle [x0, x1] x [y0, y1] at height z.
struct Receiver {
  int material = -1;
  float x0 = 0, y0 = 0, x1 = 0, y1 = 0, z = 0;
  float ao_radius = 0.02f;      ///< m, reach of the contact darkening
  float ao_strength = 0.5f;     ///< darkening right next to an occluder
  float shadow_texel = 0.003f;  ///< m, resolution of the shadow test
};

struct TableGeometry {
  bool round = false;
  float half_x = 0.6f, half_y = 0.4f;  ///< half extents (round: radius in both)
  float top_z = 0.74f;
  /// True when a disc of radius r at (x, y) lies on the top with `margin` to spare.
  bool fits(float x, float y, float r, float margin) const;
};

struct Environment {
  TableGeometry table;
  Receiver table_top, floor;
  std::vector<int> table_items;      ///< items of the table (occlude the floor)
  std::vector<int> furniture_items;  ///< items along the walls (occlude the floor)
  float room_x0 = 0, room_y0 = 0, room_x1 = 0, room_y1 = 0, room_h = 0;
};

/// Light directions and colours from the options.
LightSetup makeLight(const LightOptions& o, Rng& rng);

/// Adds a room with a table to `scene`. The room is placed so that every wall is at least
/// `clear_radius` from the table centre. Throws std::invalid_argument for unknown styles.
Environment buildEnvironment(RenderScene* scene, const RoomOptions& room, const TableOptions& table,
                             Rng& rng, float clear_radius);

/// Bakes a receiver's light maps: shadows cast along the scene light by `occluders` (item indices)
/// and contact darkening under them. `region` limits the work to [x0, y0, x1, y1] (world), or
/// the whole receiver when empty.
void bakeReceiver(RenderScene* scene, const Receiver& rc, const std::vector<int>& occluders,
                  const std::vector<float>& region = {});

/// A flat disc (triangle fan) at height z facing up, uv = planar (u along x, v along -y) over
/// [cx - r, cx + r], uv2 likewise mapped to [0, 1].
Mesh disc(float cx, float cy, float radius, float z, int segments);

}  // namespace slamaware::synth
