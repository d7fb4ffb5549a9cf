// Store and pager speed, against the alternatives a user would reach for (issue: Store).
//
//   store/rover/paged_heights, paged_surfaces   6 wheels at 1 kHz along a 1 km path over a
//       4096² float DEM (64 MiB) paged through an 8 MiB cache (8× smaller), starting cold:
//       wheel queries per second with misses included, patch loads, bytes read, and bytes
//       read over the bytes of the unique patches the wheels touched; one height() or
//       surface() call per wheel, or (…_batch6) one heights() or surfaces() batch of the six
//       wheels per step, as rover::traverse() queries
//   store/rover/survey/budget_patches:N   a lawnmower survey over 4 × 4 patches (stripes 32 m
//       apart, alternately east and west, six wheels every 0.5 m, one heights() batch per
//       step) through a cache of N patches: what the budget buys when a traverse comes back
//   store/rover/gdal_rasterio   the same wheel points through GDAL RasterIO (2×2 window
//       per query, bilinear in code) on the same data as a 256×256-tiled GeoTIFF, with
//       GDAL's block cache set to the same 8 MiB
//   store/resident/{paged,inmemory}/{rover,random}[_batch]   queries on resident patches
//       against the same samples held in one array, one height() call per point or through
//       heights() in batches of 4096; store/resident/patch_table/random is the floor: the same
//       reads through a bare table of the resident patches
//   store/patch/{cold_load,raw_hyperslab}   one 256×256 patch through the pager with an
//       empty cache, against a bare H5Dread of the same window
//   store/coarse/{pyramid,strided}   a 256×256 window at 1/8 resolution: read from pyramid
//       level 3, or from level 0 with an HDF5 hyperslab stride of 8
//
// The data are written once into $TMPDIR/regolith-store-bench (about 150 MB).
#include <regolith/store/Pager.hpp>
#include <regolith/store/Store.hpp>

#include <benchmark/benchmark.h>
#include <gdal.h>
#include <hdf5.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <numbers>
#include <random>
#include <span>
#include <string>
#include <unordered_set>
#include <utility>
#include <vector>

namespace {

using namespace regolith;
using namespace regolith::store;
using namespace regolith::topo;
namespace fs = std::filesystem;

constexpr std::size_t kSize = 4096;  // samples per side, 1 m spacing
constexpr std::size_t kPatch = 256;
constexpr std::size_t kBudget = std::size_t{8} << 20;  // 8 MiB: the grid is 8× larger
// What one full patch takes of a cache's budget: its samples and the cache's bookkeeping.
constexpr std::size_t kPatchBytes = kPatch * kPatch * sizeof(float) + 384;
constexpr double kOrigin = 0.0;  // sample (0,0) at x = 0, y = 0

float terrain(std::size_t r, std::size_t c) {
  const double x = static_cast<double>(c), y = -static_cast<double>(r);
  return static_cast<float>(40.0 * std::sin(x / 310.0) * std::cos(y / 270.0) +
                            6.0 * std::sin((x + 2.0 * y) / 53.0) +
                            0.8 * std::sin((3.0 * x - y) / 7.1));
}

struct Data {
  fs::path dir, store, tiff;
  std::shared_ptr<InMemorySamples> samples;
  GridInfo info;
};

const Data& data() {
  static const Data d = [] {
    Data x;
    x.dir = fs::temp_directory_path() / "regolith-store-bench";
    fs::create_directories(x.dir);
    x.store = x.dir / "dem.h5";
    x.tiff = x.dir / "dem.tif";
    x.samples = InMemorySamples::fromFunction(kSize, kSize, terrain);
    x.info.name = "dem";
    x.info.kind = GridKind::Dem;
    x.info.rows = x.info.cols = kSize;
    x.info.x0 = kOrigin;
    x.info.y0 = kOrigin;
    x.info.placement.originLatDeg = -2.05;
    x.info.placement.originLonDeg = -5.5;
    if (!fs::exists(x.store)) {
      std::fprintf(stderr, "store_bench: writing %s\n", x.store.c_str());
      const std::vector<GridSource> grids{{x.info, x.samples}};
      WriteOptions o;
      o.patchRows = o.patchCols = kPatch;
      writeStore(x.store, grids, o);
    }
    if (!fs::exists(x.tiff)) {
      std::fprintf(stderr, "store_bench: writing %s\n", x.tiff.c_str());
      GDALAllRegister();
      const char* opts[] = {"TILED=YES", "BLOCKXSIZE=256", "BLOCKYSIZE=256", nullptr};
      GDALDatasetH ds = GDALCreate(GDALGetDriverByName("GTiff"), x.tiff.c_str(), kSize, kSize, 1,
                                   GDT_Float32, const_cast<char**>(opts));
      const double gt[6] = {-0.5, 1.0, 0.0, 0.5, 0.0, -1.0};
      GDALSetGeoTransform(ds, const_cast<double*>(gt));
      if (GDALRasterIO(GDALGetRasterBand(ds, 1), GF_Write, 0, 0, kSize, kSize,
                       const_cast<float*>(x.samples->data().data()), kSize, kSize, GDT_Float32, 0,
                       0) != CE_None) {
        std::abort();
      }
      GDALClose(ds);
    }
    return x;
  }();
  return d;
}

// Six wheel contact points per 1 ms step, the rover driving 1 km at 1 m/s along a gentle
// S-curve: wheels at ±0.9 m across and −1, 0, +1 m along the heading.
struct Wheels {
  std::vector<double> xs, ys;
};
const Wheels& wheels() {
  static const Wheels w = [] {
    Wheels x;
    const std::size_t steps = 1000000;  // 1 km in 1 mm steps
    x.xs.reserve(6 * steps);
    x.ys.reserve(6 * steps);
    for (std::size_t i = 0; i < steps; ++i) {
      const double s = 1e-3 * static_cast<double>(i);
      const double cx = 600.0 + 0.7 * s, cy = -(600.0 + 0.7 * s + 80.0 * std::sin(s / 120.0));
      const double dx = 0.7, dy = -(0.7 + 80.0 / 120.0 * std::cos(s / 120.0));
      const double n = std::hypot(dx, dy), hx = dx / n, hy = dy / n;
      for (double along : {-1.0, 0.0, 1.0}) {
        for (double across : {-0.9, 0.9}) {
          x.xs.push_back(cx + along * hx - across * hy);
          x.ys.push_back(cy + along * hy + across * hx);
        }
      }
    }
    return x;
  }();
  return w;
}

// A survey (lawnmower) traverse over 4 × 4 patches (x and -y from 520 to 1528 m): stripes
// 32 m apart, driven alternately east and west, the six wheels every 0.5 m. Unlike the 1 km
// path above, which never comes back to a patch it left, a stripe re-crosses the patches of
// the one before, so the budget decides how many patches are loaded again: about 16 when a
// row of patches (4, plus the next row at its edge) fits, and about 4 per stripe when not.
const Wheels& surveyWheels() {
  static const Wheels w = [] {
    Wheels x;
    constexpr double lo = 520.0, hi = 1528.0, gap = 32.0, step = 0.5;
    bool east = true;
    for (double across = lo; across <= hi; across += gap, east = !east) {
      for (double along = 0.0; along <= hi - lo; along += step) {
        const double cx = east ? lo + along : hi - along, cy = -across;
        const double hx = east ? 1.0 : -1.0;  // heading along x; across the heading is y
        for (double a : {-1.0, 0.0, 1.0}) {
          for (double c : {-0.9, 0.9}) {
            x.xs.push_back(cx + a * hx);
            x.ys.push_back(cy + c * hx);
          }
        }
      }
    }
    return x;
  }();
  return w;
}

std::size_t uniquePatches(const Wheels& w) {
  std::unordered_set<std::uint64_t> seen;
  for (std::size_t i = 0; i < w.xs.size(); ++i) {
    // bilinear cells: the 2×2 stencil's samples
    const auto c = static_cast<std::uint64_t>(w.xs[i]), r = static_cast<std::uint64_t>(-w.ys[i]);
    for (std::uint64_t dr : {0u, 1u}) {
      for (std::uint64_t dc : {0u, 1u})
        seen.insert(((r + dr) / kPatch) << 32U | ((c + dc) / kPatch));
    }
  }
  return seen.size();
}

enum class RoverQuery { Heights, Surfaces, HeightsBatch, SurfacesBatch };

void roverOnPath(benchmark::State& state, RoverQuery query, std::size_t budget, const Wheels& w) {
  const Data& d = data();
  CacheStats last{};
  ReadCounters reads{};
  for (auto _ : state) {
    state.PauseTiming();
    auto store = std::make_shared<const Store>(Store::open(d.store));
    auto cache = std::make_shared<PatchCache>(budget, CachePolicy::Lru);
    const Pager pager(store, cache);
    const TopoDem dem = pager.dem("dem");
    state.ResumeTiming();
    double sink = 0.0;
    if (query == RoverQuery::Heights) {
      for (std::size_t i = 0; i < w.xs.size(); ++i) sink += dem.height(w.xs[i], w.ys[i]).height;
    } else if (query == RoverQuery::Surfaces) {
      for (std::size_t i = 0; i < w.xs.size(); ++i) {
        sink += dem.surface(w.xs[i], w.ys[i]).normal.z;
      }
    } else {
      constexpr std::size_t k = 6;  // the wheels of one step
      std::array<double, k> hs{};
      std::array<glm::dvec3, k> ns{};
      std::array<QueryStatus, k> st{}, nst{};
      const std::span<const double> xs(w.xs), ys(w.ys);
      for (std::size_t i = 0; i + k <= w.xs.size(); i += k) {
        if (query == RoverQuery::HeightsBatch) {
          dem.heights(xs.subspan(i, k), ys.subspan(i, k), hs, st);
          sink += hs[0];
        } else {
          dem.surfaces(xs.subspan(i, k), ys.subspan(i, k), hs, ns, st, Interpolation::Bilinear,
                       NormalFrame::Grid, nst);
          sink += ns[0].z;
        }
      }
    }
    benchmark::DoNotOptimize(sink);
    last = cache->stats();
    reads = store->counters();
  }
  const double unique = static_cast<double>(uniquePatches(w));
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(w.xs.size()));
  state.counters["budget_MiB"] = static_cast<double>(budget) / (1024.0 * 1024.0);
  state.counters["budget_patches"] = static_cast<double>(budget) / static_cast<double>(kPatchBytes);
  state.counters["patch_loads"] = static_cast<double>(last.loads);
  state.counters["evictions"] = static_cast<double>(last.evictions);
  state.counters["bytes_read_MB"] = static_cast<double>(reads.bytesRead) / 1e6;
  state.counters["unique_patches"] = unique;
  state.counters["bytes_read_over_unique"] =
      static_cast<double>(reads.bytesRead) / (unique * kPatch * kPatch * sizeof(float));
}

void roverPaged(benchmark::State& state, RoverQuery query, std::size_t budget) {
  roverOnPath(state, query, budget, wheels());
}

void roverSurvey(benchmark::State& state, std::size_t budget) {
  roverOnPath(state, RoverQuery::HeightsBatch, budget, surveyWheels());
}

void roverGdal(benchmark::State& state) {
  const Data& d = data();
  const Wheels& w = wheels();
  GDALAllRegister();
  for (auto _ : state) {
    state.PauseTiming();
    GDALSetCacheMax64(static_cast<GIntBig>(kBudget));
    GDALDatasetH ds = GDALOpen(d.tiff.c_str(), GA_ReadOnly);
    GDALRasterBandH band = GDALGetRasterBand(ds, 1);
    state.ResumeTiming();
    double sink = 0.0;
    float s[4];
    for (std::size_t i = 0; i < w.xs.size(); ++i) {
      const double u = w.xs[i], v = -w.ys[i];
      const auto c = static_cast<int>(u), r = static_cast<int>(v);
      if (GDALRasterIO(band, GF_Read, c, r, 2, 2, s, 2, 2, GDT_Float32, 0, 0) != CE_None) {
        state.SkipWithError("RasterIO failed");
        break;
      }
      const double tu = u - c, tv = v - r;
      const double a = s[0], b = s[1], c2 = s[2], d2 = s[3];
      const double top = a + tu * (b - a), bottom = c2 + tu * (d2 - c2);
      sink += top + tv * (bottom - top);
    }
    benchmark::DoNotOptimize(sink);
    state.PauseTiming();
    GDALClose(ds);
    state.ResumeTiming();
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(w.xs.size()));
}

struct Resident {
  std::shared_ptr<const Store> store;
  std::shared_ptr<PatchCache> cache;
  std::unique_ptr<Pager> pager;
  std::unique_ptr<TopoDem> paged, mem;
  std::vector<double> rx, ry, qx, qy;  // rover points (1 cm steps), random points
};

Resident& resident() {
  static Resident r = [] {
    Resident x;
    const Data& d = data();
    x.store = std::make_shared<const Store>(Store::open(d.store));
    x.cache = std::make_shared<PatchCache>(std::size_t{128} << 20, CachePolicy::Lru);
    x.pager = std::make_unique<Pager>(x.store, x.cache);
    x.paged = std::make_unique<TopoDem>(x.pager->dem("dem"));
    x.mem = std::make_unique<TopoDem>(topoGridOf(d.info), placementOf(d.info), d.samples);
    for (std::size_t i = 0; i < (1U << 16U); ++i) {
      const double s = 0.01 * static_cast<double>(i);
      x.rx.push_back(1000.0 + s);
      x.ry.push_back(-(1000.0 + 30.0 * std::sin(s / 50.0)));
    }
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> u(0.0, kSize - 1.0);
    for (std::size_t i = 0; i < (1U << 18U); ++i) {
      x.qx.push_back(u(rng));
      x.qy.push_back(-u(rng));
    }
    std::vector<float> all(kSize * kSize);  // make every patch resident
    x.pager->source("dem")->readWindow(0, 0, kSize, kSize, all);
    return x;
  }();
  return r;
}

void residentQueries(benchmark::State& state, bool paged, bool rover) {
  Resident& r = resident();
  const TopoDem& dem = paged ? *r.paged : *r.mem;
  const auto& xs = rover ? r.rx : r.qx;
  const auto& ys = rover ? r.ry : r.qy;
  std::size_t i = 0;
  double sink = 0.0;
  for (auto _ : state) {
    for (int k = 0; k < 4096; ++k) {
      sink += dem.height(xs[i], ys[i]).height;
      if (++i == xs.size()) i = 0;
    }
  }
  benchmark::DoNotOptimize(sink);
  state.SetItemsProcessed(state.iterations() * 4096);
  state.counters["per_query_ns"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * 4096.0,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

// The same points through the batch API, 4096 per call.
void residentBatch(benchmark::State& state, bool paged, bool rover) {
  Resident& r = resident();
  const TopoDem& dem = paged ? *r.paged : *r.mem;
  const auto& xs = rover ? r.rx : r.qx;
  const auto& ys = rover ? r.ry : r.qy;
  constexpr std::size_t kBatch = 4096;
  std::vector<double> out(kBatch);
  std::size_t i = 0;
  double sink = 0.0;
  for (auto _ : state) {
    dem.heights(std::span(xs).subspan(i, kBatch), std::span(ys).subspan(i, kBatch), out, {});
    sink += out[kBatch - 1];
    i += kBatch;
    if (i + kBatch > xs.size()) i = 0;
  }
  benchmark::DoNotOptimize(sink);
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(kBatch));
  state.counters["per_query_ns"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * kBatch,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

// The floor of any paged design: the same random bilinear reads through a plain table of
// the cache's resident patches, with no cache lookup or bookkeeping at all.
void residentPatchTable(benchmark::State& state) {
  Resident& r = resident();
  constexpr std::size_t kPatches = kSize / kPatch;
  std::vector<std::shared_ptr<const Patch>> table(kPatches * kPatches);
  for (std::size_t i = 0; i < table.size(); ++i) {
    table[i] =
        r.pager->patch(r.pager->keyOf("dem", 0, (i / kPatches) * kPatch, (i % kPatches) * kPatch));
  }
  std::size_t i = 0;
  double sink = 0.0;
  for (auto _ : state) {
    for (int k = 0; k < 4096; ++k) {
      const double u = r.qx[i], v = -r.qy[i];
      const auto c = static_cast<std::size_t>(u), row = static_cast<std::size_t>(v);
      const Patch& p = *table[(row / kPatch) * kPatches + c / kPatch];
      const std::size_t pr = row % kPatch, pc = c % kPatch;
      const float* s = p.samples.data() + pr * p.cols + pc;
      // Cells on a patch edge read their neighbours from the same patch (the floor only).
      const std::size_t dr = pr + 1 < p.rows ? p.cols : 0, dc = pc + 1 < p.cols ? 1 : 0;
      const double tu = u - static_cast<double>(c), tv = v - static_cast<double>(row);
      const double a = s[0], b = s[dc], cc = s[dr], d = s[dr + dc];
      const double top = a + tu * (b - a), bottom = cc + tu * (d - cc);
      sink += top + tv * (bottom - top);
      if (++i == r.qx.size()) i = 0;
    }
  }
  benchmark::DoNotOptimize(sink);
  state.SetItemsProcessed(state.iterations() * 4096);
  state.counters["per_query_ns"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * 4096.0,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void coldPatch(benchmark::State& state) {
  const Data& d = data();
  auto store = std::make_shared<const Store>(Store::open(d.store));
  auto cache = std::make_shared<PatchCache>(kBudget);
  const Pager pager(store, cache);
  std::uint32_t k = 0;
  for (auto _ : state) {
    cache->clear();
    const PatchKey key = pager.keyOf("dem", 0, (k % 16) * kPatch, ((k / 16) % 16) * kPatch);
    benchmark::DoNotOptimize(pager.patch(key));
    ++k;
  }
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(kPatch * kPatch * 4));
}

void rawHyperslab(benchmark::State& state) {
  const Data& d = data();
  const hid_t file = H5Fopen(d.store.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  const hid_t dset = H5Dopen2(file, "/grids/dem/level0", H5P_DEFAULT);
  const hid_t fspace = H5Dget_space(dset);
  const hsize_t count[2] = {kPatch, kPatch};
  const hid_t mspace = H5Screate_simple(2, count, nullptr);
  std::vector<float> buf(kPatch * kPatch);
  std::uint32_t k = 0;
  for (auto _ : state) {
    const hsize_t start[2] = {(k % 16) * kPatch, ((k / 16) % 16) * kPatch};
    H5Sselect_hyperslab(fspace, H5S_SELECT_SET, start, nullptr, count, nullptr);
    if (H5Dread(dset, H5T_NATIVE_FLOAT, mspace, fspace, H5P_DEFAULT, buf.data()) < 0) {
      state.SkipWithError("H5Dread failed (is the dataset path /grids/dem/level0?)");
      break;
    }
    benchmark::DoNotOptimize(buf.data());
    ++k;
  }
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(kPatch * kPatch * 4));
  H5Sclose(mspace);
  H5Sclose(fspace);
  H5Dclose(dset);
  H5Fclose(file);
}

void coarse(benchmark::State& state, bool pyramid) {
  const Data& d = data();
  const Store store = Store::open(d.store);
  std::vector<float> out(256 * 256);
  for (auto _ : state) {
    if (pyramid) {
      store.readWindow("dem", 3, 0, 0, 256, 256, out);
    } else {
      store.readWindow("dem", 0, 0, 0, 256, 256, out, 8);
    }
    benchmark::DoNotOptimize(out.data());
  }
  // Accuracy: each coarse sample against the mean of the 8 × 8 level-0 samples it stands
  // for (its footprint), summed in double from the in-memory samples (brute force).
  double maxErr = 0.0, sum2 = 0.0;
  const std::span<const float> fine = d.samples->data();
  for (std::size_t r = 0; r < 256; ++r) {
    for (std::size_t c = 0; c < 256; ++c) {
      double mean = 0.0;
      for (std::size_t i = 0; i < 8; ++i) {
        for (std::size_t j = 0; j < 8; ++j) {
          mean += static_cast<double>(fine[(8 * r + i) * kSize + 8 * c + j]);
        }
      }
      mean /= 64.0;
      const double e = std::abs(static_cast<double>(out[r * 256 + c]) - mean);
      maxErr = std::max(maxErr, e);
      sum2 += e * e;
    }
  }
  state.counters["error_m_max"] = maxErr;
  state.counters["error_m_rms"] = std::sqrt(sum2 / (256.0 * 256.0));
}

// ---- codecs: size against read time --------------------------------------------------------

constexpr std::size_t kCodecSize = 2048;  // the top-left 2048² of the same terrain

/// The store of the terrain's top-left kCodecSize² written with `codec` at deflate `level`
/// (written once into the bench folder).
fs::path codecStore(Codec codec, int level) {
  const Data& d = data();
  const fs::path path =
      d.dir / (std::string("codec_") + codecName(codec) + "_" + std::to_string(level) + ".h5");
  if (!fs::exists(path)) {
    std::fprintf(stderr, "store_bench: writing %s\n", path.c_str());
    GridInfo info = d.info;
    info.rows = info.cols = kCodecSize;
    const auto samples = InMemorySamples::fromFunction(kCodecSize, kCodecSize, terrain);
    const std::vector<GridSource> grids{{info, samples}};
    WriteOptions o;
    o.patchRows = o.patchCols = kPatch;
    o.levels = 1;
    o.codec = codec;
    o.deflate = level;
    writeStore(path, grids, o);
  }
  return path;
}

/// Arg: the deflate level (0: uncompressed), or −1 for ZFP (reversible). Each iteration
/// opens the store and reads every level-0 patch (the OS's page cache is warm: this is the
/// decoding cost, not the disk's).
void codecRead(benchmark::State& state) {
  const Codec codec = state.range(0) < 0 ? Codec::Zfp : Codec::Deflate;
  const int level = state.range(0) < 0 ? 0 : static_cast<int>(state.range(0));
  fs::path path;
  try {
    path = codecStore(codec, level);
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());  // e.g. no HDF5 ZFP filter plugin
    return;
  }
  std::vector<float> out(kPatch * kPatch);
  for (auto _ : state) {
    const Store store = Store::open(path);
    for (std::size_t r = 0; r < kCodecSize; r += kPatch) {
      for (std::size_t c = 0; c < kCodecSize; c += kPatch) {
        store.readWindow("dem", 0, r, c, kPatch, kPatch, out);
        benchmark::DoNotOptimize(out.data());
      }
    }
  }
  const double rawMB = static_cast<double>(kCodecSize * kCodecSize * sizeof(float)) / 1e6;
  state.counters["MB"] = static_cast<double>(fs::file_size(path)) / 1e6;
  state.counters["ratio"] = rawMB / (static_cast<double>(fs::file_size(path)) / 1e6);
  state.counters["deflate"] = level;
  state.SetBytesProcessed(state.iterations() *
                          static_cast<std::int64_t>(kCodecSize * kCodecSize * sizeof(float)));
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::RegisterBenchmark("store/rover/paged_heights", roverPaged, RoverQuery::Heights,
                               kBudget)
      ->Unit(benchmark::kMillisecond)
      ->Iterations(3);
  benchmark::RegisterBenchmark("store/rover/paged_surfaces", roverPaged, RoverQuery::Surfaces,
                               kBudget)
      ->Unit(benchmark::kMillisecond)
      ->Iterations(3);
  benchmark::RegisterBenchmark("store/rover/paged_heights_batch6", roverPaged,
                               RoverQuery::HeightsBatch, kBudget)
      ->Unit(benchmark::kMillisecond)
      ->Iterations(3);
  benchmark::RegisterBenchmark("store/rover/paged_surfaces_batch6", roverPaged,
                               RoverQuery::SurfacesBatch, kBudget)
      ->Unit(benchmark::kMillisecond)
      ->Iterations(3);
  // A budget of 4 patches (1 MiB, 64× smaller than the grid): fewer than the path touches.
  benchmark::RegisterBenchmark("store/rover/paged_heights_4_patches", roverPaged,
                               RoverQuery::Heights, 4 * kPatchBytes)
      ->Unit(benchmark::kMillisecond)
      ->Iterations(3);
  // The survey traverse against the budget, in patches (docs/accuracy-vs-time.md).
  for (const std::size_t patches : std::array<std::size_t, 7>{1, 2, 3, 4, 6, 8, 16}) {
    benchmark::RegisterBenchmark(
        ("store/rover/survey/budget_patches:" + std::to_string(patches)).c_str(), roverSurvey,
        patches * kPatchBytes)
        ->Unit(benchmark::kMillisecond)
        ->Iterations(10);  // each about 10 ms: 3 left the speeds to the machine's noise
  }
  benchmark::RegisterBenchmark("store/rover/gdal_rasterio", roverGdal)
      ->Unit(benchmark::kMillisecond)
      ->Iterations(1);
  for (bool rover : {true, false}) {
    const char* where = rover ? "rover" : "random";
    benchmark::RegisterBenchmark((std::string("store/resident/paged/") + where).c_str(),
                                 residentQueries, true, rover);
    benchmark::RegisterBenchmark((std::string("store/resident/inmemory/") + where).c_str(),
                                 residentQueries, false, rover);
    benchmark::RegisterBenchmark((std::string("store/resident/paged/") + where + "_batch").c_str(),
                                 residentBatch, true, rover);
    benchmark::RegisterBenchmark(
        (std::string("store/resident/inmemory/") + where + "_batch").c_str(), residentBatch, false,
        rover);
  }
  benchmark::RegisterBenchmark("store/resident/patch_table/random", residentPatchTable);
  benchmark::RegisterBenchmark("store/patch/cold_load", coldPatch)->Unit(benchmark::kMicrosecond);
  benchmark::RegisterBenchmark("store/patch/raw_hyperslab", rawHyperslab)
      ->Unit(benchmark::kMicrosecond);
  benchmark::RegisterBenchmark("store/coarse/pyramid", coarse, true)->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("store/coarse/strided", coarse, false)
      ->Unit(benchmark::kMillisecond);
  for (const auto& [name, arg] :
       {std::pair{"none", 0}, std::pair{"deflate1", 1}, std::pair{"deflate6", 6},
        std::pair{"deflate9", 9}, std::pair{"zfp", -1}}) {
    benchmark::RegisterBenchmark((std::string("store/codec/") + name).c_str(), codecRead)
        ->Arg(arg)
        ->Unit(benchmark::kMillisecond);
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
