#pragma once
// Deterministic building blocks of the procedural generators (Generate.hpp): integer hashing,
// a seeded random stream and 3D gradient noise. Only integer operations and IEEE double
// arithmetic (no libm), so the same inputs give the same bits everywhere.

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>

namespace regolith::store::gen {

/// SplitMix64's finaliser: a bijective 64-bit mix.
[[nodiscard]] constexpr std::uint64_t mix64(std::uint64_t x) noexcept {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30U)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27U)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31U);
}

/// A hash of a seed and up to three integers (order matters).
[[nodiscard]] constexpr std::uint64_t hashOf(std::uint64_t seed, std::uint64_t a,
                                             std::uint64_t b = 0, std::uint64_t c = 0) noexcept {
  return mix64(mix64(mix64(mix64(seed) ^ a) ^ b) ^ c);
}

/// A seeded stream of random numbers (SplitMix64). Not thread-safe; cheap to create.
class Random {
 public:
  explicit constexpr Random(std::uint64_t seed) noexcept : state_(seed) {}
  constexpr std::uint64_t next() noexcept {
    state_ += 0x9E3779B97F4A7C15ULL;
    std::uint64_t z = state_;
    z = (z ^ (z >> 30U)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27U)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31U);
  }
  /// Uniform in [0, 1), 53 random bits.
  double uniform() noexcept;
  /// Uniform in [lo, hi).
  double uniform(double lo, double hi) noexcept { return lo + (hi - lo) * uniform(); }
  /// Poisson-distributed count with mean lambda (Knuth's method; for small lambda).
  std::size_t poisson(double lambda) noexcept;

 private:
  std::uint64_t state_;
};

/// Gradient (Perlin-style) noise at p: zero at lattice points, about −1…1, C2 (quintic fade).
[[nodiscard]] double gradientNoise(const glm::dvec3& p, std::uint64_t seed) noexcept;

/// Fractal Brownian motion: sum over octaves o < octaves of gain^o · noise(p·2^o + offset_o),
/// each octave with its own seed and offset (derived from `seed`).
[[nodiscard]] double fbm(const glm::dvec3& p, std::size_t octaves, double gain,
                         std::uint64_t seed) noexcept;

}  // namespace regolith::store::gen
