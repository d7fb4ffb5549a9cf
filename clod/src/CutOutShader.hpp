#pragma once
// Cut-outs (scene graph, issue 6): where a DEM has data, the planet under it gives way.
// Private to clod. ClipmapTerrain compiles the test in and sets its uniforms from what
// render::SceneRenderer hands it (ClipmapTerrain::setCutOuts()).
//
// The fragment's camera-relative position is rebuilt from gl_FragCoord and its reversed-Z
// depth (depth = near / view distance), mapped to the cutting DEM's mask cells (eye → (col,
// row) by an affine map computed in double on the CPU), and discarded if that cell of the
// DEM has data. With no cut-out (uCutCount = 0, the default) nothing changes.

#include <regolith/core/Error.hpp>

#include <string>

namespace regolith::clod::shaders {

inline constexpr int kMaxCutOuts = 4;
inline constexpr int kCutOutFirstUnit = 4;  // texture units 4..7 hold the DEMs' cell masks

inline constexpr const char* kCutOutFunctions = R"(
uniform int uCutCount;
uniform vec4 uCutViewport;  // viewport x, y, width, height (pixels)
uniform vec3 uCutProj;      // near, aspect / f, 1 / f (Camera's projection)
uniform mat3 uCutEyeToCell[4];
uniform vec3 uCutCellOfCamera[4];
layout(binding = 4) uniform sampler2D uCutMask[4];  // r > 0.5: the DEM has this cell
bool regolithCutOut() {
  if (uCutCount == 0) return false;
  float d = uCutProj.x / gl_FragCoord.z;
  vec2 ndc = 2.0 * (gl_FragCoord.xy - uCutViewport.xy) / uCutViewport.zw - 1.0;
  vec3 eye = vec3(ndc.x * d * uCutProj.y, ndc.y * d * uCutProj.z, -d);
  for (int i = 0; i < 4; ++i) {
    if (i >= uCutCount) break;
    vec3 g = uCutEyeToCell[i] * eye + uCutCellOfCamera[i];
    ivec2 cell = ivec2(floor(g.xy));
    ivec2 size = textureSize(uCutMask[i], 0);
    if (any(lessThan(cell, ivec2(0))) || any(greaterThanEqual(cell, size))) continue;
    if (texelFetch(uCutMask[i], cell, 0).r > 0.5) return true;
  }
  return false;
}
)";

/// `fragment` with the cut-out functions declared before its main() and a discard as
/// main()'s first statement. Throws regolith::Error if it has no "void main() {" (a
/// shader edit that would otherwise switch cut-outs off without a word).
inline std::string withCutOuts(const std::string& fragment) {
  const std::string mainDecl = "void main() {";
  const auto at = fragment.find(mainDecl);
  if (at == std::string::npos)
    throw Error(
        "shaders::withCutOuts(): the fragment shader has no 'void main() {' to put "
        "the cut-out test in");
  std::string out = fragment.substr(0, at);
  out += kCutOutFunctions;
  out += mainDecl;
  out += "\n  if (regolithCutOut()) discard;";
  out += fragment.substr(at + mainDecl.size());
  return out;
}

}  // namespace regolith::clod::shaders
