// Renders the paper's Mars/Victoria scene headless as a PNG sequence, flying from orbit down
// to the rover on the crater rim (scene::renderFlyover), and prints the float32 jitter of the
// rover moving in 1 mm steps for the naive and the re-rooted pipelines (--jitter).
//
//   mars_victoria [--out DIR] [--frames N] [--width W] [--height H] [--jitter]
#include <regolith/scene/Jitter.hpp>
#include <regolith/scene/MarsVictoria.hpp>
#include <regolith/topo/Error.hpp>

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

namespace {

int jitter(std::size_t frames) {
  using namespace regolith::scene;
  std::printf("rover moving 1 mm per frame along +y of Victoria, %zu frames, chase camera\n",
              frames);
  for (const glm::dvec3 start : {glm::dvec3(0.0, -395.0, 8.0), glm::dvec3(0.0, -300.0, -20.0),
                                 glm::dvec3(550.0, 550.0, 1.0)}) {
    SceneGraph g("sun");
    PaperSceneLayout layout;
    layout.roverInDem = start;
    const PaperSceneNodes n = buildPaperScene(g, layout);
    std::vector<TrackedPoint> points;
    for (const glm::dvec3 p : {glm::dvec3(0.8, 0.6, 0.2), glm::dvec3(-0.8, -0.6, 0.2),
                               glm::dvec3(0.3, 0.0, 1.5), glm::dvec3(0.0)})
      points.push_back({n.rover, p});
    for (int dy = 2; dy <= 12; dy += 2)
      for (int dx = -3; dx <= 3; dx += 2)
        points.push_back({n.victoria, glm::round(start) + glm::dvec3(dx, dy, -0.3)});
    const auto step = [&](SceneGraph& gg, std::size_t i) {
      gg.setLocal(n.rover,
                  roverPose(start + glm::dvec3(0.0, 0.001 * static_cast<double>(i), 0.0), 0.0));
    };
    std::printf("from (%.0f, %.0f) m in Victoria's frame:\n", start.x, start.y);
    for (const auto& r :
         {measureJitter(g, n.chaseCamera, n.sun, n.sun, Pipeline::NaiveWorld, points, frames, step),
          measureJitter(g, n.chaseCamera, n.mars, n.mars, Pipeline::NaiveWorld, points, frames,
                        step),
          measureJitter(g, n.chaseCamera, n.victoria, n.sun, Pipeline::Rerooted, points, frames,
                        step)})
      std::printf("  %-36s jitter %11.4g px   max error %11.4g px   lost %zu of %zu\n",
                  r.name.c_str(), r.jitterPx, r.errorPx, r.lost, frames * points.size());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    regolith::scene::FlyoverOptions options;
    bool doJitter = false;
    std::size_t jitterFrames = 10000;
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      const auto next = [&]() -> std::string {
        if (i + 1 >= argc) throw regolith::InvalidArgument("mars_victoria: " + a + " needs a value");
        return argv[++i];
      };
      if (a == "--out") options.outputDir = next();
      else if (a == "--frames") options.frames = std::stoi(next());
      else if (a == "--width") options.width = std::stoi(next());
      else if (a == "--height") options.height = std::stoi(next());
      else if (a == "--jitter") doJitter = true;
      else if (a == "--jitter-frames") jitterFrames = std::stoul(next());
      else {
        std::fprintf(stderr,
                     "usage: mars_victoria [--out DIR] [--frames N] [--width W] [--height H] "
                     "[--jitter [--jitter-frames N]]\n");
        return 2;
      }
    }
    if (doJitter) return jitter(jitterFrames);
    options.progress = [](int done, int all, const std::filesystem::path& path) {
      std::printf("\r[%3d/%3d] %s", done, all, path.string().c_str());
      std::fflush(stdout);
    };
    const auto s = regolith::scene::renderFlyover(options);
    std::printf("\n%zu PNGs in %s; %.1f s (%.1f s drawing), focus Mars → Victoria at frame %d, "
                "camera %.0f m → %.1f m from the rover\n",
                s.files.size(), options.outputDir.string().c_str(), s.seconds, s.renderSeconds,
                s.focusSwitchFrame, s.startDistance, s.endDistance);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mars_victoria: %s\n", e.what());
    return 1;
  }
}
