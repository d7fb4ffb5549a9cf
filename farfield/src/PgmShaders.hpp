#pragma once
// GLSL of PgmRenderer (docs/far-field.md). The formulas mirror farfield/PgmMath.hpp, in
// float, with every difference of large numbers precomputed in double on the CPU.

namespace regolith::farfield::shaders {

/// One fragment per grid point: eye ray, normal angle, sphere normal, height, displaced point.
inline constexpr const char* kGridFragment = R"(#version 450 core
layout(location = 0) out vec4 outPos;  // displaced point - eye (body axes), radius - r_p
layout(location = 1) out vec4 outNrm;  // lighting normal, height
uniform vec2 uGrid;
uniform vec3 uFwd, uRight, uUp, uNadir, uAnyPerp;
uniform vec4 uBounds;                  // left, right, bottom, top
uniform float uD, uRp, uAlt, uD2R2;    // d, r_p, d - r_p, (d - r_p)(d + r_p)
uniform float uBegin, uTau0, uTauTop, uTauS, uOmegaSb, uRs;
uniform int uSpreadOn;
uniform float uSpread[256];            // RaySpread::table (PgmMath)
uniform float uA, uB, uAminusRp, uAB2; // ellipsoid a, b, a - r_p, (a/b)^2
uniform sampler2D uEquirect, uNorth, uSouth;
uniform float uEquirectRows, uCapSize, uCapRadius, uCapLat, uCapBlend, uLodBias;
const float PI = 3.14159265358979;

float frontGamma(float w) {
  w = min(w, uTau0);
  float s = sin(w), c = cos(w);
  float disc = max((uRp - uD * s) * (uRp + uD * s), 0.0);
  float t = uD2R2 / (uD * c + sqrt(disc));
  return asin(clamp(t * s / uRp, -1.0, 1.0));
}

float blended(float w) {
  if (w <= uBegin) return frontGamma(w);
  float span = uTauTop - uBegin;
  float f = span > 0.0 ? clamp((w - uBegin) / span, 0.0, 1.0) : 1.0;
  float u = mix(uOmegaSb, uTauS, f);
  float gs = asin(min(1.0, uD * sin(u) / uRs)) - u;
  return mix(frontGamma(w), gs, f);
}

// RaySpread::angle: the ray angle turned by the even-error spread.
float spreadAngle(float w) {
  if (uSpreadOn == 0 || !(w < uTauTop) || !(w > 0.0)) return w;
  float x = w / uTauTop * 255.0;
  int i = min(int(x), 254);
  return mix(uSpread[i], uSpread[i + 1], x - float(i));
}

// Height at the geodetic normal ng: the equirectangular layer, blended into the polar cap.
float heightOf(vec3 ng, float lodE, float lodC) {
  float lat = atan(ng.z, length(ng.xy));  // well-conditioned at the poles, unlike asin
  float lon = atan(ng.y, ng.x);
  vec2 te = vec2((lon + PI) / (2.0 * PI), (lat + 0.5 * PI) / PI);
  float h = textureLod(uEquirect, te, lodE).r;
  float w = smoothstep(uCapLat, uCapLat + uCapBlend, abs(lat));
  if (w > 0.0) {
    bool north = ng.z > 0.0;
    float k = 2.0 / (1.0 + abs(ng.z));
    vec2 pq = vec2(k * ng.y, north ? -k * ng.x : k * ng.x);
    vec2 tc = (pq + uCapRadius) / (2.0 * uCapRadius);
    float hc = north ? textureLod(uNorth, tc, lodC).r : textureLod(uSouth, tc, lodC).r;
    h = mix(h, hc, w);
  }
  return h;
}

void main() {
  vec2 g = (gl_FragCoord.xy - 0.5) / max(uGrid - 1.0, vec2(1.0));
  vec3 r = normalize(uFwd + mix(uBounds.x, uBounds.y, g.x) * uRight +
                     mix(uBounds.z, uBounds.w, g.y) * uUp);
  float c = dot(r, uNadir);
  vec3 across = r - c * uNadir;
  float sl = length(across);
  float omega = spreadAngle(atan(sl, c));
  vec3 k = sl > 1e-7 ? across / sl : uAnyPerp;
  float gamma = blended(omega);
  float sg = sin(gamma), hs = sin(0.5 * gamma);
  vec3 s = -uNadir * cos(gamma) + k * sg;                         // sphere normal
  vec3 P = (uAlt + 2.0 * uRp * hs * hs) * uNadir + uRp * sg * k;  // on the primary sphere
  vec3 ng = normalize(vec3(s.xy, s.z * uAB2));                    // geodetic normal

  // Mip level: the angle between neighbouring grid points against a texel's angle.
  float spacing = max(length(dFdx(s)), length(dFdy(s)));
  float lodE = log2(max(spacing * uEquirectRows / PI, 1e-6)) + uLodBias;
  float lodC = log2(max(spacing * uCapSize / (2.0 * uCapRadius), 1e-6)) + uLodBias;
  float h = heightOf(ng, lodE, lodC);

  // Ellipsoid radius along s, less r_p, without subtracting radii (PgmMath).
  float sin2 = s.z * s.z;
  float q = sqrt(uB * uB * (1.0 - sin2) + uA * uA * sin2);
  float above = uA * (uB - uA) * (uB + uA) * sin2 / (q * (uB + q)) + uAminusRp;
  vec3 X = P + above * s + h * ng;

  // Lighting normal from the layers' gradient at the same level (steady as the grid moves).
  vec3 east = length(vec2(ng.x, ng.y)) > 1e-6 ? normalize(vec3(-ng.y, ng.x, 0.0)) : vec3(0.0, 1.0, 0.0);
  vec3 northDir = cross(ng, east);
  float eps = max(spacing, PI / uEquirectRows * exp2(max(lodE, 0.0))) * 0.5;
  float dE = heightOf(normalize(ng + eps * east), lodE, lodC) - heightOf(normalize(ng - eps * east), lodE, lodC);
  float dN = heightOf(normalize(ng + eps * northDir), lodE, lodC) - heightOf(normalize(ng - eps * northDir), lodE, lodC);
  vec3 n = normalize(ng - (dE * east + dN * northDir) / (2.0 * eps * uA));

  outPos = vec4(X, above + h * dot(ng, s));
  outNrm = vec4(n, h);
}
)";

/// The grid as triangle strips, displaced, through the camera.
inline constexpr const char* kMeshVertex = R"(#version 450 core
uniform sampler2D uPos, uNrm;
uniform int uGridWidth;
uniform mat4 uViewProj;
out vec3 vNormal;
out float vHeight;
out float vRadius;
void main() {
  ivec2 ij = ivec2(gl_VertexID % uGridWidth, gl_VertexID / uGridWidth);
  vec4 p = texelFetch(uPos, ij, 0);
  vec4 n = texelFetch(uNrm, ij, 0);
  vNormal = n.xyz;
  vHeight = n.w;
  vRadius = p.w;
  gl_Position = uViewProj * vec4(p.xyz, 1.0);
}
)";

inline constexpr const char* kMeshFragment = R"(#version 450 core
in vec3 vNormal;
in float vHeight;
in float vRadius;
layout(location = 0) out vec4 outColor;
layout(location = 1) out float outRadius;  // radius - r_p
uniform vec3 uSun, uLow, uHigh;
uniform vec2 uHeightRange;
uniform int uHeightColours;
uniform float uAmbient;
uniform int uKeepDrawn;
uniform sampler2D uDrawnDepth;  // the target's depth before this pass (reversed Z, 0 = empty)
void main() {
  // Hand-off: where something (the near-field clipmap) is already drawn, it stays.
  if (uKeepDrawn != 0 && texelFetch(uDrawnDepth, ivec2(gl_FragCoord.xy), 0).r > 0.0) discard;
  vec3 n = normalize(vNormal);
  float range = uHeightRange.y - uHeightRange.x;
  float t = range > 1.0 ? clamp((vHeight - uHeightRange.x) / range, 0.0, 1.0) : 0.5;
  vec3 albedo = uHeightColours != 0 ? mix(uLow, uHigh, t) : uHigh;
  float light = uAmbient + (1.0 - uAmbient) * max(dot(n, uSun), 0.0);
  outColor = vec4(albedo * light, 1.0);
  outRadius = vRadius;
}
)";

/// Minimum of the radius buffer. Each invocation takes the minimum of a column of 64
/// pixels; a workgroup of 64 invocations (a 64 × 64 tile) meets once at a barrier, and its
/// first invocation does one atomicMin on the float's order-preserving bits. One barrier per
/// tile instead of a log-step tree of barriers: on llvmpipe, whose compute invocations run as
/// coroutines on the CPU, each barrier is a switch of every invocation, and the tree made
/// the reduction cost as much as the mesh pass (docs/far-field.md, "The reduction").
inline constexpr const char* kReduceCompute = R"(#version 450 core
layout(local_size_x = 64) in;
layout(binding = 3) uniform sampler2D uRadius;
layout(std430, binding = 1) buffer Result { uint minBits; };
shared float part[64];
uint orderedBits(float f) {
  uint u = floatBitsToUint(f);
  return (u & 0x80000000u) != 0u ? ~u : (u | 0x80000000u);
}
void main() {
  ivec2 size = textureSize(uRadius, 0);
  int x = int(gl_GlobalInvocationID.x);
  int y0 = int(gl_WorkGroupID.y) * 64;
  float v = 3.0e38;
  if (x < size.x) {
    int y1 = min(y0 + 64, size.y);
    for (int y = y0; y < y1; ++y) v = min(v, texelFetch(uRadius, ivec2(x, y), 0).r);
  }
  part[gl_LocalInvocationIndex] = v;
  barrier();
  if (gl_LocalInvocationIndex == 0u) {
    float m = part[0];
    for (uint i = 1u; i < 64u; ++i) m = min(m, part[i]);
    atomicMin(minBits, orderedBits(m));
  }
}
)";

}  // namespace regolith::farfield::shaders
