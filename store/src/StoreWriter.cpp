// writeStore(): writes grids and their pyramids into a temporary file, then renames it into
// place (docs/store-format.md, "Crash-safe writing").
#include <regolith/core/AtomicFile.hpp>
#include <regolith/core/Executor.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/store/Store.hpp>
#include <regolith/topo/Pyramid.hpp>

#include "Hdf5.hpp"
#include "StoreFormat.hpp"

#include <fcntl.h>
#include <libdeflate.h>
#include <unistd.h>
#include <zfp.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <exception>
#include <functional>
#include <limits>
#include <map>
#include <mutex>
#include <set>
#include <thread>

namespace regolith::store {

namespace {

using hdf5::Context;
using hdf5::fail;

constexpr float kNan = std::numeric_limits<float>::quiet_NaN();

[[noreturn]] void invalid(const Context& ctx, const std::string& what) {
  throw InvalidArgument(ctx.prefix + ": " + what);
}

void validateOptions(const WriteOptions& o, const Context& ctx) {
  if (o.patchRows == 0 || o.patchCols == 0) {
    invalid(ctx, "patch size " + std::to_string(o.patchRows) + "x" + std::to_string(o.patchCols) +
                     ", expected both > 0");
  }
  // HDF5 chunks are limited to 4 GiB.
  constexpr std::size_t kMaxChunkSamples = (std::size_t{1} << 32U) / sizeof(float) - 1;
  if (o.patchRows > kMaxChunkSamples / o.patchCols) {
    invalid(ctx, "patch size " + std::to_string(o.patchRows) + "x" + std::to_string(o.patchCols) +
                     " exceeds HDF5's 4 GiB chunk limit");
  }
  if (o.deflate < 0 || o.deflate > 9) {
    invalid(ctx, "deflate level " + std::to_string(o.deflate) + ", expected 0 to 9");
  }
  if (o.codec == Codec::Zfp && o.deflate != 0) {
    invalid(ctx, "deflate level " + std::to_string(o.deflate) +
                     " with the zfp codec, which has no level (expected 0)");
  }
  if (o.codec != Codec::Deflate && o.codec != Codec::Zfp) {
    invalid(ctx, "codec " + std::to_string(static_cast<int>(o.codec)) +
                     ", expected Codec::Deflate or Codec::Zfp");
  }
}

/// One tile as it will be written: its bounds, and its samples or its opened external store.
struct PreparedTile {
  std::size_t row0 = 0, col0 = 0, rows = 0, cols = 0;
  std::shared_ptr<const topo::SampleSource> samples;
  std::shared_ptr<const Store> external;
  std::string file, grid;  // as recorded
};

struct Prepared {
  GridInfo info;
  std::vector<PreparedTile> tiles;
};

std::string tileRange(const PreparedTile& t) {
  return "rows " + std::to_string(t.row0) + "-" + std::to_string(t.row0 + t.rows - 1) + ", cols " +
         std::to_string(t.col0) + "-" + std::to_string(t.col0 + t.cols - 1);
}

/// Checks tile i of a tiled grid: one source, inside the mosaic, and an external grid that
/// opens, is plain and gives the tile's size.
PreparedTile prepareTile(const TileSource& ts, std::size_t i, const GridInfo& info,
                         const std::filesystem::path& storeDir, const Context& ctx) {
  const std::string towner = "grid '" + info.name + "' tile " + std::to_string(i);
  PreparedTile t;
  t.row0 = ts.row0;
  t.col0 = ts.col0;
  const bool hasExternal = !ts.externalStore.empty();
  if (static_cast<bool>(ts.samples) == hasExternal) {
    invalid(ctx, towner + " has " +
                     (hasExternal ? "both samples and externalStore"
                                  : "neither samples nor externalStore") +
                     ", expected exactly one");
  }
  if (ts.samples) {
    t.samples = ts.samples;
    t.rows = ts.samples->rows();
    t.cols = ts.samples->cols();
  } else {
    t.file = ts.externalStore.string();
    t.grid = ts.externalGrid;
    const std::filesystem::path resolved =
        ts.externalStore.is_relative() ? storeDir / ts.externalStore : ts.externalStore;
    try {
      t.external = std::make_shared<const Store>(Store::open(resolved));
    } catch (const StoreError& e) {
      invalid(ctx,
              towner + " has externalStore '" + t.file + "' that cannot be opened: " + e.what());
    }
    const std::string ext = "externalGrid '" + t.grid + "'";
    if (!t.external->hasGrid(t.grid)) {
      invalid(ctx, towner + " has " + ext + ", which " + resolved.string() + " does not have");
    }
    if (t.external->tiled(t.grid)) {
      invalid(ctx, towner + " has " + ext + " of " + resolved.string() +
                       ", which is itself tiled; expected a plain grid");
    }
    t.rows = t.external->grid(t.grid).rows;
    t.cols = t.external->grid(t.grid).cols;
  }
  if (t.rows == 0 || t.cols == 0 || t.rows > info.rows || t.row0 > info.rows - t.rows ||
      t.cols > info.cols || t.col0 > info.cols - t.cols) {
    invalid(ctx, towner + " (row0 " + std::to_string(t.row0) + ", col0 " + std::to_string(t.col0) +
                     ", " + std::to_string(t.rows) + "x" + std::to_string(t.cols) +
                     " samples) reaches outside the mosaic's " + std::to_string(info.rows) + "x" +
                     std::to_string(info.cols) + " samples (info.rows, info.cols)");
  }
  return t;
}

[[noreturn]] void overlap(const Context& ctx, const GridInfo& info, std::size_t i,
                          const PreparedTile& a, std::size_t j, const PreparedTile& b) {
  invalid(ctx, "grid '" + info.name + "' tiles " + std::to_string(i) + " (" + tileRange(a) +
                   ") and " + std::to_string(j) + " (" + tileRange(b) + ") overlap");
}

/// Checks the tiles of a tiled grid (prepareTile) and that no two overlap.
std::vector<PreparedTile> prepareTiles(const GridSource& src, const GridInfo& info,
                                       const std::filesystem::path& storeDir, const Context& ctx) {
  std::vector<PreparedTile> out;
  for (std::size_t i = 0; i < src.tiles.size(); ++i) {
    PreparedTile t = prepareTile(src.tiles[i], i, info, storeDir, ctx);
    for (std::size_t j = 0; j < out.size(); ++j) {
      const PreparedTile& o = out[j];
      if (t.row0 < o.row0 + o.rows && o.row0 < t.row0 + t.rows && t.col0 < o.col0 + o.cols &&
          o.col0 < t.col0 + t.cols) {
        overlap(ctx, info, j, o, i, t);
      }
    }
    out.push_back(std::move(t));
  }
  return out;
}

/// Checks one grid and returns the description that will be written: levels and patch size
/// from the options, scale 1 and offset 0 (the writer stores heights in metres as float32).
Prepared prepare(const GridSource& src, const WriteOptions& o,
                 const std::filesystem::path& storeDir, const Context& ctx) {
  GridInfo info = src.info;
  const std::string owner = "grid '" + info.name + "'";
  if (info.name.empty() || info.name.find('/') != std::string::npos || info.name == "." ||
      info.name == "..") {
    invalid(ctx, owner + ": name must be non-empty and contain no '/'");
  }
  const bool tiled = !src.tiles.empty();
  if (tiled && src.samples) invalid(ctx, owner + " has both samples and tiles, expected one");
  if (!tiled && !src.samples) invalid(ctx, owner + " has no samples");
  if (info.rows == 0 || info.cols == 0) {
    invalid(ctx, owner + " has " + std::to_string(info.rows) + "x" + std::to_string(info.cols) +
                     " samples, expected both > 0");
  }
  for (const auto& [field, v] : {std::pair{"rows", info.rows}, std::pair{"cols", info.cols}}) {
    if (v > kMaxGridSide) {
      invalid(ctx, owner + " has " + field + " " + std::to_string(v) + ", expected at most " +
                       std::to_string(kMaxGridSide) + " (the limit of docs/store-format.md)");
    }
  }
  if (const std::size_t n = patchCount(info.rows, info.cols, o.patchRows, o.patchCols);
      n > kMaxPatchesPerGrid) {
    invalid(ctx, owner + " has " + std::to_string(info.rows) + "x" + std::to_string(info.cols) +
                     " samples in patches of " + std::to_string(o.patchRows) + "x" +
                     std::to_string(o.patchCols) + ": " + std::to_string(n) +
                     " patches, expected at most " + std::to_string(kMaxPatchesPerGrid) +
                     " (use larger patches; the limit of docs/store-format.md)");
  }
  if (!tiled && (src.samples->rows() != info.rows || src.samples->cols() != info.cols)) {
    invalid(ctx, owner + " describes " + std::to_string(info.rows) + "x" +
                     std::to_string(info.cols) + " samples but its source holds " +
                     std::to_string(src.samples->rows()) + "x" +
                     std::to_string(src.samples->cols()));
  }
  const std::string unit = info.kind == GridKind::Dem ? " m" : " deg";
  const auto checkSpacing = [&](double s) {
    if (!(std::isfinite(s) && s > 0.0)) {
      invalid(ctx, owner + " has spacing " + core::number(s) + unit + ", expected > 0");
    }
  };
  checkSpacing(info.spacingX);
  checkSpacing(info.spacingY);
  for (const auto& [name, v] : {std::pair{"x0", info.x0}, std::pair{"y0", info.y0},
                                std::pair{"scale", info.scale}, std::pair{"offset", info.offset}}) {
    if (!std::isfinite(v)) {
      invalid(ctx, owner + " has " + name + " " + core::number(v) + ", expected a finite number");
    }
  }
  if (info.nodata && std::isnan(*info.nodata)) info.nodata.reset();
  if (info.nodata && std::isinf(*info.nodata)) {
    invalid(ctx, owner + " has nodata " + core::number(static_cast<double>(*info.nodata)) +
                     ", expected a finite number or none");
  }
  try {
    (void)bodyOf(info);
    if (info.kind == GridKind::Dem) (void)placementOf(info);
  } catch (const InvalidArgument& e) {
    invalid(ctx, owner + ": " + e.what());
  }

  const std::size_t maxLevels = format::maxLevels(info.rows, info.cols);
  info.patchRows = o.patchRows;
  info.patchCols = o.patchCols;
  if (o.levels == 0) {
    info.levels = 1;
    while (info.levelRows(info.levels - 1) > o.patchRows ||
           info.levelCols(info.levels - 1) > o.patchCols) {
      ++info.levels;
    }
  } else if (o.levels > maxLevels) {
    invalid(ctx, "options.levels is " + std::to_string(o.levels) + ", but " + owner +
                     " reaches 1x1 samples at " + std::to_string(maxLevels) + " levels");
  } else {
    info.levels = o.levels;
  }
  info.scale = 1.0;
  info.offset = 0.0;
  Prepared p;
  if (tiled) p.tiles = prepareTiles(src, info, storeDir, ctx);
  p.info = std::move(info);
  return p;
}

void writeAttributes(hid_t g, const GridInfo& info, bool tiled, bool statistics,
                     const Context& ctx) {
  using namespace hdf5;
  writeInt32s(g, format::kFormatVersion,
              {kFormatVersionMajor,
               std::max(kFormatVersionMinor, format::gridFormatMinor(info, tiled, statistics))},
              ctx);
  writeString(g, format::kKind,
              std::string(info.kind == GridKind::Dem ? format::kDem : format::kPlanet), ctx);
  writeUInt64(g, format::kRows, info.rows, ctx);
  writeUInt64(g, format::kCols, info.cols, ctx);
  writeDouble(g, format::kX0, info.x0, ctx);
  writeDouble(g, format::kY0, info.y0, ctx);
  writeDoubles(g, format::kSpacing, {info.spacingX, info.spacingY}, ctx);
  writeString(g, format::kUnits, info.units, ctx);
  writeString(g, format::kSampleType, std::string(format::toString(format::SampleType::Float32)),
              ctx);
  writeDouble(g, format::kScale, info.scale, ctx);
  writeDouble(g, format::kOffset, info.offset, ctx);
  // Always present: NaN says "no nodata value; missing samples are stored as NaN".
  writeFloat(g, format::kNodata, info.nodata.value_or(kNan), ctx);
  writeString(g, format::kBody, info.bodyName, ctx);
  writeDouble(g, format::kEquatorialRadius, info.equatorialRadius, ctx);
  writeDouble(g, format::kPolarRadius, info.polarRadius, ctx);
  writeString(
      g, format::kLatitudeType,
      std::string(info.latitudeType == topo::LatitudeType::Planetocentric ? format::kPlanetocentric
                                                                          : format::kPlanetodetic),
      ctx);
  writeUInt64(g, format::kLevels, info.levels, ctx);
  writeUInt64s(g, format::kPatchShape, {info.patchRows, info.patchCols}, ctx);
  if (!info.provenance.empty()) writeString(g, format::kProvenance, info.provenance, ctx);
  if (info.kind != GridKind::Dem) return;
  const PlacementInfo& p = info.placement;
  writeString(g, format::kPlacement, std::string(placementKindName(p.kind)), ctx);
  switch (p.kind) {
    case PlacementInfo::Kind::LocalTangentPlane:
      writeDouble(g, format::kOriginLat, p.originLatDeg, ctx);
      writeDouble(g, format::kOriginLon, p.originLonDeg, ctx);
      writeDouble(g, format::kOriginHeight, p.originHeight, ctx);
      writeDouble(g, format::kHeading, p.headingDeg, ctx);
      break;
    case PlacementInfo::Kind::PolarStereographic:
      writeInt32(g, format::kPole, p.pole >= 0 ? 1 : -1, ctx);
      if (p.latTrueScaleDeg) writeDouble(g, format::kLatTrueScale, *p.latTrueScaleDeg, ctx);
      if (p.scaleFactor) writeDouble(g, format::kScaleFactor, *p.scaleFactor, ctx);
      writeDouble(g, format::kLonCentre, p.lonCentreDeg, ctx);
      writeDouble(g, format::kFalseEasting, p.falseEasting, ctx);
      writeDouble(g, format::kFalseNorthing, p.falseNorthing, ctx);
      break;
    case PlacementInfo::Kind::Equirectangular:
      writeDouble(g, format::kProjectionRadius, p.projectionRadius, ctx);
      if (p.latTrueScaleDeg) writeDouble(g, format::kLatTrueScale, *p.latTrueScaleDeg, ctx);
      writeDouble(g, format::kLonCentre, p.lonCentreDeg, ctx);
      writeDouble(g, format::kLatOrigin, p.latOriginDeg, ctx);
      break;
    case PlacementInfo::Kind::TransverseMercator:
      writeDouble(g, format::kLonCentre, p.lonCentreDeg, ctx);
      writeDouble(g, format::kLatOrigin, p.latOriginDeg, ctx);
      writeDouble(g, format::kScaleFactor,
                  p.scaleFactor.value_or(std::numeric_limits<double>::quiet_NaN()), ctx);
      writeDouble(g, format::kFalseEasting, p.falseEasting, ctx);
      writeDouble(g, format::kFalseNorthing, p.falseNorthing, ctx);
      break;
    case PlacementInfo::Kind::Projected: writeString(g, format::kCrsWkt, p.crs, ctx); break;
  }
}

/// Reports progress by samples written, at most about once per 1/1000 of the work.
class Progress {
 public:
  Progress(const WriteOptions& o, double total) : fn_(o.progress), total_(total) {}
  void advance(double samples, std::string_view what) {
    done_ += samples;
    const double f = std::min(1.0, done_ / total_);
    if (fn_ && (f - last_ >= 1e-3 || what != lastWhat_)) {
      last_ = f;
      lastWhat_ = what;
      fn_(f, what);
    }
  }
  void finish() const {
    if (fn_) fn_(1.0, "done");
  }

 private:
  const ProgressFn& fn_;
  double total_;
  double done_ = 0.0, last_ = -1.0;
  std::string lastWhat_;
};

/// A group (no modification times: rewriting the same input changes no content).
hdf5::Group createGroup(hid_t parent, const std::string& name, const Context& ctx) {
  const hdf5::Lock lock;
  const std::string what = "cannot create group '" + name + "'";
  const hdf5::PropertyList gcpl(hdf5::check(H5Pcreate(H5P_GROUP_CREATE), ctx, what));
  hdf5::check(H5Pset_obj_track_times(gcpl.get(), 0), ctx, what);
  return hdf5::Group(hdf5::check(
      H5Gcreate2(parent, name.c_str(), H5P_DEFAULT, gcpl.get(), H5P_DEFAULT), ctx, what));
}

void checkCancel(const WriteOptions& o, const Context& ctx) {
  if (o.cancel != nullptr && o.cancel->load()) fail(ctx, "cancelled");
}

/// Missing-sample test in the stored domain.
struct Missing {
  std::optional<float> nodata;
  [[nodiscard]] bool operator()(float v) const noexcept {
    return std::isnan(v) || (nodata && v == *nodata);
  }
  [[nodiscard]] float stored() const noexcept { return nodata.value_or(kNan); }
};

/// Level 0's valid heights in one block: the parts of HeightStatistics.
struct BlockStats {
  double min = std::numeric_limits<double>::infinity();
  double max = -std::numeric_limits<double>::infinity();
  double sum = 0.0;
  std::uint64_t count = 0;
};

class LevelWriter {
 public:
  LevelWriter(hid_t group, const GridInfo& info, std::size_t level, const WriteOptions& o,
              const Context& ctx)
      : LevelWriter(group, info, format::levelName(level),
                    {info.levelRows(level), info.levelCols(level)}, format::chunkShape(info, level),
                    o, ctx) {}

  LevelWriter(hid_t group, const GridInfo& info, std::string name,
              const std::array<hsize_t, 2>& shape, const std::array<hsize_t, 2>& chunk,
              const WriteOptions& o, const Context& ctx)
      : info_(info), ctx_(ctx), name_(std::move(name)) {
    const hdf5::Lock lock;
    const std::string what = "cannot create grid '" + info.name + "' dataset '" + name_ + "'";
    const hdf5::Dataspace space(hdf5::check(H5Screate_simple(2, shape.data(), nullptr), ctx, what));
    const hdf5::PropertyList dcpl(hdf5::check(H5Pcreate(H5P_DATASET_CREATE), ctx, what));
    hdf5::check(H5Pset_chunk(dcpl.get(), 2, chunk.data()), ctx, what);
    // No modification times in object headers: rewriting the same input changes no content.
    hdf5::check(H5Pset_obj_track_times(dcpl.get(), 0), ctx, what);
    const float fill = Missing{info.nodata}.stored();
    hdf5::check(H5Pset_fill_value(dcpl.get(), H5T_NATIVE_FLOAT, &fill), ctx, what);
    if (o.codec == Codec::Zfp) {
      // H5Z-ZFP's generic interface: mode 5 is reversible. At H5Dcreate the plugin turns
      // these values into its stored form (its version and ZFP's header for this chunk
      // shape), which is what decodes the chunks encodeChunk() writes.
      const std::array<unsigned, 6> zfpReversible{5, 0, 0, 0, 0, 0};
      hdf5::check(H5Pset_filter(dcpl.get(), kZfpFilterId, H5Z_FLAG_MANDATORY, zfpReversible.size(),
                                zfpReversible.data()),
                  ctx, what);
    } else if (o.deflate > 0) {
      hdf5::check(H5Pset_shuffle(dcpl.get()), ctx, what);
      hdf5::check(H5Pset_deflate(dcpl.get(), static_cast<unsigned>(o.deflate)), ctx, what);
    }
    // Every write covers whole chunks (clipped at the level's edge), so no chunk cache is
    // needed here either.
    const hdf5::PropertyList dapl(hdf5::check(H5Pcreate(H5P_DATASET_ACCESS), ctx, what));
    hdf5::check(H5Pset_chunk_cache(dapl.get(), 0, 0, 1.0), ctx, what);
    ds_ = hdf5::Dataset(hdf5::check(H5Dcreate2(group, name_.c_str(), H5T_IEEE_F32LE, space.get(),
                                               H5P_DEFAULT, dcpl.get(), dapl.get()),
                                    ctx, what));
  }

  [[nodiscard]] hid_t id() const noexcept { return ds_.get(); }

  /// Writes one chunk, already encoded (encodeChunk()), at element offset (row0, col0).
  void writeChunk(std::size_t row0, std::size_t col0,
                  const std::vector<unsigned char>& bytes) const {
    const hdf5::Lock lock;
    const std::array<hsize_t, 2> offset{row0, col0};
    hdf5::check(
        H5Dwrite_chunk(ds_.get(), H5P_DEFAULT, 0, offset.data(), bytes.size(), bytes.data()), ctx_,
        "cannot write grid '" + info_.name + "' dataset '" + name_ + "'");
  }

  /// Reads rows [row0, row0 + nr) × columns [col0, col0 + nc), already written, into `out`
  /// (row-major, as stored: missing samples are the stored nodata value).
  void read(std::size_t row0, std::size_t col0, std::size_t nr, std::size_t nc, float* out) const {
    const hdf5::Lock lock;
    const std::string what = "cannot read back grid '" + info_.name + "' dataset '" + name_ + "'";
    const std::array<hsize_t, 2> start{row0, col0}, count{nr, nc};
    const hdf5::Dataspace fileSpace(hdf5::check(H5Dget_space(ds_.get()), ctx_, what));
    hdf5::check(H5Sselect_hyperslab(fileSpace.get(), H5S_SELECT_SET, start.data(), nullptr,
                                    count.data(), nullptr),
                ctx_, what);
    const hdf5::Dataspace memSpace(
        hdf5::check(H5Screate_simple(2, count.data(), nullptr), ctx_, what));
    hdf5::check(
        H5Dread(ds_.get(), H5T_NATIVE_FLOAT, memSpace.get(), fileSpace.get(), H5P_DEFAULT, out),
        ctx_, what);
  }

  void close() {
    const hdf5::Lock lock;
    hdf5::check(H5Dclose(ds_.release()), ctx_,
                "cannot close grid '" + info_.name + "' dataset '" + name_ + "'");
  }

 private:
  const GridInfo& info_;
  const Context& ctx_;
  std::string name_;
  hdf5::Dataset ds_;
};

/// Level 0 of one chunk: the source's heights, missing samples as the stored nodata value.
/// Infinite heights are refused (they are neither data nor a declared nodata).
void level0Block(const topo::SampleSource& src, const GridInfo& info, std::size_t r0,
                 std::size_t c0, std::size_t nr, std::size_t nc, std::vector<float>& out,
                 const Context& ctx) {
  out.resize(nr * nc);
  src.readWindow(r0, c0, nr, nc, out);
  const Missing missing{info.nodata};
  for (std::size_t i = 0; i < out.size(); ++i) {
    float& v = out[i];
    if (missing(v)) {
      v = missing.stored();
    } else if (std::isinf(v)) {
      invalid(ctx, "grid '" + info.name + "' sample (" + std::to_string(r0 + i / nc) + ", " +
                       std::to_string(c0 + i % nc) + ") is " +
                       core::number(static_cast<double>(v)) + ", expected a finite height or NaN");
    }
  }
}

/// Level k ≥ 1 of one chunk: topo::downsample2x2() of level k−1 (read back from the file),
/// the one definition of the format's pyramid rule.
using FineReader = std::function<void(std::size_t, std::size_t, std::size_t, std::size_t, float*)>;

void coarseBlock(const FineReader& below, const GridInfo& info, std::size_t level, std::size_t r0,
                 std::size_t c0, std::size_t nr, std::size_t nc, std::vector<float>& fine,
                 std::vector<float>& out) {
  const std::size_t fineRows = info.levelRows(level - 1), fineCols = info.levelCols(level - 1);
  const std::size_t fr0 = 2 * r0, fc0 = 2 * c0;
  const std::size_t fnr = std::min(2 * nr, fineRows - fr0);
  const std::size_t fnc = std::min(2 * nc, fineCols - fc0);
  fine.resize(fnr * fnc);
  below(fr0, fc0, fnr, fnc, fine.data());
  const Missing missing{info.nodata};
  out.resize(nr * nc);
  topo::downsample2x2(fine.data(), fnr, fnc, out.data(), nr, nc, missing, missing.stored());
}

/// Level 0 of a tiled grid's block as stored: each tile's samples (missing as the stored
/// nodata value), the stored nodata value where no tile lies.
void mosaicBlock(const Prepared& p, std::size_t r0, std::size_t c0, std::size_t nr, std::size_t nc,
                 float* out, const Context& ctx) {
  const Missing missing{p.info.nodata};
  std::fill(out, out + nr * nc, missing.stored());
  std::vector<float> buffer;
  for (const PreparedTile& t : p.tiles) {
    const std::size_t a0 = std::max(r0, t.row0), a1 = std::min(r0 + nr, t.row0 + t.rows);
    const std::size_t b0 = std::max(c0, t.col0), b1 = std::min(c0 + nc, t.col0 + t.cols);
    if (a0 >= a1 || b0 >= b1) continue;
    const std::size_t tr = a1 - a0, tc = b1 - b0;
    if (t.samples) {
      level0Block(*t.samples, p.info, a0 - t.row0, b0 - t.col0, tr, tc, buffer, ctx);
    } else {
      buffer.resize(tr * tc);
      t.external->readWindow(t.grid, 0, a0 - t.row0, b0 - t.col0, tr, tc, buffer);
      for (float& v : buffer) {
        if (std::isnan(v)) v = missing.stored();
      }
    }
    for (std::size_t r = 0; r < tr; ++r) {
      std::copy_n(buffer.begin() + static_cast<std::ptrdiff_t>(r * tc), tc,
                  out + (a0 - r0 + r) * nc + (b0 - c0));
    }
  }
}

// ---- parallel chunk encoding ------------------------------------------------------------------
// Chunks are computed (source reads, 2×2 means) and encoded (HDF5's shuffle then deflate
// filters, applied here with libdeflate) by worker threads, then written in a fixed order with
// H5Dwrite_chunk under the HDF5 lock. The file does not depend on the thread count.

static_assert(std::endian::native == std::endian::little,
              "chunks are written as raw little-endian float32 (H5T_IEEE_F32LE)");

unsigned threadCount(const WriteOptions& o) {
  if (o.threads > 0) return o.threads;
  if (o.executor != nullptr) return o.executor->concurrency() + 1;
  return std::max(1U, std::thread::hardware_concurrency());
}

/// Runs f(0) … f(n − 1) on up to threadCount(o) threads, the caller's included: on the
/// options' executor, or on a pool made for the call; rethrows the first exception once all
/// have stopped.
void parallelFor(std::size_t n, const WriteOptions& o, const std::function<void(std::size_t)>& f) {
  core::parallelFor(o.executor, n, f, threadCount(o));
}

/// A chunk of cr × cc floats as H5Z-ZFP (filter 32013) stores it in reversible mode: one bare
/// ZFP stream, no header (the header is in the filter's stored values). Like the plugin, a
/// chunk with a dimension of 1 is one-dimensional. Lossless for every float, NaN included.
std::vector<unsigned char> zfpEncode(std::vector<float>& full, std::size_t cr, std::size_t cc) {
  // Per thread, as for deflate below. zfp_stream_open allocates nothing but the stream.
  struct Stream {
    zfp_stream* z = zfp_stream_open(nullptr);
    Stream() {
      if (z != nullptr) zfp_stream_set_reversible(z);
    }
    Stream(const Stream&) = delete;
    Stream& operator=(const Stream&) = delete;
    Stream(Stream&&) = delete;
    Stream& operator=(Stream&&) = delete;
    ~Stream() { zfp_stream_close(z); }
  };
  thread_local Stream stream;
  if (stream.z == nullptr) throw StoreError("store::writeStore(): cannot open a ZFP stream");
  zfp_field* field = cr == 1 || cc == 1 ? zfp_field_1d(full.data(), zfp_type_float, cr * cc)
                                        : zfp_field_2d(full.data(), zfp_type_float, cc, cr);
  if (field == nullptr) throw StoreError("store::writeStore(): cannot describe a ZFP field");
  std::vector<unsigned char> out(zfp_stream_maximum_size(stream.z, field));
  bitstream* bits = stream_open(out.data(), out.size());
  zfp_stream_set_bit_stream(stream.z, bits);
  zfp_stream_rewind(stream.z);
  const std::size_t size = zfp_compress(stream.z, field);
  stream_close(bits);
  zfp_field_free(field);
  if (size == 0) throw StoreError("store::writeStore(): cannot compress a chunk with ZFP");
  out.resize(size);
  return out;
}

/// One chunk as HDF5 stores it: the block padded to the full chunk shape with `fill`, then
/// ZFP-encoded (Codec::Zfp) or, with deflate, byte-shuffled (H5Z_FILTER_SHUFFLE) and
/// zlib-compressed (H5Z_FILTER_DEFLATE).
std::vector<unsigned char> encodeChunk(const float* block, std::size_t nr, std::size_t nc,
                                       const std::array<hsize_t, 2>& chunk, float fill,
                                       const WriteOptions& o) {
  const std::size_t cr = chunk[0], cc = chunk[1], n = cr * cc;
  const int deflate = o.deflate;
  std::vector<float> full(n, fill);
  for (std::size_t r = 0; r < nr; ++r) {
    std::copy_n(block + r * nc, nc, full.begin() + static_cast<std::ptrdiff_t>(r * cc));
  }
  if (o.codec == Codec::Zfp) return zfpEncode(full, cr, cc);
  std::vector<unsigned char> raw(n * sizeof(float));
  std::memcpy(raw.data(), full.data(), raw.size());
  if (deflate <= 0) return raw;
  std::vector<unsigned char> shuffled(raw.size());
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t b = 0; b < sizeof(float); ++b)
      shuffled[b * n + i] = raw[i * sizeof(float) + b];
  }
  // One compressor per thread and level (libdeflate: zlib-format output, which is what
  // HDF5's deflate filter reads, at several times zlib's speed).
  struct Compressor {
    int level = -1;
    libdeflate_compressor* c = nullptr;
    Compressor() = default;
    Compressor(const Compressor&) = delete;
    Compressor& operator=(const Compressor&) = delete;
    Compressor(Compressor&&) = delete;
    Compressor& operator=(Compressor&&) = delete;
    ~Compressor() { libdeflate_free_compressor(c); }
  };
  thread_local Compressor comp;
  if (comp.level != deflate) {
    libdeflate_free_compressor(comp.c);
    comp.c = libdeflate_alloc_compressor(deflate);
    comp.level = comp.c != nullptr ? deflate : -1;
  }
  if (comp.c == nullptr) throw StoreError("store::writeStore(): cannot allocate a compressor");
  std::vector<unsigned char> out(libdeflate_zlib_compress_bound(comp.c, shuffled.size()));
  const std::size_t size =
      libdeflate_zlib_compress(comp.c, shuffled.data(), shuffled.size(), out.data(), out.size());
  if (size == 0) throw StoreError("store::writeStore(): cannot compress a chunk");
  out.resize(size);
  return out;
}

/// Writes rows [r0, r0 + nr) of a dataset whose chunks are `chunk`, chunk column by chunk
/// column: block(c0, nc, out) fills the nr×nc block at column c0 (on a worker thread), the
/// encoded chunks are then written in order. With groupChunks > 0 the band goes in column
/// tiles of that many chunks, each computed, encoded and written before the next, and
/// beforeGroup(c0, nc) (if set) runs first for the tile's columns [c0, c0 + nc) on the calling
/// thread. The file does not depend on the grouping.
void writeBandChunks(
    const LevelWriter& writer, const std::array<hsize_t, 2>& chunk, std::size_t r0, std::size_t nr,
    std::size_t cols, float fill, const WriteOptions& o,
    const std::function<void(std::size_t, std::size_t, std::vector<float>&)>& block,
    Progress& progress, const std::string& what, const Context& ctx, std::size_t groupChunks = 0,
    const std::function<void(std::size_t, std::size_t)>& beforeGroup = {}) {
  const std::size_t cc = chunk[1];
  const std::size_t n = (cols + cc - 1) / cc;
  const std::size_t group = groupChunks == 0 ? n : std::min(groupChunks, n);
  for (std::size_t g0 = 0; g0 < n; g0 += group) {
    const std::size_t gn = std::min(group, n - g0);
    if (beforeGroup) beforeGroup(g0 * cc, std::min(gn * cc, cols - g0 * cc));
    std::vector<std::vector<unsigned char>> encoded(gn);
    parallelFor(gn, o, [&](std::size_t i) {
      checkCancel(o, ctx);  // before every chunk
      std::vector<float> b;
      const std::size_t c0 = (g0 + i) * cc, nc = std::min(cc, cols - c0);
      block(c0, nc, b);
      encoded[i] = encodeChunk(b.data(), nr, nc, chunk, fill, o);
    });
    for (std::size_t i = 0; i < gn; ++i) {
      const std::size_t c0 = (g0 + i) * cc;
      writer.writeChunk(r0, c0, encoded[i]);
      std::vector<unsigned char>().swap(encoded[i]);
      progress.advance(static_cast<double>(nr * std::min(cc, cols - c0)), what);
    }
  }
}

// ---- the writer's memory (WriteOptions::memoryBudgetBytes, docs/import.md "Memory") --------
// Estimates of the buffers the writer itself holds, in units of one chunk C of floats:
// - each thread: a block (C), its 4 fine samples (4C), encodeChunk's padded, raw, shuffled and
//   compressed copies (4C, the compressor's bound rounded up): 10C;
// - whole-width bands: per level a held band, the pair it joins (twice), and the band being
//   made (4 bands of that level), and level 0's encoded chunks (5/4 of a band);
// - column tiles of T chunks: the fine tile read back (4TC) and its encoded chunks (5/4 TC).

constexpr std::size_t kScratchChunksPerThread = 10;

std::size_t encodedBound(std::size_t bytes) { return bytes + bytes / 4; }

std::size_t levelCount(const GridInfo& info, const WriteOptions& o) {
  if (o.levels != 0) return std::min(o.levels, format::maxLevels(info.rows, info.cols));
  std::size_t levels = 1;
  while (info.levelRows(levels - 1) > o.patchRows || info.levelCols(levels - 1) > o.patchCols) {
    ++levels;
  }
  return levels;
}

WriterMemoryPlan planMemory(const GridInfo& info, std::size_t levels, const WriteOptions& o) {
  const std::size_t chunk = o.patchRows * o.patchCols * sizeof(float);
  const std::size_t perThread = kScratchChunksPerThread * chunk;
  const std::size_t perTileChunk = 4 * chunk + encodedBound(chunk);
  WriterMemoryPlan plan;
  plan.threads = threadCount(o);
  plan.minimumBytes = perTileChunk + perThread;  // one chunk column, one thread
  const auto band = [&](std::size_t k) {
    return std::min(o.patchRows, info.levelRows(k)) * info.levelCols(k) * sizeof(float);
  };
  plan.untiledBytes = encodedBound(band(0)) + plan.threads * perThread;
  for (std::size_t k = 0; k < levels; ++k) plan.untiledBytes += 4 * band(k);
  std::size_t budget = o.memoryBudgetBytes;
  if (budget == kDefaultMemoryBudget) budget = std::max(budget, plan.minimumBytes);
  if (budget == 0 || plan.untiledBytes <= budget) {
    plan.plannedBytes = plan.untiledBytes;
    return plan;
  }
  // Column tiles: every thread the budget allows beside one tile chunk, then the widest tile.
  const std::size_t room = budget > perTileChunk ? budget - perTileChunk : 0;
  plan.threads = std::clamp<std::size_t>(room / perThread, 1, plan.threads);
  const std::size_t chunkCols = (info.cols + o.patchCols - 1) / o.patchCols;
  const std::size_t scratch = plan.threads * perThread;
  const std::size_t fits = budget > scratch ? (budget - scratch) / perTileChunk : 0;
  plan.tileChunks = std::clamp<std::size_t>(fits, 1, chunkCols);
  plan.plannedBytes = plan.tileChunks * perTileChunk + scratch;
  return plan;
}

/// Builds the pyramid band by band: a band of level k (up to patchRows rows, full width) is
/// written, then kept until the band after it arrives, and the two make one band of level
/// k + 1. Each level holds at most two bands in memory. With tileChunks > 0 (the memory
/// budget is smaller than that) no band is kept: each is built in column tiles of that many
/// chunks, and a band of level k + 1 reads the two bands below back from the file (level 1 of
/// a tiled grid: from its tiles), tile by tile. Both ways give the same file.
class Pyramid {
 public:
  Pyramid(hid_t group, const Prepared& p, const WriteOptions& o, std::size_t tileChunks,
          Progress& progress, const Context& ctx)
      : p_(p),
        info_(p.info),
        o_(o),
        tileChunks_(tileChunks),
        progress_(progress),
        ctx_(ctx),
        tiled_(!p.tiles.empty()),
        pending_(p.info.levels) {
    writers_.reserve(info_.levels);
    for (std::size_t level = 0; level < info_.levels; ++level) {
      if (level == 0 && tiled_) {
        writers_.emplace_back(std::nullopt);
      } else {
        writers_.emplace_back(std::in_place, group, info_, level, o, ctx);
      }
    }
  }

  /// Level-0 rows [r0, r0 + nr), produced by block(r0, c0, nr, nc, out) per chunk column.
  void level0Band(std::size_t r0, std::size_t nr,
                  const std::function<void(std::size_t, std::size_t, std::size_t, std::size_t,
                                           std::vector<float>&)>& block) {
    checkCancel(o_, ctx_);
    if (!writers_[0] && info_.levels == 1) return;  // tiled, no pyramid: nothing to build
    const std::size_t cols = info_.cols;
    if (tileChunks_ > 0) {
      level0Tiled(r0, nr, block);
      return;
    }
    Band band{r0, nr, std::vector<float>(nr * cols)};
    const auto fill = [&](std::size_t c0, std::size_t nc, std::vector<float>& out) {
      block(r0, c0, nr, nc, out);
      for (std::size_t r = 0; r < nr; ++r) {
        std::copy_n(out.begin() + static_cast<std::ptrdiff_t>(r * nc), nc,
                    band.data.begin() + static_cast<std::ptrdiff_t>(r * cols + c0));
      }
    };
    if (writers_[0]) {
      writeBandChunks(*writers_[0], format::chunkShape(info_, 0), r0, nr, cols,
                      Missing{info_.nodata}.stored(), o_, fill, progress_,
                      "grid '" + info_.name + "' level 0", ctx_);
    } else {
      // Tiled: level 0 lives in the tiles; the mosaic's band is only read for level 1.
      const std::size_t cc = info_.patchCols;
      parallelFor((cols + cc - 1) / cc, o_, [&](std::size_t k) {
        std::vector<float> b;
        fill(k * cc, std::min(cc, cols - k * cc), b);
      });
    }
    push(1, std::move(band));
  }

  void close() {
    for (auto& w : writers_) {
      if (w) w->close();
    }
  }

 private:
  /// level0Band() in column tiles, keeping nothing: level 1 reads the band back.
  void level0Tiled(std::size_t r0, std::size_t nr,
                   const std::function<void(std::size_t, std::size_t, std::size_t, std::size_t,
                                            std::vector<float>&)>& block) {
    const std::size_t cols = info_.cols;
    const auto fill = [&](std::size_t c0, std::size_t nc, std::vector<float>& out) {
      block(r0, c0, nr, nc, out);
    };
    if (writers_[0]) {
      writeBandChunks(*writers_[0], format::chunkShape(info_, 0), r0, nr, cols,
                      Missing{info_.nodata}.stored(), o_, fill, progress_,
                      "grid '" + info_.name + "' level 0", ctx_, tileChunks_);
    } else {
      // Tiled grid: the blocks only feed the statistics (and check the samples).
      const std::size_t cc = info_.patchCols;
      parallelFor((cols + cc - 1) / cc, o_, [&](std::size_t k) {
        std::vector<float> b;
        fill(k * cc, std::min(cc, cols - k * cc), b);
      });
    }
    push(1, Band{r0, nr, {}});
  }

  struct Band {
    std::size_t row0 = 0, rows = 0;
    std::vector<float> data;  // rows × levelCols, row-major
  };

  /// A band of level `level − 1` arrives for level `level`.
  void push(std::size_t level, Band fine) {
    if (level >= info_.levels) return;
    std::optional<Band>& held = pending_[level];
    const bool last = fine.row0 + fine.rows == info_.levelRows(level - 1);
    const bool evenBand = (fine.row0 / info_.patchRows) % 2 == 0;
    if (evenBand && !last) {
      held = std::move(fine);
      return;
    }
    Band pair;
    if (held) {
      pair = std::move(*held);
      held.reset();
      pair.rows += fine.rows;
      pair.data.insert(pair.data.end(), fine.data.begin(), fine.data.end());
    } else {
      pair = std::move(fine);
    }
    coarseBand(level, pair);
  }

  /// Level `level`'s band made of fine rows [fine.row0, fine.row0 + fine.rows): from
  /// fine.data, or (column tiles) read back tile by tile.
  void coarseBand(std::size_t level, const Band& fine) {
    checkCancel(o_, ctx_);
    const std::size_t fineCols = info_.levelCols(level - 1);
    const std::size_t cols = info_.levelCols(level);
    const std::size_t r0 = fine.row0 / 2, nr = (fine.rows + 1) / 2;
    const bool keep = tileChunks_ == 0;
    Band band{r0, nr, keep ? std::vector<float>(nr * cols) : std::vector<float>{}};
    // Column tiles: fine columns [tileCol0, tileCol0 + tileCols) of the band, read back.
    std::vector<float> tile;
    std::size_t tileCol0 = 0, tileCols = 0;
    const auto readTile = [&](std::size_t c0, std::size_t nc) {
      tileCol0 = 2 * c0;
      tileCols = std::min(2 * nc, fineCols - tileCol0);
      tile.resize(fine.rows * tileCols);
      if (writers_[level - 1]) {
        writers_[level - 1]->read(fine.row0, tileCol0, fine.rows, tileCols, tile.data());
      } else {
        mosaicBlock(p_, fine.row0, tileCol0, fine.rows, tileCols, tile.data(), ctx_);
      }
    };
    const FineReader reader = [&](std::size_t fr0, std::size_t fc0, std::size_t fnr,
                                  std::size_t fnc, float* data) {
      const float* from = keep ? fine.data.data() : tile.data();
      const std::size_t stride = keep ? fineCols : tileCols, col0 = keep ? 0 : tileCol0;
      for (std::size_t r = 0; r < fnr; ++r) {
        std::copy_n(from + (fr0 - fine.row0 + r) * stride + (fc0 - col0), fnc, data + r * fnc);
      }
    };
    const auto fill = [&](std::size_t c0, std::size_t nc, std::vector<float>& out) {
      std::vector<float> scratch;
      coarseBlock(reader, info_, level, r0, c0, nr, nc, scratch, out);
      if (!keep) return;
      for (std::size_t r = 0; r < nr; ++r) {
        std::copy_n(out.begin() + static_cast<std::ptrdiff_t>(r * nc), nc,
                    band.data.begin() + static_cast<std::ptrdiff_t>(r * cols + c0));
      }
    };
    writeBandChunks(*writers_[level], format::chunkShape(info_, level), r0, nr, cols,
                    Missing{info_.nodata}.stored(), o_, fill, progress_,
                    "grid '" + info_.name + "' level " + std::to_string(level), ctx_, tileChunks_,
                    keep ? std::function<void(std::size_t, std::size_t)>{} : readTile);
    std::vector<float>().swap(tile);
    push(level + 1, std::move(band));
  }

  const Prepared& p_;
  const GridInfo& info_;
  const WriteOptions& o_;
  std::size_t tileChunks_;
  Progress& progress_;
  const Context& ctx_;
  bool tiled_;
  std::vector<std::optional<LevelWriter>> writers_;
  std::vector<std::optional<Band>> pending_;
};

/// Writes tile i of a tiled grid: its group tiles/<i> with its bounds and either its level0
/// dataset or the reference to its external grid.
void writeTile(hid_t tilesGroup, std::size_t i, const Prepared& p, const WriteOptions& o,
               Progress& progress, const Context& ctx) {
  const GridInfo& info = p.info;
  const PreparedTile& t = p.tiles[i];
  const std::string what = "grid '" + info.name + "' tile " + std::to_string(i);
  hdf5::Group tg = createGroup(tilesGroup, std::to_string(i), ctx);
  hdf5::writeUInt64(tg.get(), format::kTileRow0, t.row0, ctx);
  hdf5::writeUInt64(tg.get(), format::kTileCol0, t.col0, ctx);
  hdf5::writeUInt64(tg.get(), format::kTileRows, t.rows, ctx);
  hdf5::writeUInt64(tg.get(), format::kTileCols, t.cols, ctx);
  if (t.external) {
    hdf5::writeString(tg.get(), format::kExternalFile, t.file, ctx);
    hdf5::writeString(tg.get(), format::kExternalGrid, t.grid, ctx);
  } else {
    const std::array<hsize_t, 2> chunk = format::tileChunkShape(info, t.rows, t.cols);
    LevelWriter writer(tg.get(), info, "level0", {t.rows, t.cols}, chunk, o, ctx);
    for (std::size_t r0 = 0; r0 < t.rows; r0 += info.patchRows) {
      const std::size_t nr = std::min(info.patchRows, t.rows - r0);
      checkCancel(o, ctx);
      writeBandChunks(
          writer, chunk, r0, nr, t.cols, Missing{info.nodata}.stored(), o,
          [&](std::size_t c0, std::size_t nc, std::vector<float>& out) {
            level0Block(*t.samples, info, r0, c0, nr, nc, out, ctx);
          },
          progress, what, ctx);
    }
    writer.close();
  }
  const hdf5::Lock lock;
  hdf5::check(H5Gclose(tg.release()), ctx, "cannot close the group of " + what);
}

/// Writes the tiles of a tiled grid: tile_count and a group tiles/<i> per tile.
void writeTiles(hid_t group, const Prepared& p, const WriteOptions& o, Progress& progress,
                const Context& ctx) {
  hdf5::writeUInt64(group, format::kTileCount, p.tiles.size(), ctx);
  hdf5::Group tilesGroup = createGroup(group, format::kTiles, ctx);
  for (std::size_t i = 0; i < p.tiles.size(); ++i) {
    writeTile(tilesGroup.get(), i, p, o, progress, ctx);
  }
  const hdf5::Lock lock;
  hdf5::check(H5Gclose(tilesGroup.release()), ctx,
              "cannot close group '/grids/" + p.info.name + "/tiles'");
}

void writeGrid(hid_t grids, const GridSource& src, const Prepared& p, const WriteOptions& o,
               Progress& progress, const Context& ctx) {
  const GridInfo& info = p.info;
  // The threads the memory budget allows (all of them unless it forces column tiles).
  const WriterMemoryPlan plan = planMemory(info, info.levels, o);
  WriteOptions oPlanned = o;
  oPlanned.threads = static_cast<unsigned>(plan.threads);
  const bool tiled = !p.tiles.empty();
  hdf5::Group group = createGroup(grids, info.name, ctx);
  writeAttributes(group.get(), info, tiled, o.statistics, ctx);
  if (tiled) writeTiles(group.get(), p, o, progress, ctx);
  // Level 0's statistics, per block keyed by its position and summed in that order (band by
  // band, then along the band), so that they do not depend on the threads.
  std::mutex statsMutex;
  std::map<std::pair<std::size_t, std::size_t>, BlockStats> blockStats;
  BlockStats all;
  const auto sumBand = [&] {
    for (const auto& [key, b] : blockStats) {
      all.min = std::min(all.min, b.min);
      all.max = std::max(all.max, b.max);
      all.sum += b.sum;
      all.count += b.count;
    }
    blockStats.clear();
  };
  const Missing missing{info.nodata};
  const auto collect = [&](std::size_t br0, std::size_t c0, const std::vector<float>& out) {
    if (!o.statistics) return;
    BlockStats b;
    for (const float v : out) {
      if (missing(v)) continue;
      const auto d = static_cast<double>(v);
      b.min = std::min(b.min, d);
      b.max = std::max(b.max, d);
      b.sum += d;
      ++b.count;
    }
    const std::lock_guard lock(statsMutex);
    blockStats[{br0, c0}] = b;
  };
  {
    Pyramid pyramid(group.get(), p, oPlanned, plan.tileChunks, progress, ctx);
    // Level 0 band by band; each band flows up the pyramid as soon as its pair is complete.
    // The source and the progress callback run without the HDF5 lock: the source may itself
    // be a pager reading another store.
    for (std::size_t r0 = 0; r0 < info.rows; r0 += info.patchRows) {
      const std::size_t nr = std::min(info.patchRows, info.rows - r0);
      pyramid.level0Band(r0, nr,
                         [&](std::size_t br0, std::size_t c0, std::size_t bnr, std::size_t nc,
                             std::vector<float>& out) {
                           if (tiled) {
                             out.resize(bnr * nc);
                             mosaicBlock(p, br0, c0, bnr, nc, out.data(), ctx);
                           } else {
                             level0Block(*src.samples, info, br0, c0, bnr, nc, out, ctx);
                           }
                           collect(br0, c0, out);
                         });
      sumBand();
    }
    pyramid.close();
  }
  if (o.statistics) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const bool none = all.count == 0;
    hdf5::writeDouble(group.get(), format::kHeightMin, none ? nan : all.min, ctx);
    hdf5::writeDouble(group.get(), format::kHeightMax, none ? nan : all.max, ctx);
    hdf5::writeDouble(group.get(), format::kHeightMean,
                      none ? nan : all.sum / static_cast<double>(all.count), ctx);
    hdf5::writeUInt64(group.get(), format::kValidSamples, all.count, ctx);
  }
  const hdf5::Lock lock;
  hdf5::check(H5Gclose(group.release()), ctx, "cannot close group '/grids/" + info.name + "'");
}

}  // namespace

const char* codecName(Codec c) noexcept {
  return c == Codec::Zfp ? "zfp" : c == Codec::Deflate ? "deflate" : "unknown";
}

Codec codecNamed(std::string_view name) {
  if (name == "deflate") return Codec::Deflate;
  if (name == "zfp") return Codec::Zfp;
  throw InvalidArgument("store::codecNamed(): codec '" + std::string(name) +
                        "', expected deflate or zfp");
}

WriterMemoryPlan writerMemoryPlan(std::size_t rows, std::size_t cols, const WriteOptions& options) {
  GridInfo info;
  info.rows = rows;
  info.cols = cols;
  return planMemory(info, levelCount(info, options), options);
}

std::size_t writerMemoryMinimum(const WriteOptions& options) {
  return writerMemoryPlan(1, 1, options).minimumBytes;
}

void writeStore(const std::filesystem::path& path, std::span<const GridSource> grids,
                const WriteOptions& options) {
  const Context ctx("store::writeStore()", path);
  validateOptions(options, ctx);
  if (const std::size_t least = writerMemoryMinimum(options);
      options.memoryBudgetBytes != 0 && options.memoryBudgetBytes != kDefaultMemoryBudget &&
      options.memoryBudgetBytes < least) {
    invalid(ctx, "options.memoryBudgetBytes is " + std::to_string(options.memoryBudgetBytes) +
                     " bytes, below the minimum of " + std::to_string(least) +
                     " bytes for patches of " + std::to_string(options.patchRows) + "x" +
                     std::to_string(options.patchCols) +
                     " (one column tile of one chunk, and one thread's scratch); expected at "
                     "least that, or 0 for no bound");
  }
  std::filesystem::path dir = path.parent_path();
  if (dir.empty()) dir = ".";
  std::vector<Prepared> prepared;
  std::set<std::string, std::less<>> names;
  double totalSamples = 0.0;
  int rootMinor = kFormatVersionMinor;
  for (const GridSource& src : grids) {
    prepared.push_back(prepare(src, options, dir, ctx));
    const GridInfo& info = prepared.back().info;
    rootMinor = std::max(rootMinor, format::gridFormatMinor(info, !prepared.back().tiles.empty(),
                                                            options.statistics));
    for (const PreparedTile& t : prepared.back().tiles) {
      if (t.samples) totalSamples += static_cast<double>(t.rows * t.cols);
    }
    if (!names.insert(info.name).second) {
      invalid(ctx, "grid '" + info.name + "' appears twice");
    }
    for (std::size_t k = prepared.back().tiles.empty() ? 0 : 1; k < info.levels; ++k) {
      totalSamples += static_cast<double>(info.levelRows(k) * info.levelCols(k));
    }
  }
  if (options.codec == Codec::Deflate && options.deflate > 0) {
    const hdf5::Lock lock;
    if (H5Zfilter_avail(H5Z_FILTER_DEFLATE) <= 0) {
      fail(ctx, "deflate level " + std::to_string(options.deflate) +
                    " requested, but this HDF5 library has no deflate filter");
    }
  }
  if (options.codec == Codec::Zfp) {
    const hdf5::Lock lock;
    if (H5Zfilter_avail(kZfpFilterId) <= 0) {
      (void)hdf5::takeErrorStack();  // the failed plugin search; the message says what matters
      fail(ctx,
           "the zfp codec needs HDF5's ZFP filter (id 32013), which this HDF5 library "
           "cannot load: " +
               hdf5::missingFilterHint(kZfpFilterId));
    }
  }
  checkCancel(options, ctx);

  Progress progress(options, std::max(totalSamples, 1.0));
  const auto write = [&](const std::filesystem::path& tmp) {
    hdf5::File file;
    hdf5::Group gridsGroup;
    {
      const hdf5::Lock lock;
      const std::string what = "cannot create the temporary file " + tmp.string();
      // The HDF5 1.8 file format: checksummed metadata (corruption is reported, not
      // misread), readable by any HDF5 since 1.8.
      const hdf5::PropertyList fapl(hdf5::check(H5Pcreate(H5P_FILE_ACCESS), ctx, what));
      hdf5::check(H5Pset_libver_bounds(fapl.get(), H5F_LIBVER_V18, H5F_LIBVER_V18), ctx, what);
      file = hdf5::File(
          hdf5::check(H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()), ctx, what));
      const hdf5::Group root(
          hdf5::check(H5Gopen2(file.get(), "/", H5P_DEFAULT), ctx, "cannot open '/'"));
      hdf5::writeString(root.get(), format::kMarker, format::kMarkerValue, ctx);
      hdf5::writeInt32s(root.get(), format::kFormatVersion, {kFormatVersionMajor, rootMinor}, ctx);
      gridsGroup = createGroup(file.get(), format::kGrids, ctx);
    }
    for (std::size_t i = 0; i < grids.size(); ++i) {
      writeGrid(gridsGroup.get(), grids[i], prepared[i], options, progress, ctx);
    }
    checkCancel(options, ctx);
    {
      const hdf5::Lock lock;
      hdf5::check(H5Gclose(gridsGroup.release()), ctx, "cannot close group '/grids'");
      hdf5::check(H5Fflush(file.get(), H5F_SCOPE_GLOBAL), ctx, "cannot flush " + tmp.string());
      hdf5::check(H5Fclose(file.release()), ctx, "cannot close " + tmp.string());
    }
    checkCancel(options, ctx);
  };
  // core::writeFileAtomically: a unique temporary beside the target, synced, renamed into
  // place, then the folder synced (durable before visible).
  try {
    core::writeFileAtomically(path, write, "store::writeStore()");
  } catch (const IoError& e) {
    throw StoreError(e.what());
  }
  progress.finish();
}

}  // namespace regolith::store
