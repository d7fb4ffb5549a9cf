// `regolith generate mars-planet|mars-cap|mars-strip|victoria`: procedural stores
// (store/Generate.hpp).
#include <regolith/core/Error.hpp>
#include <regolith/store/Generate.hpp>

#include "CancelOnSignal.hpp"
#include "Commands.hpp"
#include "FiniteRange.hpp"
#include "OutputFolder.hpp"
#include "TerminalProgress.hpp"

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>

namespace regolith::tools {

namespace {

/// Options every generator shares: the output and how it is written.
struct WriteArgs {
  std::string out;
  std::uint64_t seed = 1;
  std::size_t patch = 256;
  std::size_t levels = 0;
  int deflate = 0;
  std::string compression = "deflate";
  std::string grid;
};

void addWriteOptions(CLI::App& cmd, WriteArgs& w) {
  cmd.add_option("-o,--out", w.out, "Store file to write (replaced atomically if it exists)")
      ->required();
  cmd.add_option("--seed", w.seed, "Random seed: the same seed gives bit-identical samples")
      ->capture_default_str();
  cmd.add_option("--patch", w.patch, "Patch (HDF5 chunk) size in samples, square")
      ->check(CLI::Range(std::size_t{8}, std::size_t{8192}))
      ->capture_default_str();
  cmd.add_option("--levels", w.levels,
                 "Pyramid levels including level 0 (0: until a level fits in one patch)")
      ->check(CLI::Range(0, 40))
      ->capture_default_str();
  cmd.add_option("--deflate", w.deflate, "Deflate level 0-9 (0: uncompressed)")
      ->check(CLI::Range(0, 9))
      ->capture_default_str();
  cmd.add_option("--compression", w.compression, kCompressionHelp)
      ->check(CLI::IsMember({"deflate", "zfp"}))
      ->capture_default_str();
}

store::WriteOptions writeOptions(const WriteArgs& w, TerminalProgress& progress) {
  store::WriteOptions o;
  o.patchRows = o.patchCols = w.patch;
  o.levels = w.levels;
  o.deflate = w.deflate;
  o.codec = store::codecNamed(w.compression);
  o.progress = progress.callback();
  o.cancel = CancelOnSignal::flag();
  return o;
}

void report(const std::string& out, const store::GridInfo& info, const char* what) {
  std::cout << "Wrote " << out << ": " << what << " grid '" << info.name << "', " << info.rows
            << " x " << info.cols << " samples\n";
}

void addPlanet(CLI::App& generate) {
  struct Args {
    WriteArgs w;
    std::size_t rows = 720;
    double resolution = 0.0;
    bool ellipsoid = false;
    double craters = 1.0;
    std::size_t threads = 0;
  };
  auto a = std::make_shared<Args>();
  a->w.grid = "mars";
  auto* cmd = generate.add_subcommand(
      "mars-planet",
      "A global Mars-like planet (lat/lon grid, both poles, planetocentric): crustal "
      "dichotomy, a Tharsis-like bulge with shield volcanoes, fractal relief and craters "
      "with a power-law size distribution");
  addWriteOptions(*cmd, a->w);
  auto* size = cmd->add_option("--size", a->rows,
                               "Latitude samples pole to pole; the grid has twice as many "
                               "longitude samples")
                   ->check(CLI::Range(std::size_t{2}, std::size_t{1} << 20U))
                   ->capture_default_str();
  cmd->add_option("--resolution", a->resolution,
                  "Sample spacing in degrees (instead of --size; 180/spacing must be a whole "
                  "number)")
      ->check(FinitePositive())
      ->excludes(size);
  cmd->add_flag("--ellipsoid", a->ellipsoid,
                "Use the IAU Mars ellipsoid (3396190/3376200 m) instead of the sphere");
  cmd->add_option("--craters", a->craters, "Crater density multiplier (0: no craters)")
      ->check(FiniteRange(0.0, 100.0))
      ->capture_default_str();
  cmd->add_option("--threads", a->threads,
                  "Threads computing samples (0: the cores this process may run on)")
      ->capture_default_str();
  cmd->add_option("--grid", a->w.grid, "Name of the grid in the store")->capture_default_str();
  cmd->callback([a] {
    store::MarsPlanetOptions o;
    o.rows = a->rows;
    if (a->resolution > 0.0) {
      const double rows = 180.0 / a->resolution;
      if (std::abs(rows - std::round(rows)) > 1e-9 * rows || std::round(rows) < 2.0) {
        throw InvalidArgument("generate mars-planet: --resolution " +
                              std::to_string(a->resolution) +
                              " degrees does not divide 180 degrees into a whole number (>= 2) "
                              "of rows");
      }
      o.rows = static_cast<std::size_t>(std::round(rows));
    }
    requireOutputFolder("generate mars-planet", a->w.out);
    o.seed = a->w.seed;
    o.ellipsoid = a->ellipsoid;
    o.gridName = a->w.grid;
    o.craterDensity = a->craters;
    o.threads = a->threads;
    TerminalProgress progress = TerminalProgress::forStderr();
    o.write = writeOptions(a->w, progress);
    const store::MarsPlanetGenerator g(o);
    const CancelOnSignal cancel;
    g.write(a->w.out);
    report(a->w.out, g.gridInfo(), "planet");
  });
}

/// Options of the planet a cap or a strip refines (the same flags as mars-planet's).
void addPlanetOfOptions(CLI::App& cmd, store::PlanetOf& p, std::size_t& threads) {
  cmd.add_flag("--ellipsoid", p.ellipsoid,
               "The planet is on the IAU Mars ellipsoid (as mars-planet --ellipsoid)");
  cmd.add_option("--craters", p.craterDensity,
                 "Crater density multiplier, as for mars-planet (0: no craters)")
      ->check(FiniteRange(0.0, 100.0))
      ->capture_default_str();
  cmd.add_option("--threads", threads,
                 "Threads computing samples (0: the cores this process may run on)")
      ->capture_default_str();
}

void addCap(CLI::App& generate) {
  struct Args {
    WriteArgs w;
    store::PolarCapOptions o;
    std::string pole = "north";
  };
  auto a = std::make_shared<Args>();
  auto* cmd = generate.add_subcommand(
      "mars-cap",
      "A polar cap of the generated Mars (the planet of mars-planet with the same --seed, "
      "--ellipsoid and --craters): a square polar stereographic DEM around a pole at a finer "
      "resolution, with the planet's finer relief and craters and spiral troughs of layered "
      "deposits");
  addWriteOptions(*cmd, a->w);
  cmd->add_option("--pole", a->pole, "Which pole")
      ->check(CLI::IsMember({"north", "south"}))
      ->capture_default_str();
  cmd->add_option("--min-lat", a->o.minLatitudeDeg,
                  "The cap holds every point with |planetocentric latitude| >= this (degrees, "
                  "between 0 and 90)")
      ->check(FiniteRange(0.0, 90.0))
      ->capture_default_str();
  cmd->add_option("--resolution", a->o.spacing, "Sample spacing in map metres")
      ->check(FinitePositive())
      ->capture_default_str();
  cmd->add_option("--troughs", a->o.troughDepth,
                  "Depth of the layered deposits' spiral troughs in metres (0: no deposits)")
      ->check(FiniteRange(0.0, 10000.0))
      ->capture_default_str();
  addPlanetOfOptions(*cmd, a->o.planet, a->o.threads);
  cmd->add_option("--grid", a->w.grid,
                  "Name of the grid in the store (default north_cap or "
                  "south_cap)");
  cmd->callback([a] {
    requireOutputFolder("generate mars-cap", a->w.out);
    store::PolarCapOptions o = a->o;
    o.pole = a->pole == "north" ? store::PolarCapOptions::Pole::North
                                : store::PolarCapOptions::Pole::South;
    o.planet.seed = a->w.seed;
    o.gridName = a->w.grid;
    TerminalProgress progress = TerminalProgress::forStderr();
    o.write = writeOptions(a->w, progress);
    const store::PolarCapGenerator g(o);
    const CancelOnSignal cancel;
    g.write(a->w.out);
    report(a->w.out, g.gridInfo(), "polar stereographic DEM");
  });
}

void addStrip(CLI::App& generate) {
  struct Args {
    WriteArgs w;
    store::StripOptions o;
    double lengthKm = 300.0, widthKm = 10.0;
  };
  auto a = std::make_shared<Args>();
  a->w.grid = "strip";
  auto* cmd = generate.add_subcommand(
      "mars-strip",
      "A long, narrow DEM of the generated Mars (the planet of mars-planet with the same "
      "--seed, --ellipsoid and --craters) along a satellite's ground track: oblique Mercator "
      "about the great circle of an inclined orbit, at a finer resolution, with ragged edges "
      "(missing samples)");
  addWriteOptions(*cmd, a->w);
  cmd->add_option("--lat", a->o.centreLatDeg, "Centre latitude, planetocentric degrees")
      ->check(FiniteRange(-90.0, 90.0))
      ->capture_default_str();
  cmd->add_option("--lon", a->o.centreLonDeg, "Centre longitude, degrees east")
      ->check(FiniteRange(-360.0, 360.0))
      ->capture_default_str();
  cmd->add_option("--inclination", a->o.inclinationDeg,
                  "Orbit inclination in degrees, 0-180 (above 90: retrograde); |--lat| must be "
                  "within its reach")
      ->check(FiniteRange(0.0, 180.0))
      ->capture_default_str();
  cmd->add_flag("--descending", a->o.descending, "A southbound pass (default: northbound)");
  cmd->add_option("--length-km", a->lengthKm, "Length along the track, km")
      ->check(FinitePositive())
      ->capture_default_str();
  cmd->add_option("--width-km", a->widthKm, "Width across the track, km")
      ->check(FinitePositive())
      ->capture_default_str();
  cmd->add_option("--resolution", a->o.spacing, "Sample spacing in metres")
      ->check(FinitePositive())
      ->capture_default_str();
  cmd->add_option("--ragged", a->o.raggedness,
                  "How far the edges wander inwards, as a fraction of half the width, 0-0.9 "
                  "(0: every sample valid)")
      ->check(FiniteRange(0.0, 0.9))
      ->capture_default_str();
  addPlanetOfOptions(*cmd, a->o.planet, a->o.threads);
  cmd->add_option("--grid", a->w.grid, "Name of the grid in the store")->capture_default_str();
  cmd->callback([a] {
    requireOutputFolder("generate mars-strip", a->w.out);
    store::StripOptions o = a->o;
    o.length = 1000.0 * a->lengthKm;
    o.width = 1000.0 * a->widthKm;
    o.planet.seed = a->w.seed;
    o.gridName = a->w.grid;
    TerminalProgress progress = TerminalProgress::forStderr();
    o.write = writeOptions(a->w, progress);
    const store::StripGenerator g(o);
    const CancelOnSignal cancel;
    g.write(a->w.out);
    report(a->w.out, g.gridInfo(), "oblique Mercator DEM");
  });
}

void addVictoria(CLI::App& generate) {
  struct Args {
    WriteArgs w;
    std::size_t size = 1201;
    double resolution = 1.0;
  };
  auto a = std::make_shared<Args>();
  a->w.grid = "victoria";
  auto* cmd = generate.add_subcommand(
      "victoria",
      "A Victoria-crater-like local DEM on Mars (local tangent plane at 2.05S 5.5W on the "
      "IAU ellipsoid): a crater about 750 m across with a raised, scalloped rim and dunes on "
      "its floor, centred in the grid");
  addWriteOptions(*cmd, a->w);
  cmd->add_option("--size", a->size, "Samples per side of the square grid")
      ->check(CLI::Range(std::size_t{2}, std::size_t{1} << 20U))
      ->capture_default_str();
  cmd->add_option("--resolution", a->resolution, "Sample spacing in metres")
      ->check(FinitePositive())
      ->capture_default_str();
  cmd->add_option("--grid", a->w.grid, "Name of the grid in the store")->capture_default_str();
  cmd->callback([a] {
    requireOutputFolder("generate victoria", a->w.out);
    store::VictoriaOptions o;
    o.size = a->size;
    o.spacing = a->resolution;
    o.seed = a->w.seed;
    o.gridName = a->w.grid;
    TerminalProgress progress = TerminalProgress::forStderr();
    o.write = writeOptions(a->w, progress);
    const store::VictoriaGenerator g(o);
    const CancelOnSignal cancel;
    g.write(a->w.out);
    report(a->w.out, g.gridInfo(), "DEM");
  });
}

}  // namespace

void addGenerateCommand(CLI::App& app) {
  auto* generate = app.add_subcommand(
      "generate",
      "Write a procedural terrain store: deterministic for a seed, at any resolution, "
      "computed patch by patch (outputs larger than RAM are fine)");
  generate->require_subcommand(1);
  generate->footer(
      "Examples:\n"
      "  regolith generate victoria --out victoria.h5\n"
      "  regolith generate victoria --out v2m.h5 --size 601 --resolution 2 --seed 7\n"
      "  regolith generate mars-planet --out mars.h5 --resolution 0.25 --deflate 4\n"
      "  regolith generate mars-cap --out north.h5 --pole north --resolution 1000\n"
      "  regolith generate mars-strip --out strip.h5 --lat 20 --lon 30 --inclination 60\n"
      "A progress bar is drawn on stderr when it is a terminal; Ctrl-C cancels cleanly "
      "(no partial file).");
  addPlanet(*generate);
  addCap(*generate);
  addStrip(*generate);
  addVictoria(*generate);
}

}  // namespace regolith::tools
