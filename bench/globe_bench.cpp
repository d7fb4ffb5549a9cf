// The ray-cast globe (docs/ray-cast-globe.md): frame time and rays cast against rays hit for
// the bounding box and the bounding polygon, and the impostor against a tessellated sphere of
// equal silhouette error. Headless: Mesa llvmpipe through EGL surfaceless, 1280 × 720, the
// Mars ellipsoid (a = 3396190 m, b = 3376200 m), flat albedo and Lambert shading.
//
//   globe/full      the whole globe, 90 % of the image height (eye 9.9e6 m from the centre)
//   globe/horizon   500 km above 30° N looking at the horizon 10° below the horizontal
//
// Each iteration draws one frame of every variant, one after the other (clear, draw,
// glFinish, each timed), so a drift of the shared machine hits them all:
//   clear          the clear alone (the floor under every variant)
//   box            RayCastGlobe with the front-face-culled bounding box
//   polygonN       RayCastGlobe with the bounding polygon of N = 4, 8, 16, 64 tangent points
//   polygon16_tex  as polygon16, with a 2048 × 1024 mipmapped equirectangular texture
//   uvsphere       a UV-sphere mesh of the ellipsoid (n segments around, n/2 rings), drawn
//                  with per-vertex geodetic normals and Lambert; n is the smallest whose chord
//                  sagitta on the silhouette is ≤ 0.5 px: n = ⌈π / acos(1 − 0.5 / r)⌉, with r
//                  the silhouette circle's radius in pixels (f · ρ / D: ρ its radius, D its
//                  distance from the eye). The ray cast samples the exact silhouette at pixel
//                  centres, so both are within 0.5 px of it.
// Counters: <variant>_ms (mean frame time, ms); <variant>_cast and _hit (fragments that ran
// the ray cast and rays that hit, from a separate counting draw so that the atomics do not
// weigh on the timed frames) and _miss (the fraction cast in vain); <variant>_fs (fragment
// shader invocations from a GL_FRAGMENT_SHADER_INVOCATIONS query: llvmpipe shades whole 2 × 2
// quads, so quads cut by a proxy's edges count in full, for each triangle); sphere_segments,
// sphere_triangles; coverage_diff_px (pixels covered by exactly one of polygon16 and
// uvsphere); box_over_polygon16 and polygon16_over_uvsphere (ratios of frame times, clear
// included, from the same interleaved frames).
//
// Run: build/bench/globe_bench --benchmark_min_time=20x
// With GLOBE_BENCH_PNG_DIR=<dir> each variant's frame is written there.
#include <regolith/clod/Camera.hpp>
#include <regolith/farfield/RayCastGlobe.hpp>
#include <regolith/gl/Gl.hpp>
#include <regolith/gl/HeadlessContext.hpp>
#include <regolith/gl/Image.hpp>
#include <regolith/gl/Program.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/topo/Body.hpp>

#include <benchmark/benchmark.h>
#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

namespace {

using namespace regolith;
using farfield::GlobeBody;
using farfield::GlobeProxy;
using farfield::RayCastGlobe;

constexpr double kDeg = std::numbers::pi / 180.0;
const glm::vec4 kClear{0.0F, 0.0F, 0.0F, 1.0F};

struct View {
  clod::Camera camera;
  GlobeBody body;
  glm::dvec3 sun{1.0, 0.0, 0.0};
  double silhouettePx = 0.0;  // radius of the silhouette circle in pixels, f · ρ / D
};

View makeView(bool horizon) {
  const topo::Body mars = topo::Body::marsEllipsoid();
  View v;
  v.body.a = mars.equatorialRadius();
  v.body.b = mars.polarRadius();
  v.body.colour = glm::vec3(0.85F, 0.55F, 0.35F);
  clod::Camera& c = v.camera;
  c.width = 1280;
  c.height = 720;
  c.fovYDegrees = 45.0;
  c.near = 1.0;
  if (horizon) {
    const glm::dmat3 enu = mars.enuFrame(30.0, 40.0);
    c.position = mars.toBodyFixed({30.0, 40.0, 5.0e5});
    const double down = 10.0 * kDeg + std::acos(v.body.a / glm::length(c.position));
    c.target = c.position + 1.0e5 * (std::cos(down) * enu[1] - std::sin(down) * enu[2]);
    c.up = enu[2];
    v.sun = glm::normalize(enu[2] + enu[0]);
  } else {
    // The disc's radius is f·tan(asin(a/d)) ≈ 0.45 × 720 px.
    const double f = 0.5 * c.height / std::tan(0.5 * c.fovYDegrees * kDeg);
    const double d = v.body.a / std::sin(std::atan(0.45 * c.height / f));
    c.position = d * glm::normalize(glm::dvec3(1.0, 0.6, 0.35));
    c.target = glm::dvec3(0.0);
    c.up = glm::dvec3(0.0, 0.0, 1.0);
    v.sun = glm::normalize(glm::dvec3(1.0, -0.5, 0.3));
  }
  const double d = glm::length(c.position);
  const double rho = v.body.a * std::sqrt(1.0 - (v.body.a / d) * (v.body.a / d));
  v.silhouettePx = c.focalPixels() * rho / std::sqrt(d * d - v.body.a * v.body.a);
  return v;
}

/// A UV sphere of the ellipsoid, positions in body axes (float: 0.25 m steps at Mars's
/// radius), drawn camera-relative.
class UvSphere {
 public:
  explicit UvSphere(const GlobeBody& body, int segments)
      : segments_(segments),
        program_("uv sphere", {R"(#version 450 core
layout(location = 0) in vec3 aPos;     // body axes, metres
layout(location = 1) in vec3 aNormal;  // geodetic normal, body axes
uniform mat4 uViewProj;
uniform mat3 uOrientation;
uniform vec3 uCentre;                  // centre − camera, scene axes
out vec3 vNormal;
void main() {
  vNormal = aNormal;
  gl_Position = uViewProj * vec4(uOrientation * aPos + uCentre, 1.0);
}
)",
                               "", R"(#version 450 core
in vec3 vNormal;
out vec4 oColour;
uniform vec3 uSun;  // body axes
uniform vec3 uColour;
uniform float uAmbient;
void main() {
  float diffuse = max(dot(normalize(vNormal), uSun), 0.0);
  oColour = vec4(uColour * (uAmbient + (1.0 - uAmbient) * diffuse), 1.0);
}
)"}) {
    const int rings = segments / 2;
    std::vector<float> data;
    for (int j = 0; j <= rings; ++j) {
      const double lat = std::numbers::pi * (0.5 - static_cast<double>(j) / rings);
      for (int i = 0; i <= segments; ++i) {
        const double lon = 2.0 * std::numbers::pi * i / segments;
        const glm::dvec3 u{std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon),
                           std::sin(lat)};
        const glm::dvec3 n = glm::normalize(u * glm::dvec3(1.0, 1.0, body.a / body.b));
        for (const double x : {body.a * u.x, body.a * u.y, body.b * u.z, n.x, n.y, n.z})
          data.push_back(static_cast<float>(x));
      }
    }
    std::vector<GLuint> index;
    const auto row = static_cast<GLuint>(segments + 1);
    for (int j = 0; j < rings; ++j)
      for (int i = 0; i < segments; ++i) {
        const GLuint a = static_cast<GLuint>(j) * row + static_cast<GLuint>(i), b = a + row;
        if (j > 0) index.insert(index.end(), {a, b, a + 1});  // no slivers at the poles
        if (j < rings - 1) index.insert(index.end(), {a + 1, b, b + 1});
      }
    count_ = static_cast<GLsizei>(index.size());
    glNamedBufferStorage(vbo_.id(), static_cast<GLsizeiptr>(data.size() * sizeof(float)),
                         data.data(), 0);
    glNamedBufferStorage(ibo_.id(), static_cast<GLsizeiptr>(index.size() * sizeof(GLuint)),
                         index.data(), 0);
    glVertexArrayVertexBuffer(vao_.id(), 0, vbo_.id(), 0, 6 * sizeof(float));
    glVertexArrayElementBuffer(vao_.id(), ibo_.id());
    for (GLuint a = 0; a < 2; ++a) {
      glVertexArrayAttribFormat(vao_.id(), a, 3, GL_FLOAT, GL_FALSE, 3 * a * sizeof(float));
      glVertexArrayAttribBinding(vao_.id(), a, 0);
      glEnableVertexArrayAttrib(vao_.id(), a);
    }
  }

  [[nodiscard]] int triangles() const noexcept { return count_ / 3; }

  void draw(const clod::Camera& cam, const GlobeBody& body, const glm::dvec3& sun,
            float ambient) const {
    program_.use();
    program_.set("uViewProj", cam.viewProjection());
    program_.set("uOrientation", glm::mat3(body.orientation));
    program_.set("uCentre", glm::vec3(body.centre - cam.position));
    program_.set("uSun", glm::vec3(glm::normalize(glm::transpose(body.orientation) * sun)));
    program_.set("uColour", body.colour);
    program_.set("uAmbient", ambient);
    glEnable(GL_CULL_FACE);
    glCullFace(GL_BACK);
    glBindVertexArray(vao_.id());
    glDrawElements(GL_TRIANGLES, count_, GL_UNSIGNED_INT, nullptr);
    glBindVertexArray(0);
    glDisable(GL_CULL_FACE);
  }

 private:
  int segments_;
  gl::Program program_;
  gl::Buffer vbo_, ibo_;
  gl::VertexArray vao_;
  GLsizei count_ = 0;
};

double ms(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

gl::RgbaImage textureImage(int w, int h) {
  gl::RgbaImage img{
      w, h,
      std::vector<std::uint8_t>(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 4)};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      auto* p = img.rgba.data() + 4 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(w) +
                                       static_cast<std::size_t>(x));
      const double s = std::sin(x * 0.05) * std::cos(y * 0.07);
      p[0] = static_cast<std::uint8_t>(std::lround(180.0 + 60.0 * s));
      p[1] = static_cast<std::uint8_t>(std::lround(120.0 + 40.0 * s));
      p[2] = static_cast<std::uint8_t>(std::lround(80.0 + 30.0 * s));
      p[3] = 255;
    }
  return img;
}

void globe(benchmark::State& state, bool horizon) {
  const View v = makeView(horizon);
  const gl::RenderTarget target(v.camera.width, v.camera.height);
  const gl::Texture texture = farfield::makeEquirectangularTexture(textureImage(2048, 1024), true);
  GlobeBody textured = v.body;
  textured.albedoTexture = texture.id();
  textured.colour = glm::vec3(1.0F);

  struct Variant {
    std::string name;
    std::unique_ptr<RayCastGlobe> globe;  // null: not ray-cast
    const GlobeBody* body = nullptr;
    std::function<void()> draw;
    double total = 0.0;
  };
  std::vector<Variant> variants;
  variants.push_back({"clear", nullptr, nullptr, [] {}});
  auto rayCast = [&](std::string name, GlobeProxy proxy, int points, const GlobeBody* body) {
    farfield::GlobeOptions o;
    o.proxy = proxy;
    o.polygonPoints = points;
    Variant var{std::move(name), std::make_unique<RayCastGlobe>(o), body, {}};
    RayCastGlobe* g = var.globe.get();
    var.draw = [g, body, &v] { (void)g->draw(v.camera, *body, v.sun); };
    variants.push_back(std::move(var));
  };
  rayCast("box", GlobeProxy::Box, 4, &v.body);
  for (const int n : {4, 8, 16, 64})
    rayCast("polygon" + std::to_string(n), GlobeProxy::Polygon, n, &v.body);
  rayCast("polygon16_tex", GlobeProxy::Polygon, 16, &textured);
  const int segments =
      static_cast<int>(std::ceil(std::numbers::pi / std::acos(1.0 - 0.5 / v.silhouettePx)));
  const UvSphere sphere(v.body, segments);
  const float ambient = farfield::GlobeOptions{}.ambient;
  variants.push_back(
      {"uvsphere", nullptr, nullptr, [&] { sphere.draw(v.camera, v.body, v.sun, ambient); }});

  // Counting draws (atomics on), then one warm-up frame of each variant (shader JIT).
  for (Variant& var : variants) {
    if (!var.globe) continue;
    var.globe->setCountRays(true);
    target.clear(kClear);
    const farfield::GlobeFrame f = var.globe->draw(v.camera, *var.body, v.sun);
    var.globe->setCountRays(false);
    // Fragment shader invocations as the driver counts them (GL 4.6 / ARB_pipeline_
    // statistics_query; Mesa counts helper invocations of partly covered quads too).
    GLuint query = 0;
    glGenQueries(1, &query);
    target.clear(kClear);
    glBeginQuery(GL_FRAGMENT_SHADER_INVOCATIONS_ARB, query);
    (void)var.globe->draw(v.camera, *var.body, v.sun);
    glEndQuery(GL_FRAGMENT_SHADER_INVOCATIONS_ARB);
    GLuint64 invocations = 0;
    glGetQueryObjectui64v(query, GL_QUERY_RESULT, &invocations);
    glDeleteQueries(1, &query);
    if (glGetError() == GL_NO_ERROR)
      state.counters[var.name + "_fs"] = static_cast<double>(invocations);
    state.counters[var.name + "_cast"] = static_cast<double>(f.raysCast);
    state.counters[var.name + "_hit"] = static_cast<double>(f.raysHit);
    state.counters[var.name + "_miss"] =
        1.0 - static_cast<double>(f.raysHit) / static_cast<double>(f.raysCast);
  }
  const char* pngDir = std::getenv("GLOBE_BENCH_PNG_DIR");
  std::vector<gl::DepthImage> depth;
  for (Variant& var : variants) {
    target.clear(kClear);
    var.draw();
    glFinish();
    if (var.name == "polygon16" || var.name == "uvsphere") depth.push_back(target.readDepth());
    if (pngDir != nullptr && *pngDir != '\0')
      gl::writePng(
          std::string(pngDir) + "/globe_" + (horizon ? "horizon_" : "full_") + var.name + ".png",
          target.readColor());
  }
  long diff = 0;
  for (std::size_t i = 0; i < depth[0].depth.size(); ++i)
    diff += (depth[0].depth[i] > 0.0F) != (depth[1].depth[i] > 0.0F) ? 1 : 0;

  for (auto _ : state) {
    for (Variant& var : variants) {
      const auto t0 = std::chrono::steady_clock::now();
      target.clear(kClear);
      var.draw();
      glFinish();
      var.total += ms(t0);
    }
  }
  const auto n = static_cast<double>(state.iterations());
  for (const Variant& var : variants) state.counters[var.name + "_ms"] = var.total / n;
  auto total = [&](const char* name) {
    for (const Variant& var : variants)
      if (var.name == name) return var.total;
    return 0.0;
  };
  state.counters["box_over_polygon16"] = total("box") / total("polygon16");
  state.counters["polygon16_over_uvsphere"] = total("polygon16") / total("uvsphere");
  state.counters["sphere_segments"] = segments;
  state.counters["sphere_triangles"] = sphere.triangles();
  state.counters["silhouette_px"] = v.silhouettePx;
  state.counters["coverage_diff_px"] = static_cast<double>(diff);
}

}  // namespace

int main(int argc, char** argv) {
  const gl::HeadlessContext context;  // one GL context for every case
  for (const bool horizon : {false, true})
    benchmark::RegisterBenchmark(horizon ? "globe/horizon" : "globe/full",
                                 [horizon](benchmark::State& s) { globe(s, horizon); })
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime()  // llvmpipe draws on its own threads: CPU time of this one undercounts
        ->MinWarmUpTime(0.0);
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
