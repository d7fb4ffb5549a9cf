// Store: opens and validates a store file, and reads windows of its levels by hyperslab.
#include <regolith/core/FileIdentity.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/store/Store.hpp>

#include "Hdf5.hpp"
#include "Mosaic.hpp"
#include "StoreFormat.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <type_traits>

namespace regolith::store {

namespace {

using format::SampleType;
using hdf5::Context;
using hdf5::fail;
using hdf5::failHdf5;

/// One level-0 tile of a tiled grid: a dataset of this file or a grid of another store.
struct Tile {
  std::size_t index = 0, row0 = 0, col0 = 0, rows = 0, cols = 0;
  hdf5::Dataset dataset;                  // internal tile
  std::shared_ptr<const Store> external;  // external tile
  std::string externalGrid;
};

/// One validated grid of an open store.
struct GridEntry {
  GridInfo info;
  SampleType type = SampleType::Float32;
  /// The stored value that marks missing samples (besides NaN), if any.
  std::optional<double> nodata;
  std::vector<hdf5::Dataset> levels;  // levels[0] is empty for a tiled grid
  std::vector<Tile> tiles;            // empty for a plain grid
};

/// One top-level Store::open and the external stores it opens, however deep: their files
/// and bytes against the caller's budget, and the stores already open, by file identity
/// (device and inode), so that a file named by many tiles, through any spelling, symlink or
/// hard link, opens once. Without that, files nested 7 deep with 10 links each to the next
/// opened 10^6 times.
struct OpenState {
  OpenLimits limits;
  std::size_t files = 0;
  std::uintmax_t bytes = 0;
  std::map<std::pair<dev_t, ino_t>, std::shared_ptr<const Store>> externals;
};
/// The open in progress on this thread (nested opens of external tiles share it), and the
/// nesting depth (a guard against cycles).
thread_local OpenState* tlOpenState = nullptr;
thread_local int tlOpenDepth = 0;
constexpr int kMaxOpenDepth = 8;

/// Counts one more file of `bytes` against the open's budget.
void chargeBudget(OpenState& state, std::uintmax_t bytes, const Context& ctx) {
  ++state.files;
  state.bytes += bytes;
  if (state.files > state.limits.maxFiles) {
    fail(ctx, "the store and its external tiles take more than " +
                  std::to_string(state.limits.maxFiles) +
                  " files, the open's budget (store::OpenLimits::maxFiles)");
  }
  if (state.bytes > state.limits.maxBytes) {
    fail(ctx, "the store and its external tiles take more than " +
                  std::to_string(state.limits.maxBytes) +
                  " bytes of files, the open's budget (store::OpenLimits::maxBytes)");
  }
}

std::string dims(hsize_t r, hsize_t c) { return std::to_string(r) + "x" + std::to_string(c); }

std::string versionString(const std::vector<long long>& v) {
  return std::to_string(v[0]) + "." + std::to_string(v[1]);
}

void checkVersion(const std::vector<long long>& v, const Context& ctx, const std::string& owner) {
  if (v[0] > kFormatVersionMajor) {
    fail(ctx, owner + " has format version " + versionString(v) + ", newer than " +
                  std::to_string(kFormatVersionMajor) + "." + std::to_string(kFormatVersionMinor) +
                  " that this library reads; a newer Regolith is needed");
  }
  if (v[0] < 1 || v[1] < 0) {
    fail(ctx, owner + " has format version " + versionString(v) + ", expected 1.0 or later");
  }
}

bool typeMatches(hid_t type, SampleType t) {
  const H5T_class_t cls = H5Tget_class(type);
  const std::size_t size = H5Tget_size(type);
  if (size != format::sizeOf(t)) return false;
  switch (t) {
    case SampleType::Int16:
    case SampleType::Int32: return cls == H5T_INTEGER && H5Tget_sign(type) == H5T_SGN_2;
    case SampleType::UInt16: return cls == H5T_INTEGER && H5Tget_sign(type) == H5T_SGN_NONE;
    case SampleType::Float32:
    case SampleType::Float64: return cls == H5T_FLOAT;
  }
  return false;
}

double finiteNumber(hid_t g, const char* name, const Context& ctx, const std::string& owner) {
  const double v = hdf5::readNumber(g, name, ctx, owner);
  if (!std::isfinite(v)) {
    fail(ctx, owner + " has " + name + " " + core::number(v) + ", expected a finite number");
  }
  return v;
}

void readPlacement(hid_t g, GridInfo& info, const Context& ctx, const std::string& owner) {
  PlacementInfo& p = info.placement;
  const std::string kind = hdf5::readString(g, format::kPlacement, ctx, owner);
  if (kind == format::kLocalTangentPlane) {
    p.kind = PlacementInfo::Kind::LocalTangentPlane;
    p.originLatDeg = finiteNumber(g, format::kOriginLat, ctx, owner);
    p.originLonDeg = finiteNumber(g, format::kOriginLon, ctx, owner);
    p.originHeight = finiteNumber(g, format::kOriginHeight, ctx, owner);
    p.headingDeg = finiteNumber(g, format::kHeading, ctx, owner);
  } else if (kind == format::kPolarStereographic) {
    p.kind = PlacementInfo::Kind::PolarStereographic;
    const double pole = finiteNumber(g, format::kPole, ctx, owner);
    if (pole != 1.0 && pole != -1.0) {
      fail(ctx, owner + " has pole " + core::number(pole) + ", expected 1 or -1");
    }
    p.pole = pole > 0 ? 1 : -1;
    if (hdf5::hasAttribute(g, format::kLatTrueScale, ctx)) {
      p.latTrueScaleDeg = finiteNumber(g, format::kLatTrueScale, ctx, owner);
    }
    if (hdf5::hasAttribute(g, format::kScaleFactor, ctx)) {
      p.scaleFactor = finiteNumber(g, format::kScaleFactor, ctx, owner);
    }
    p.lonCentreDeg = finiteNumber(g, format::kLonCentre, ctx, owner);
    p.falseEasting = finiteNumber(g, format::kFalseEasting, ctx, owner);
    p.falseNorthing = finiteNumber(g, format::kFalseNorthing, ctx, owner);
  } else if (kind == format::kEquirectangular) {
    p.kind = PlacementInfo::Kind::Equirectangular;
    p.projectionRadius = finiteNumber(g, format::kProjectionRadius, ctx, owner);
    if (hdf5::hasAttribute(g, format::kLatTrueScale, ctx)) {
      p.latTrueScaleDeg = finiteNumber(g, format::kLatTrueScale, ctx, owner);
    }
    p.lonCentreDeg = finiteNumber(g, format::kLonCentre, ctx, owner);
    p.latOriginDeg = finiteNumber(g, format::kLatOrigin, ctx, owner);
  } else if (kind == format::kTransverseMercator) {
    p.kind = PlacementInfo::Kind::TransverseMercator;
    p.lonCentreDeg = finiteNumber(g, format::kLonCentre, ctx, owner);
    p.latOriginDeg = finiteNumber(g, format::kLatOrigin, ctx, owner);
    p.scaleFactor = finiteNumber(g, format::kScaleFactor, ctx, owner);
    p.falseEasting = finiteNumber(g, format::kFalseEasting, ctx, owner);
    p.falseNorthing = finiteNumber(g, format::kFalseNorthing, ctx, owner);
  } else if (kind == format::kProjected) {
    p.kind = PlacementInfo::Kind::Projected;
    p.crs = hdf5::readString(g, format::kCrsWkt, ctx, owner);
  } else {
    fail(ctx, owner + " has placement '" + kind +
                  "', expected 'local_tangent_plane', 'polar_stereographic', 'equirectangular', "
                  "'transverse_mercator' or 'projected'");
  }
  try {
    (void)placementOf(info);
  } catch (const Error& e) {
    fail(ctx, owner + " has an unusable placement (" + e.what() + ")");
  }
}

/// Reads and checks the attributes of one grid group (everything but the datasets).
void readAttributes(hid_t g, GridEntry& entry, const Context& ctx, const std::string& owner) {
  GridInfo& info = entry.info;
  checkVersion(hdf5::readIntegers(g, format::kFormatVersion, 2, ctx, owner), ctx, owner);
  // A store before format 1.4: its text attributes are read in one child process, not one
  // each (hdf5::VariableStringBatch); a 1.4 store has none to read there.
  const hdf5::VariableStringBatch texts(
      g,
      {format::kKind, format::kUnits, format::kSampleType, format::kBody, format::kLatitudeType,
       format::kPlacement, format::kCrsWkt, format::kProvenance},
      ctx);

  const std::string kind = hdf5::readString(g, format::kKind, ctx, owner);
  if (kind == format::kDem) {
    info.kind = GridKind::Dem;
  } else if (kind == format::kPlanet) {
    info.kind = GridKind::Planet;
  } else {
    fail(ctx, owner + " has kind '" + kind + "', expected 'dem' or 'planet'");
  }
  const std::string unit = info.kind == GridKind::Dem ? " m" : " deg";

  info.rows = hdf5::readCount(g, format::kRows, ctx, owner);
  info.cols = hdf5::readCount(g, format::kCols, ctx, owner);
  for (const auto& [name, v] : {std::pair{"rows", info.rows}, std::pair{"cols", info.cols}}) {
    if (v == 0) fail(ctx, owner + " has " + name + " 0, expected > 0");
    if (v > kMaxGridSide) {
      fail(ctx, owner + " has " + name + " " + std::to_string(v) + ", expected at most " +
                    std::to_string(kMaxGridSide) + " (the limit of docs/store-format.md)");
    }
  }
  info.x0 = finiteNumber(g, format::kX0, ctx, owner);
  info.y0 = finiteNumber(g, format::kY0, ctx, owner);
  const std::vector<double> spacing = hdf5::readNumbers(g, format::kSpacing, 2, ctx, owner);
  const auto checkSpacing = [&](double s) {
    if (!(std::isfinite(s) && s > 0.0)) {
      fail(ctx, owner + " has spacing " + core::number(s) + unit + ", expected > 0");
    }
    // A subnormal spacing makes every fractional index infinite: every point "outside".
    if (!std::isnormal(s)) {
      fail(ctx, owner + " has spacing " + core::number(s) + unit +
                    ", expected a normal double (at least 2.2250738585072014e-308)");
    }
  };
  checkSpacing(spacing[0]);
  checkSpacing(spacing[1]);
  info.spacingX = spacing[0];
  info.spacingY = spacing[1];

  info.units = hdf5::readString(g, format::kUnits, ctx, owner);
  const std::string typeName = hdf5::readString(g, format::kSampleType, ctx, owner);
  const auto type = format::sampleTypeFrom(typeName);
  if (!type) {
    fail(ctx, owner + " has sample_type '" + typeName +
                  "', expected int16, uint16, int32, float32 or float64");
  }
  entry.type = *type;
  info.scale = finiteNumber(g, format::kScale, ctx, owner);
  if (info.scale == 0.0) fail(ctx, owner + " has scale 0.0, expected a non-zero number");
  info.offset = finiteNumber(g, format::kOffset, ctx, owner);
  if (hdf5::hasAttribute(g, format::kNodata, ctx)) {
    const double nodata = hdf5::readNumber(g, format::kNodata, ctx, owner);
    if (std::isinf(nodata)) {
      fail(ctx, owner + " has nodata " + core::number(nodata) +
                    ", expected a finite "
                    "number or NaN");
    }
    if (!std::isnan(nodata)) {
      entry.nodata = nodata;
      info.nodata = static_cast<float>(nodata);
    }
  }

  info.bodyName = hdf5::readString(g, format::kBody, ctx, owner);
  info.equatorialRadius = hdf5::readNumber(g, format::kEquatorialRadius, ctx, owner);
  info.polarRadius = hdf5::readNumber(g, format::kPolarRadius, ctx, owner);
  if (!(std::isfinite(info.equatorialRadius) && std::isfinite(info.polarRadius) &&
        info.polarRadius > 0.0 && info.polarRadius <= info.equatorialRadius)) {
    fail(ctx, owner + " has equatorial_radius " + core::number(info.equatorialRadius) +
                  " m and polar_radius " + core::number(info.polarRadius) +
                  " m, expected 0 < polar_radius <= equatorial_radius");
  }
  // A sample larger than its body (1e308 m) made every query "outside" or blamed the point.
  const bool planet = info.kind == GridKind::Planet;
  const double maxSpacing = planet ? 360.0 : 2.0 * std::numbers::pi * info.equatorialRadius;
  for (const double sp : {info.spacingX, info.spacingY}) {
    if (sp > maxSpacing) {
      std::string why = owner + " has spacing ";
      why += core::number(sp) + unit + ", expected at most ";
      why += core::number(maxSpacing) + unit;
      if (!planet) why += " (the circumference of its body, " + info.bodyName + ")";
      fail(ctx, why);
    }
  }
  const std::string lat = hdf5::readString(g, format::kLatitudeType, ctx, owner);
  if (lat == format::kPlanetocentric) {
    info.latitudeType = topo::LatitudeType::Planetocentric;
  } else if (lat == format::kPlanetodetic) {
    info.latitudeType = topo::LatitudeType::Planetodetic;
  } else {
    fail(ctx,
         owner + " has latitude_type '" + lat + "', expected 'planetocentric' or 'planetodetic'");
  }
  if (info.kind == GridKind::Dem) readPlacement(g, info, ctx, owner);

  info.levels = hdf5::readCount(g, format::kLevels, ctx, owner);
  const std::size_t maxLevels = format::maxLevels(info.rows, info.cols);
  if (info.levels < 1 || info.levels > maxLevels) {
    fail(ctx, owner + " has levels " + std::to_string(info.levels) + ", expected 1 to " +
                  std::to_string(maxLevels) + " for " + dims(info.rows, info.cols) + " samples");
  }
  const std::vector<long long> patch = hdf5::readIntegers(g, format::kPatchShape, 2, ctx, owner);
  if (patch[0] < 1 || patch[1] < 1) {
    fail(ctx, owner + " has patch_shape " + std::to_string(patch[0]) + "x" +
                  std::to_string(patch[1]) + ", expected both > 0");
  }
  info.patchRows = static_cast<std::size_t>(patch[0]);
  info.patchCols = static_cast<std::size_t>(patch[1]);
  if (const std::size_t n = patchCount(info.rows, info.cols, info.patchRows, info.patchCols);
      n > kMaxPatchesPerGrid) {
    fail(ctx, owner + " has " + dims(info.rows, info.cols) + " samples in patches of " +
                  dims(info.patchRows, info.patchCols) + ": " + std::to_string(n) +
                  " patches, expected at most " + std::to_string(kMaxPatchesPerGrid) +
                  " (attribute patch_shape; the limit of docs/store-format.md)");
  }
  if (hdf5::hasAttribute(g, format::kProvenance, ctx)) {  // format 1.3
    info.provenance = hdf5::readString(g, format::kProvenance, ctx, owner);
  }
  if (hdf5::hasAttribute(g, format::kValidSamples, ctx)) {  // format 1.3
    HeightStatistics st;
    st.validSamples = hdf5::readCount(g, format::kValidSamples, ctx, owner);
    st.min = hdf5::readNumber(g, format::kHeightMin, ctx, owner);
    st.max = hdf5::readNumber(g, format::kHeightMax, ctx, owner);
    st.mean = hdf5::readNumber(g, format::kHeightMean, ctx, owner);
    info.statistics = st;
  }
}

/// Opens and checks one sample dataset: rank, shape, type, chunking and filters. `shapeNote`
/// says where the expected shape comes from, `missing` what to say if it does not exist.
hdf5::Dataset openDataset(hid_t g, const GridEntry& entry, const std::string& name,
                          const std::string& what, hsize_t rows, hsize_t cols,
                          const std::array<hsize_t, 2>& expected, const std::string& shapeNote,
                          const std::string& missing, const char* clipTo, const Context& ctx) {
  const hdf5::Lock lock;
  const GridInfo& info = entry.info;
  const htri_t exists = H5Lexists(g, name.c_str(), H5P_DEFAULT);
  if (exists < 0) failHdf5(ctx, "cannot look up " + what);
  if (exists == 0) fail(ctx, missing);
  {
    const hdf5::Object obj(
        hdf5::check(H5Oopen(g, name.c_str(), H5P_DEFAULT), ctx, "cannot open " + what));
    if (H5Iget_type(obj.get()) != H5I_DATASET) {
      fail(ctx, what + " is not a dataset");
    }
  }
  // The pager caches whole patches itself; HDF5's own chunk cache would hold the same bytes
  // a second time, so it is switched off (docs/store-format.md, "Chunk cache").
  const hdf5::PropertyList dapl(
      hdf5::check(H5Pcreate(H5P_DATASET_ACCESS), ctx, "cannot open " + what));
  hdf5::check(H5Pset_chunk_cache(dapl.get(), 0, 0, 1.0), ctx, "cannot open " + what);
  hdf5::Dataset ds(hdf5::check(H5Dopen2(g, name.c_str(), dapl.get()), ctx, "cannot open " + what));

  const hdf5::Dataspace space(
      hdf5::check(H5Dget_space(ds.get()), ctx, "cannot read the shape of " + what));
  const int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank < 0) failHdf5(ctx, "cannot read the shape of " + what);
  if (rank != 2) {
    fail(ctx, what + " has rank " + std::to_string(rank) + ", expected 2");
  }
  std::array<hsize_t, 2> shape{};
  hdf5::check(H5Sget_simple_extent_dims(space.get(), shape.data(), nullptr), ctx,
              "cannot read the shape of " + what);
  if (shape[0] != rows || shape[1] != cols) {
    fail(ctx, what + " has shape " + dims(shape[0], shape[1]) + ", expected " + dims(rows, cols) +
                  " (" + shapeNote + ")");
  }

  const hdf5::Datatype type(
      hdf5::check(H5Dget_type(ds.get()), ctx, "cannot read the type of " + what));
  if (!typeMatches(type.get(), entry.type)) {
    fail(ctx, what + " has type " + hdf5::describeType(type.get()) + ", expected " +
                  std::string(format::toString(entry.type)) + " (attribute sample_type)");
  }

  const hdf5::PropertyList dcpl(
      hdf5::check(H5Dget_create_plist(ds.get()), ctx, "cannot read the layout of " + what));
  const std::string expectedText = dims(expected[0], expected[1]) + " (attribute patch_shape " +
                                   dims(info.patchRows, info.patchCols) + ", clipped to the " +
                                   clipTo + ")";
  if (H5Pget_layout(dcpl.get()) != H5D_CHUNKED) {
    fail(ctx, what + " is not chunked, expected chunks of " + expectedText);
  }
  std::array<hsize_t, 2> chunk{};
  if (H5Pget_chunk(dcpl.get(), 2, chunk.data()) != 2) {
    failHdf5(ctx, "cannot read the chunk shape of " + what);
  }
  if (chunk != expected) {
    fail(ctx, what + " has chunks " + dims(chunk[0], chunk[1]) + ", expected " + expectedText);
  }
  const int nfilters = H5Pget_nfilters(dcpl.get());
  if (nfilters < 0) failHdf5(ctx, "cannot read the filters of " + what);
  for (unsigned i = 0; i < static_cast<unsigned>(nfilters); ++i) {
    unsigned flags = 0, config = 0;
    std::size_t nelmts = 0;
    std::array<char, 64> fname{};
    const H5Z_filter_t id = H5Pget_filter2(dcpl.get(), i, &flags, &nelmts, nullptr, fname.size(),
                                           fname.data(), &config);
    if (id < 0) failHdf5(ctx, "cannot read the filters of " + what);
    if (H5Zfilter_avail(id) <= 0) {
      (void)hdf5::takeErrorStack();  // the failed plugin search
      fail(ctx, what + " needs HDF5 filter " + std::to_string(id) + " ('" +
                    std::string(fname.data()) +
                    "'), which this HDF5 library cannot load: " + hdf5::missingFilterHint(id));
    }
  }
  return ds;
}

/// Opens and checks one level dataset of a grid.
hdf5::Dataset openLevel(hid_t g, const GridEntry& entry, std::size_t level, const Context& ctx,
                        const std::string& owner) {
  const GridInfo& info = entry.info;
  const std::string name = format::levelName(level);
  return openDataset(
      g, entry, name, owner + " dataset '" + name + "'", info.levelRows(level),
      info.levelCols(level), format::chunkShape(info, level),
      level > 0 ? "attributes rows, cols, halved per level" : "attributes rows, cols",
      owner + " has no dataset '" + name + "' (attribute levels is " + std::to_string(info.levels) +
          ")",
      "level", ctx);
}

/// Reads and checks tile i of a tiled grid: its bounds, and its dataset or its external grid.
Tile openTile(hid_t tiles, std::size_t i, const GridEntry& entry, const Context& ctx,
              const std::string& owner, const std::filesystem::path& storePath, OpenState& state) {
  const GridInfo& info = entry.info;
  const std::string tname = std::to_string(i);
  const std::string towner = owner + " tile " + tname;
  const htri_t has = H5Lexists(tiles, tname.c_str(), H5P_DEFAULT);
  if (has < 0) failHdf5(ctx, "cannot look up " + towner);
  if (has == 0) fail(ctx, owner + " has no group 'tiles/" + tname + "' (attribute tile_count)");
  const hdf5::Group tg(
      hdf5::check(H5Gopen2(tiles, tname.c_str(), H5P_DEFAULT), ctx, "cannot open " + towner));
  Tile t;
  t.index = i;
  t.row0 = hdf5::readCount(tg.get(), format::kTileRow0, ctx, towner);
  t.col0 = hdf5::readCount(tg.get(), format::kTileCol0, ctx, towner);
  t.rows = hdf5::readCount(tg.get(), format::kTileRows, ctx, towner);
  t.cols = hdf5::readCount(tg.get(), format::kTileCols, ctx, towner);
  if (t.rows == 0 || t.cols == 0) {
    fail(ctx, towner + " has rows x cols " + dims(t.rows, t.cols) + ", expected both > 0");
  }
  if (t.rows > info.rows || t.row0 > info.rows - t.rows || t.cols > info.cols ||
      t.col0 > info.cols - t.cols) {
    fail(ctx, towner + " (row0 " + std::to_string(t.row0) + ", col0 " + std::to_string(t.col0) +
                  ", " + dims(t.rows, t.cols) + " samples) reaches outside the mosaic's " +
                  dims(info.rows, info.cols) + " samples (attributes rows, cols)");
  }
  if (!hdf5::hasAttribute(tg.get(), format::kExternalFile, ctx)) {
    t.dataset = openDataset(
        tg.get(), entry, "level0", towner + " dataset 'level0'", t.rows, t.cols,
        format::tileChunkShape(info, t.rows, t.cols), "the tile's attributes rows, cols",
        towner + " has neither a dataset 'level0' nor an attribute 'external_file'", "tile", ctx);
    return t;
  }
  const hdf5::VariableStringBatch texts(tg.get(), {format::kExternalFile, format::kExternalGrid},
                                        ctx);
  const std::string file = hdf5::readString(tg.get(), format::kExternalFile, ctx, towner);
  t.externalGrid = hdf5::readString(tg.get(), format::kExternalGrid, ctx, towner);
  std::filesystem::path resolved(file);
  if (resolved.is_relative()) resolved = storePath.parent_path() / resolved;
  const std::string key = resolved.lexically_normal().string();
  const auto openExternal = [&] {
    try {
      return std::make_shared<const Store>(Store::open(resolved));
    } catch (const StoreError& e) {
      fail(ctx, towner + " has external_file '" + file + "' that cannot be opened: " + e.what());
    }
  };
  struct stat st {};
  if (::stat(resolved.c_str(), &st) != 0) (void)openExternal();  // throws, explaining why
  auto it = state.externals.find({st.st_dev, st.st_ino});
  if (it == state.externals.end()) {
    it = state.externals.emplace(std::pair{st.st_dev, st.st_ino}, openExternal()).first;
  }
  t.external = it->second;
  const std::string ext = "external_grid '" + t.externalGrid + "'";
  if (!t.external->hasGrid(t.externalGrid)) {
    fail(ctx, towner + " has " + ext + ", which " + key + " does not have");
  }
  if (t.external->tiled(t.externalGrid)) {
    fail(ctx,
         towner + " has " + ext + " of " + key + ", which is itself tiled; expected a plain grid");
  }
  const GridInfo& x = t.external->grid(t.externalGrid);
  if (x.rows != t.rows || x.cols != t.cols) {
    fail(ctx, towner + " is " + dims(t.rows, t.cols) + " samples (attributes rows, cols) but its " +
                  ext + " of " + key + " has " + dims(x.rows, x.cols));
  }
  return t;
}

std::string readTileWhat(const std::string& owner, const Tile& t) {
  return "cannot read " + owner + " tile " + std::to_string(t.index) + " dataset 'level0'";
}

[[noreturn]] void failOverlap(const Context& ctx, const std::string& owner, const Tile& a,
                              const Tile& b) {
  fail(ctx, owner + " tiles " + std::to_string(a.index) + " (" + mosaic::range(mosaic::rectOf(a)) +
                ") and " + std::to_string(b.index) + " (" + mosaic::range(mosaic::rectOf(b)) +
                ") overlap");
}

/// Reads and checks the tiles of a tiled grid (tile_count present), and that no two overlap.
void openTiles(hid_t g, GridEntry& entry, const Context& ctx, const std::string& owner,
               const std::filesystem::path& storePath, OpenState& state) {
  const std::size_t count = hdf5::readCount(g, format::kTileCount, ctx, owner);
  if (count == 0) fail(ctx, owner + " has tile_count 0, expected >= 1");
  const htri_t exists = H5Lexists(g, format::kTiles, H5P_DEFAULT);
  if (exists < 0) failHdf5(ctx, "cannot look up " + owner + " group 'tiles'");
  if (exists == 0) {
    fail(ctx, owner + " has tile_count " + std::to_string(count) + " but no group 'tiles'");
  }
  const hdf5::Group tiles(hdf5::check(H5Gopen2(g, format::kTiles, H5P_DEFAULT), ctx,
                                      "cannot open " + owner + " group 'tiles'"));
  for (std::size_t i = 0; i < count; ++i) {
    Tile t = openTile(tiles.get(), i, entry, ctx, owner, storePath, state);
    for (const Tile& o : entry.tiles) {
      if (mosaic::overlap(mosaic::rectOf(o), mosaic::rectOf(t))) failOverlap(ctx, owner, o, t);
    }
    entry.tiles.push_back(std::move(t));
  }
}

GridEntry openGrid(hid_t grids, const std::string& name, const Context& ctx,
                   const std::filesystem::path& storePath, OpenState& state) {
  const hdf5::Lock lock;
  const std::string owner = "grid '" + name + "'";
  const hdf5::Object obj(
      hdf5::check(H5Oopen(grids, name.c_str(), H5P_DEFAULT), ctx, "cannot open " + owner));
  if (H5Iget_type(obj.get()) != H5I_GROUP) {
    fail(ctx, "'/grids/" + name + "' is not a group");
  }
  GridEntry entry;
  entry.info.name = name;
  readAttributes(obj.get(), entry, ctx, owner);
  const bool tiled = hdf5::hasAttribute(obj.get(), format::kTileCount, ctx);
  if (tiled) openTiles(obj.get(), entry, ctx, owner, storePath, state);
  for (std::size_t k = 0; k < entry.info.levels; ++k) {
    entry.levels.push_back(tiled && k == 0 ? hdf5::Dataset()
                                           : openLevel(obj.get(), entry, k, ctx, owner));
  }
  return entry;
}

std::vector<std::string> memberNames(hid_t group, const Context& ctx) {
  const hdf5::Lock lock;
  H5G_info_t ginfo{};
  hdf5::check(H5Gget_info(group, &ginfo), ctx, "cannot list '/grids'");
  std::vector<std::string> names;
  for (hsize_t i = 0; i < ginfo.nlinks; ++i) {
    const ssize_t len =
        H5Lget_name_by_idx(group, ".", H5_INDEX_NAME, H5_ITER_INC, i, nullptr, 0, H5P_DEFAULT);
    if (len < 0) failHdf5(ctx, "cannot list '/grids'");
    std::string n(static_cast<std::size_t>(len) + 1, '\0');
    if (H5Lget_name_by_idx(group, ".", H5_INDEX_NAME, H5_ITER_INC, i, n.data(), n.size(),
                           H5P_DEFAULT) < 0) {
      failHdf5(ctx, "cannot list '/grids'");
    }
    n.resize(static_cast<std::size_t>(len));
    names.push_back(std::move(n));
  }
  return names;
}

/// Converts stored samples to heights: offset + scale·stored, NaN where missing. Samples that
/// are not finite (the writer refuses ±inf; a crafted file may hold it) and heights that are
/// not finite as float32 are missing too: a query must never call ±inf or NaN a valid height.
/// `x - x == 0` is false exactly for ±inf and NaN, and vectorises where std::isfinite does not.
template <typename T>
void toHeights(const T* in, std::span<float> out, double scale, double offset,
               std::optional<double> nodata) {
  const bool hasNodata = nodata.has_value();
  const double nd = nodata.value_or(0.0);
  constexpr float kNan = std::numeric_limits<float>::quiet_NaN();
  for (std::size_t i = 0; i < out.size(); ++i) {
    const auto v = static_cast<double>(in[i]);
    const auto h = static_cast<float>(offset + scale * v);
    out[i] = (hasNodata && v == nd) || !(h - h == 0.0f) ? kNan : h;
  }
}

/// Refuses a read whose chunks the file's chunk index describes impossibly: a chunk that
/// ends beyond the end of the file; a chunk stored as is (no filter, or every filter but
/// shuffle skipped by its filter mask) whose size is not the chunk's bytes; a compressed one
/// more than twice that (deflate and ZFP never grow a chunk so much). HDF5 1.10 trusts
/// these: a chunk of 123 bytes whose mask says "not compressed" makes H5Dread copy 128 bytes
/// out of it (found by tests/fuzz/fuzz_store; StoreTest ReadRefusesAChunkIndexThatLies). Only
/// the chunks the selection (start, step, count) meets are looked up, one B-tree search each.
void checkChunks(hid_t ds, const Context& ctx, const std::string& what,
                 const std::array<hsize_t, 2>& start, const std::array<hsize_t, 2>& step,
                 const std::array<hsize_t, 2>& count) {
  if (count[0] == 0 || count[1] == 0) return;
  const hdf5::PropertyList dcpl(hdf5::check(H5Dget_create_plist(ds), ctx, what));
  std::array<hsize_t, 2> chunk{};
  if (H5Pget_layout(dcpl.get()) != H5D_CHUNKED || H5Pget_chunk(dcpl.get(), 2, chunk.data()) != 2 ||
      chunk[0] == 0 || chunk[1] == 0) {
    return;  // Store::open() accepts chunked datasets only
  }
  // Bit k of a chunk's filter mask set: filter k was skipped for it. Shuffle keeps the size.
  unsigned sizeChanging = 0;
  const int nfilters = std::min(H5Pget_nfilters(dcpl.get()), 32);
  for (unsigned k = 0; k < static_cast<unsigned>(std::max(nfilters, 0)); ++k) {
    unsigned flags = 0;
    std::size_t nelmts = 0;
    const H5Z_filter_t id =
        H5Pget_filter2(dcpl.get(), k, &flags, &nelmts, nullptr, 0, nullptr, nullptr);
    if (id != H5Z_FILTER_SHUFFLE) sizeChanging |= 1U << k;
  }
  const hdf5::Datatype type(hdf5::check(H5Dget_type(ds), ctx, what));
  const hsize_t chunkBytes = chunk[0] * chunk[1] * H5Tget_size(type.get());
  const hdf5::File file(hdf5::check(H5Iget_file_id(ds), ctx, what));
  hsize_t fileSize = 0;
  hdf5::check(H5Fget_filesize(file.get(), &fileSize), ctx, what);
  const hsize_t lastRow = start[0] + (count[0] - 1) * step[0];
  const hsize_t lastCol = start[1] + (count[1] - 1) * step[1];
  for (hsize_t cr = start[0] / chunk[0]; cr <= lastRow / chunk[0]; ++cr) {
    for (hsize_t cc = start[1] / chunk[1]; cc <= lastCol / chunk[1]; ++cc) {
      const std::array<hsize_t, 2> offset{cr * chunk[0], cc * chunk[1]};
      unsigned mask = 0;
      haddr_t addr = HADDR_UNDEF;
      hsize_t size = 0;
      hdf5::check(H5Dget_chunk_info_by_coord(ds, offset.data(), &mask, &addr, &size), ctx, what);
      if (addr == HADDR_UNDEF) continue;  // never written: reads the fill value
      const bool fits = addr <= fileSize && size <= fileSize - addr;
      const bool filtered = (sizeChanging & ~mask) != 0;
      const bool sized = filtered ? size <= 2 * chunkBytes : size == chunkBytes;
      if (!fits || !sized) {
        fail(ctx, what + ": the chunk at row " + std::to_string(offset[0]) + ", col " +
                      std::to_string(offset[1]) + " is recorded as " + std::to_string(size) +
                      " bytes at byte " + std::to_string(addr) +
                      (filtered ? " compressed"
                                : " not compressed (filter mask " + std::to_string(mask) + ")") +
                      ", expected " +
                      (filtered ? "at most " + std::to_string(2 * chunkBytes)
                                : std::to_string(chunkBytes)) +
                      " bytes within the file's " + std::to_string(fileSize) +
                      " (corrupt chunk index)");
      }
    }
  }
}

/// Throws if the file of `ds` is now shorter than HDF5's end of allocation: cut after it was
/// opened. HDF5's sec2 driver reads the missing bytes as zeros, so an uncompressed chunk
/// past the cut would come back as zero heights without an error (issue 17). Called after
/// each read, under the HDF5 lock: a cut before the read's end is caught, one after it did
/// not touch the samples read.
void checkNotTruncated(hid_t ds, const Context& ctx) {
  const hdf5::File file(hdf5::check(H5Iget_file_id(ds), ctx, "cannot get the dataset's file"));
  haddr_t eoa = 0;
  void* handle = nullptr;
  hdf5::check(H5Fget_eoa(file.get(), &eoa), ctx, "cannot get the end of allocation");
  hdf5::check(H5Fget_vfd_handle(file.get(), H5P_DEFAULT, &handle), ctx,
              "cannot get the file handle");
  struct stat st {};
  if (::fstat(*static_cast<const int*>(handle), &st) != 0)
    fail(ctx, std::string("cannot stat the open file: ") + std::strerror(errno));
  if (static_cast<unsigned long long>(st.st_size) < eoa)
    fail(ctx, "the file is now " + std::to_string(st.st_size) + " bytes, expected at least " +
                  std::to_string(eoa) +
                  " (the end of its HDF5 allocation: truncated after it was opened?)");
}

/// Reads rows×cols samples at (row0, col0), every `stride`-th, of one dataset of a grid with
/// one hyperslab read, into `out` as heights (NaN where missing).
void readDataset(const GridEntry& e, hid_t ds, const Context& ctx, const std::string& what,
                 std::size_t row0, std::size_t col0, std::size_t rows, std::size_t cols,
                 std::size_t stride, std::span<float> out) {
  const GridInfo& info = e.info;
  const std::size_t n = rows * cols;
  const std::array<hsize_t, 2> start{row0, col0};
  const std::array<hsize_t, 2> step{stride, stride};
  const std::array<hsize_t, 2> count{rows, cols};
  const auto read = [&](hid_t memType, void* buffer) {
    const hdf5::Lock lock;
    checkChunks(ds, ctx, what, start, step, count);
    const hdf5::Dataspace fileSpace(hdf5::check(H5Dget_space(ds), ctx, what));
    hdf5::check(H5Sselect_hyperslab(fileSpace.get(), H5S_SELECT_SET, start.data(), step.data(),
                                    count.data(), nullptr),
                ctx, what);
    const hdf5::Dataspace memSpace(
        hdf5::check(H5Screate_simple(2, count.data(), nullptr), ctx, what));
    hdf5::check(H5Dread(ds, memType, memSpace.get(), fileSpace.get(), H5P_DEFAULT, buffer), ctx,
                what);
    checkNotTruncated(ds, ctx);
  };
  const auto readAs = [&]<typename T>(T /*tag*/) {
    if constexpr (std::is_same_v<T, float>) {
      // float32 reads straight into the output; the conversion then runs in place.
      read(format::nativeType(e.type), out.data());
      if (info.scale == 1.0 && info.offset == 0.0) {
        // Branch-free so that it vectorises (std::replace's conditional store does not: it
        // took 60 % of a warm 256×256 read). ±inf is missing, as in toHeights().
        constexpr float kNan = std::numeric_limits<float>::quiet_NaN();
        if (e.nodata) {
          const auto nd = static_cast<float>(*e.nodata);
          for (float& v : out) v = v == nd || !(v - v == 0.0f) ? kNan : v;
        } else {
          for (float& v : out) v = v - v == 0.0f ? v : kNan;
        }
      } else {
        toHeights(out.data(), out, info.scale, info.offset, e.nodata);
      }
    } else {
      std::vector<T> buffer(n);
      read(format::nativeType(e.type), buffer.data());
      toHeights(buffer.data(), out, info.scale, info.offset, e.nodata);
    }
  };
  switch (e.type) {
    case SampleType::Int16: readAs(std::int16_t{}); break;
    case SampleType::UInt16: readAs(std::uint16_t{}); break;
    case SampleType::Int32: readAs(std::int32_t{}); break;
    case SampleType::Float32: readAs(float{}); break;
    case SampleType::Float64: readAs(double{}); break;
  }
}

}  // namespace

struct Store::Impl {
  std::filesystem::path path;
  hdf5::File file;  // declared before the grids: closed after their datasets
  std::map<std::string, GridEntry, std::less<>> grids;
  std::array<int, 2> formatVersion{0, 0};
  mutable std::atomic<std::uint64_t> reads{0};
  mutable std::atomic<std::uint64_t> bytesRead{0};

  [[nodiscard]] const GridEntry& entry(std::string_view name, const Context& ctx) const {
    const auto it = grids.find(name);
    if (it == grids.end()) {
      std::string known;
      for (const auto& [n, e] : grids) known += (known.empty() ? "" : ", ") + n;
      fail(ctx, "no grid '" + std::string(name) +
                    "' (grids: " + (known.empty() ? std::string("none") : known) + ")");
    }
    return it->second;
  }
};

Store::Store(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Store::Store(Store&&) noexcept = default;
Store& Store::operator=(Store&&) noexcept = default;
Store::~Store() = default;

Store Store::open(const std::filesystem::path& path, const OpenLimits& limits) {
  const Context ctx("store::open()", path);
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (const auto problem = core::pathProblem(path)) fail(ctx, *problem);
  if (std::filesystem::is_directory(status)) fail(ctx, "is a directory, expected a file");
  if (tlOpenDepth >= kMaxOpenDepth) {
    fail(ctx, "external tiles nest more than " + std::to_string(kMaxOpenDepth) +
                  " stores deep (a cycle of external_file references?)");
  }
  OpenState top{limits, 0, 0, {}};
  struct Depth {  // the outermost open owns the state its nested opens share
    explicit Depth(OpenState* top) : owner(tlOpenState == nullptr) {
      if (owner) tlOpenState = top;
      ++tlOpenDepth;
    }
    ~Depth() {
      --tlOpenDepth;
      if (owner) tlOpenState = nullptr;
    }
    Depth(const Depth&) = delete;
    Depth& operator=(const Depth&) = delete;
    Depth(Depth&&) = delete;
    Depth& operator=(Depth&&) = delete;
    bool owner;
  } const depth(&top);
  OpenState& state = *tlOpenState;
  const std::uintmax_t bytes = std::filesystem::file_size(path, ec);  // -1 with ec: not regular
  chargeBudget(state, ec ? 0 : bytes, ctx);

  auto impl = std::make_unique<Impl>();
  impl->path = path;
  const hdf5::Lock lock;
  const htri_t isHdf5 = H5Fis_hdf5(path.c_str());
  if (isHdf5 < 0) failHdf5(ctx, "cannot be read");
  if (isHdf5 == 0) fail(ctx, "is not an HDF5 file (no HDF5 signature)");
  impl->file = hdf5::File(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT));
  if (!impl->file.valid()) {
    failHdf5(ctx, "cannot open the HDF5 file (truncated or corrupt?)");
  }
  const hdf5::Group root(
      hdf5::check(H5Gopen2(impl->file.get(), "/", H5P_DEFAULT), ctx, "cannot open '/'"));
  const std::string rootOwner = "the root group";
  if (!hdf5::hasAttribute(root.get(), format::kMarker, ctx)) {
    fail(ctx, "is not a Regolith store (the root group has no attribute 'regolith_store')");
  }
  const std::vector<long long> version =
      hdf5::readIntegers(root.get(), format::kFormatVersion, 2, ctx, rootOwner);
  checkVersion(version, ctx, rootOwner);
  impl->formatVersion = {static_cast<int>(version[0]), static_cast<int>(version[1])};
  const htri_t hasGrids = H5Lexists(root.get(), format::kGrids, H5P_DEFAULT);
  if (hasGrids < 0) failHdf5(ctx, "cannot look up '/grids'");
  if (hasGrids == 0) fail(ctx, "has no group '/grids'");
  const hdf5::Object grids(
      hdf5::check(H5Oopen(root.get(), format::kGrids, H5P_DEFAULT), ctx, "cannot open '/grids'"));
  if (H5Iget_type(grids.get()) != H5I_GROUP) fail(ctx, "'/grids' is not a group");
  for (const std::string& name : memberNames(grids.get(), ctx)) {
    impl->grids.emplace(name, openGrid(grids.get(), name, ctx, path, state));
  }
  return Store(std::move(impl));
}

void skipHdf5ShutdownAtExit() noexcept { (void)H5dont_atexit(); }

bool Store::isHdf5(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return false;
  const hdf5::Lock lock;
  return H5Fis_hdf5(path.c_str()) > 0;
}

const std::filesystem::path& Store::path() const noexcept { return impl_->path; }

std::array<int, 2> Store::formatVersion() const noexcept { return impl_->formatVersion; }

std::vector<std::string> Store::gridNames() const {
  std::vector<std::string> names;
  names.reserve(impl_->grids.size());
  for (const auto& [name, entry] : impl_->grids) names.push_back(name);
  return names;
}

bool Store::hasGrid(std::string_view name) const noexcept {
  return impl_->grids.find(name) != impl_->grids.end();
}

const GridInfo& Store::grid(std::string_view name) const {
  return impl_->entry(name, Context("store::grid()", impl_->path)).info;
}

bool Store::tiled(std::string_view name) const {
  return !impl_->entry(name, Context("store::tiled()", impl_->path)).tiles.empty();
}

void Store::readWindow(std::string_view grid, std::size_t level, std::size_t row0, std::size_t col0,
                       std::size_t rows, std::size_t cols, std::span<float> out,
                       std::size_t stride) const {
  const Context ctx("store::readWindow()", impl_->path);
  const GridEntry& e = impl_->entry(grid, ctx);
  const GridInfo& info = e.info;
  const std::string owner = "grid '" + info.name + "'";
  if (level >= info.levels) {
    fail(ctx, owner + " has no level " + std::to_string(level) + " (levels 0 to " +
                  std::to_string(info.levels - 1) + ")");
  }
  if (stride == 0) {
    throw InvalidArgument(ctx.prefix + ": " + owner + " stride 0, expected >= 1");
  }
  if (out.size() != rows * cols) {
    throw InvalidArgument(ctx.prefix + ": " + owner + " output holds " +
                          std::to_string(out.size()) +
                          " floats, expected rows x cols = " + std::to_string(rows * cols));
  }
  if (rows == 0 || cols == 0) return;
  const std::size_t levelRows = info.levelRows(level), levelCols = info.levelCols(level);
  // The last sample read in each direction must lie inside the level (no overflow: each
  // term is checked against the level size before it is added).
  const auto inside = [stride](std::size_t first, std::size_t n, std::size_t size) {
    return first < size && (n - 1) <= (size - 1 - first) / stride;
  };
  if (!inside(row0, rows, levelRows) || !inside(col0, cols, levelCols)) {
    fail(ctx, owner + " level " + std::to_string(level) + ": window of " + dims(rows, cols) +
                  " samples at (" + std::to_string(row0) + ", " + std::to_string(col0) +
                  ") with stride " + std::to_string(stride) + " reaches outside the level's " +
                  dims(levelRows, levelCols) + " samples");
  }

  const std::size_t bytesPerSample = format::sizeOf(e.type);
  if (level > 0 || e.tiles.empty()) {
    readDataset(e, e.levels[level].get(), ctx,
                "cannot read " + owner + " dataset '" + format::levelName(level) + "'", row0, col0,
                rows, cols, stride, out);
    impl_->reads.fetch_add(1, std::memory_order_relaxed);
    impl_->bytesRead.fetch_add(rows * cols * bytesPerSample, std::memory_order_relaxed);
    return;
  }
  // A tiled level 0: one read per tile the window meets; samples no tile covers stay NaN.
  if (stride != 1) {
    fail(ctx, owner + " level 0 is tiled: stride " + std::to_string(stride) +
                  " is not supported there, only 1 (coarse views read a pyramid level)");
  }
  mosaic::assemble(std::span<const Tile>(e.tiles), {row0, col0, rows, cols},
                   std::numeric_limits<float>::quiet_NaN(), out.data(),
                   [&](const Tile& t, const mosaic::Rect& part, std::vector<float>& buffer) {
                     if (t.external) {
                       t.external->readWindow(t.externalGrid, 0, part.row0, part.col0, part.rows,
                                              part.cols, buffer);
                     } else {
                       readDataset(e, t.dataset.get(), ctx, readTileWhat(owner, t), part.row0,
                                   part.col0, part.rows, part.cols, 1, buffer);
                       impl_->bytesRead.fetch_add(part.rows * part.cols * bytesPerSample,
                                                  std::memory_order_relaxed);
                     }
                     impl_->reads.fetch_add(1, std::memory_order_relaxed);
                   });
}

ReadCounters Store::counters() const noexcept {
  return {impl_->reads.load(std::memory_order_relaxed),
          impl_->bytesRead.load(std::memory_order_relaxed)};
}

}  // namespace regolith::store
