#pragma once
// GLSL sources shared by the clipmap and the brute-force mesh renderer. Private to clod.

namespace regolith::clod::shaders {

// Drops every triangle with a vertex over nodata (valid < 0.5), passes the rest through.
inline constexpr const char* kDropNodataGeometry = R"(#version 450 core
layout(triangles) in;
layout(triangle_strip, max_vertices = 3) out;
in VS { vec3 normal; float valid; } gsIn[];
out vec3 fNormal;
void main() {
  if (gsIn[0].valid < 0.5 || gsIn[1].valid < 0.5 || gsIn[2].valid < 0.5) return;
  for (int i = 0; i < 3; ++i) {
    gl_Position = gl_in[i].gl_Position;
    fNormal = gsIn[i].normal;
    EmitVertex();
  }
  EndPrimitive();
}
)";

// Lambert lighting from a light direction (towards the light, scene frame), an albedo and
// an ambient term.
inline constexpr const char* kLitFragment = R"(#version 450 core
in vec3 fNormal;
uniform vec3 uLight;
uniform vec3 uAlbedo;
uniform float uAmbient;
out vec4 color;
void main() {
  vec3 n = normalize(fNormal);
  float d = max(dot(n, uLight), 0.0);
  color = vec4(uAlbedo * (uAmbient + (1.0 - uAmbient) * d), 1.0);
}
)";

// Clipmap level: vertex (i, j, skirt) of the n × n level grid. Positions come from the
// level's toroidal RGBA32F texture (xyz relative to the level anchor, w height or NaN);
// uAnchorRel = anchor − camera, computed in double on the CPU.
inline constexpr const char* kClipmapVertex = R"(#version 450 core
layout(location = 0) in ivec3 aVertex;
layout(binding = 0) uniform sampler2D uPos;
uniform ivec2 uOrigin;
uniform int uN;
uniform vec3 uAnchorRel;
uniform vec3 uAnchorFromCentre;
uniform int uPlanet;
uniform vec3 uUp;  // "up" for non-planet levels (a plane's +z, a placed DEM's h axis)
uniform float uSkirtDepth;
uniform mat4 uViewProj;
uniform vec4 uFinerRect;   // the finer level's window in this level's (i, j); empty if none
uniform float uDepthPush;  // relative depth push for vertices under the finer level
out VS { vec3 normal; float valid; } vsOut;
vec4 fetch(int i, int j) {
  i = clamp(i, 0, uN - 1);
  j = clamp(j, 0, uN - 1);
  return texelFetch(uPos, ivec2((uOrigin.x + i) % uN, (uOrigin.y + j) % uN), 0);
}
vec3 around(vec4 t, vec3 p) { return isnan(t.w) ? p : t.xyz; }
void main() {
  int i = aVertex.x, j = aVertex.y;
  vec4 c = fetch(i, j);
  vec3 p = c.xyz;
  vec3 up = uPlanet != 0 ? normalize(p + uAnchorFromCentre) : uUp;
  vec3 east = around(fetch(i + 1, j), p) - around(fetch(i - 1, j), p);
  vec3 north = around(fetch(i, j - 1), p) - around(fetch(i, j + 1), p);
  vec3 n = cross(east, north);
  n = dot(n, n) > 0.0 ? normalize(n) : up;
  vsOut.normal = dot(n, up) < 0.0 ? -n : n;  // lattices mirrored over a pole stay upright
  if (aVertex.z != 0) p -= up * uSkirtDepth;
  vsOut.valid = isnan(c.w) ? 0.0 : 1.0;
  gl_Position = uViewProj * vec4(p + uAnchorRel, 1.0);
  // Where a finer level overlaps this one, this level's surface loses the depth test by a
  // small relative margin, so the finer (more exact) surface shows. Only depth changes.
  if (float(i) > uFinerRect.x && float(i) < uFinerRect.z && float(j) > uFinerRect.y &&
      float(j) < uFinerRect.w)
    gl_Position.z *= 1.0 - uDepthPush;
}
)";

// Brute-force reference: every sample of a plane DEM is a vertex. Attributeless: instance
// = row strip j..j+1, gl_VertexID = 2·i + (0: row j, 1: row j+1). Heights from an R32F
// texture of the whole grid; uOriginRel = position of sample (0, 0) at height 0 − camera.
inline constexpr const char* kMeshVertex = R"(#version 450 core
layout(binding = 0) uniform sampler2D uHeights;
uniform vec3 uOriginRel;
uniform vec2 uSpacing;
uniform mat4 uViewProj;
out VS { vec3 normal; float valid; } vsOut;
float h(ivec2 ij) {
  ivec2 size = textureSize(uHeights, 0);
  return texelFetch(uHeights, clamp(ij, ivec2(0), size - 1), 0).r;
}
float around(ivec2 ij, float c) { float v = h(ij); return isnan(v) ? c : v; }
void main() {
  ivec2 ij = ivec2(gl_VertexID >> 1, gl_InstanceID + (gl_VertexID & 1));
  float c = h(ij);
  float dzdx = (around(ij + ivec2(1, 0), c) - around(ij - ivec2(1, 0), c)) / (2.0 * uSpacing.x);
  float dzdy = (around(ij - ivec2(0, 1), c) - around(ij + ivec2(0, 1), c)) / (2.0 * uSpacing.y);
  vsOut.normal = normalize(vec3(-dzdx, -dzdy, 1.0));
  vsOut.valid = isnan(c) ? 0.0 : 1.0;
  vec3 p = vec3(float(ij.x) * uSpacing.x, -float(ij.y) * uSpacing.y, c);
  gl_Position = uViewProj * vec4(p + uOriginRel, 1.0);
}
)";

}  // namespace regolith::clod::shaders
