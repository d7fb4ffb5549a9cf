// Interactive clipmap viewer of one grid (gl::Window: a GLFW window, OpenGL 4.5 core). The
// full viewer, on any store or the demo scene, is `regolith view` (docs/viewer.md); this
// example shows the few calls a program needs to draw a clipmap in a window.
//
//   regolith_viewer [store.h5 grid]     a store's grid, paged; without arguments a
//                                       synthetic 4097² crater DEM at 1 m
//   regolith_viewer ... --frames N --screenshot out.png
//                                       runs N frames (synchronous loading), saves the
//                                       last one and exits (the smoke test under Xvfb)
//
// Mouse: left drag orbits around the look-at point, wheel zooms. Keys: W/A/S/D move the
// look-at point (and with it the focus), T ties the focus to a marker driving in circles
// (again: untie), L toggles background loading, P saves a screenshot (viewer-NNN.png),
// Esc quits. The frame time is in the window title and drawn as a bar at the top left
// (green under 16.7 ms, red above; full width = 100 ms).
#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/clod/FocusController.hpp>
#include <regolith/clod/Render.hpp>
#include <regolith/gl/Gl.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/gl/Window.hpp>
#include <regolith/store/Pager.hpp>
#include <regolith/store/Store.hpp>

#include <glm/geometric.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using namespace regolith;
using namespace regolith::clod;

// A store's grid as the renderer's pyramid: one level per stored pyramid level, each paged.
std::shared_ptr<const HeightPyramid> pyramidFromStore(const std::string& path,
                                                      const std::string& grid) {
  auto store = std::make_shared<const store::Store>(store::Store::open(path));
  auto cache = std::make_shared<store::PatchCache>(std::size_t{512} << 20);
  return std::make_shared<const HeightPyramid>(store::Pager(store, cache).pyramid(grid));
}

std::shared_ptr<const HeightPyramid> syntheticDem() {
  const std::size_t side = 4097;
  const double half = 0.5 * static_cast<double>(side - 1);
  const topo::TopoGrid grid(side, side, -half, half, 1.0, 1.0);
  auto samples = topo::InMemorySamples::fromFunction(side, side, [&](std::size_t r, std::size_t c) {
    const double x = static_cast<double>(c) - half, y = half - static_cast<double>(r);
    const double d = std::hypot(x, y);
    const double crater = d < 400.0
                              ? 30.0 - 120.0 * (1.0 - (d / 400.0) * (d / 400.0))
                              : 30.0 * std::exp(-((d - 400.0) / 120.0) * ((d - 400.0) / 120.0));
    return static_cast<float>(crater + 25.0 * std::sin(x / 170.0) * std::cos(y / 230.0) +
                              6.0 * std::sin((x + 2.0 * y) / 23.0));
  });
  return std::make_shared<const HeightPyramid>(
      HeightPyramid::fromSamples(grid, samples, SurfaceKind::Plane));
}

struct Orbit {
  glm::dvec3 target{0.0, 0.0, 0.0};
  double heading = 30.0, pitch = 35.0, distance = 900.0;  // degrees, metres
  bool dragging = false;
  double lastX = 0.0, lastY = 0.0;
  std::set<int> keys;  // held down
};

Camera orbitCamera(const Orbit& o, const HeightPyramid& pyramid, int width, int height) {
  return cameraLookingAt(pyramid, o.target, o.heading, o.pitch, o.distance, 45.0, width, height);
}

}  // namespace

int main(int argc, char** argv) {
  try {
    std::vector<std::string> positional;
    long frameLimit = 0;  // 0: until the window closes
    std::string finalShot;
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      if ((arg == "--frames" || arg == "--screenshot") && i + 1 < argc) {
        const std::string value = argv[++i];
        if (arg == "--screenshot") {
          finalShot = value;
        } else {
          frameLimit = std::strtol(value.c_str(), nullptr, 10);
          if (frameLimit <= 0) throw std::invalid_argument("--frames " + value + ": expected > 0");
        }
      } else if (arg.rfind("--", 0) == 0) {
        throw std::invalid_argument("unknown option " + arg +
                                    " (usage: regolith_viewer [store.h5 grid] [--frames N "
                                    "--screenshot out.png])");
      } else {
        positional.push_back(arg);
      }
    }
    if (positional.size() != 0 && positional.size() != 2)
      throw std::invalid_argument("expected a store and a grid name, or nothing");
    const auto pyramid =
        positional.size() == 2 ? pyramidFromStore(positional[0], positional[1]) : syntheticDem();
    gl::Window window(1280, 720, "regolith viewer");
    {
      Orbit orbit;
      const auto& g0 = pyramid->level(0).grid;
      const glm::dvec2 mid = g0.sampleCentre(0.5 * static_cast<double>(g0.rows()),
                                             0.5 * static_cast<double>(g0.cols()));
      orbit.target = pyramid->position(mid.x, mid.y, 0.0);
      if (pyramid->kind() == SurfaceKind::Planet) orbit.distance = 200e3;
      ClipmapOptions options;
      options.overlapDepthPush = 0.02F;  // finer levels win where levels overlap
      ClipmapTerrain terrain(pyramid, options);
      FocusController focus;
      int width = 1280, height = 720;
      focus.addCamera(orbitCamera(orbit, *pyramid, width, height), gl::Window::time());
      auto target = std::make_unique<gl::RenderTarget>(width, height);
      // A scripted run (--frames) loads synchronously so its frames are deterministic.
      bool async = frameLimit == 0, tiedPrev = false, screenshotPrev = false, asyncPrev = false;
      long frames = 0;
      int shots = 0;
      double frameMs = 0.0;
      while (!window.shouldClose()) {
        const auto t0 = std::chrono::steady_clock::now();
        double mx = orbit.lastX, my = orbit.lastY;
        for (const gl::WindowEvent& e : window.poll()) {
          if (e.type == gl::WindowEvent::Type::Scroll) orbit.distance *= std::pow(0.9, e.y);
          if (e.type == gl::WindowEvent::Type::CursorMove) {
            mx = e.x;
            my = e.y;
          }
          if (e.type == gl::WindowEvent::Type::MouseButton && e.code == 0) orbit.dragging = e.press;
          if (e.type == gl::WindowEvent::Type::Key) {
            if (e.press)
              orbit.keys.insert(e.code);
            else
              orbit.keys.erase(e.code);
          }
        }
        const auto down = [&](int key) { return orbit.keys.contains(key); };
        const double now = gl::Window::time();
        auto [fw, fh] = window.framebufferSize();
        if (fw > 0 && fh > 0 && (fw != width || fh != height)) {
          width = fw;
          height = fh;
          target = std::make_unique<gl::RenderTarget>(width, height);
        }
        // Mouse orbit.
        if (orbit.dragging) {
          orbit.heading += 0.3 * (mx - orbit.lastX);
          orbit.pitch = std::clamp(orbit.pitch + 0.3 * (my - orbit.lastY), 2.0, 89.0);
        }
        orbit.lastX = mx;
        orbit.lastY = my;
        // Keys move the look-at point along the ground.
        const Camera before = orbitCamera(orbit, *pyramid, width, height);
        const glm::dvec3 up = pyramid->up(orbit.target);
        glm::dvec3 fwd = before.forward() - up * glm::dot(before.forward(), up);
        fwd = glm::normalize(fwd);
        const glm::dvec3 right = glm::cross(fwd, up);
        const double step = 0.01 * orbit.distance;
        if (down('W')) orbit.target += fwd * step;
        if (down('S')) orbit.target -= fwd * step;
        if (down('D')) orbit.target += right * step;
        if (down('A')) orbit.target -= right * step;
        if (down(gl::keys::kEscape)) window.requestClose();
        const bool tieKey = down('T');
        if (tieKey && !tiedPrev) {
          if (focus.tied()) {
            focus.untie();
          } else {
            const glm::dvec3 centre = orbit.target;
            focus.tieTo([centre] {
              const double t = gl::Window::time();
              return centre + glm::dvec3(200.0 * std::cos(0.2 * t), 200.0 * std::sin(0.2 * t), 0.0);
            });
          }
        }
        tiedPrev = tieKey;
        const bool asyncKey = down('L');
        if (asyncKey && !asyncPrev) {
          async = !async;
          if (!async) terrain.finishLoading();
        }
        asyncPrev = asyncKey;

        const Camera cam = orbitCamera(orbit, *pyramid, width, height);
        focus.update(0, cam, now);
        if (async) {
          terrain.requestFocus(focus.focus(now));
          terrain.update(false);
        } else {
          terrain.setFocus(focus.focus(now));
        }
        target->clear({0.02F, 0.02F, 0.05F, 1.0F});
        const ClipmapFrame frame = terrain.draw(cam);
        // Frame-time bar.
        glEnable(GL_SCISSOR_TEST);
        const int bar = static_cast<int>(std::min(frameMs / 100.0, 1.0) * width);
        glScissor(0, height - 8, std::max(bar, 1), 8);
        if (frameMs < 16.7)
          glClearColor(0.1F, 0.9F, 0.2F, 1.0F);
        else
          glClearColor(0.9F, 0.1F, 0.1F, 1.0F);
        glClear(GL_COLOR_BUFFER_BIT);
        glDisable(GL_SCISSOR_TEST);

        const bool shotKey = down('P');
        if (shotKey && !screenshotPrev) {
          char name[64];
          std::snprintf(name, sizeof name, "viewer-%03d.png", shots++);
          gl::writePng(name, target->readColor());
          std::printf("saved %s\n", name);
        }
        screenshotPrev = shotKey;
        if (frameLimit > 0 && ++frames >= frameLimit) {
          const gl::RgbaImage last = target->readColor();
          std::size_t covered = 0;
          for (int y = 8; y < last.height; ++y)  // below the frame-time bar
            for (int x = 0; x < last.width; ++x) covered += last.is(x, y, 5, 5, 13) ? 0U : 1U;
          const double share =
              100.0 * static_cast<double>(covered) /
              (static_cast<double>(last.width) * static_cast<double>(last.height - 8));
          if (!finalShot.empty()) gl::writePng(finalShot, last);
          std::printf("%ld frames in a %dx%d window; terrain on %.0f%% of pixels%s%s\n", frames,
                      width, height, share, finalShot.empty() ? "" : "; saved ", finalShot.c_str());
          window.requestClose();
        }
        glBlitNamedFramebuffer(target->framebuffer(), 0, 0, 0, width, height, 0, 0, width, height,
                               GL_COLOR_BUFFER_BIT, GL_NEAREST);
        window.swap();
        frameMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                      .count();
        char title[160];
        std::snprintf(
            title, sizeof title, "regolith viewer  %.1f ms  levels %zu-%zu  %zu vertices  %s%s",
            frameMs, frame.firstLevel, frame.firstLevel + frame.levelsDrawn - 1, frame.vertices,
            async ? "background loading" : "synchronous", focus.tied() ? "  focus: marker" : "");
        window.setTitle(title);
      }
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "regolith_viewer: %s\n", e.what());
    return 1;
  }
}
