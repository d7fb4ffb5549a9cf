// Hashing, random numbers and gradient noise for the procedural generators.
#include "GenerateNoise.hpp"

#include <array>
#include <cmath>

namespace regolith::store::gen {

double Random::uniform() noexcept { return static_cast<double>(next() >> 11U) * 0x1.0p-53; }

std::size_t Random::poisson(double lambda) noexcept {
  // Knuth: count uniforms until their product drops below e^−λ. exp() is the only libm
  // call; λ is a constant per band, so its value is the same for every draw.
  const double limit = std::exp(-lambda);
  std::size_t k = 0;
  double p = uniform();
  while (p > limit && k < 1000) {
    ++k;
    p *= uniform();
  }
  return k;
}

namespace {

// The 12 edge directions of a cube (Perlin's improved-noise gradient set).
constexpr std::array<glm::dvec3, 12> kGradients{{{1, 1, 0},
                                                 {-1, 1, 0},
                                                 {1, -1, 0},
                                                 {-1, -1, 0},
                                                 {1, 0, 1},
                                                 {-1, 0, 1},
                                                 {1, 0, -1},
                                                 {-1, 0, -1},
                                                 {0, 1, 1},
                                                 {0, -1, 1},
                                                 {0, 1, -1},
                                                 {0, -1, -1}}};

double fade(double t) noexcept { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }

double lerp(double a, double b, double t) noexcept { return a + t * (b - a); }

double corner(std::int64_t ix, std::int64_t iy, std::int64_t iz, double fx, double fy, double fz,
              std::uint64_t seed) noexcept {
  // One mix of the lattice point's coordinates times large odd constants: enough for a
  // gradient choice, and a quarter of hashOf()'s cost on the hottest path.
  const std::uint64_t h = mix64(seed ^ (static_cast<std::uint64_t>(ix) * 0x9E3779B97F4A7C15ULL) ^
                                (static_cast<std::uint64_t>(iy) * 0xC2B2AE3D27D4EB4FULL) ^
                                (static_cast<std::uint64_t>(iz) * 0x165667B19E3779F9ULL));
  const glm::dvec3& g = kGradients[(h >> 32U) % kGradients.size()];
  return g.x * fx + g.y * fy + g.z * fz;
}

}  // namespace

double gradientNoise(const glm::dvec3& p, std::uint64_t seed) noexcept {
  const double flx = std::floor(p.x), fly = std::floor(p.y), flz = std::floor(p.z);
  const auto ix = static_cast<std::int64_t>(flx), iy = static_cast<std::int64_t>(fly),
             iz = static_cast<std::int64_t>(flz);
  const double fx = p.x - flx, fy = p.y - fly, fz = p.z - flz;
  const double u = fade(fx), v = fade(fy), w = fade(fz);
  const double c000 = corner(ix, iy, iz, fx, fy, fz, seed);
  const double c100 = corner(ix + 1, iy, iz, fx - 1.0, fy, fz, seed);
  const double c010 = corner(ix, iy + 1, iz, fx, fy - 1.0, fz, seed);
  const double c110 = corner(ix + 1, iy + 1, iz, fx - 1.0, fy - 1.0, fz, seed);
  const double c001 = corner(ix, iy, iz + 1, fx, fy, fz - 1.0, seed);
  const double c101 = corner(ix + 1, iy, iz + 1, fx - 1.0, fy, fz - 1.0, seed);
  const double c011 = corner(ix, iy + 1, iz + 1, fx, fy - 1.0, fz - 1.0, seed);
  const double c111 = corner(ix + 1, iy + 1, iz + 1, fx - 1.0, fy - 1.0, fz - 1.0, seed);
  return lerp(lerp(lerp(c000, c100, u), lerp(c010, c110, u), v),
              lerp(lerp(c001, c101, u), lerp(c011, c111, u), v), w);
}

double fbm(const glm::dvec3& p, std::size_t octaves, double gain, std::uint64_t seed) noexcept {
  double sum = 0.0, amplitude = 1.0, frequency = 1.0;
  for (std::size_t o = 0; o < octaves; ++o) {
    const std::uint64_t s = hashOf(seed, o);
    // An offset per octave, so lattice points (where noise is zero) do not line up.
    Random r(s);
    const glm::dvec3 offset(r.uniform(0.0, 256.0), r.uniform(0.0, 256.0), r.uniform(0.0, 256.0));
    sum += amplitude * gradientNoise(p * frequency + offset, s);
    amplitude *= gain;
    frequency *= 2.0;
  }
  return sum;
}

}  // namespace regolith::store::gen
