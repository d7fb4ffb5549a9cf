// The `regolith` command. Subcommands grow with the issues; today: `demo`.
#include <regolith/topo/Error.hpp>

#include "TopoDemo.hpp"

#include <CLI/CLI.hpp>

#include <iostream>

int main(int argc, char** argv) try {
  CLI::App app{"Regolith: planetary terrain for simulation and visualization"};
  app.require_subcommand(1);

  regolith::tools::TopoDemoOptions demo;
  std::string outDir = demo.outDir.string();
  auto* demoCmd = app.add_subcommand(
      "demo",
      "Topo walkthrough: builds a Victoria-like crater DEM on Mars in memory, queries "
      "heights and normals along a rover path, reports accuracy and speed per kernel, and "
      "exports the crater's west rim as a PLY mesh");
  demoCmd->add_option("--size", demo.size, "Samples per side of the square DEM")
      ->check(CLI::Range(16, 20001))
      ->capture_default_str();
  demoCmd->add_option("--spacing", demo.spacing, "Sample spacing in metres")
      ->check(CLI::Range(0.01, 100.0))
      ->capture_default_str();
  demoCmd->add_option("--queries", demo.queries, "Queries for the throughput measurement")
      ->check(CLI::Range(1000, 100000000))
      ->capture_default_str();
  demoCmd->add_option("--out", outDir, "Folder for output files")->capture_default_str();

  CLI11_PARSE(app, argc, argv);
  if (*demoCmd) {
    demo.outDir = outDir;
    return regolith::tools::runTopoDemo(demo, std::cout);
  }
  return 0;
} catch (const regolith::Error& e) {
  std::cerr << "regolith: error: " << e.what() << '\n';
  return 1;
} catch (const std::exception& e) {
  std::cerr << "regolith: unexpected error: " << e.what() << '\n';
  return 2;
}
