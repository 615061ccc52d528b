#pragma once
// Procedural noise for textures: gradient (Perlin) noise, fractal sums of it, and cellular
// (Worley) noise. Every function is a pure function of its arguments and a seed. A period > 0
// makes the noise tile along x (for textures wrapped around a surface of revolution).
#include <cstdint>

namespace slamaware::synth {

/// Gradient noise in about [-1, 1]; period_x > 0 makes it periodic in x with that many cells.
float gradientNoise(float x, float y, uint32_t seed, int period_x = 0);

/// Fractal sum of `octaves` gradient noises (lacunarity 2, the given gain), normalised to
/// about [-1, 1]. period_x (cells of the first octave) doubles with each octave.
float fbm(float x, float y, uint32_t seed, int octaves, float gain = 0.5f, int period_x = 0);

/// Ridged fractal noise in [0, 1] (sharp creases: marble veins, cracks).
float ridged(float x, float y, uint32_t seed, int octaves, int period_x = 0);

/// Cellular noise: distance to the nearest and second nearest feature point (cell units) and a
/// hash of the nearest cell. period_x > 0 tiles in x.
struct Cell {
  float f1 = 0, f2 = 0;
  uint32_t id = 0;
};
Cell worley(float x, float y, uint32_t seed, int period_x = 0);

/// A hash of integer coordinates in [0, 1).
float hash01(int x, int y, uint32_t seed);
uint32_t hash32(int x, int y, uint32_t seed);

}  // namespace slamaware::synth
