#pragma once
/// \file
/// Triangle meshes of grid regions, for physics engines (PLY and OBJ).

#include <regolith/topo/TopoDem.hpp>
#include <regolith/topo/TopoPlanet.hpp>

#include <glm/vec3.hpp>

#include <array>
#include <cstdint>
#include <iosfwd>
#include <vector>

namespace regolith::topo {

/// A rectangular block of samples. rows/cols of 0 mean "to the grid's edge".
struct GridWindow {
  std::size_t row0 = 0, col0 = 0, rows = 0, cols = 0;
};

/// Which coordinates mesh vertices are in.
/// - Grid: (x, y, h) of the DEM's grid, metres.
/// - BodyFixed: body-fixed metres, minus the mesh origin.
enum class MeshFrame : std::uint8_t { Grid, BodyFixed };

/// An indexed triangle mesh. Vertices are relative to `origin` (so a body-fixed mesh keeps
/// its precision after conversion to float); triangles wind counter-clockwise seen from
/// above the surface, so their normals point up.
struct TriangleMesh {
  glm::dvec3 origin{0.0};
  std::vector<glm::dvec3> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

/// One vertex per valid sample of the window; each cell becomes two triangles, and a
/// triangle touching a nodata sample is left out (a hole, never a spike to zero).
/// Throws InvalidArgument for a window outside the grid or one with fewer than 2×2 samples.
[[nodiscard]] TriangleMesh buildMesh(const TopoDem& dem, const GridWindow& window,
                                     MeshFrame frame = MeshFrame::Grid,
                                     const glm::dvec3& origin = glm::dvec3(0.0));
/// The same for a planet region, in body-fixed coordinates minus `origin`.
[[nodiscard]] TriangleMesh buildMesh(const TopoPlanet& planet, const GridWindow& window,
                                     const glm::dvec3& origin = glm::dvec3(0.0));

/// Wavefront OBJ text (vertices at full double precision, 1-based faces).
void writeObj(std::ostream& out, const TriangleMesh& mesh);
/// PLY, binary little-endian: double x, y, z per vertex and uint32 triangle lists; the
/// mesh origin is recorded in a comment line.
void writePly(std::ostream& out, const TriangleMesh& mesh);

}  // namespace regolith::topo
