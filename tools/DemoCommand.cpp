// `regolith demo` (the main job, MainDemo.hpp) and `regolith walkthrough` (the topo
// walkthrough, TopoDemo.hpp).
#include "Commands.hpp"
#include "FiniteRange.hpp"
#include "MainDemo.hpp"
#include "OutputFolder.hpp"
#include "TopoDemo.hpp"

#include <CLI/CLI.hpp>

#include <iostream>
#include <memory>
#include <string>

namespace regolith::tools {

namespace {

void addMainDemo(CLI::App& app) {
  struct Args {
    MainDemoOptions demo;
    std::string outDir = MainDemoOptions{}.outDir.string();
    std::string dataDir;
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "demo",
      "The main job: generates the default data if absent (a procedural Mars and a "
      "Victoria-like crater DEM on it), drives a six-wheel rover across the crater with wheel "
      "queries every 1 ms through a paged store, renders the scene headless, and prints a "
      "summary of what was computed and how fast");
  cmd->add_option("--out", args->outDir, "Folder for the images and the report")
      ->capture_default_str();
  cmd->add_option("--data", args->dataDir,
                  "Folder of the default stores, generated there if absent (default: OUT/data)");
  cmd->add_option("--cache-mb", args->demo.cacheMb, "Patch cache budget of the traverse, MiB")
      ->check(CLI::Range(std::size_t{1}, std::size_t{1} << 20U))
      ->capture_default_str();
  cmd->add_option("--frames", args->demo.frames, "Frames of the orbit-to-surface sequence")
      ->check(CLI::Range(std::size_t{2}, std::size_t{10000}))
      ->capture_default_str();
  cmd->add_option("--width", args->demo.width, "Image width")
      ->check(CLI::Range(64, 8192))
      ->capture_default_str();
  cmd->add_option("--height", args->demo.height, "Image height")
      ->check(CLI::Range(64, 8192))
      ->capture_default_str();
  cmd->add_flag("--quick", args->demo.quick,
                "Small stores and few frames: a smoke run in seconds (tests)");
  cmd->callback([args] {
    requireFolderToWrite("demo", args->outDir);
    if (!args->dataDir.empty()) requireFolderToWrite("demo", args->dataDir);
    args->demo.outDir = args->outDir;
    args->demo.dataDir = args->dataDir;
    runMainDemo(args->demo, std::cout);
  });
}

void addWalkthrough(CLI::App& app) {
  struct Args {
    TopoDemoOptions demo;
    std::string outDir = TopoDemoOptions{}.outDir.string();
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "walkthrough",
      "Topo walkthrough: builds a Victoria-like crater DEM on Mars in memory, queries "
      "heights and normals along a rover path, reports accuracy and speed per kernel, and "
      "exports the crater's west rim as a PLY mesh");
  cmd->add_option("--size", args->demo.size, "Samples per side of the square DEM")
      ->check(CLI::Range(16, 20001))
      ->capture_default_str();
  cmd->add_option("--spacing", args->demo.spacing, "Sample spacing in metres")
      ->check(FiniteRange(0.01, 100.0))
      ->capture_default_str();
  cmd->add_option("--queries", args->demo.queries, "Queries for the throughput measurement")
      ->check(CLI::Range(1000, 100000000))
      ->capture_default_str();
  cmd->add_option("--out", args->outDir, "Folder for output files")->capture_default_str();
  cmd->callback([args] {
    requireFolderToWrite("walkthrough", args->outDir);
    args->demo.outDir = args->outDir;
    const int rc = runTopoDemo(args->demo, std::cout);
    if (rc != 0) throw CLI::RuntimeError(rc);
  });
}

}  // namespace

void addDemoCommand(CLI::App& app) {
  addMainDemo(app);
  addWalkthrough(app);
}

}  // namespace regolith::tools
