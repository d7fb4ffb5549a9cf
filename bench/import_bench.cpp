// GDAL import against gdal_translate to a COG (issue: Import and CLI, "Performance").
//
//   import/regolith      importRaster() of an 8192×8192 float32 GeoTIFF into a store with its
//                        full pyramid (6 levels of 256×256 patches), deflate 6 after HDF5's
//                        shuffle filter, 2 threads
//   import/regolith_zfp  the same with the ZFP codec (reversible, HDF5 filter 32013)
//   import/gdal_cog      GDALTranslate (the library behind gdal_translate) of the same input
//                        with -of COG -co COMPRESS=DEFLATE -co PREDICTOR=YES
//                        -co NUM_THREADS=2, which builds overviews too
//
// Both report wall seconds and the output's size (counter "MB", 10^6 bytes). They alternate
// (--benchmark_repetitions with interleaving is not available, so each runs its repetitions
// in turn; use --benchmark_repetitions=N and compare medians).
//
// The input is generated once into $TMPDIR/regolith-import-bench/input_8192.tif (256 MiB,
// 256×256-tiled, uncompressed): fractal relief (8 octaves of value noise) plus craters, in
// float32 metres, on a local equirectangular map of Mars.
#include <regolith/core/AtomicFile.hpp>
#include <regolith/store/Import.hpp>
#include <regolith/store/Store.hpp>

#include <benchmark/benchmark.h>
#include <cpl_conv.h>
#include <gdal.h>
#include <gdal_utils.h>
#include <ogr_srs_api.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using namespace regolith;
namespace fs = std::filesystem;

constexpr int kSize = 8192;

fs::path benchDir() {
  const char* t = std::getenv("TMPDIR");
  const fs::path dir = fs::path(t != nullptr && *t != '\0' ? t : "/tmp") / "regolith-import-bench";
  fs::create_directories(dir);
  return dir;
}

/// A hash of a lattice point in [0, 1).
double lattice(std::int64_t i, std::int64_t j, std::uint64_t seed) {
  auto h = static_cast<std::uint64_t>(i) * 0x9E3779B97F4A7C15ULL ^
           static_cast<std::uint64_t>(j) * 0xC2B2AE3D27D4EB4FULL ^ seed;
  h ^= h >> 31;
  h *= 0xBF58476D1CE4E5B9ULL;
  h ^= h >> 27;
  return static_cast<double>(h >> 11) / 9007199254740992.0;
}

double valueNoise(double x, double y, std::uint64_t seed) {
  const double fx = std::floor(x), fy = std::floor(y);
  const auto i = static_cast<std::int64_t>(fx), j = static_cast<std::int64_t>(fy);
  double u = x - fx, v = y - fy;
  u = u * u * (3.0 - 2.0 * u);
  v = v * v * (3.0 - 2.0 * v);
  const double a = lattice(i, j, seed), b = lattice(i + 1, j, seed);
  const double c = lattice(i, j + 1, seed), d = lattice(i + 1, j + 1, seed);
  return (a + (b - a) * u) + ((c + (d - c) * u) - (a + (b - a) * u)) * v;
}

float height(int row, int col) {
  const double x = col, y = row;
  double h = 0.0, amp = 120.0, freq = 1.0 / 1024.0;
  for (int o = 0; o < 8; ++o) {
    h += amp * (valueNoise(x * freq, y * freq, 1234U + static_cast<std::uint64_t>(o)) - 0.5);
    amp *= 0.5;
    freq *= 2.0;
  }
  // A few craters: bowl plus raised rim.
  const double cx[3] = {2100.0, 5600.0, 6900.0}, cy[3] = {3000.0, 1800.0, 6200.0};
  const double cr[3] = {700.0, 380.0, 1200.0};
  for (int k = 0; k < 3; ++k) {
    const double d = std::hypot(x - cx[k], y - cy[k]) / cr[k];
    if (d < 1.0) h += -0.2 * cr[k] * (1.0 - d * d) + 0.04 * cr[k] * std::pow(d, 6.0);
    if (d >= 1.0 && d < 2.0) h += 0.04 * cr[k] * std::exp(-6.0 * (d - 1.0));
  }
  return static_cast<float>(h);
}

fs::path input() {
  static const fs::path p = [] {
    GDALAllRegister();
    const fs::path path = benchDir() / "input_8192.tif";
    if (fs::exists(path)) return path;
    core::writeFileAtomically(
        path,
        [](const fs::path& tmp) {
          char tiled[] = "TILED=YES", bx[] = "BLOCKXSIZE=256", by[] = "BLOCKYSIZE=256";
          char* opts[] = {tiled, bx, by, nullptr};
          GDALDatasetH ds = GDALCreate(GDALGetDriverByName("GTiff"), tmp.c_str(), kSize, kSize, 1,
                                       GDT_Float32, opts);
          if (ds == nullptr) throw std::runtime_error("cannot create " + tmp.string());
          double gt[6] = {-4096.0, 1.0, 0.0, -121500.0, 0.0, -1.0};
          GDALSetGeoTransform(ds, gt);
          OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
          OSRSetFromUserInput(srs, "+proj=eqc +lat_ts=0 +lon_0=354.5 +R=3396190 +units=m +no_defs");
          GDALSetSpatialRef(ds, srs);
          OSRDestroySpatialReference(srs);
          std::vector<float> band(static_cast<std::size_t>(kSize) * 256);
          for (int r0 = 0; r0 < kSize; r0 += 256) {
            for (int r = 0; r < 256; ++r) {
              for (int c = 0; c < kSize; ++c) {
                band[static_cast<std::size_t>(r) * kSize + static_cast<std::size_t>(c)] =
                    height(r0 + r, c);
              }
            }
            if (GDALRasterIO(GDALGetRasterBand(ds, 1), GF_Write, 0, r0, kSize, 256, band.data(),
                             kSize, 256, GDT_Float32, 0, 0) != CE_None) {
              throw std::runtime_error("cannot write " + tmp.string());
            }
          }
          GDALClose(ds);
        },
        "import_bench input()");
    return path;
  }();
  return p;
}

// Arg: the deflate level, or −1 for the ZFP codec (reversible).
void ImportRegolith(benchmark::State& state) {
  const fs::path in = input();
  const fs::path out = benchDir() / "out.h5";
  for (auto _ : state) {
    store::ImportOptions o;
    if (state.range(0) < 0) {
      o.codec = store::Codec::Zfp;
    } else {
      o.deflate = static_cast<int>(state.range(0));
    }
    o.threads = 2;
    const store::ImportReport rep = store::importRaster(in, out, o);
    state.counters["levels"] = static_cast<double>(rep.info.levels);
  }
  state.counters["MB"] = static_cast<double>(fs::file_size(out)) / 1e6;
  if (std::getenv("REGOLITH_BENCH_KEEP") == nullptr) fs::remove(out);
}

void ImportGdalCog(benchmark::State& state) {
  const fs::path in = input();
  const fs::path out = benchDir() / "out_cog.tif";
  for (auto _ : state) {
    GDALDatasetH src = GDALOpen(in.c_str(), GA_ReadOnly);
    char a0[] = "-of", a1[] = "COG", a2[] = "-co", a3[] = "COMPRESS=DEFLATE", a4[] = "-co",
         a5[] = "PREDICTOR=YES", a6[] = "-co", a7[] = "NUM_THREADS=2";
    char* argv[] = {a0, a1, a2, a3, a4, a5, a6, a7, nullptr};
    GDALTranslateOptions* opts = GDALTranslateOptionsNew(argv, nullptr);
    int usage = 0;
    GDALDatasetH dst = GDALTranslate(out.c_str(), src, opts, &usage);
    GDALTranslateOptionsFree(opts);
    if (dst == nullptr) {
      state.SkipWithError("GDALTranslate failed");
    } else {
      GDALClose(dst);
    }
    GDALClose(src);
  }
  state.counters["MB"] = static_cast<double>(fs::file_size(out)) / 1e6;
  if (std::getenv("REGOLITH_BENCH_KEEP") == nullptr) fs::remove(out);
}

}  // namespace

BENCHMARK(ImportRegolith)
    ->Name("import/regolith")
    ->Arg(6)
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();
BENCHMARK(ImportRegolith)
    ->Name("import/regolith_zfp")
    ->Arg(-1)
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();
BENCHMARK(ImportGdalCog)
    ->Name("import/gdal_cog")
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();

BENCHMARK_MAIN();
