#pragma once
/// \file
/// The geometry of planetary projective grid mapping (../shared/papers/planetary-pgm.txt,
/// §3–§5 and §7), on the CPU in double: the ray–circle reduction, the reference spheres and
/// the sampling camera. The GPU pass of PgmRenderer evaluates the same formulas in float;
/// these functions are its reference and its per-frame set-up (docs/far-field.md).
///
/// Conventions. The eye E is at distance d from the body's centre C. The nadir n̂ is the
/// unit vector from E towards C. A ray r̂ has the ray angle ω = ∠(r̂, n̂). Where a ray meets a
/// sphere about C, the normal angle γ is the angle between the sphere's normal there and the
/// antinadir −n̂ (the angle at C between E and the hit). Angles are radians.

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include <optional>
#include <vector>

namespace regolith::farfield {

/// Normal angle γ of the front hit of a ray at angle ω with the sphere of radius r seen from
/// distance d > r, or nullopt if the ray misses (ω > asin(r/d)). Stable for small altitudes
/// and small angles: the distance to the hit is t = (d² − r²) / (d·cos ω + √(r² − d²·sin² ω))
/// (no difference of near-equal terms) and sin γ = t·sin ω / r (law of sines).
[[nodiscard]] std::optional<double> frontNormalAngle(double omega, double d, double r) noexcept;

/// Normal angle of the back (far) hit of a ray at angle ω with the sphere of radius r, seen
/// from distance d (the eye may be inside the sphere), or nullopt if it misses.
[[nodiscard]] std::optional<double> backNormalAngle(double omega, double d, double r) noexcept;

/// The point of a sphere of radius r at normal angle γ in the plane of n̂ and k̂ (k̂ ⊥ n̂, unit,
/// towards the ray), relative to the eye at distance d: (d − r·cos γ)·n̂ + r·sin γ·k̂, with
/// d − r·cos γ evaluated as (d − r) + 2r·sin²(γ/2) so that a small altitude keeps its digits.
/// This is the paper's eye-space position P (§3, law of sines) written as a difference-free
/// sum; unlike t·r̂ it also places a blended γ (which lies on neither reference sphere along
/// r̂) on the primary sphere.
[[nodiscard]] glm::dvec3 eyeSpacePoint(double gamma, double d, double r, const glm::dvec3& nadir,
                                       const glm::dvec3& k) noexcept;

/// The two reference spheres of one frame (§4) and the angles the ray pass blends by.
struct ReferenceSpheres {
  double d = 0.0;            ///< eye distance from the centre
  double primary = 0.0;      ///< r_p: the minimum visible radius of the previous frame, clamped
  double maximum = 0.0;      ///< r_max: the body's maximum radius (highest datum)
  double secondary = 0.0;    ///< r_s = d·cos γ₀ (eq. 4); ≤ 0: no secondary sphere (impostor)
  double zeta = 0.0;         ///< the blend threshold ζ ∈ (0, 1]
  double tau0 = 0.0;         ///< τ₀ = asin(r_p/d), the primary sphere's tangent angle (eq. 3)
  double tauTop = 0.0;       ///< top of the pertinent rays: asin(r_max/d), or π/2 inside r_max
  double begin = 0.0;        ///< b = ζ·τ₀: rays below it use the primary sphere only
  double gammaBegin = 0.0;   ///< γ_p(b)
  double gamma0 = 0.0;       ///< γ₀: normal angle where the primary tangent leaves r_max
  double tauS = 0.0;         ///< tangent angle of the secondary sphere, asin(r_s/d)
  double omegaSBegin = 0.0;  ///< the ray angle on the secondary sphere whose hit has γ_p(b)

  /// True if the secondary sphere exists (r_s > 0). When false the view is too far for PGM
  /// and the body is drawn as a ray-cast impostor (RayCastGlobe).
  [[nodiscard]] bool secondaryExists() const noexcept { return secondary > 0.0; }
};

/// Builds the reference spheres for an eye at distance d (> primary) from the centre.
/// `primary` is clamped into (0, d); `maximum` is raised to at least `primary`; zeta is
/// clamped into [0.05, 1].
[[nodiscard]] ReferenceSpheres referenceSpheres(double d, double primary, double maximum,
                                                double zeta) noexcept;

/// The normal angle γ the ray pass assigns to a ray at angle ω (the blend of eq. 1 between
/// the primary sphere and the secondary sphere, monotone in ω, reaching γ₀ at τ_top):
/// - ω ≤ b: the front hit on the primary sphere;
/// - b < ω: f = (ω − b)/(τ_top − b) clamped to [0, 1]; the primary's γ at min(ω, τ₀) mixed
///   by f with the secondary's γ at the ray angle mix(b, τ_s, f) (§4: "mixing between the
///   beginning ray angle and the angle of the ray tangent to the secondary reference
///   sphere"), b taken as min(b, τ_s) so the ray still meets S when r_s → 0.
/// Requires s.secondaryExists(). The paper's eq. 1 reads f = (ω − τ₀)/(b − τ₀), which would
/// be 1 (all secondary) at b, against its own text; this uses the reading the text states.
[[nodiscard]] double blendedNormalAngle(const ReferenceSpheres& s, double omega) noexcept;

/// The even-error spread of the grid's rays (PgmOptions::evenError; not in the paper,
/// docs/far-field.md). The sampling camera's grid is even in its image plane, so its cells are
/// longest on the ground where the rays graze the body: at the limb, and just inside it where
/// the occluded-area blend turns γ faster still. A cell's screen-space error grows as its
/// ground length squared over its distance, so an even grid is far finer than it needs to be
/// in the middle of the view and coarsest at the limb, where the error's 99th percentile lies.
///
/// The spread turns each grid ray about the nadir, within its plane: a ray at angle
/// ω < τ_top becomes the ray at F(ω). F is the inverse of the normalised cumulative of
/// dγ/√(distance) over the ray angle, with γ the blended normal angle and the distance that of
/// the point on the primary sphere; so each step of the grid spans about the same
/// (ground length)² / distance. F is monotone, F(0) = 0, F(τ_top) = τ_top, and F(ω) ≥ ω
/// (the cumulative's inverse is raised to the identity where it falls below it), so a grid
/// that holds the nadir still covers every ray it covered: along each azimuth the grid's rays
/// from the nadir to its edge, [0, ω_edge], become [0, F(ω_edge)] ⊇ [0, ω_edge].
struct RaySpread {
  double top = 0.0;           ///< τ_top: rays at or beyond it are left alone
  std::vector<double> table;  ///< F at ω = top·i/(n − 1), i = 0 … n − 1; empty: no spread

  [[nodiscard]] bool active() const noexcept { return table.size() >= 2; }
  /// F(ω): the table interpolated linearly, as the grid pass does in float.
  [[nodiscard]] double angle(double omega) const noexcept;
  /// The unit ray r turned about the nadir to the angle F(ω) (r itself where ω ≥ top, or
  /// where r is the nadir).
  [[nodiscard]] glm::dvec3 ray(const glm::dvec3& r, const glm::dvec3& nadir) const noexcept;
};

/// The spread for one frame's reference spheres (which must have a secondary sphere), as a
/// table of `entries` ≥ 2 values; an inactive spread if the spheres give no ray angles to
/// spread (τ_top ≤ 0).
[[nodiscard]] RaySpread evenErrorSpread(const ReferenceSpheres& s, int entries = 256);

/// The sampling camera of §5: its orientation and its frustum bounds on the plane at unit
/// distance, so that grid point (u, v) ∈ [0, 1]² has the eye ray
/// normalize(forward + (left + u·(right − left))·rightAxis + (bottom + v·(top − bottom))·up).
struct SamplingCamera {
  glm::dvec3 forward{0.0, 0.0, -1.0};
  glm::dvec3 rightAxis{1.0, 0.0, 0.0};
  glm::dvec3 up{0.0, 1.0, 0.0};  ///< towards the horizon: v = 1 is the far side
  double left = -1.0, right = 1.0, bottom = -1.0, top = 1.0;
  /// The corner rays of the frustum intersection (unit), before the nadir is added.
  std::vector<glm::dvec3> corners;
  /// True if the view frustum misses the planet frustum (the view looks away): the planet
  /// frustum's corners were used (§5, last paragraph of the frustum intersection).
  bool lookedAway = false;

  /// The unit eye ray of grid point (u, v).
  [[nodiscard]] glm::dvec3 ray(double u, double v) const noexcept;
  /// True if the direction lies in the sampling frustum: in front of the camera and within
  /// the bounds (with a relative tolerance of 1e-9).
  [[nodiscard]] bool holds(const glm::dvec3& direction) const noexcept;
};

/// A viewing frustum as four unit corner rays, counter-clockwise seen from the eye (for
/// example bottom-left, bottom-right, top-right, top-left), in the same axes as `nadir`.
struct Frustum {
  glm::dvec3 corners[4];
};

/// The corner rays of a pinhole camera: forward, right and up unit axes, vertical field of
/// view and aspect (width / height).
[[nodiscard]] Frustum viewFrustum(const glm::dvec3& forward, const glm::dvec3& right,
                                  const glm::dvec3& up, double fovYRadians, double aspect) noexcept;

/// The sampling camera for a view frustum, an eye at distance d from the centre in the
/// direction −nadir, and the pertinent cone's half-angle tauTop (ReferenceSpheres::tauTop):
/// the view frustum intersected with the planet frustum (a square frustum about the nadir
/// whose sides touch the cone, its up in the plane of the view's up and forward), done in the
/// horizon-aligned frame by clipping one convex cone by the other's planes (which yields
/// exactly the paper's two rules: corners of either inside the other, and plane–plane
/// intersections inside both), with the nadir included; then the view direction (mean of
/// the rays and the nadir with the sideways component removed) and the bounds on the unit
/// plane. Rays more than `maxHalfAngle` from the view direction are pulled in to it, so the
/// projection stays finite when the set spans nearly a half-space.
[[nodiscard]] SamplingCamera samplingCamera(const Frustum& view, const glm::dvec3& nadir,
                                            double tauTop, double maxHalfAngle = 1.45) noexcept;

/// §7 without the radius: equirectangular coordinates (p, q) = ((λ − λ₀)·cos φ₀, φ) in
/// radians of a unit body-fixed direction's planetodetic latitude φ and longitude λ (λ − λ₀
/// wrapped into [−π, π)). `surfaceNormal` is the ellipsoid's unit normal at the point.
struct MapCoords {
  double p = 0.0, q = 0.0;
};
[[nodiscard]] MapCoords equirectangular(const glm::dvec3& surfaceNormal, double lon0,
                                        double lat0) noexcept;
/// Polar stereographic coordinates on the unit sphere of the normal, (p, q) =
/// 2·tan(π/4 − |φ|/2)·(sin λ, ∓cos λ) (north: −cos, south: +cos), the radius left out, so
/// that a map in metres is (p, q)·k₀·R_map. Finite at the pole itself (0, 0).
[[nodiscard]] MapCoords polarStereographic(const glm::dvec3& surfaceNormal, bool north) noexcept;

/// The planetodetic unit normal of the ellipsoid (a, b) at the surface point in the
/// geocentric unit direction `s` (the sphere normal of PGM): normalize(s.x/a², s.y/a², s.z/b²).
[[nodiscard]] glm::dvec3 geodeticNormal(const glm::dvec3& s, double a, double b) noexcept;

/// The ellipsoid's radius along the unit direction s, less `reference`, evaluated without
/// subtracting radii: a·(b² − a²)·sin²ψ / (q·(b + q)) + (a − reference) with
/// q = √(b²·cos²ψ + a²·sin²ψ), ψ the geocentric latitude of s.
[[nodiscard]] double ellipsoidRadiusAbove(const glm::dvec3& s, double a, double b,
                                          double reference) noexcept;

}  // namespace regolith::farfield
