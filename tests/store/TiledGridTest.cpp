// Tiled grids (docs/store-format.md, "Tiled grids"): a level 0 made of internal tile datasets
// or of other store files behaves exactly like one grid. Windows and pager patches that
// straddle 2 or 4 tiles are assembled correctly, with tile sizes (100×90, 37×113, ...) that do
// not divide the 64×64 patch; gaps read NaN; coarse levels are 2×2 means across tile borders;
// bad tilings are refused with errors naming the file and the field.
#include <regolith/core/Error.hpp>
#include <regolith/store/Pager.hpp>
#include <regolith/store/Store.hpp>
#include <regolith/topo/TopoDem.hpp>

#include <gtest/gtest.h>
#include <hdf5.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

using namespace regolith;
using namespace regolith::store;
using namespace regolith::topo;
namespace fs = std::filesystem;

namespace {

constexpr float kNan = std::numeric_limits<float>::quiet_NaN();
constexpr std::size_t kPatch = 64;
constexpr Interpolation kAll[] = {Interpolation::Nearest, Interpolation::Bilinear,
                                  Interpolation::Bicubic};

fs::path scratchDir() {
  struct Dir {
    fs::path path = fs::temp_directory_path() / ("regolith-tiles-" + std::to_string(::getpid()));
    Dir() { fs::create_directories(path); }
    Dir(const Dir&) = delete;
    Dir& operator=(const Dir&) = delete;
    Dir(Dir&&) = delete;
    Dir& operator=(Dir&&) = delete;
    ~Dir() {
      std::error_code ec;
      fs::remove_all(path, ec);
    }
  };
  static const Dir dir;
  return dir.path;
}

/// Mosaic content: smooth terrain with scattered missing samples (some NaN, some equal to
/// the nodata value), so missing samples also sit on tile borders.
float terrain(std::size_t r, std::size_t c) {
  if ((r * 13 + c * 7) % 53 == 0) return kNan;
  if ((r * 5 + c * 11) % 61 == 0) return -32768.0f;
  const auto x = static_cast<double>(c), y = static_cast<double>(r);
  return static_cast<float>(30.0 * std::sin(x / 17.0) + 20.0 * std::cos(y / 11.0) + 0.01 * x * y);
}

GridInfo mosaicInfo(const std::string& name, std::size_t rows, std::size_t cols) {
  GridInfo g;
  g.name = name;
  g.kind = GridKind::Dem;
  g.rows = rows;
  g.cols = cols;
  g.x0 = -120.0;
  g.y0 = 80.0;
  g.spacingX = 1.0;
  g.spacingY = 1.5;
  g.nodata = -32768.0f;
  g.equatorialRadius = 3396190.0;
  g.polarRadius = 3376200.0;
  g.placement.kind = PlacementInfo::Kind::LocalTangentPlane;
  g.placement.originLatDeg = -2.05;
  g.placement.originLonDeg = -5.5;
  return g;
}

struct TileSpec {
  std::size_t row0, col0, rows, cols;
};

std::shared_ptr<InMemorySamples> tileSamples(const TileSpec& t) {
  return InMemorySamples::fromFunction(t.rows, t.cols, [t](std::size_t r, std::size_t c) {
    return terrain(t.row0 + r, t.col0 + c);
  });
}

/// The full mosaic as heights (NaN where missing or where no tile lies).
std::vector<float> reference(std::size_t rows, std::size_t cols,
                             const std::vector<TileSpec>& tiles) {
  std::vector<float> ref(rows * cols, kNan);
  for (const TileSpec& t : tiles) {
    for (std::size_t r = t.row0; r < t.row0 + t.rows; ++r) {
      for (std::size_t c = t.col0; c < t.col0 + t.cols; ++c) {
        const float v = terrain(r, c);
        ref[r * cols + c] = v == -32768.0f ? kNan : v;
      }
    }
  }
  return ref;
}

/// A written tiled store, its reference mosaic and its tile layout.
struct Mosaic {
  fs::path path;
  std::string grid;
  std::size_t rows = 0, cols = 0;
  std::vector<TileSpec> tiles;
  std::vector<float> ref;
  std::vector<std::size_t> cornerRows, cornerCols;  // tile borders, for probing
};

WriteOptions options() {
  WriteOptions o;
  o.patchRows = o.patchCols = kPatch;
  return o;
}

// Six internal tiles on row borders 100, 137 and column border 90 of a 237×203 mosaic, one of
// them (rows 137–236, cols 90–202) left out: a gap.
const Mosaic& internalMosaic() {
  static const Mosaic m = [] {
    Mosaic x;
    x.path = scratchDir() / "internal.h5";
    x.grid = "mosaic";
    x.rows = 237;
    x.cols = 203;
    x.tiles = {{0, 0, 100, 90},
               {0, 90, 100, 113},
               {100, 0, 37, 90},
               {100, 90, 37, 113},
               {137, 0, 100, 90}};
    x.ref = reference(x.rows, x.cols, x.tiles);
    x.cornerRows = {0, 100, 137, 236};
    x.cornerCols = {0, 90, 202};
    GridSource src{mosaicInfo(x.grid, x.rows, x.cols), nullptr};
    for (const TileSpec& t : x.tiles) src.tiles.push_back({t.row0, t.col0, tileSamples(t), {}, {}});
    writeStore(x.path, std::span<const GridSource>(&src, 1), options());
    return x;
  }();
  return m;
}

// Four SRTM-like tile files (each a plain single-grid store with its own 50×50 patches), and
// a store referencing them (three by relative path, one by absolute path) as a 250×210
// mosaic whose last 13 rows and 7 columns no tile covers.
const Mosaic& externalMosaic() {
  static const Mosaic m = [] {
    Mosaic x;
    x.path = scratchDir() / "external.h5";
    x.grid = "srtm";
    x.rows = 250;
    x.cols = 210;
    x.tiles = {{0, 0, 100, 90}, {0, 90, 100, 113}, {100, 0, 137, 90}, {100, 90, 137, 113}};
    x.ref = reference(x.rows, x.cols, x.tiles);
    x.cornerRows = {0, 100, 236, 237, 249};
    x.cornerCols = {0, 90, 202, 203, 209};
    GridSource src{mosaicInfo(x.grid, x.rows, x.cols), nullptr};
    for (std::size_t i = 0; i < x.tiles.size(); ++i) {
      const TileSpec& t = x.tiles[i];
      const std::string file = "srtm_" + std::to_string(i) + ".h5";
      GridInfo info = mosaicInfo("tile", t.rows, t.cols);
      const GridSource tile{info, tileSamples(t)};
      WriteOptions o;
      o.patchRows = o.patchCols = 50;
      writeStore(scratchDir() / file, std::span<const GridSource>(&tile, 1), o);
      const fs::path ref = i == 3 ? scratchDir() / file : fs::path(file);
      src.tiles.push_back({t.row0, t.col0, nullptr, ref, "tile"});
    }
    writeStore(x.path, std::span<const GridSource>(&src, 1), options());
    return x;
  }();
  return m;
}

bool sameFloat(float a, float b) {
  return (std::isnan(a) && std::isnan(b)) || std::memcmp(&a, &b, sizeof a) == 0;
}

class TiledGrid : public ::testing::TestWithParam<bool> {
 protected:
  [[nodiscard]] static const Mosaic& mosaic() {
    return GetParam() ? externalMosaic() : internalMosaic();
  }
};

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

TEST_P(TiledGrid, IsTiledAndDescribesTheWholeMosaic) {
  const Mosaic& m = mosaic();
  const Store s = Store::open(m.path);
  EXPECT_TRUE(s.tiled(m.grid));
  EXPECT_EQ(s.grid(m.grid).rows, m.rows);
  EXPECT_EQ(s.grid(m.grid).cols, m.cols);
  EXPECT_EQ(s.grid(m.grid).levels, 3u);  // 237 or 250 rows: levels until one fits 64×64
}

TEST_P(TiledGrid, WindowsAtTileCornersEqualTheUntiledData) {
  const Mosaic& m = mosaic();
  const Store s = Store::open(m.path);
  std::size_t windows = 0;
  for (std::size_t cr : m.cornerRows) {
    for (std::size_t cc : m.cornerCols) {
      for (const auto& [h, w] : {std::pair{7, 9}, std::pair{1, 1}, std::pair{64, 64},
                                 std::pair{3, 130}, std::pair{120, 2}}) {
        const auto nh = static_cast<std::size_t>(h), nw = static_cast<std::size_t>(w);
        const std::size_t r0 = std::min(cr >= nh / 2 ? cr - nh / 2 : 0, m.rows - nh);
        const std::size_t c0 = std::min(cc >= nw / 2 ? cc - nw / 2 : 0, m.cols - nw);
        std::vector<float> got(nh * nw, 1234.0f);
        s.readWindow(m.grid, 0, r0, c0, nh, nw, got);
        for (std::size_t r = 0; r < nh; ++r) {
          for (std::size_t c = 0; c < nw; ++c) {
            ASSERT_TRUE(sameFloat(got[r * nw + c], m.ref[(r0 + r) * m.cols + c0 + c]))
                << "window " << nh << "x" << nw << " at (" << r0 << ", " << c0 << "), sample ("
                << r0 + r << ", " << c0 + c << ")";
          }
        }
        ++windows;
      }
    }
  }
  EXPECT_GT(windows, 50u);
  // The whole mosaic in one window.
  std::vector<float> all(m.rows * m.cols);
  s.readWindow(m.grid, 0, 0, 0, m.rows, m.cols, all);
  for (std::size_t i = 0; i < all.size(); ++i) ASSERT_TRUE(sameFloat(all[i], m.ref[i])) << i;
}

TEST_P(TiledGrid, OneReadPerTileTheWindowMeets) {
  const Mosaic& m = mosaic();
  const Store s = Store::open(m.path);
  std::vector<float> v(4);
  s.readWindow(m.grid, 0, 99, 89, 2, 2, v);  // the corner shared by tiles 0, 1, 2 and 3
  EXPECT_EQ(s.counters().reads, 4u);
  s.readWindow(m.grid, 0, 10, 10, 2, 2, v);  // inside tile 0
  EXPECT_EQ(s.counters().reads, 5u);
}

TEST_P(TiledGrid, PatchesStraddlingTwoAndFourTilesAreAssembledSampleBySample) {
  const Mosaic& m = mosaic();
  auto store = std::make_shared<const Store>(Store::open(m.path));
  const Pager pager(store, std::make_shared<PatchCache>(std::size_t{16} << 20));
  // 64×64 patches: patch (1, 0) holds rows 64–127 (tile border at row 100) of cols 0–63: two
  // tiles; patch (0, 1) holds cols 64–127 (border at col 90): two tiles; patch (1, 1): four.
  // Patch (2, 1) meets three tiles and the gap (internal) or two tiles (external).
  struct Case {
    std::size_t row, col, tilesMet;
  };
  for (const Case& k :
       {Case{64, 0, 2}, Case{0, 64, 2}, Case{64, 64, 4}, Case{128, 64, GetParam() ? 2u : 3u}}) {
    const std::uint64_t before = store->counters().reads;
    const auto patch = pager.patch(pager.keyOf(m.grid, 0, k.row, k.col));
    EXPECT_EQ(store->counters().reads - before, k.tilesMet) << k.row << "," << k.col;
    ASSERT_EQ(patch->rows, kPatch);
    ASSERT_EQ(patch->cols, kPatch);
    for (std::size_t r = 0; r < patch->rows; ++r) {
      for (std::size_t c = 0; c < patch->cols; ++c) {
        ASSERT_TRUE(
            sameFloat(patch->samples[r * patch->cols + c], m.ref[(k.row + r) * m.cols + k.col + c]))
            << "patch at (" << k.row << ", " << k.col << ") sample (" << r << ", " << c << ")";
      }
    }
  }
}

TEST_P(TiledGrid, PagedDemAnswersBitIdenticallyToTheInMemoryMosaic) {
  const Mosaic& m = mosaic();
  auto store = std::make_shared<const Store>(Store::open(m.path));
  const Pager pager(store, std::make_shared<PatchCache>(std::size_t{16} << 20));
  const TopoDem paged = pager.dem(m.grid);
  const GridInfo& info = store->grid(m.grid);
  const TopoDem mem(topoGridOf(info), placementOf(info),
                    std::make_shared<InMemorySamples>(m.rows, m.cols, m.ref));
  const auto check = [&](double px, double py) {
    for (Interpolation k : kAll) {
      for (NormalFrame f : {NormalFrame::BodyFixed, NormalFrame::Grid}) {
        const SurfaceSample a = mem.surface(px, py, k, f);
        const SurfaceSample b = paged.surface(px, py, k, f);
        ASSERT_EQ(a.status, b.status) << px << ", " << py;
        ASSERT_EQ(a.normalStatus, b.normalStatus) << px << ", " << py;
        if (a.valid()) {
          ASSERT_EQ(a.height, b.height) << px << ", " << py;
        }
        // Height and normal validity are apart (docs/queries.md): a height next to a hole
        // may be valid where its normal has no stencil.
        if (a.normalValid()) {
          ASSERT_EQ(a.normal, b.normal) << px << ", " << py;
        }
      }
      const HeightSample ha = mem.height(px, py, k), hb = paged.height(px, py, k);
      ASSERT_EQ(ha.status, hb.status) << px << ", " << py;
      ASSERT_TRUE((std::isnan(ha.height) && std::isnan(hb.height)) || ha.height == hb.height)
          << px << ", " << py;
    }
  };
  // At and around every tile corner, in quarter-sample steps.
  for (std::size_t cr : m.cornerRows) {
    for (std::size_t cc : m.cornerCols) {
      for (int dr = -12; dr <= 12; ++dr) {
        for (int dc = -12; dc <= 12; ++dc) {
          const double col = static_cast<double>(cc) + 0.25 * dc;
          const double row = static_cast<double>(cr) + 0.25 * dr;
          check(info.x0 + col * info.spacingX, info.y0 - row * info.spacingY);
        }
      }
    }
  }
  // Random points over the whole mosaic and a little beyond.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> col(-1.0, static_cast<double>(m.cols));
  std::uniform_real_distribution<double> row(-1.0, static_cast<double>(m.rows));
  for (int i = 0; i < 3000; ++i) {
    check(info.x0 + col(rng) * info.spacingX, info.y0 - row(rng) * info.spacingY);
  }
}

TEST_P(TiledGrid, GapsReadNanAndQueriesThereReturnNodata) {
  const Mosaic& m = mosaic();
  auto store = std::make_shared<const Store>(Store::open(m.path));
  // A point well inside the gap: internal mosaic rows 137–236 × cols 90–202; external: the
  // uncovered strip of rows 237–249.
  const std::size_t gr = GetParam() ? 243 : 180, gc = GetParam() ? 50 : 150;
  std::vector<float> v(9, 0.0f);
  store->readWindow(m.grid, 0, gr - 1, gc - 1, 3, 3, v);
  for (float x : v) EXPECT_TRUE(std::isnan(x));
  const std::uint64_t before = store->counters().reads;
  store->readWindow(m.grid, 0, gr - 1, gc - 1, 3, 3, v);
  EXPECT_EQ(store->counters().reads, before);  // no tile there: nothing read
  const Pager pager(store, std::make_shared<PatchCache>(std::size_t{16} << 20));
  const TopoDem dem = pager.dem(m.grid);
  const GridInfo& info = store->grid(m.grid);
  const double x = info.x0 + static_cast<double>(gc) * info.spacingX + 0.3;
  const double y = info.y0 - static_cast<double>(gr) * info.spacingY - 0.2;
  for (Interpolation k : kAll) {
    const SurfaceSample s = dem.surface(x, y, k);
    EXPECT_EQ(s.status, QueryStatus::Nodata);
    EXPECT_TRUE(std::isnan(s.height));
  }
}

TEST_P(TiledGrid, CoarseLevelsAreTwoByTwoMeansAcrossTileBorders) {
  const Mosaic& m = mosaic();
  const Store s = Store::open(m.path);
  const GridInfo& info = s.grid(m.grid);
  std::vector<float> fine = m.ref;
  std::size_t fr = m.rows, fc = m.cols;
  for (std::size_t k = 1; k < info.levels; ++k) {
    const std::size_t cr = (fr + 1) / 2, cc = (fc + 1) / 2;
    std::vector<float> coarse(cr * cc);
    for (std::size_t r = 0; r < cr; ++r) {
      for (std::size_t c = 0; c < cc; ++c) {
        double sum = 0.0;
        int n = 0;
        for (std::size_t a = 2 * r; a < std::min(2 * r + 2, fr); ++a) {
          for (std::size_t b = 2 * c; b < std::min(2 * c + 2, fc); ++b) {
            const float x = fine[a * fc + b];
            if (!std::isnan(x)) {
              sum += static_cast<double>(x);
              ++n;
            }
          }
        }
        coarse[r * cc + c] = n > 0 ? static_cast<float>(sum / n) : kNan;
      }
    }
    ASSERT_EQ(info.levelRows(k), cr);
    ASSERT_EQ(info.levelCols(k), cc);
    std::vector<float> got(cr * cc);
    s.readWindow(m.grid, k, 0, 0, cr, cc, got);
    for (std::size_t i = 0; i < got.size(); ++i) {
      ASSERT_TRUE(sameFloat(got[i], coarse[i])) << "level " << k << " sample " << i;
    }
    fine = std::move(coarse);
    fr = cr;
    fc = cc;
  }
}

TEST_P(TiledGrid, StridedReadsOfATiledLevelZeroAreRefusedClearly) {
  const Mosaic& m = mosaic();
  const Store s = Store::open(m.path);
  std::vector<float> v(4);
  EXPECT_EQ(errorOf([&] { s.readWindow(m.grid, 0, 0, 0, 2, 2, v, 2); }),
            "store::readWindow(): " + m.path.string() + ": grid '" + m.grid +
                "' level 0 is tiled: stride 2 is not supported there, only 1 (coarse views read a "
                "pyramid level)");
  EXPECT_NO_THROW(s.readWindow(m.grid, 1, 0, 0, 2, 2, v, 2));
}

INSTANTIATE_TEST_SUITE_P(Tiles, TiledGrid, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& p) {
                           return p.param ? std::string("ExternalFiles")
                                          : std::string("InternalDatasets");
                         });

// ---- bad input ----------------------------------------------------------------------------

namespace {

GridSource tiledSource(const std::string& name, std::size_t rows, std::size_t cols,
                       const std::vector<TileSpec>& tiles) {
  GridSource src{mosaicInfo(name, rows, cols), nullptr};
  for (const TileSpec& t : tiles) src.tiles.push_back({t.row0, t.col0, tileSamples(t), {}, {}});
  return src;
}

std::string writeError(const fs::path& p, const GridSource& src) {
  return errorOf([&] { writeStore(p, std::span<const GridSource>(&src, 1), options()); });
}

/// Overwrites one uint64 attribute of a tile group with the raw HDF5 API.
void setTileAttr(const fs::path& p, const std::string& object, const char* name,
                 std::uint64_t value) {
  const hid_t f = H5Fopen(p.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  const hid_t g = H5Gopen2(f, object.c_str(), H5P_DEFAULT);
  ASSERT_GE(g, 0);
  ASSERT_GE(H5Adelete(g, name), 0);
  const hid_t s = H5Screate(H5S_SCALAR);
  const hid_t a = H5Acreate2(g, name, H5T_STD_U64LE, s, H5P_DEFAULT, H5P_DEFAULT);
  ASSERT_GE(a, 0);
  ASSERT_GE(H5Awrite(a, H5T_NATIVE_UINT64, &value), 0);
  H5Aclose(a);
  H5Sclose(s);
  H5Gclose(g);
  ASSERT_GE(H5Fclose(f), 0);
}

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

}  // namespace

TEST(TiledGridErrors, WriterRefusesOverlappingTiles) {
  const fs::path p = scratchDir() / "overlap.h5";
  const std::string e = writeError(
      p, tiledSource("m", 100, 100, {{0, 0, 50, 50}, {0, 50, 50, 50}, {40, 40, 20, 20}}));
  EXPECT_EQ(e, "store::writeStore(): " + p.string() +
                   ": grid 'm' tiles 0 (rows 0-49, cols 0-49) and 2 (rows 40-59, cols 40-59) "
                   "overlap");
  EXPECT_FALSE(fs::exists(p));
}

TEST(TiledGridErrors, WriterRefusesATileOutsideTheMosaic) {
  const fs::path p = scratchDir() / "outside.h5";
  const std::string e =
      writeError(p, tiledSource("m", 100, 100, {{0, 0, 50, 50}, {60, 70, 40, 37}}));
  EXPECT_EQ(e, "store::writeStore(): " + p.string() +
                   ": grid 'm' tile 1 (row0 60, col0 70, 40x37 samples) reaches outside the "
                   "mosaic's 100x100 samples (info.rows, info.cols)");
}

TEST(TiledGridErrors, WriterRefusesAMissingExternalFileAndBadTileSources) {
  const fs::path p = scratchDir() / "missing-ext.h5";
  GridSource src{mosaicInfo("m", 100, 100), nullptr};
  src.tiles.push_back({0, 0, nullptr, "no-such-tile.h5", "tile"});
  EXPECT_EQ(writeError(p, src), "store::writeStore(): " + p.string() +
                                    ": grid 'm' tile 0 has externalStore 'no-such-tile.h5' that "
                                    "cannot be opened: store::open(): " +
                                    (scratchDir() / "no-such-tile.h5").string() + ": no such file");
  src.tiles[0] = {0, 0, nullptr, {}, {}};
  EXPECT_TRUE(
      contains(writeError(p, src),
               "grid 'm' tile 0 has neither samples nor externalStore, expected exactly one"));
  src.tiles[0] = {0, 0, tileSamples({0, 0, 10, 10}), "x.h5", "tile"};
  EXPECT_TRUE(contains(writeError(p, src),
                       "grid 'm' tile 0 has both samples and externalStore, expected exactly one"));
  src.tiles[0] = {0, 0, tileSamples({0, 0, 10, 10}), {}, {}};
  src.samples = tileSamples({0, 0, 100, 100});
  EXPECT_TRUE(contains(writeError(p, src), "grid 'm' has both samples and tiles, expected one"));
}

TEST(TiledGridErrors, ReaderRefusesOverlapsAndTilesOutsideTheMosaic) {
  const fs::path p = scratchDir() / "edited.h5";
  const GridSource src = tiledSource("m", 100, 100, {{0, 0, 50, 50}, {0, 50, 50, 50}});
  writeStore(p, std::span<const GridSource>(&src, 1), options());
  ASSERT_NO_THROW((void)Store::open(p));
  setTileAttr(p, "/grids/m/tiles/1", "col0", 30);
  EXPECT_EQ(errorOf([&] { (void)Store::open(p); }),
            "store::open(): " + p.string() +
                ": grid 'm' tiles 0 (rows 0-49, cols 0-49) and 1 (rows 0-49, cols 30-79) overlap");
  setTileAttr(p, "/grids/m/tiles/1", "col0", 51);
  EXPECT_EQ(errorOf([&] { (void)Store::open(p); }),
            "store::open(): " + p.string() +
                ": grid 'm' tile 1 (row0 0, col0 51, 50x50 samples) reaches outside the mosaic's "
                "100x100 samples (attributes rows, cols)");
  setTileAttr(p, "/grids/m/tiles/1", "col0", 50);
  setTileAttr(p, "/grids/m/tiles/1", "rows", 40);
  EXPECT_EQ(errorOf([&] { (void)Store::open(p); }),
            "store::open(): " + p.string() +
                ": grid 'm' tile 1 dataset 'level0' has shape 50x50, expected 40x50 (the tile's "
                "attributes rows, cols)");
}

TEST(TiledGridErrors, ReaderRefusesAMissingExternalFileAndAnExternalGridOfTheWrongSize) {
  const fs::path dir = scratchDir() / "ext-errors";
  fs::create_directories(dir);
  const TileSpec t{0, 0, 40, 30};
  const auto writeTile = [&](std::size_t rows, std::size_t cols) {
    const GridSource tile{mosaicInfo("tile", rows, cols), tileSamples({0, 0, rows, cols})};
    writeStore(dir / "t.h5", std::span<const GridSource>(&tile, 1), options());
  };
  writeTile(t.rows, t.cols);
  GridSource src{mosaicInfo("m", 40, 60), nullptr};
  src.tiles.push_back({0, 0, nullptr, "t.h5", "tile"});
  src.tiles.push_back({0, 30, nullptr, dir / "t.h5", "tile"});
  const fs::path p = dir / "m.h5";
  writeStore(p, std::span<const GridSource>(&src, 1), options());
  ASSERT_NO_THROW((void)Store::open(p));

  writeTile(41, 30);  // same file, wrong size
  EXPECT_EQ(errorOf([&] { (void)Store::open(p); }),
            "store::open(): " + p.string() +
                ": grid 'm' tile 0 is 40x30 samples (attributes rows, cols) but its "
                "external_grid 'tile' of " +
                (dir / "t.h5").string() + " has 41x30");

  fs::remove(dir / "t.h5");
  EXPECT_EQ(
      errorOf([&] { (void)Store::open(p); }),
      "store::open(): " + p.string() +
          ": grid 'm' tile 0 has external_file 't.h5' that cannot be opened: store::open(): " +
          (dir / "t.h5").string() + ": no such file");

  // A grid the external file does not have.
  const GridSource other{mosaicInfo("other", 40, 30), tileSamples(t)};
  writeStore(dir / "t.h5", std::span<const GridSource>(&other, 1), options());
  EXPECT_EQ(errorOf([&] { (void)Store::open(p); }),
            "store::open(): " + p.string() + ": grid 'm' tile 0 has external_grid 'tile', which " +
                (dir / "t.h5").string() + " does not have");
}

TEST(TiledGridErrors, AnExternalTileMustBeAPlainGrid) {
  const fs::path dir = scratchDir() / "nested";
  fs::create_directories(dir);
  const GridSource inner = tiledSource("tile", 40, 30, {{0, 0, 40, 30}});
  writeStore(dir / "inner.h5", std::span<const GridSource>(&inner, 1), options());
  GridSource src{mosaicInfo("m", 40, 30), nullptr};
  src.tiles.push_back({0, 0, nullptr, "inner.h5", "tile"});
  EXPECT_TRUE(contains(writeError(dir / "m.h5", src),
                       "grid 'm' tile 0 has externalGrid 'tile' of " + (dir / "inner.h5").string() +
                           ", which is itself tiled; expected a plain grid"));
}

TEST(TiledGridErrors, ATiledGridAndItsRootSayFormatOneFour) {
  // Tiles need a 1.1 reader; every grid is written as 1.4 (fixed-length strings).
  const fs::path p = internalMosaic().path;
  const hid_t f = H5Fopen(p.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  for (const char* obj : {"/", "/grids/mosaic"}) {
    const hid_t a = H5Aopen_by_name(f, obj, "format_version", H5P_DEFAULT, H5P_DEFAULT);
    ASSERT_GE(a, 0);
    int v[2] = {0, 0};
    ASSERT_GE(H5Aread(a, H5T_NATIVE_INT, v), 0);
    EXPECT_EQ(v[0], 1);
    EXPECT_EQ(v[1], 4);
    H5Aclose(a);
  }
  H5Fclose(f);
}

// ---- External tiles that fan out: each file opens once, within a budget (issue 17) ----------

namespace {

/// Writes `depth` + 1 stores f0 … f<depth> in `dir`: f<depth> holds a 1×1 plain grid 'p'; each
/// other f<k> holds 'p' and a 1×`fanout` mosaic 'm' whose tiles all name grid 'p' of f<k+1>,
/// each through its own symlink (l<k>_<i>.h5 → f<k+1>.h5). Opening f0 opened f1 `fanout`
/// times, each of those f2 `fanout` times, and so on: fanout^depth opens.
fs::path fanOutChain(const fs::path& dir, int depth, int fanout) {
  fs::create_directories(dir);
  // snprintf: GCC 12 warns falsely (-Wrestrict) on "f" + std::to_string(k) here.
  const auto name = [](const char* format, int k, int i = 0) {
    std::array<char, 32> buf{};
    std::snprintf(buf.data(), buf.size(), format, k, i);
    return std::string(buf.data());
  };
  const GridSource plain{mosaicInfo("p", 1, 1), tileSamples({10, 20, 1, 1})};
  for (int k = depth; k >= 0; --k) {
    std::vector<GridSource> grids{plain};
    if (k < depth) {
      GridSource m{mosaicInfo("m", 1, static_cast<std::size_t>(fanout)), nullptr};
      for (int i = 0; i < fanout; ++i) {
        const std::string link = name("l%d_%d.h5", k, i);
        fs::remove(dir / link);
        fs::create_symlink(name("f%d.h5", k + 1), dir / link);
        m.tiles.push_back({0, static_cast<std::size_t>(i), nullptr, link, "p"});
      }
      grids.push_back(m);
    }
    writeStore(dir / name("f%d.h5", k), grids, options());
  }
  return dir / name("f%d.h5", 0);
}

}  // namespace

TEST(TiledGridErrors, TilesThatFanOutOpenEachFileOnceWithinTheOpensBudget) {
  // 10^6 opens before; now each of the 8 files opens once, whatever the links.
  const fs::path top = fanOutChain(scratchDir() / "fanout", 7, 10);
  OpenLimits eight;
  eight.maxFiles = 8;
  const Store s = Store::open(top, eight);
  std::vector<float> v(10);
  s.readWindow("m", 0, 0, 0, 1, 10, v);
  const float h = tileSamples({10, 20, 1, 1})->sample(0, 0);
  ASSERT_FALSE(std::isnan(h));
  EXPECT_EQ(v, std::vector<float>(10, h));

  OpenLimits seven;
  seven.maxFiles = 7;
  const std::string e = errorOf([&] { (void)Store::open(top, seven); });
  EXPECT_TRUE(contains(e,
                       "the store and its external tiles take more than 7 files, the open's "
                       "budget (store::OpenLimits::maxFiles)"))
      << e;
  OpenLimits small;
  small.maxBytes = fs::file_size(top) + 100;  // the top file fits, the next one does not
  const std::string b = errorOf([&] { (void)Store::open(top, small); });
  EXPECT_TRUE(contains(b, "the store and its external tiles take more than " +
                              std::to_string(small.maxBytes) +
                              " bytes of files, the open's budget (store::OpenLimits::maxBytes)"))
      << b;
  EXPECT_TRUE(contains(b, "store::open(): " + top.string() +
                              ": grid 'm' tile 0 has external_file "
                              "'l0_0.h5' that cannot be opened"))
      << b;
}
