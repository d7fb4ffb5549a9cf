#pragma once
/// \file
/// A ray-cast ellipsoid impostor for bodies too far for PGM (Cozzi and Stoner, "GPU Ray
/// Casting of Virtual Globes", ../shared/papers/cozzi-stoner-gpu-ray-casting-globes.txt;
/// docs/ray-cast-globe.md).
///
/// Proxy geometry that bounds the ellipsoid as seen from the eye invokes a fragment shader
/// that intersects the pixel's eye ray with the ellipsoid in the space where it is a unit
/// sphere, discards misses, shades the hit with the geodetic normal, textures it by latitude
/// and longitude, and writes its depth in the reversed-Z convention of clod::Camera, so that
/// rasterised objects depth-test against it.

#include <regolith/clod/Camera.hpp>
#include <regolith/gl/GlObjects.hpp>
#include <regolith/gl/Image.hpp>
#include <regolith/gl/Program.hpp>

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace regolith::farfield {

/// One body to draw: an ellipsoid of revolution in the scene's frame (metres, double).
struct GlobeBody {
  glm::dvec3 centre{0.0};       ///< the body's centre in the scene's frame
  glm::dmat3 orientation{1.0};  ///< body-fixed → scene rotation (columns: body x, y, z)
  double a = 1.0;               ///< equatorial radius, metres (> 0, finite)
  double b = 1.0;               ///< polar radius, metres (> 0, finite), along body z
  /// An equirectangular RGBA8 texture (0 for none), sampled with its own filter state.
  /// Column 0 starts at longitude −180°, the first row uploaded (GL row 0) is the north edge
  /// (+90°), texel centres at (i + 0.5) · 360° / width. It must wrap (GL_REPEAT) in s, so
  /// that ±180° blends both edge columns; makeEquirectangularTexture() sets it up so.
  gl::Id albedoTexture = 0;
  glm::vec3 colour{0.8F, 0.8F, 0.8F};  ///< the albedo without a texture, or its tint
};

/// Proxy geometry that invokes the ray-casting fragment shader.
enum class GlobeProxy {
  Box,      ///< the ellipsoid's bounding box (8 corners, 12 triangles), front faces culled
  Polygon,  ///< a viewport-aligned polygon about the silhouette circle, as a triangle fan
};

struct GlobeOptions {
  GlobeProxy proxy = GlobeProxy::Polygon;
  /// Vertices of the bounding polygon (≥ 3): its edges touch the silhouette circle at this
  /// many tangent points. More points: fewer ray misses, more vertices.
  int polygonPoints = 16;
  /// Count rays cast and rays hit with atomic counters (GlobeFrame::raysCast, raysHit).
  /// Costs an atomic per fragment and a read-back stall per draw: for measurements.
  bool countRays = false;
  float ambient = 0.08F;  ///< light where the sun does not shine, as a fraction of the albedo
};

/// What one draw did.
struct GlobeFrame {
  /// False if nothing was drawn: the eye is inside the ellipsoid (or on it).
  bool drawn = false;
  int proxyVertices = 0;       ///< vertices submitted (36 for the box, N for the polygon)
  std::uint64_t raysCast = 0;  ///< fragments that ran the ray cast (GlobeOptions::countRays)
  std::uint64_t raysHit = 0;   ///< of these, rays that hit the ellipsoid
};

/// The proxy geometry of one view, on the CPU in double (the draw's set-up, public so that
/// it can be tested on its own).
struct GlobeProxyGeometry {
  /// Vertices relative to the camera position (scene axes, metres): 36 (12 triangles of the
  /// box, counter-clockwise seen from outside) or N (a convex fan, counter-clockwise seen
  /// from the eye). Empty if the eye is inside the ellipsoid.
  std::vector<glm::dvec3> vertices;
  /// Eye − centre in the scaled space (body axes divided by a, a, b): the ellipsoid is the
  /// unit sphere there.
  glm::dvec3 eyeScaled{0.0};
  /// |eyeScaled|² − 1, formed in double as (|e| − 1)(|e| + 1): the constant term of the
  /// ray–sphere quadratic, > 0 outside.
  double c = 0.0;
};

/// Builds the proxy of `body` seen from `camera`. The polygon is built in the scaled space:
/// the silhouette circle of the unit sphere seen from the eye has its centre at
/// (1 − 1/|e|²)·(−e) from the eye and radius √(1 − 1/|e|²); the N-gon whose edges touch it
/// (vertices at radius / cos(π/N), plus 1e-6·(|e| + 1)), its first vertex towards the
/// camera's up, is mapped back by the body's scale and rotation. The box is the body's [−a, a]² ×
/// [−b, b] inflated by 1e-6 of the eye's distance plus 1e-6 of a, so that float rounding of its
/// vertices cannot cut a silhouette pixel. Throws InvalidArgument for a non-finite or non-positive
/// radius or a non-finite centre.
[[nodiscard]] GlobeProxyGeometry globeProxy(const clod::Camera& camera, const GlobeBody& body,
                                            GlobeProxy proxy, int polygonPoints);

/// An equirectangular RGBA8 texture for GlobeBody::albedoTexture from an image whose row 0
/// is the north edge: wraps in s, clamps in t, trilinear with mipmaps if `mipmaps`, else
/// bilinear on level 0. Throws InvalidArgument for an empty image.
[[nodiscard]] gl::Texture makeEquirectangularTexture(const gl::RgbaImage& image, bool mipmaps);

/// Draws ellipsoids as ray-cast impostors.
///
/// Precision: the GPU never sees a position of planetary magnitude. The CPU forms the eye
/// relative to the body in double, in the scaled space, and hands the shader that vector,
/// the quadratic's constant term |e|² − 1 (exact in double), and the eye → scaled-space
/// matrix. The shader takes the ray through the pixel centre from gl_FragCoord, as the ray
/// through the centre's own pixel (parallel to the centre by construction) plus a small
/// offset that the float matrix rounds in proportion to its size, and solves
/// the quadratic in the form that loses no digits in float: the discriminant as 1 − |l|²
/// with l the ray's closest approach to the centre (never the difference of two squares of
/// the distance, which at 10^11 m would cancel), and the near root as c / (b + √disc) (never
/// b − √disc, which cancels above the nadir from a low eye). Depth = near / view distance.
///
/// Low eye: for c < 1/2 the discriminant is (b − √c)(b + √c) instead, which keeps the
/// horizon of an eye a few metres or millimetres up to the float ray's own precision.
/// Hits nearer than the camera's near plane are discarded, as the rasteriser clips there.
///
/// Draws into the bound framebuffer, whose viewport must be camera.width × camera.height at
/// origin (0, 0), with the reversed-Z state of gl::RenderTarget::bind() (gl::useReversedZ).
/// Leaves its program bound and the culling state as it found it. The relief is not shaded
/// (no height texture): the surface is the smooth ellipsoid. Move-only; belongs to its GL
/// context's thread.
class RayCastGlobe {
 public:
  /// Compiles the shaders. Throws InvalidArgument if polygonPoints < 3 or > 4096, GlError
  /// if a shader does not compile.
  explicit RayCastGlobe(const GlobeOptions& options = {});

  [[nodiscard]] const GlobeOptions& options() const noexcept { return options_; }
  /// Changes the proxy (the polygon's point count is checked as in the constructor).
  void setProxy(GlobeProxy proxy, int polygonPoints);
  void setCountRays(bool on) noexcept { options_.countRays = on; }

  /// Draws `body` seen from `camera`, lit by the unit direction towards the sun
  /// `sunDirection` (scene axes). Throws InvalidArgument for a bad body (globeProxy) or a
  /// non-finite sun direction, GlError if GL reports an error.
  ///
  /// `keepDepth`: a depth texture of the target's size holding what was drawn before (0:
  /// none). Pixels where it is non-zero are left alone: the impostor fills in only around
  /// what is drawn (FarField's hand-off).
  GlobeFrame draw(const clod::Camera& camera, const GlobeBody& body, const glm::dvec3& sunDirection,
                  gl::Id keepDepth = 0);

 private:
  GlobeOptions options_;
  gl::Program program_;
  gl::Program countingProgram_;
  gl::VertexArray vao_;
  gl::Buffer vertices_;
  gl::Buffer counters_;
  std::ptrdiff_t capacity_ = 0;  // bytes (GLsizeiptr)
};

}  // namespace regolith::farfield
