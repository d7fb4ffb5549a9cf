#pragma once
// Helpers for the effect tests: render a terrain with colour and depth, recover the ground
// point under a pixel, compare images.

#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/gl/RenderTarget.hpp>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cstdlib>
#include <memory>
#include <optional>

namespace regolith::test {

struct Shot {
  gl::RgbaImage color;
  gl::DepthImage depth;
};

inline Shot renderShot(const clod::ClipmapTerrain& terrain, const clod::Camera& cam) {
  gl::RenderTarget target(cam.width, cam.height);
  target.clear({1.0F, 0.0F, 1.0F, 1.0F});
  (void)terrain.draw(cam);
  return {target.readColor(), target.readDepth()};
}

/// The scene point drawn at pixel (x, y), from the depth buffer; nullopt over background.
inline std::optional<glm::dvec3> groundAt(const Shot& s, const clod::Camera& cam, int x, int y) {
  const float z = s.depth.at(x, y);
  if (z <= 0.0F) return std::nullopt;
  const glm::dvec3 d = cam.ray(x + 0.5, y + 0.5);
  return cam.position + cam.viewDistance(z) / glm::dot(d, cam.forward()) * d;
}

/// Largest per-channel difference between pixel (x, y) of two images.
inline int pixelDiff(const gl::RgbaImage& a, const gl::RgbaImage& b, int x, int y) {
  int worst = 0;
  for (int c = 0; c < 3; ++c)
    worst = std::max(worst, std::abs(int{a.pixel(x, y)[c]} - int{b.pixel(x, y)[c]}));
  return worst;
}

/// A camera looking straight down at (x, y, h) from `height` above it, north up.
inline clod::Camera downCamera(const glm::dvec3& at, double height, int w, int h, double fov) {
  clod::Camera cam;
  cam.position = at + glm::dvec3(0.0, 0.0, height);
  cam.target = at;
  cam.up = {0.0, 1.0, 0.0};
  cam.fovYDegrees = fov;
  cam.width = w;
  cam.height = h;
  cam.near = 0.05;
  return cam;
}

}  // namespace regolith::test
