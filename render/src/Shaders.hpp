#pragma once
// GLSL of the surface-map accumulation (docs/colour-composition.md). The fragment shaders
// are kVersion + kHelpers + the pass's source.

namespace regolith::render::shaders {

inline constexpr const char* kVersion = "#version 450 core\n";

/// One dataset's accumulation pass. Every quantity that would lose precision in float as an
/// absolute value (latitude, longitude, map coordinates, heights) is formed as a difference
/// from the dataset's reference point R, whose own values the CPU computed in double.
inline constexpr const char* kHelpers = R"(
// sin, tan and atan of small arguments by their series: the GPU's own functions are
// accurate in absolute terms (~1e-9 on llvmpipe), which at a few 1e-5 rad (100 m on Mars)
// would be a relative error of 1e-4 and, times the radius, centimetres.
float sinS(float x) {
  if (abs(x) < 1e-2) {
    float x2 = x * x;
    return x * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0));
  }
  return sin(x);
}
float tanS(float x) {
  if (abs(x) < 1e-2) {
    float x2 = x * x;
    return x * (1.0 + x2 * (1.0 / 3.0 + x2 * (2.0 / 15.0)));
  }
  return tan(x);
}
float atanhS(float x) {
  if (abs(x) < 1e-2) {
    float x2 = x * x;
    return x * (1.0 + x2 * (1.0 / 3.0 + x2 / 5.0));
  }
  return atanh(x);
}
float atanS(float y, float x) {
  if (x > 0.0 && abs(y) < 1e-2 * x) {
    float t = y / x, t2 = t * t;
    return t * (1.0 - t2 * (1.0 / 3.0 - t2 / 5.0));
  }
  return atan(y, x);
}

)";

/// The frame's geodetic pass (Kooima's deferred texturing, thesis §3.4.2): per pixel, the
/// planetodetic latitude and longitude as differences from the frame's reference point R0
/// (radians), and the height above the reference surface, into an RGBA32F target. Every
/// dataset pass then starts from these. Every quantity that would lose precision in float
/// as an absolute value is formed as a difference from R0's, computed in double on the CPU.
inline constexpr const char* kGeodeticFragment = R"(
layout(binding = 2) uniform sampler2D uDepth;
layout(location = 0) out vec4 oGeo;
uniform mat3 uEyeToWorld;   // columns: camera right, up, back in world (body-fixed) axes
uniform vec2 uViewport;     // width, height in pixels
uniform float uFocal;       // focal length, pixels
uniform float uNear;        // near plane, metres
uniform vec3 uRRel;         // R0 − camera, metres
uniform mat3 uWorldToEnu;   // body-fixed → east, north, up at R0
uniform vec4 uRef;          // sin φ0, cos φ0, ρ0 (distance from the axis), N(φ0)
uniform float uA;           // equatorial radius
uniform float uE2;          // first eccentricity squared

void main() {
  vec2 frag = gl_FragCoord.xy;
  float depth = texelFetch(uDepth, ivec2(frag), 0).r;
  if (depth <= 0.0) discard;
  // Camera-relative position (the depth holds near / distance along the view axis).
  vec3 eye = vec3((frag - 0.5 * uViewport) / uFocal, -1.0) * (uNear / depth);
  vec3 q = uWorldToEnu * (uEyeToWorld * eye - uRRel);  // east, north, up from R0

  // Planetodetic latitude and longitude as differences from R0's (radians), and the height.
  float sR = uRef.x, cR = uRef.y, rhoR = uRef.z, NR = uRef.w;
  float dx = cR * q.z - sR * q.y;  // towards the axis-normal at λR
  float ye = q.x;                  // east
  float dz = cR * q.y + sR * q.z;  // along the axis
  float xr = rhoR + dx;
  float dLon = atanS(ye, xr);
  float rho = sqrt(xr * xr + ye * ye);
  float dRho = xr > 0.0 ? dx + ye * ye / (rho + xr) : rho - rhoR;
  float ZR = NR * sR;
  float WR = sqrt(1.0 - uE2 * sR * sR);
  float dPhi = 0.0, dZ = dz, dN = 0.0, N = NR, W = WR, s = sR, h2 = 0.0;
  // φ = atan2(z + e² N(φ) sin φ, ρ) iterated (exact at any height); as a difference from
  // φR each term is small, so float keeps its relative precision. Each update shrinks the
  // error by about e² (Mars: 0.012), so three leave ~1e-7 of the distance, float's own
  // precision (a sphere needs one; the count is constant so that the loop unrolls).
  for (int it = 0; it <= 3; ++it) {  // a constant count: the compiler unrolls it
    float sD = sinS(dPhi);
    h2 = sinS(0.5 * dPhi);
    s = sR * (1.0 - 2.0 * h2 * h2) + cR * sD;
    float ds = cR * sD - 2.0 * sR * h2 * h2;  // sin φ − sin φR
    W = sqrt(1.0 - uE2 * s * s);
    N = uA / W;
    dN = N * NR * uE2 * ds * (s + sR) / (uA * (W + WR));  // N − NR
    dZ = dz + uE2 * (N * ds + dN * sR);
    if (it < 3) dPhi = atanS(dZ * rhoR - dRho * ZR, (rhoR + dRho) * rhoR + (ZR + dZ) * ZR);
  }
  float sinPhi = s;
  float cosPhi = cR * (1.0 - 2.0 * h2 * h2) - sR * sinS(dPhi);
  float height = -dN - 2.0 * NR * h2 * h2 + dRho * cosPhi + dZ * sinPhi;

  oGeo = vec4(dPhi, dLon, height, 1.0);
}
)";

/// One dataset's accumulation pass.
inline constexpr const char* kAccumulateFragment = R"(
layout(binding = 0) uniform sampler2D uWindowTex;  // (value or 0, valid, mask), bilinear
layout(binding = 1) uniform sampler2D uGeo;    // the geodetic pass's output
layout(binding = 2) uniform sampler2D uDepth;
layout(location = 0) out vec4 oSums;
layout(location = 1) out vec4 oCover;

uniform mat3 uEyeToWorld;   // columns: camera right, up, back in world (body-fixed) axes
uniform vec2 uViewport;     // width, height in pixels
uniform float uFocal;       // focal length, pixels
uniform float uNear;        // near plane, metres
uniform vec3 uRRel;         // R − camera, metres
uniform mat3 uWorldToEnu;   // body-fixed → east, north, up at R
uniform vec4 uRef;          // sin φR, cos φR (R: this dataset's reference point)
uniform float uA;           // equatorial radius
uniform float uE2;          // first eccentricity squared
uniform vec2 uRefDelta;     // φR − φ0, λR − λ0 (radians, wrapped): R from the frame's R0
uniform int uKind;          // 0 latitude/longitude grid or equirectangular, 1 polar
                            // stereographic, 2 local tangent plane
uniform int uCentric;       // kind 0: the grid reads planetocentric latitudes
uniform vec2 uLinScale;     // kind 0: grid units per radian of longitude, of latitude
uniform vec4 uPolar;        // kind 1: sign (+1 north), tan(π/4 − φNR/2), ρR, ρR / tan(...)
uniform vec2 uPolarDl;      // kind 1: sin, cos of λR − λ0
uniform float uEcc;         // kind 1: first eccentricity
uniform vec3 uPlaneX;       // kind 2: the plane's x axis in R's east-north-up frame
uniform vec3 uPlaneY;       // kind 2: its y axis
uniform float uHmid;        // kind 2: the height at which the dataset is located
uniform vec2 uTexR;         // R in window texels (column, row) of the level read
uniform vec2 uSpacingL;     // that level's spacing, grid units
uniform vec2 uSpacing0;     // level 0's spacing, grid units
uniform ivec2 uWindow;      // window size, texels
uniform vec4 uEdge;         // grid units from R to the west, east, south and north edge
uniform vec4 uEdgeOn;       // 1 for an edge that bounds the data (0: wraps, or a pole)
uniform int uPlanet;        // edges in degrees (metres otherwise)
uniform float uFeather;     // metres; 0: a hard edge
uniform int uRole;          // 0 albedo, 1 overlay
uniform float uLogN;        // log n of the quality
uniform float uMinQuality;

void main() {
  vec2 frag = gl_FragCoord.xy;
  float depth = texelFetch(uDepth, ivec2(frag), 0).r;
  // Camera-relative position (the depth holds near / distance along the view axis).
  vec3 eye = vec3((frag - 0.5 * uViewport) / uFocal, -1.0) * (uNear / max(depth, 1e-30));
  vec3 q = uWorldToEnu * (uEyeToWorld * eye - uRRel);  // east, north, up from R

  // Latitude and longitude as differences from R's, from the geodetic pass's (from R0's).
  vec4 geo = texelFetch(uGeo, ivec2(frag), 0);
  float sR = uRef.x, cR = uRef.y;
  float dPhi = geo.x - uRefDelta.x;
  float dLon = geo.y - uRefDelta.y;
  const float kPi = 3.14159265358979;
  if (dLon > kPi) dLon -= 2.0 * kPi;
  if (dLon < -kPi) dLon += 2.0 * kPi;
  float height = geo.z;
  float h2 = sinS(0.5 * dPhi), sD = sinS(dPhi);
  float sinPhi = sR * (1.0 - 2.0 * h2 * h2) + cR * sD;
  float cosPhi = cR * (1.0 - 2.0 * h2 * h2) - sR * sD;
  float W = sqrt(1.0 - uE2 * sinPhi * sinPhi);
  float N = uA / W;

  // Grid coordinates relative to R's, in grid units (x east, y north).
  vec2 g = vec2(0.0);
  if (uKind == 0) {
    float dLat = dPhi;
    if (uCentric == 1) {
      float k = 1.0 - uE2;
      dLat = atanS(k * sinS(dPhi), cosPhi * cR + k * k * sinPhi * sR);
    }
    g = uLinScale * vec2(dLon, dLat);
  } else if (uKind == 1) {
    float sg = uPolar.x, tA = uPolar.y, rhoPR = uPolar.z, K = uPolar.w;
    float sN = sg * sinPhi, sNR = sg * sR;
    float td = tanS(0.5 * sg * dPhi);
    float dBase = -K * td * (1.0 + tA * tA) / (1.0 + tA * td);
    float xE = uEcc * atanhS(uEcc * (sN - sNR) / (1.0 - uE2 * sN * sNR));
    float em1 = abs(xE) < 1e-2 ? xE * (1.0 + xE * (0.5 + xE * (1.0 / 6.0 + xE / 24.0)))
                               : exp(xE) - 1.0;
    float dRhoP = dBase * (1.0 + em1) + rhoPR * em1;
    float sl = sinS(dLon), hl = sinS(0.5 * dLon);
    float sinR = uPolarDl.x, cosR = uPolarDl.y;
    float dSin = cosR * sl - 2.0 * sinR * hl * hl;
    float dCos = -sinR * sl - 2.0 * cosR * hl * hl;
    g = vec2(rhoPR * dSin + dRhoP * (sinR + dSin), -sg * (rhoPR * dCos + dRhoP * (cosR + dCos)));
  } else {
    // The point at the dataset's mid height on this point's normal, in the plane's frame.
    float hL = sinS(0.5 * dLon);
    vec3 u = vec3(cosPhi * (1.0 - 2.0 * hL * hL), cosPhi * sinS(dLon), sinPhi);  // (axis-normal, east, z)
    vec3 uEnu = vec3(u.y, -sR * u.x + cR * u.z, cR * u.x + sR * u.z);
    vec3 v = q + (uHmid - height) * uEnu - vec3(0.0, 0.0, uHmid);
    g = vec2(dot(uPlaneX, v), dot(uPlaneY, v));
  }

  // Kooima's projection quality from the screen derivatives of level-0 texel coordinates.
  vec2 t0 = g / uSpacing0;
  float ux = dFdxFine(t0.x), uy = dFdyFine(t0.x), vx = dFdxFine(t0.y), vy = dFdyFine(t0.y);
  float k2 = (ux * ux + uy * uy) / (vx * vx + vy * vy);
  float alpha = clamp(1.0 - abs(0.5 * log(k2)) / uLogN, uMinQuality, 1.0);
  if (isnan(alpha) || isinf(k2) || k2 == 0.0) alpha = uMinQuality;
  if (depth <= 0.0 || geo.w <= 0.0) discard;

  // Coverage: inside the pixel extent, border feather × mask (compose::Dataset's rule).
  vec4 d = vec4(uEdge.x + g.x, uEdge.y - g.x, uEdge.z + g.y, uEdge.w - g.y);
  bvec4 out4 = bvec4(uEdgeOn.x > 0.5 && d.x < 0.0, uEdgeOn.y > 0.5 && d.y < 0.0,
                     uEdgeOn.z > 0.5 && d.z < 0.0, uEdgeOn.w > 0.5 && d.w < 0.0);
  if (any(out4) || any(isnan(g))) discard;
  float coverage = 1.0;
  if (uFeather > 0.0) {
    vec2 metres = vec2(1.0);
    if (uPlanet == 1) {
      const float kDeg = 3.14159265358979 / 180.0;
      metres = kDeg * vec2(N * cosPhi, N * (1.0 - uE2) / (W * W));
    }
    vec4 m = d * vec4(metres.x, metres.x, metres.y, metres.y);
    float dist = 1e30;
    for (int i = 0; i < 4; ++i) {
      if (uEdgeOn[i] > 0.5) dist = min(dist, m[i]);
    }
    coverage = smoothstep(0.0, 1.0, dist / uFeather);
  }
  vec2 tex = uTexR + vec2(g.x / uSpacingL.x, -g.y / uSpacingL.y);
  vec3 t = textureLod(uWindowTex, (tex + 0.5) / vec2(uWindow), 0.0).rgb;
  coverage *= t.b;
  if (t.g <= 0.0 || coverage <= 0.0) discard;
  float value = t.r / t.g;
  float w = coverage * alpha;
  if (uRole == 0) {
    oSums = vec4(w * value, w, 0.0, 0.0);
    oCover = vec4(coverage, 0.0, 0.0, 0.0);
  } else {
    oSums = vec4(0.0, 0.0, w * value, w);
    oCover = vec4(0.0, coverage, 0.0, 0.0);
  }
}
)";

/// The normalising pass: dual-source blending, colour = out0 + colour × out1.
inline constexpr const char* kNormaliseFragment = R"(#version 450 core
layout(binding = 0) uniform sampler2D uSums;
layout(binding = 1) uniform sampler2D uCover;
layout(location = 0, index = 0) out vec4 oAdd;
layout(location = 0, index = 1) out vec4 oFactor;
uniform float uGain;
uniform float uOverlayOpacity;
uniform vec2 uOverlayRange;

vec3 ramp(float t) {
  t = clamp(t, 0.0, 1.0);
  vec3 lo = vec3(0.15, 0.3, 0.9), mid = vec3(0.95, 0.9, 0.2), hi = vec3(0.9, 0.15, 0.1);
  return t < 0.5 ? mix(lo, mid, 2.0 * t) : mix(mid, hi, 2.0 * t - 1.0);
}

void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  vec4 sums = texelFetch(uSums, p, 0);
  vec2 cover = texelFetch(uCover, p, 0).rg;
  float albedoShown = 1.0 - cover.r;
  float albedo = sums.g > 0.0 ? sums.r / sums.g : 1.0;
  float factor = mix(1.0, albedo * uGain, albedoShown);
  float overlayShown = sums.a > 0.0 ? uOverlayOpacity * (1.0 - cover.g) : 0.0;
  float overlay = sums.a > 0.0 ? sums.b / sums.a : 0.0;
  vec3 colour = ramp((overlay - uOverlayRange.x) / (uOverlayRange.y - uOverlayRange.x));
  oAdd = vec4(colour * overlayShown, 0.0);
  oFactor = vec4(vec3(factor * (1.0 - overlayShown)), 1.0);
}
)";

}  // namespace regolith::render::shaders
