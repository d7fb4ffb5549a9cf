#include "EffectShaders.hpp"

#include <regolith/gl/GlError.hpp>

#include "Shaders.hpp"

#include <cstdio>
#include <string>

namespace regolith::clod {

namespace {

// Inserts `text` after (or, with before = true, before) the one occurrence of `anchor`.
void insertAt(std::string& src, const char* stage, const std::string& anchor,
              const std::string& text, bool before = false) {
  const auto at = src.find(anchor);
  if (at == std::string::npos || src.find(anchor, at + 1) != std::string::npos)
    throw gl::GlError(std::string("composeClipmapSources(): the bare ") + stage +
                      " shader has no unique anchor '" + anchor + "'");
  // Rebuilt rather than std::string::insert, which trips GCC 12's -Wrestrict.
  const std::size_t cut = before ? at : at + anchor.size();
  src = src.substr(0, cut) + text + src.substr(cut);
}

void replaceAt(std::string& src, const char* stage, const std::string& anchor,
               const std::string& text) {
  insertAt(src, stage, anchor, text, true);
  const std::size_t at = src.find(anchor);
  src = src.substr(0, at) + src.substr(at + anchor.size());
}

std::string replaceAll(const std::string& s, const std::string& from, const std::string& to) {
  std::string out;
  std::size_t pos = 0;
  for (auto at = s.find(from); at != std::string::npos; at = s.find(from, pos)) {
    out += s.substr(pos, at - pos) + to;
    pos = at + from.size();
  }
  return out + s.substr(pos);
}

// ---- Vertex ----------------------------------------------------------------------------

constexpr const char* kGridVertexDecl =
    R"(uniform vec2 uGrid0;      // grid point of window vertex (0, 0) − frame grid origin
uniform vec2 uGridStep;   // grid units per vertex step (x: +i, y: −j)
uniform int uGridFromBody;  // planets on a polar lattice: grid from the position
uniform vec2 uGridOrigin;   // the frame's grid origin (degrees) for that case
uniform float uGridLatRatio2;  // a²/b² for a planetodetic grid, 1 for planetocentric
)";

// Planets: on the polar lattice the grid point is computed per fragment from the position
// (a varying interpolated across large polar cells would be off by a fraction of a cell).
constexpr const char* kGridFragmentDecl = R"(in vec2 fGridV;
uniform int uGridFromBody;
uniform vec2 uGridOrigin;
uniform float uGridLatRatio2;
vec2 fGrid;
)";
constexpr const char* kGridFragmentMain = R"(  fGrid = fGridV;
  if (uGridFromBody != 0) {
    fGrid = vec2(degrees(atan(fBody.y, fBody.x)),
                 degrees(atan(uGridLatRatio2 * fBody.z, length(fBody.xy)))) - uGridOrigin;
    fGrid.x = mod(fGrid.x + 180.0, 360.0) - 180.0;
  }
)";
constexpr const char* kGridVertexMain = R"(  if (uGridFromBody != 0) {
    vec3 b = c.xyz + uAnchorFromCentre;
    vsOut.grid = vec2(degrees(atan(b.y, b.x)), degrees(atan(uGridLatRatio2 * b.z, length(b.xy)))) -
                 uGridOrigin;
    vsOut.grid.x = mod(vsOut.grid.x + 180.0, 360.0) - 180.0;
  } else {
    vsOut.grid = uGrid0 + vec2(float(i) * uGridStep.x, -float(j) * uGridStep.y);
  }
)";

// ---- Fragment --------------------------------------------------------------------------

constexpr const char* kAxesDecl =
    R"(uniform vec3 uAxisX;  // scene vector per grid unit along +x, divided by its length squared
uniform vec3 uAxisY;
)";

// A texture clipmap lookup; '$' is replaced by the layer's name (Albedo, Overlay).
constexpr const char* kDrapeDecl = R"(layout(binding = BINDING) uniform sampler2DArray u$Tex;
uniform int u$Levels;
uniform float u$Spacing0;   // level-0 texel size, grid units
uniform vec4 u$Win[16];     // per level: west, north edge (− grid origin), width, height
vec4 drape$(vec2 g) {
  vec2 fw = max(abs(dFdx(g)), abs(dFdy(g)));
  float lod = log2(max(max(fw.x, fw.y) / u$Spacing0, 1.0));
  for (int l = min(int(floor(lod)), u$Levels - 1); l < u$Levels; ++l) {
    vec4 w = u$Win[l];
    vec2 uv = vec2((g.x - w.x) / w.z, (w.y - g.y) / w.w);
    vec2 m = 0.5 / vec2(textureSize(u$Tex, 0).xy);
    if (all(greaterThanEqual(uv, m)) && all(lessThanEqual(uv, 1.0 - m)))
      return texture(u$Tex, vec3(uv, float(l)));
  }
  return vec4(0.0);
}
)";

constexpr const char* kNoiseDecl = R"(uniform float uNoiseAmp;     // metres
uniform float uNoiseWave;    // grid units, coarsest octave
uniform int uNoiseOctaves;
uniform vec2 uNoiseOffset;   // (grid origin / wavelength) mod 256
uniform vec4 uNoiseRegion;   // xmin, ymin, xmax, ymax − grid origin
uniform float uNoiseAlbedo;
float noiseHash(ivec2 q) {
  uvec2 u = uvec2(q & 255);
  uint h = u.x * 1597334677u ^ u.y * 3812015801u;
  h ^= h >> 15; h *= 0x2c1b3c6du; h ^= h >> 12; h *= 0x297a2d39u; h ^= h >> 15;
  return float(h & 0xffffffu) / 16777215.0;
}
// Value noise and its gradient (d/dx, d/dy) in one pass.
vec3 valueNoise(vec2 x) {
  vec2 i = floor(x), f = x - i;
  vec2 u = f * f * (3.0 - 2.0 * f), du = 6.0 * f * (1.0 - f);
  ivec2 k = ivec2(i);
  float a = noiseHash(k), b = noiseHash(k + ivec2(1, 0));
  float c = noiseHash(k + ivec2(0, 1)), d = noiseHash(k + ivec2(1, 1));
  float v = a + (b - a) * u.x + (c - a) * u.y + (a - b - c + d) * u.x * u.y;
  return vec3(v, du * (vec2(b - a, c - a) + (a - b - c + d) * u.yx));
}
vec3 fbm(vec2 g) {  // value in [0, 1], gradient per grid unit
  vec2 x = g / uNoiseWave + uNoiseOffset;
  float a = 0.5, t = 0.0, scale = 1.0 / uNoiseWave;
  vec3 s = vec3(0.0);
  for (int o = 0; o < uNoiseOctaves; ++o) {
    vec3 n = valueNoise(x);
    s += a * vec3(n.x, n.yz * scale);
    t += a;
    a *= 0.5;
    scale *= 2.0;
    x = x * 2.0 + vec2(37.0, 17.0);
  }
  return s / t;
}
)";
constexpr const char* kNoiseMain =
    R"(  if (all(greaterThanEqual(fGrid, uNoiseRegion.xy)) && all(lessThanEqual(fGrid, uNoiseRegion.zw))) {
    vec3 f = fbm(fGrid);
    vec2 slope = 2.0 * uNoiseAmp * f.yz;  // metres per grid unit
    n = normalize(n - slope.x * uAxisX - slope.y * uAxisY);
    albedo *= 1.0 + uNoiseAlbedo * (2.0 * f.x - 1.0);
  }
)";

constexpr const char* kTracksDecl =
    R"(layout(binding = 1) uniform sampler2D uTracks;  // rut depth, metres
uniform vec2 uTrackOrigin;   // grid point of the window's south-west corner − grid origin
uniform float uTrackExtent;  // window side, grid units
uniform float uTrackTexel;
uniform float uTrackDarken;
)";
constexpr const char* kTracksMain = R"(  {
    vec2 uv = (fGrid - uTrackOrigin) / uTrackExtent;
    float du = uTrackTexel / uTrackExtent;
    float d = texture(uTracks, uv).r;
    // A rut's cos² profile is flat at its edge: where the depth is 0 the gradient is too.
    if (d > 0.0) {
      float ddx = (texture(uTracks, uv + vec2(du, 0.0)).r - texture(uTracks, uv - vec2(du, 0.0)).r) /
                  (2.0 * uTrackTexel);
      float ddy = (texture(uTracks, uv + vec2(0.0, du)).r - texture(uTracks, uv - vec2(0.0, du)).r) /
                  (2.0 * uTrackTexel);
      n = normalize(n + ddx * uAxisX + ddy * uAxisY);  // the surface is lowered by d
      albedo *= 1.0 - uTrackDarken * smoothstep(0.0, 0.002, d);
    }
  }
)";

constexpr const char* kHeightDecl = R"(uniform vec2 uHeightRange;
uniform int uHeightShaded;
vec3 heightRamp(float h) {
  const vec3 stops[5] = vec3[5](RAMP);
  float t = clamp((h - uHeightRange.x) / (uHeightRange.y - uHeightRange.x), 0.0, 1.0) * 4.0;
  int k = min(int(floor(t)), 3);
  return mix(stops[k], stops[k + 1], t - float(k));
}
)";
constexpr const char* kHeightMain = R"(  {
    vec3 hc = heightRamp(fHeight);
    color.rgb = uHeightShaded != 0 ? hc * (uAmbient + (1.0 - uAmbient) * d) : hc;
  }
)";

constexpr const char* kOverlayMain = R"(  {
    vec4 ov = drapeOverlay(fGrid);
    color.rgb = mix(color.rgb, ov.rgb, ov.a * uOverlayOpacity);
  }
)";

constexpr const char* kLatLonDecl = R"(uniform float uLatLonSpacing;  // degrees
uniform vec3 uLatLonColour;
uniform float uLatLonWidth;     // pixels
uniform float uLatAxisRatio2;   // a²/b² for planetodetic latitude, 1 for planetocentric
)";
constexpr const char* kLatLonMain = R"(  {
    float rho = length(fBody.xy);
    vec2 ll = vec2(degrees(atan(fBody.y, fBody.x)), degrees(atan(uLatAxisRatio2 * fBody.z, rho)));
    // The longitude's screen rate, without the jump at ±180°.
    float lonRate = min(fwidth(ll.x), fwidth(degrees(atan(-fBody.y, -fBody.x))));
    vec2 rate = vec2(lonRate, fwidth(ll.y));
    vec2 dist = abs(fract(ll / uLatLonSpacing + 0.5) - 0.5) * uLatLonSpacing;
    if (any(lessThan(dist, rate * (0.5 * uLatLonWidth)))) color.rgb = uLatLonColour;
  }
)";

std::string rampGlsl() {
  std::string out;
  for (std::size_t k = 0; k < kHeightRamp.size(); ++k) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "%svec3(%.9g, %.9g, %.9g)", k == 0 ? "" : ", ",
                  static_cast<double>(kHeightRamp[k].x), static_cast<double>(kHeightRamp[k].y),
                  static_cast<double>(kHeightRamp[k].z));
    out += buf;
  }
  return out;
}

std::string drapeDecl(const std::string& name, int binding) {
  return replaceAll(replaceAll(kDrapeDecl, "$", name), "BINDING", std::to_string(binding));
}

}  // namespace

EffectNeeds EffectNeeds::of(const Effects& e, bool planet) noexcept {
  EffectNeeds n;
  n.grid = e.albedo || e.overlay || e.tracks || e.noise;
  n.height = e.heightColours.has_value();
  n.body = e.latLon.has_value() || (planet && n.grid);
  n.axes = e.tracks || e.noise;
  return n;
}

gl::ShaderSources composeClipmapSources(const Effects& e, bool planet) {
  gl::ShaderSources s{shaders::kClipmapVertex, shaders::kDropNodataGeometry, shaders::kLitFragment};
  const EffectNeeds need = EffectNeeds::of(e, planet);
  const bool gridPerFragment = planet && need.grid;
  const bool surface = e.albedo || e.noise || e.tracks;
  if (!need.grid && !need.height && !need.body) return s;  // no effect: the bare pipeline

  // Varyings: vertex block fields and code, geometry pass-through, fragment inputs.
  std::string fields, vsDecl, vsMain, gsOut, gsCopy, fsIn;
  if (need.grid) {
    fields += " vec2 grid;";
    vsDecl += kGridVertexDecl;
    vsMain += kGridVertexMain;
    // Planets: the geometry shader's output is fGridV and fGrid a per-fragment global.
    gsOut += gridPerFragment ? "out vec2 fGridV;\n" : "out vec2 fGrid;\n";
    gsCopy += gridPerFragment ? "    fGridV = gsIn[i].grid;\n" : "    fGrid = gsIn[i].grid;\n";
    if (!gridPerFragment) fsIn += "in vec2 fGrid;\n";
  }
  if (need.height) {
    fields += " float height;";
    vsMain += "  vsOut.height = c.w;\n";
    gsOut += "out float fHeight;\n";
    gsCopy += "    fHeight = gsIn[i].height;\n";
    fsIn += "in float fHeight;\n";
  }
  if (need.body) {
    fields += " vec3 body;";
    vsMain += "  vsOut.body = p + uAnchorFromCentre;\n";
    gsOut += "out vec3 fBody;\n";
    gsCopy += "    fBody = gsIn[i].body;\n";
    fsIn += "in vec3 fBody;\n";
  }
  insertAt(s.vertex, "vertex", "float valid;", fields);
  insertAt(s.vertex, "vertex", "out VS {", vsDecl, true);
  insertAt(s.vertex, "vertex", "  vsOut.valid = isnan(c.w) ? 0.0 : 1.0;\n", vsMain);
  insertAt(s.geometry, "geometry", "float valid;", fields);
  insertAt(s.geometry, "geometry", "out vec3 fNormal;\n", gsOut);
  insertAt(s.geometry, "geometry", "    fNormal = gsIn[i].normal;\n", gsCopy);

  std::string fsDecl = fsIn, fsSurface, fsColour;
  if (gridPerFragment) fsDecl += kGridFragmentDecl;
  if (need.axes) fsDecl += kAxesDecl;
  if (e.albedo) {
    fsDecl += drapeDecl("Albedo", 2);
    fsSurface += "  { vec4 a = drapeAlbedo(fGrid); albedo = mix(albedo, a.rgb, a.a); }\n";
  }
  if (e.noise) {
    fsDecl += kNoiseDecl;
    fsSurface += kNoiseMain;
  }
  if (e.tracks) {
    fsDecl += kTracksDecl;
    fsSurface += kTracksMain;
  }
  if (e.heightColours) {
    fsDecl += replaceAll(kHeightDecl, "RAMP", rampGlsl());
    fsColour += kHeightMain;
  }
  if (e.overlay) {
    fsDecl += drapeDecl("Overlay", 3);
    fsDecl += "uniform float uOverlayOpacity;\n";
    fsColour += kOverlayMain;
  }
  if (e.latLon) {
    fsDecl += kLatLonDecl;
    fsColour += kLatLonMain;
  }
  insertAt(s.fragment, "fragment", "out vec4 color;\n", fsDecl, true);
  if (gridPerFragment)
    insertAt(s.fragment, "fragment", "  vec3 n = normalize(fNormal);\n", kGridFragmentMain, true);
  if (surface) {
    insertAt(s.fragment, "fragment", "  vec3 n = normalize(fNormal);\n",
             "  vec3 albedo = uAlbedo;\n" + fsSurface);
    replaceAt(s.fragment, "fragment", "uAlbedo * (", "albedo * (");
  }
  insertAt(s.fragment, "fragment", "(1.0 - uAmbient) * d), 1.0);\n", fsColour);
  return s;
}

}  // namespace regolith::clod
