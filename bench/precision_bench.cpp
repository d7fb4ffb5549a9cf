// Float against double and re-rooted positions: the error of a terrain vertex's position
// relative to the camera against the distance of the terrain from the scene's origin
// (docs/accuracy-vs-time.md, `regolith report`), and what each way costs per vertex.
//
// The scene: a SceneGraph whose root is the origin (a planet's centre, or the Sun); a site
// frame D metres from it (along a skew direction, so every coordinate rounds); a terrain
// node at the site, holding 4,096 vertices within ±100 m of the site as float (a renderer's
// vertex buffer); a camera node 12 m from the site. The exact eye-space position of each
// vertex is known in double (the vertex minus the camera's offset, both small numbers), and
// every mode is compared with it:
//
//   precision/float_absolute/distance:D   the naive pipeline: world positions in float (the
//       vertex buffer in the root's frame), the camera's world position in float, one float
//       subtraction per vertex
//   precision/double_absolute/distance:D  the same in double, the result cast to float
//   precision/float_rerooted/distance:D   SceneGraph::renderList() re-rooted at the terrain
//       (once per iteration), then the item's float modelView() times each float vertex in
//       the terrain's own frame: what the GPU gets
//
// Counters: distance_m, error_m_max and error_m_rms (eye-space position error, metres, over
// the 4,096 vertices), s_per_vertex (CPU time per vertex, including the per-frame
// renderList() for the re-rooted mode).
//
// Run: build/bench/precision_bench --benchmark_min_time=0.05

#include <regolith/scenegraph/SceneGraph.hpp>

#include <benchmark/benchmark.h>
#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <random>
#include <string>
#include <vector>

namespace {

using regolith::scenegraph::NodeKind;
using regolith::scenegraph::Pose;
using regolith::scenegraph::SceneGraph;

constexpr std::size_t kVertices = 4096;
const glm::dvec3 kCameraOffset{7.0, -9.0, 3.5};  // camera from the site, metres

enum class Mode { FloatAbsolute, DoubleAbsolute, FloatRerooted };

struct Scene {
  SceneGraph graph{"origin"};
  std::size_t terrain = 0, camera = 0;
  std::vector<glm::vec3> local;    // vertices in the terrain's frame (float)
  std::vector<glm::dvec3> exact;   // eye-space positions, double
  std::vector<glm::vec3> worldF;   // vertices in the root's frame, float
  std::vector<glm::dvec3> worldD;  // the same in double
  glm::vec3 cameraWorldF{0.0F};
  glm::dvec3 cameraWorldD{0.0};
};

Scene makeScene(double distance) {
  Scene s;
  const glm::dvec3 dir = glm::normalize(glm::dvec3(1.0, 0.61, 0.37));
  Pose site;
  site.translation = dir * distance;
  const auto siteNode = s.graph.add(s.graph.root(), "site", site);
  s.terrain = s.graph.add(siteNode, "terrain", Pose::identity(), NodeKind::Terrain, 0);
  Pose cam;
  cam.translation = kCameraOffset;
  s.camera = s.graph.add(siteNode, "camera", cam, NodeKind::Camera);
  std::mt19937_64 rng(20261202);
  std::uniform_real_distribution<float> coord(-100.0F, 100.0F);
  const Pose terrainInRoot = s.graph.inRoot(s.terrain);
  s.cameraWorldD = s.graph.inRoot(s.camera).translation;
  s.cameraWorldF = glm::vec3(s.cameraWorldD);
  for (std::size_t i = 0; i < kVertices; ++i) {
    const glm::vec3 v(coord(rng), coord(rng), 0.1F * coord(rng));
    s.local.push_back(v);
    s.exact.push_back(glm::dvec3(v) - kCameraOffset);  // identity rotations: exact in double
    s.worldD.push_back(terrainInRoot.apply(glm::dvec3(v)));
    s.worldF.push_back(glm::vec3(s.worldD.back()));
  }
  return s;
}

void transform(const Scene& s, Mode mode, std::vector<glm::vec3>& out) {
  switch (mode) {
    case Mode::FloatAbsolute:
      for (std::size_t i = 0; i < kVertices; ++i) out[i] = s.worldF[i] - s.cameraWorldF;
      break;
    case Mode::DoubleAbsolute:
      for (std::size_t i = 0; i < kVertices; ++i) out[i] = glm::vec3(s.worldD[i] - s.cameraWorldD);
      break;
    case Mode::FloatRerooted: {
      const auto list = s.graph.renderList(s.terrain, s.camera);
      const glm::mat4 mv = list.find(s.terrain)->modelView();
      for (std::size_t i = 0; i < kVertices; ++i)
        out[i] = glm::vec3(mv * glm::vec4(s.local[i], 1.0F));
      break;
    }
  }
}

void precision(benchmark::State& state, Mode mode, double distance) {
  const Scene s = makeScene(distance);
  std::vector<glm::vec3> out(kVertices);
  for (auto _ : state) {
    transform(s, mode, out);
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  double maxErr = 0.0, sum2 = 0.0;
  for (std::size_t i = 0; i < kVertices; ++i) {
    const double e = glm::length(glm::dvec3(out[i]) - s.exact[i]);
    maxErr = std::max(maxErr, e);
    sum2 += e * e;
  }
  state.counters["distance_m"] = distance;
  state.counters["error_m_max"] = maxErr;
  state.counters["error_m_rms"] = std::sqrt(sum2 / static_cast<double>(kVertices));
  state.counters["s_per_vertex"] = benchmark::Counter(
      static_cast<double>(kVertices),
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

const int kRegistered = [] {
  const std::pair<const char*, Mode> modes[] = {{"float_absolute", Mode::FloatAbsolute},
                                                {"double_absolute", Mode::DoubleAbsolute},
                                                {"float_rerooted", Mode::FloatRerooted}};
  for (const auto& [name, mode] : modes) {
    // 1 m to 1e11 m: a local scene, a planet's radius (3.4e6 m), Mars from the Sun (2.3e11).
    for (int e = 0; e <= 11; ++e) {
      const double d = std::pow(10.0, e);
      const std::string label =
          std::string("precision/") + name + "/distance:1e" + std::to_string(e);
      const Mode m = mode;
      benchmark::RegisterBenchmark(label.c_str(),
                                   [m, d](benchmark::State& st) { precision(st, m, d); });
    }
  }
  return 0;
}();

}  // namespace

BENCHMARK_MAIN();
