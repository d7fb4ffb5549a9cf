#pragma once
/// \file
/// Captured images: 8-bit RGBA colour and float depth, row 0 at the top.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace regolith::gl {

/// An RGBA8 image, row-major, row 0 at the top (as a PNG stores it). Value type.
struct RgbaImage {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgba;  ///< width·height·4 bytes

  [[nodiscard]] const std::uint8_t* pixel(int x, int y) const noexcept {
    return rgba.data() + 4 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
                              static_cast<std::size_t>(x));
  }
  /// True if pixel (x, y) has exactly colour (r, g, b).
  [[nodiscard]] bool is(int x, int y, std::uint8_t r, std::uint8_t g,
                        std::uint8_t b) const noexcept {
    const auto* p = pixel(x, y);
    return p[0] == r && p[1] == g && p[2] == b;
  }
};

/// A depth image in [0, 1] as the depth buffer holds it, row 0 at the top. With the
/// reversed-Z projection of Camera, depth = near / (distance along the view axis), and 0
/// where nothing was drawn. Value type.
struct DepthImage {
  int width = 0, height = 0;
  std::vector<float> depth;  ///< width·height values

  [[nodiscard]] float at(int x, int y) const noexcept {
    return depth[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
                 static_cast<std::size_t>(x)];
  }
  /// True if the inner pixel (x, y) and its 4 neighbours were drawn and the neighbours' view
  /// distances (near / depth, Camera::viewDistance) lie within `tolerance` × that of (x, y):
  /// no depth discontinuity there. For comparing renders away from silhouettes.
  [[nodiscard]] bool smoothAt(int x, int y, double near, double tolerance) const noexcept {
    const float r = at(x, y);
    if (r <= 0.0F) return false;
    const double dr = near / static_cast<double>(r);
    for (const auto& [dx, dy] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
      const float n = at(x + dx, y + dy);
      if (!(n > 0.0F && std::abs(near / static_cast<double>(n) - dr) < tolerance * dr)) {
        return false;
      }
    }
    return true;
  }
};

/// Writes an 8-bit RGBA PNG with libpng, crash-safely (a temporary name beside `path`, then
/// rename). Throws regolith::Error naming the path if the file cannot be written.
void writePng(const std::string& path, const RgbaImage& image);

/// Reads an 8-bit RGB or RGBA PNG (as written by writePng) back into RGBA. Throws
/// regolith::Error naming the path if it is missing or not such a PNG.
[[nodiscard]] RgbaImage readPng(const std::string& path);

}  // namespace regolith::gl
