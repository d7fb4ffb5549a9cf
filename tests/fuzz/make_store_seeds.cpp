// Writes the seed corpus of the store fuzz targets (fuzz_store, fuzz_info_json): small
// stores of every grid kind and placement the format has, written by the library's own
// writer, and stores imported from small real fixtures (tests/data/dem), which carry height
// statistics and provenance (format 1.3). Each seed is a few KiB.
//
//   make_store_seeds <fixtures folder> <output folder>...
//
// scripts/fuzz.sh --seeds runs it into tests/fuzz/corpus/fuzz_store and
// tests/fuzz/corpus/fuzz_info_json.
#include <regolith/store/GridInfo.hpp>
#include <regolith/store/Import.hpp>
#include <regolith/store/Store.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace {

using namespace regolith;
using namespace regolith::store;
namespace fs = std::filesystem;

constexpr float kNan = std::numeric_limits<float>::quiet_NaN();

std::shared_ptr<const topo::SampleSource> wavy(std::size_t rows, std::size_t cols) {
  return topo::InMemorySamples::fromFunction(rows, cols, [](std::size_t r, std::size_t c) {
    if ((r * 7 + c * 3) % 11 == 0) return kNan;
    return static_cast<float>(100.0 * std::sin(0.7 * static_cast<double>(r)) +
                              3.0 * static_cast<double>(c));
  });
}

GridInfo demInfo(const char* name, std::size_t rows, std::size_t cols) {
  GridInfo g;
  g.name = name;
  g.kind = GridKind::Dem;
  g.rows = rows;
  g.cols = cols;
  g.x0 = -10.0;
  g.y0 = 20.0;
  g.spacingX = 2.0;
  g.spacingY = 1.5;
  g.nodata = -32768.0f;
  g.latitudeType = topo::LatitudeType::Planetodetic;
  g.placement.kind = PlacementInfo::Kind::LocalTangentPlane;
  g.placement.originLatDeg = -2.05;
  g.placement.originLonDeg = -5.5;
  g.placement.headingDeg = 10.0;
  return g;
}

GridInfo planetInfo() {
  GridInfo g;
  g.name = "planet";
  g.kind = GridKind::Planet;
  g.rows = 8;
  g.cols = 16;
  g.x0 = -168.75;
  g.y0 = 78.75;
  g.spacingX = g.spacingY = 22.5;
  g.bodyName = "Moon";
  g.equatorialRadius = g.polarRadius = 1737400.0;
  g.scale = 0.5;
  g.offset = 10.0;
  return g;
}

GridInfo polarInfo() {
  GridInfo g = demInfo("polar", 9, 7);
  g.bodyName = "Moon";
  g.equatorialRadius = g.polarRadius = 1737400.0;
  g.placement = {};
  g.placement.kind = PlacementInfo::Kind::PolarStereographic;
  g.placement.pole = -1;
  g.placement.latTrueScaleDeg = -90.0;
  return g;
}

GridInfo utmInfo() {
  GridInfo g = demInfo("utm", 6, 5);
  g.x0 = 393000.0;
  g.y0 = 6345000.0;
  g.bodyName = "Earth";
  g.equatorialRadius = 6378137.0;
  g.polarRadius = 6356752.314245;
  g.placement = {};
  g.placement.kind = PlacementInfo::Kind::TransverseMercator;
  g.placement.lonCentreDeg = -123.0;
  g.placement.scaleFactor = 0.9996;
  g.placement.falseEasting = 500000.0;
  g.placement.falseNorthing = 10000000.0;
  return g;
}

GridInfo equirectangularInfo() {
  GridInfo g = demInfo("eqc", 5, 8);
  g.x0 = 1000.0;
  g.y0 = 5000.0;
  g.placement = {};
  g.placement.kind = PlacementInfo::Kind::Equirectangular;
  g.placement.projectionRadius = 3396190.0;
  g.placement.latTrueScaleDeg = 0.0;
  return g;
}

void write(const fs::path& path, std::vector<GridSource> grids, WriteOptions o) {
  o.threads = 1;
  writeStore(path, grids, o);
}

void writeSeeds(const fs::path& fixtures, const fs::path& out) {
  WriteOptions small;
  small.patchRows = 4;
  small.patchCols = 4;
  small.statistics = true;
  write(out / "dem_ltp.h5", {{demInfo("dem", 12, 10), wavy(12, 10)}}, small);
  WriteOptions deflate = small;
  deflate.deflate = 6;
  deflate.patchCols = 8;
  write(out / "planet_deflate.h5", {{planetInfo(), wavy(8, 16)}}, deflate);
  write(out / "three_placements.h5",
        {{polarInfo(), wavy(9, 7)}, {utmInfo(), wavy(6, 5)}, {equirectangularInfo(), wavy(5, 8)}},
        small);
  WriteOptions zfp = small;
  zfp.codec = Codec::Zfp;
  write(out / "dem_zfp.h5", {{demInfo("dem", 8, 8), wavy(8, 8)}}, zfp);
  GridSource mosaic{demInfo("mosaic", 10, 12), nullptr};
  mosaic.tiles.push_back({0, 0, wavy(6, 5), {}, {}});
  mosaic.tiles.push_back({0, 5, wavy(6, 7), {}, {}});
  write(out / "tiled.h5", {mosaic}, small);
  // Imports of real rasters: statistics, provenance (label fields), corrections.
  ImportOptions io;
  io.patchRows = io.patchCols = 8;
  io.threads = 1;
  (void)importRaster(fixtures / "Ares4_Marth_Crater_3557E_126N_ngate_03_lowres.cub",
                     out / "import_hirise_isis3.h5", io);
  io.window = SampleWindow{100, 200, 12, 16};
  (void)importRaster(fixtures / "megt90n000cb.lbl", out / "import_mola_pds3.h5", io);
  io.window = SampleWindow{0, 0, 16, 16};
  (void)importRaster(fixtures / "Shoemaker_1k.tif", out / "import_shoemaker_gtiff.h5", io);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: make_store_seeds <fixtures folder> <output folder>...\n");
    return 2;
  }
  try {
    const fs::path first = argv[2];
    fs::create_directories(first);
    writeSeeds(argv[1], first);
    for (int k = 3; k < argc; ++k) {
      fs::create_directories(argv[k]);
      for (const auto& f : fs::directory_iterator(first)) {
        // regression_* files are one target's inputs of fixed findings, not seeds written here.
        if (f.path().filename().string().rfind("regression_", 0) == 0) continue;
        fs::copy_file(f.path(), fs::path(argv[k]) / f.path().filename(),
                      fs::copy_options::overwrite_existing);
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "make_store_seeds: %s\n", e.what());
    return 1;
  }
  return 0;
}
