#pragma once
/// \file
/// The cut-out test a ClipmapTerrain applies where a DEM wins over it (ClipmapCutOut): what
/// the scene renderer computes for it on the CPU (render/CutOutGeometry.hpp), with no GL type,
/// so that CPU geometry needs no GL header.

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include <cstddef>

namespace regolith::clod {

/// Most DEMs that can win over one terrain (the cut-out shader's arrays).
inline constexpr std::size_t kMaxClipmapCutOuts = 4;

/// The affine map eye → DEM mask cell that the cut-out test applies per fragment:
/// (col, row, h / 1) = eyeToCell · eye + cellOfCamera, where integer (col, row) are the
/// corners of cell (row, col) (topo::TopoGrid::fractionalIndex of the grid-frame point).
/// Double precision (render::cutOutTransform() makes it); the shader takes it cast to float.
struct CutOutTransform {
  glm::dmat3 eyeToCell{1.0};
  glm::dvec3 cellOfCamera{0.0};
};

/// What the cut-out test needs of the projection to rebuild a fragment's eye position from
/// gl_FragCoord and its reversed-Z depth: (near, aspect / f, 1 / f), f = 1 / tan(fovY / 2),
/// aspect = width / height (Camera's projection). Defined in ClipmapTerrain.cpp.
[[nodiscard]] glm::dvec3 cutOutProjection(double near, double fovYDegrees, int width, int height);

}  // namespace regolith::clod
