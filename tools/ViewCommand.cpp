// `regolith view STORE | --demo`: the interactive viewer (docs/viewer.md) in a GLFW window.
#include <regolith/core/Error.hpp>
#include <regolith/gl/Gl.hpp>
#include <regolith/gl/Window.hpp>

#include "Commands.hpp"
#include "viewer/Script.hpp"
#include "viewer/ViewScene.hpp"
#include "viewer/Viewer.hpp"

#include <CLI/CLI.hpp>
#include <malloc.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

namespace regolith::tools {

namespace {

struct Args {
  std::string store;
  std::string grid;
  std::size_t cacheMb = 512;
  bool demo = false;
  std::string script;
  int width = 1280, height = 720;
  int clipmapSize = 127;  // a quarter of render's vertices: interactive on llvmpipe
};

// Keeps freed heap for reuse rather than handing it back to the kernel: glibc trims the top of
// its heap once more than M_TRIM_THRESHOLD is free there (a threshold that otherwise follows
// the largest mapped block freed, a few MiB), and a frame's large transient buffers then
// came back as fresh zeroed pages every frame. The demo scene in split viewports spent
// half its frame in those page faults: 157-175 ms a frame with glibc's default, 77-85 ms
// with 64 MiB (docs/viewer.md, "Frame time"). A viewer holds its working set anyway.
void keepFreedHeap() {
#ifdef __GLIBC__
  (void)mallopt(M_TRIM_THRESHOLD, 64 << 20);
#endif
}

void runView(const Args& a) {
  if (a.demo == !a.store.empty())
    throw InvalidArgument("view: give a store, a scene file or --demo (one of them)");
  keepFreedHeap();
  // Scene data first, so a bad store fails before a window opens.
  std::vector<viewer::ScriptStep> script;
  if (!a.script.empty()) script = viewer::parseScript(a.script);
  const bool sceneFile = a.store.size() > 5 && a.store.ends_with(".json");
  viewer::ViewScene scene =
      a.demo      ? viewer::demoScene()
      : sceneFile ? viewer::sceneFileScene(a.store, a.cacheMb << 20U)
                  : viewer::storeScene(a.store, a.grid, a.cacheMb << 20U, a.clipmapSize);
  gl::Window window(a.width, a.height, "regolith view: " + scene.title);
  const std::string title = scene.title;
  auto [fw, fh] = window.framebufferSize();
  // A script's screenshots and picks must not depend on how fast the terrain reads.
  viewer::Viewer view(std::move(scene), fw, fh, std::cout,
                      a.script.empty() ? render::Loading::Background : render::Loading::Wait);
  std::vector<double> frameMs;
  std::size_t step = 0;
  double last = 0.0;
  while (!window.shouldClose() && !view.quitRequested()) {
    const auto t0 = std::chrono::steady_clock::now();
    for (const gl::WindowEvent& e : window.poll())
      if (a.script.empty()) view.handle(e);  // a script owns the input
    const viewer::ScriptStep* s = nullptr;
    if (!a.script.empty()) {
      if (step >= script.size()) break;
      s = &script[step++];
      for (const gl::WindowEvent& e : s->events) view.handle(e);
    }
    std::tie(fw, fh) = window.framebufferSize();
    view.setFrameMs(last);
    view.draw(fw, fh);
    if (s != nullptr) {
      if (s->after == viewer::ScriptStep::After::Pick) (void)view.pick(s->x, s->y);
      if (s->after == viewer::ScriptStep::After::Screenshot) view.screenshot(s->file);
      if (s->after == viewer::ScriptStep::After::Quit) break;
    }
    glBlitNamedFramebuffer(view.image().framebuffer(), 0, 0, 0, fw, fh, 0, 0, fw, fh,
                           GL_COLOR_BUFFER_BIT, GL_NEAREST);
    window.swap();
    last = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    frameMs.push_back(last);
    char t[256];
    std::snprintf(t, sizeof t, "regolith view: %s  %.1f ms", title.c_str(), last);
    window.setTitle(t);
  }
  if (!frameMs.empty()) {
    // The first frame builds the clipmaps' windows from nothing: left out of the median.
    std::vector<double> sorted(frameMs.begin() + (frameMs.size() > 1 ? 1 : 0), frameMs.end());
    std::sort(sorted.begin(), sorted.end());
    std::printf("%zu frames in a %dx%d window; median frame %.1f ms (min %.1f, max %.1f)\n",
                frameMs.size(), fw, fh, sorted[sorted.size() / 2], sorted.front(), sorted.back());
  }
}

}  // namespace

void addViewCommand(CLI::App& app) {
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "view",
      "Opens a store (one terrain), a scene file or the demo scene in an interactive window: "
      "orbit and fly cameras, focus switching, effect toggles, picking, split viewports, a HUD and "
      "screenshots (docs/viewer.md). Needs a display (xvfb-run for a virtual one)");
  cmd->add_option("store", a->store,
                  "Store file (HDF5), or a scene file (.json, docs/scene-format.md)");
  cmd->add_option("--grid", a->grid, "Grid to view (default: the store's only grid)");
  cmd->add_option("--cache-mb", a->cacheMb, "Patch cache budget in MiB")
      ->check(CLI::Range(std::size_t{1}, std::size_t{1} << 20U))
      ->capture_default_str();
  cmd->add_flag("--demo", a->demo,
                "The Mars/Victoria scene (generated): Mars, two DEMs, the rover and its cameras");
  cmd->add_option("--script", a->script,
                  "Input events from a file instead of the mouse and keyboard, one frame per "
                  "event (docs/viewer.md, 'Scripts'); the viewer exits at its end");
  cmd->add_option("--width", a->width, "Window width")
      ->check(CLI::Range(64, 8192))
      ->capture_default_str();
  cmd->add_option("--height", a->height, "Window height")
      ->check(CLI::Range(64, 8192))
      ->capture_default_str();
  cmd->add_option("--clipmap-size", a->clipmapSize,
                  "Vertices per clipmap level side (odd, 15 to 2047)")
      ->check(CLI::Range(15, 2047))
      ->capture_default_str();
  cmd->footer(
      "Examples:\n"
      "  regolith view mars.h5\n"
      "  regolith view --demo\n"
      "  xvfb-run -a regolith view mars.h5 --script events.txt\n"
      "Exit status: 0 on success; non-zero with 'regolith: error: ...' on stderr otherwise "
      "(including when no window with an OpenGL 4.5 context can be opened).");
  cmd->callback([a] { runView(*a); });
}

}  // namespace regolith::tools
