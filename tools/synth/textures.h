#pragma once
// Procedural textures (8-bit BGR images) for the room, the furniture and the objects. Each is a
// pure function of its random stream and size: multi-scale noise, wood grain, tiles and bricks
// with per-piece irregularity, fabrics, stone, printed packaging with text and logos, posters.
// Surface textures are generated at a physical texel size over the whole surface, so nothing
// repeats exactly (a tracker must not see the same patch twice).
#include <opencv2/core.hpp>
#include <string>

#include "tools/synth/rng.h"

namespace slamaware::synth {

/// BGR colour in [0, 1] from hue (degrees), saturation, value.
cv::Vec3f hsvColor(float hue_deg, float sat, float val);
/// A random pronounceable brand-like word of `syllables` syllables (upper or lower case).
std::string pseudoWord(Rng& rng, int syllables, bool upper);

// ---- Room surfaces: size in metres, `texel` metres per texel --------------------------------

/// Floors: "wood" (planks), "tiles", "carpet", "concrete", "parquet", "linoleum".
cv::Mat floorTexture(Rng& rng, const std::string& style, float width_m, float height_m,
                     float texel_m);
/// Walls: "wallpaper", "brick", "plaster", "panels", "stripes", "tiles".
cv::Mat wallTexture(Rng& rng, const std::string& style, float width_m, float height_m,
                    float texel_m);
/// Table tops: "wood", "laminate", "cloth", "marble", "checker", "stone".
cv::Mat tableTexture(Rng& rng, const std::string& style, float width_m, float height_m,
                     float texel_m);
/// Plain wood (furniture, table edges, legs); grain along x.
cv::Mat woodTexture(Rng& rng, float width_m, float height_m, float texel_m, cv::Vec3f light,
                    cv::Vec3f dark);
/// A ceiling: off-white with mottling and, sometimes, acoustic tiles.
cv::Mat ceilingTexture(Rng& rng, float width_m, float height_m, float texel_m);

// ---- Decorations ------------------------------------------------------------------------------

/// A poster, painting or calendar of w x h pixels.
cv::Mat posterTexture(Rng& rng, int w, int h);
/// Book spines side by side along x (a shelf's worth), w x h pixels.
cv::Mat bookSpinesTexture(Rng& rng, int w, int h, int* books);

// ---- Object surfaces -----------------------------------------------------------------------

/// Printed packaging: a brand word, a picture (bowl of food, fruit, logo), stripes, small text.
/// `theme` hue in degrees. For box atlases, `front` is the rectangle (pixels) of the front face.
cv::Mat packagingTexture(Rng& rng, int w, int h, float theme_hue, const cv::Rect& front, bool busy);
/// A wrap-around label (cans, bottles, jars): bands, a brand word repeated around, a logo.
cv::Mat labelTexture(Rng& rng, int w, int h, float theme_hue);
/// Glazed ceramic / plastic: a base colour with a pattern ("plain", "bands", "dots", "logo",
/// "floral").
cv::Mat ceramicTexture(Rng& rng, int w, int h, cv::Vec3f base, const std::string& pattern);
/// Woven fabric (caps, towels), optionally with a stitched logo.
cv::Mat fabricTexture(Rng& rng, int w, int h, cv::Vec3f base, bool logo, float period_px = 3.f);
/// Fruit and vegetable skins: "apple", "orange", "lemon", "lime", "peach", "pear", "tomato",
/// "potato", "onion", "garlic", "pepper", "mushroom", "banana", "greens". Wraps in u.
cv::Mat skinTexture(Rng& rng, const std::string& kind, int w, int h, cv::Vec3f base);
/// Brushed or painted metal.
cv::Mat metalTexture(Rng& rng, int w, int h, cv::Vec3f base, bool brushed);
/// A noisy plastic with mild mottling (the default for plain parts).
cv::Mat plasticTexture(Rng& rng, int w, int h, cv::Vec3f base, float noise = 0.04f);
/// A grid of keys (keyboards, calculators, phones' keypads) with legends.
cv::Mat keysTexture(Rng& rng, int w, int h, int cols, int rows, cv::Vec3f body, cv::Vec3f key,
                    bool legends);
/// A phone or calculator display with icons or digits.
cv::Mat screenTexture(Rng& rng, int w, int h, bool icons);
/// Porous sponge foam.
cv::Mat spongeTexture(Rng& rng, int w, int h, cv::Vec3f base);
/// A notebook / binder cover (solid, patterned or printed, with a title).
cv::Mat coverTexture(Rng& rng, int w, int h, cv::Vec3f base);

}  // namespace slamaware::synth
