// Only what the scene declares is simulated: a disabled effect adds no shader code, no
// uniform, no texture bind and no pass.

#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/gl/Gl.hpp>
#include <regolith/rover/TrackLayer.hpp>
#include <regolith/topo/Placement.hpp>

#include "EffectFixtures.hpp"
#include "TerrainFixtures.hpp"
#include "gl/GlContext.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace regolith::clod {
namespace {

std::set<std::string> activeUniforms(GLuint program) {
  GLint count = 0;
  glGetProgramiv(program, GL_ACTIVE_UNIFORMS, &count);
  std::set<std::string> out;
  for (GLint i = 0; i < count; ++i) {
    char name[256];
    GLsizei len = 0;
    GLint size = 0;
    GLenum type = 0;
    glGetActiveUniform(program, static_cast<GLuint>(i), sizeof name, &len, &size, &type, name);
    out.insert(std::string(name, static_cast<std::size_t>(len)));
  }
  return out;
}

// A small DEM placed on Mars, so every effect (lat/lon lines included) applies.
std::shared_ptr<const HeightPyramid> placedHills() {
  const topo::LocalTangentPlane plane(topo::Body::marsSphere(), {4.5, 137.4, -4400.0}, 0.0);
  const auto grid = test::centredGrid(129, 129, 2.0);
  auto samples = topo::InMemorySamples::fromFunction(129, 129, [&](std::size_t r, std::size_t c) {
    const auto p = grid.sampleCentre(static_cast<double>(r), static_cast<double>(c));
    return static_cast<float>(test::hills(p.x, p.y) + 1400.0);
  });
  return std::make_shared<const HeightPyramid>(
      HeightPyramid::fromSamples(grid, samples, topo::Placement(plane)));
}

DrapedTexture smallTexture(std::size_t channels) {
  DrapedTexture t;
  const auto grid = test::centredGrid(256, 256, 1.0);
  for (std::size_t c = 0; c < channels; ++c)
    t.channels.push_back(test::planePyramid(grid, [c](double x, double y) {
      return 0.5 + 0.4 * std::sin(x / 7.0 + static_cast<double>(c)) * std::cos(y / 5.0);
    }));
  t.window = 64;
  return t;
}

// The uniforms and code words that belong to each effect alone.
const std::map<std::string, std::vector<std::string>>& effectWords() {
  static const std::map<std::string, std::vector<std::string>> words{
      {"albedo", {"uAlbedoTex", "uAlbedoWin"}}, {"tracks", {"uTracks", "uTrackOrigin"}},
      {"noise", {"uNoiseAmp", "fbm("}},         {"heightColours", {"uHeightRange", "heightRamp("}},
      {"latLon", {"uLatLonSpacing", "fBody"}},  {"overlay", {"uOverlayTex", "uOverlayOpacity"}}};
  return words;
}

Effects only(const std::string& name) {
  Effects e;
  if (name == "albedo") e.albedo = smallTexture(1);
  if (name == "tracks") e.tracks = std::make_shared<rover::TrackLayer>(0.05);
  if (name == "noise") e.noise = StructuredNoise{};
  if (name == "heightColours") e.heightColours = HeightColours{0.0F, 40.0F, false};
  if (name == "latLon") e.latLon = LatLonLines{};
  if (name == "overlay") e.overlay = smallTexture(3);
  return e;
}

Camera placedCamera(const HeightPyramid& pyramid) {
  Camera cam;
  cam.position = pyramid.position(-60.0, -90.0, 80.0);
  cam.target = pyramid.position(0.0, 0.0, 0.0);
  cam.up = pyramid.up(cam.target);
  cam.width = 96;
  cam.height = 64;
  cam.near = 0.5;
  return cam;
}

TEST(EffectsGLTest, NoEffectIsTheBarePipeline) {
  test::glContext();
  const auto pyramid = placedHills();
  ClipmapOptions opt;
  opt.size = 31;
  ClipmapTerrain terrain(pyramid, opt);
  terrain.setFocus(pyramid->position(0.0, 0.0, 0.0));
  const gl::ShaderSources bare = ClipmapTerrain::bareSources();
  EXPECT_EQ(terrain.programSources().vertex, bare.vertex);
  EXPECT_EQ(terrain.programSources().geometry, bare.geometry);
  EXPECT_EQ(terrain.programSources().fragment, bare.fragment);
  EXPECT_EQ(terrain.passes(), std::vector<std::string>{"terrain"});
  const gl::Program reference("bare", bare);
  EXPECT_EQ(activeUniforms(terrain.program().id()), activeUniforms(reference.id()));
  const Camera cam = placedCamera(*pyramid);
  gl::RenderTarget target(cam.width, cam.height);
  target.clear({0.0F, 0.0F, 0.0F, 1.0F});
  const ClipmapFrame frame = terrain.draw(cam);
  ASSERT_GT(frame.levelsDrawn, 1U);
  EXPECT_EQ(frame.textureBinds, frame.levelsDrawn);  // the level textures, nothing else
}

TEST(EffectsGLTest, EachEffectAddsOnlyItsOwnCodeUniformsBindsAndPasses) {
  test::glContext();
  const auto pyramid = placedHills();
  const std::set<std::string> bareUniforms =
      activeUniforms(gl::Program("bare", ClipmapTerrain::bareSources()).id());
  const std::map<std::string, std::size_t> extraBinds{{"albedo", 1}, {"tracks", 1},
                                                      {"noise", 0},  {"heightColours", 0},
                                                      {"latLon", 0}, {"overlay", 1}};
  const std::map<std::string, std::vector<std::string>> extraPasses{
      {"albedo", {"albedo-clipmap"}},
      {"tracks", {"track-upload"}},
      {"overlay", {"overlay-clipmap"}}};
  for (const auto& [name, words] : effectWords()) {
    SCOPED_TRACE(name);
    ClipmapOptions opt;
    opt.size = 31;
    opt.trackWindow = 256;
    opt.effects = only(name);
    ASSERT_EQ(opt.effects.declared(), std::vector<std::string>{name});
    ClipmapTerrain terrain(pyramid, opt);
    terrain.setFocus(pyramid->position(0.0, 0.0, 0.0));
    const gl::ShaderSources& s = terrain.programSources();
    const std::string all = s.vertex + s.geometry + s.fragment;
    const std::set<std::string> uniforms = activeUniforms(terrain.program().id());
    for (const auto& [other, otherWords] : effectWords()) {
      for (const auto& w : otherWords) {
        const bool inCode = all.find(w) != std::string::npos;
        EXPECT_EQ(inCode, other == name) << w;
        if (w.front() == 'u') {
          EXPECT_EQ(uniforms.count(w) + uniforms.count(w + "[0]"), other == name ? 1U : 0U) << w;
        }
      }
    }
    // The bare program's uniforms are all still there (the pipeline is extended, not
    // replaced), except the albedo colour that height colours paint over.
    for (const auto& u : bareUniforms)
      EXPECT_EQ(uniforms.count(u), name == "heightColours" && u == "uAlbedo" ? 0U : 1U) << u;
    std::vector<std::string> passes =
        extraPasses.count(name) ? extraPasses.at(name) : std::vector<std::string>{};
    passes.emplace_back("terrain");
    EXPECT_EQ(terrain.passes(), passes);
    const Camera cam = placedCamera(*pyramid);
    gl::RenderTarget target(cam.width, cam.height);
    target.clear({0.0F, 0.0F, 0.0F, 1.0F});
    const ClipmapFrame frame = terrain.draw(cam);
    EXPECT_EQ(frame.textureBinds, frame.levelsDrawn + extraBinds.at(name));
  }
}

TEST(EffectsGLTest, EffectsThatCannotApplyAreRejectedAtConstruction) {
  test::glContext();
  const auto plane = test::planePyramid(test::centredGrid(65, 65, 1.0), test::hills);
  ClipmapOptions opt;
  opt.size = 31;
  opt.effects.latLon = LatLonLines{};
  EXPECT_THROW(ClipmapTerrain(plane, opt), InvalidArgument);  // no body, no latitude
  opt.effects = {};
  opt.effects.heightColours = HeightColours{10.0F, 10.0F, false};
  EXPECT_THROW(ClipmapTerrain(plane, opt), InvalidArgument);
  opt.effects = {};
  opt.effects.albedo = smallTexture(2);  // neither grey nor RGB(A)
  EXPECT_THROW(ClipmapTerrain(plane, opt), InvalidArgument);
  opt.effects = {};
  opt.effects.noise = StructuredNoise{};
  opt.effects.noise->octaves = 0;
  EXPECT_THROW(ClipmapTerrain(plane, opt), InvalidArgument);
  // The declared set is fixed once built.
  opt.effects.noise->octaves = 3;
  ClipmapTerrain terrain(plane, opt);
  ClipmapOptions changed = opt;
  changed.effects.noise->amplitude = 0.2;  // a parameter: fine
  EXPECT_NO_THROW(terrain.setOptions(changed));
  changed.effects.heightColours = HeightColours{};
  EXPECT_THROW(terrain.setOptions(changed), InvalidArgument);
  // A draped texture's sources are part of the declaration, its opacity is a parameter.
  ClipmapOptions draped = opt;
  draped.effects.overlay = smallTexture(3);
  ClipmapTerrain withOverlay(plane, draped);
  ClipmapOptions other = draped;
  other.effects.overlay->opacity = 0.3F;
  EXPECT_NO_THROW(withOverlay.setOptions(other));
  other.effects.overlay = smallTexture(3);  // new pyramids
  EXPECT_THROW(withOverlay.setOptions(other), InvalidArgument);
}

}  // namespace
}  // namespace regolith::clod
