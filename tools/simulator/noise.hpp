// simulator/noise: procedural value noise for textures evaluated in ground (world) coordinates.
//
// Contract: all functions are pure functions of (position, seed): the same world point gets
// the same value in every frame and from every thread, which keeps textures consistent
// across frames. Values are in [0, 1] (fbm: about [0, 1], mean 0.5). Inputs are metres times
// a frequency; float precision is ample for scenes within a few hundred metres of the origin.
#pragma once

#include <cstdint>

namespace vp::sim {

// Hash of an integer lattice point, in [0, 1).
float latticeValue(int x, int y, std::uint32_t seed);
// Smooth (quintic) value noise on the unit lattice.
float valueNoise(float x, float y, std::uint32_t seed);
// Fractal sum of `octaves` value noises (lacunarity 2, gain 0.5), normalised to ~[0, 1].
float fbm(float x, float y, int octaves, std::uint32_t seed);
// 1 - |2 n - 1| of value noise: thin bright ridges along the zero set, for cracks and veins.
float ridge(float x, float y, std::uint32_t seed);
// Distance to the nearest feature point of a jittered grid (cellular / Worley), in cells.
float cellular(float x, float y, std::uint32_t seed, std::uint32_t* cellHash = nullptr);
// 3D value noise (for tree canopies, whose texture must not stretch on steep faces).
float valueNoise3(float x, float y, float z, std::uint32_t seed);

}  // namespace vp::sim
