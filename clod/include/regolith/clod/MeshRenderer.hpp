#pragma once
/// \file
/// Brute-force reference renderer: every sample of a plane DEM is a vertex.

#include <regolith/clod/Camera.hpp>
#include <regolith/gl/GlObjects.hpp>
#include <regolith/gl/Program.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include <glm/vec3.hpp>

#include <cstddef>

namespace regolith::clod {

/// Draws a whole plane DEM at full resolution: one triangle strip per pair of rows, heights
/// from an R32F texture of the entire grid, the same triangulation, nodata rule and lighting
/// as ClipmapTerrain. It is the reference that clipmap images are compared with, and the
/// baseline of bench/clod_bench. Its cost grows with the DEM (rows·cols vertices per frame).
///
/// Positions: (x, y, h) in the grid frame, sent as offsets from sample (0, 0) plus that
/// sample's camera-relative position (double on the CPU). Needs a current GL 4.5 context.
class MeshRenderer {
 public:
  /// Reads every sample of `source` (rows·cols floats go to the GPU). Throws
  /// InvalidArgument if the source's size differs from the grid or exceeds 16384 a side.
  MeshRenderer(const topo::TopoGrid& grid, const topo::SampleSource& source);

  /// Draws into the bound framebuffer. Returns the vertices submitted.
  std::size_t draw(const Camera& camera) const;

  glm::vec3 lightDirection{0.4F, -0.3F, 0.866F};
  glm::vec3 albedo{0.78F, 0.66F, 0.55F};
  float ambient = 0.2F;

 private:
  topo::TopoGrid grid_;
  gl::Program program_;
  gl::VertexArray vao_;
  gl::Texture heights_;
};

}  // namespace regolith::clod
