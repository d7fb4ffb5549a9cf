#pragma once
// GLSL of the ray-cast globe (docs/ray-cast-globe.md). The counting variant is kVersion +
// "#define COUNT_RAYS\n" + kFragment.

namespace regolith::farfield::globe_shaders {

inline constexpr const char* kVersion = "#version 450 core\n";

/// The proxy: vertices relative to the camera (float of a double difference), projected by
/// clod::Camera::viewProjection(). Nothing is interpolated: the fragment shader takes its ray
/// from gl_FragCoord, so both proxies give bit-identical fragments.
inline constexpr const char* kVertex = R"(#version 450 core
layout(location = 0) in vec3 aPos;
uniform mat4 uViewProj;
void main() { gl_Position = uViewProj * vec4(aPos, 1.0); }
)";

/// The ray cast. Scaled space: body axes divided by (a, a, b) and multiplied by a, so the
/// ellipsoid is the unit sphere and the eye-to-scaled matrix has entries of order 1.
inline constexpr const char* kFragment = R"(
layout(location = 0) out vec4 oColour;
layout(binding = 0) uniform sampler2D uAlbedo;
#ifdef COUNT_RAYS
layout(binding = 0, offset = 0) uniform atomic_uint uCast;
layout(binding = 0, offset = 4) uniform atomic_uint uHit;
#endif
uniform vec2 uRefPx;          // the reference pixel (gl_FragCoord axes)
uniform vec3 uRefDir;         // its eye ray (view-axis component 1), scaled space
uniform float uK;             // uRefDir = uK·uCentre (centre mode), else 0
uniform float uFocal;         // focal length, pixels
uniform mat3 uEyeToScaled;    // eye axes → scaled space (· a): diag(1, 1, a/b)·Rbodyᵀ·Rcamᵀ
uniform vec3 uCentre;         // the sphere's centre from the eye, scaled space (−e)
uniform float uC;             // |e|² − 1, from double (> 0)
uniform float uSqrtC;         // √c from double if c < 1/2, else 0
uniform float uNearOverA;     // camera near / a
uniform float uAOverB;        // a / b
uniform vec3 uSun;            // unit direction to the sun, body axes
uniform vec3 uColour;
uniform float uAmbient;
uniform int uTextured;
uniform int uKeepDrawn;
layout(binding = 1) uniform sampler2D uDrawnDepth;  // depth before this draw (0 = empty)

const float PI = 3.14159265358979;

void main() {
  // Hand-off: pixels something else already drew keep it.
  if (uKeepDrawn != 0 && texelFetch(uDrawnDepth, ivec2(gl_FragCoord.xy), 0).r > 0.0) discard;
#ifdef COUNT_RAYS
  atomicCounterIncrement(uCast);
#endif
  // The eye ray through this pixel centre (view-axis component 1, so that the hit's
  // parameter along it is the view distance), as the reference pixel's ray plus a small
  // offset w: the float matrix then rounds only the offset. In centre mode the reference is
  // the pixel of the centre, whose ray uK·uCentre is parallel to uCentre by construction.
  vec3 w = uEyeToScaled * vec3((gl_FragCoord.xy - uRefPx) / uFocal, 0.0);
  vec3 d = uRefDir + w;
  float dl = length(d);
  vec3 dh = d / dl;
  // |s·dh − c|² = 1. With b = dh·c and l = c − b·dh (the closest approach to the centre),
  // the discriminant is 1 − |l|²: no difference of two squares of the distance. In centre
  // mode l = ((w·dh)·dh − w) / uK, from the small offset alone: c − b·dh would lose ulp(|c|)
  // (a pixel's worth at 10^11 m through a narrow field of view).
  float b = dot(dh, uCentre);
  vec3 l = uK > 0.0 ? (dot(w, dh) * dh - w) / uK : uCentre - b * dh;
  // Near the horizon of a low eye (c < 1/2) b ≈ √c is small and b² − c keeps more digits
  // than 1 − |l|² (whose rounding, ε·|c|, is 1e-3 px of horizon there): pick per frame.
  float disc = uSqrtC > 0.0 ? (b - uSqrtC) * (b + uSqrtC) : 1.0 - dot(l, l);
  bool hit = disc >= 0.0 && b > 0.0;
  float sq = sqrt(max(disc, 0.0));
  // Hit − centre = (s − b)·dh − l with s − b = −√disc: unit, and no cancellation. On a miss
  // (kept for the derivatives of the texture lookup) it is the closest approach.
  vec3 n = normalize(-(l + sq * dh));
  // Geodetic normal (body axes): the gradient of x² + y² + (a/b)²·z² at (n.x, n.y, n.z·a/b).
  vec3 g = normalize(vec3(n.xy, n.z * uAOverB));
  vec3 albedo = uColour;
  if (uTextured != 0) {
    float lat = atan(g.z, length(g.xy));
    float lon = atan(n.y, n.x);
    // Tarini's seam fix: u and a copy that jumps at 0° instead of ±180°; each quad takes the
    // derivatives of the one that is continuous there, so ±180° gets no coarse-mip line.
    float u1 = lon / (2.0 * PI) + 0.5;
    float u2 = fract(u1 + 0.5) - 0.5;
    float v = 0.5 - lat / PI;
    vec2 dx = vec2(dFdxFine(u1), dFdxFine(v)), dy = vec2(dFdyFine(u1), dFdyFine(v));
    float dx2 = dFdxFine(u2), dy2 = dFdyFine(u2);
    if (abs(dx2) < abs(dx.x)) dx.x = dx2;
    if (abs(dy2) < abs(dy.x)) dy.x = dy2;
    // The level of detail of the ground footprint: a texel row near a pole spans less ground
    // than its width says, so the longitude derivative is scaled by cos φ (else every pixel
    // about a pole reads the coarsest level, the map's average, as a dot).
    dx.x *= cos(lat);
    dy.x *= cos(lat);
    albedo *= textureGrad(uAlbedo, vec2(u1, v), dx, dy).rgb;
  }
  // Near root s = c / (b + √disc) (b − √disc would cancel above the nadir from a low eye);
  // view distance t = s / |d|·a, depth = near / t. Hits nearer than the near plane are
  // clipped, as the rasteriser clips triangles there.
  float depth = uNearOverA * dl * (b + sq) / uC;
  if (!hit || depth > 1.0) discard;
#ifdef COUNT_RAYS
  atomicCounterIncrement(uHit);
#endif
  gl_FragDepth = depth;
  float diffuse = max(dot(g, uSun), 0.0);
  oColour = vec4(albedo * (uAmbient + (1.0 - uAmbient) * diffuse), 1.0);
}
)";

}  // namespace regolith::farfield::globe_shaders
