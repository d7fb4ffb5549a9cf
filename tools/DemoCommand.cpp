// `regolith demo`: the topo walkthrough (TopoDemo.hpp).
#include "Commands.hpp"
#include "TopoDemo.hpp"

#include <CLI/CLI.hpp>

#include <iostream>
#include <memory>
#include <string>

namespace regolith::tools {

void addDemoCommand(CLI::App& app) {
  struct Args {
    TopoDemoOptions demo;
    std::string outDir = TopoDemoOptions{}.outDir.string();
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "demo",
      "Topo walkthrough: builds a Victoria-like crater DEM on Mars in memory, queries "
      "heights and normals along a rover path, reports accuracy and speed per kernel, and "
      "exports the crater's west rim as a PLY mesh");
  cmd->add_option("--size", args->demo.size, "Samples per side of the square DEM")
      ->check(CLI::Range(16, 20001))
      ->capture_default_str();
  cmd->add_option("--spacing", args->demo.spacing, "Sample spacing in metres")
      ->check(CLI::Range(0.01, 100.0))
      ->capture_default_str();
  cmd->add_option("--queries", args->demo.queries, "Queries for the throughput measurement")
      ->check(CLI::Range(1000, 100000000))
      ->capture_default_str();
  cmd->add_option("--out", args->outDir, "Folder for output files")->capture_default_str();
  cmd->callback([args] {
    args->demo.outDir = args->outDir;
    const int rc = runTopoDemo(args->demo, std::cout);
    if (rc != 0) throw CLI::RuntimeError(rc);
  });
}

}  // namespace regolith::tools
