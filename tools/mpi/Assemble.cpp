// regolith-mpi: joining the part stores (Assemble.hpp). HDF5's C API directly: the chunks are
// copied as the parts' writers encoded them (H5Dread_chunk / H5Dwrite_chunk), never decoded.
#include "Assemble.hpp"

#include <regolith/core/AtomicFile.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/store/Store.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include <hdf5.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <span>
#include <utility>

namespace regolith::tools::mpi {

namespace {

/// An HDF5 identifier closed by `close` when it goes out of scope.
class Id {
 public:
  Id() = default;
  Id(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  Id(const Id&) = delete;
  Id& operator=(const Id&) = delete;
  Id(Id&& o) noexcept : id_(std::exchange(o.id_, -1)), close_(o.close_) {}
  Id& operator=(Id&& o) noexcept {
    std::swap(id_, o.id_);
    std::swap(close_, o.close_);
    return *this;
  }
  ~Id() {
    if (id_ >= 0 && close_ != nullptr) close_(id_);
  }
  [[nodiscard]] hid_t get() const noexcept { return id_; }

 private:
  hid_t id_ = -1;
  herr_t (*close_)(hid_t) = nullptr;
};

hid_t check(hid_t id, const std::string& what) {
  if (id < 0) throw store::StoreError("regolith-mpi: assemble: " + what);
  return id;
}

Id file(hid_t id, const std::string& what) { return {check(id, what), H5Fclose}; }
Id group(hid_t id, const std::string& what) { return {check(id, what), H5Gclose}; }
Id dataset(hid_t id, const std::string& what) { return {check(id, what), H5Dclose}; }
Id plist(hid_t id, const std::string& what) { return {check(id, what), H5Pclose}; }
Id space(hid_t id, const std::string& what) { return {check(id, what), H5Sclose}; }
Id type(hid_t id, const std::string& what) { return {check(id, what), H5Tclose}; }
Id attribute(hid_t id, const std::string& what) { return {check(id, what), H5Aclose}; }

/// Copies every attribute of `from` onto `to` (same names, types, shapes and bytes).
void copyAttributes(hid_t from, hid_t to, const std::string& what) {
  H5O_info_t info{};
  check(H5Oget_info2(from, &info, H5O_INFO_NUM_ATTRS), "cannot list the attributes of " + what);
  for (hsize_t i = 0; i < info.num_attrs; ++i) {
    const Id a = attribute(
        H5Aopen_by_idx(from, ".", H5_INDEX_NAME, H5_ITER_INC, i, H5P_DEFAULT, H5P_DEFAULT),
        "cannot open an attribute of " + what);
    const ssize_t nameLength = H5Aget_name(a.get(), 0, nullptr);
    std::string name(static_cast<std::size_t>(std::max<ssize_t>(nameLength, 0)) + 1, '\0');
    check(H5Aget_name(a.get(), name.size(), name.data()), "cannot name an attribute of " + what);
    name.resize(static_cast<std::size_t>(nameLength));
    std::string about = "attribute ";
    about += name;
    about += " of ";
    about += what;
    const Id t = type(H5Aget_type(a.get()), "cannot type " + about);
    const Id s = space(H5Aget_space(a.get()), "cannot shape " + about);
    const hssize_t n = H5Sget_simple_extent_npoints(s.get());
    std::vector<unsigned char> bytes(static_cast<std::size_t>(std::max<hssize_t>(n, 1)) *
                                     H5Tget_size(t.get()));
    check(H5Aread(a.get(), t.get(), bytes.data()), "cannot read " + about);
    const Id b = attribute(H5Acreate2(to, name.c_str(), t.get(), s.get(), H5P_DEFAULT, H5P_DEFAULT),
                           "cannot write " + about);
    check(H5Awrite(b.get(), t.get(), bytes.data()), "cannot write " + about);
  }
}

/// Replaces the scalar attribute `name` of `obj`, keeping its stored type, by `v` (given as
/// `memType`).
template <typename T>
void setScalar(hid_t obj, const char* name, hid_t memType, T v, const std::string& what) {
  const std::string w = "cannot set attribute " + std::string(name) + " of " + what;
  Id fileType;
  if (H5Aexists(obj, name) > 0) {
    const Id a = attribute(H5Aopen(obj, name, H5P_DEFAULT), w);
    fileType = type(H5Aget_type(a.get()), w);
    check(H5Adelete(obj, name), w);
  } else {
    fileType = type(H5Tcopy(memType), w);
  }
  const Id s = space(H5Screate(H5S_SCALAR), w);
  const Id a =
      attribute(H5Acreate2(obj, name, fileType.get(), s.get(), H5P_DEFAULT, H5P_DEFAULT), w);
  check(H5Awrite(a.get(), memType, &v), w);
}

/// Replaces the text attribute `name` by `text`, as the writer stores text (fixed length,
/// NUL-padded, UTF-8, one NUL for an empty text).
void setText(hid_t obj, const char* name, const std::string& text, const std::string& what) {
  const std::string w = "cannot set attribute " + std::string(name) + " of " + what;
  if (H5Aexists(obj, name) > 0) check(H5Adelete(obj, name), w);
  const Id t = type(H5Tcopy(H5T_C_S1), w);
  check(H5Tset_size(t.get(), std::max<std::size_t>(text.size(), 1)), w);
  check(H5Tset_strpad(t.get(), H5T_STR_NULLPAD), w);
  check(H5Tset_cset(t.get(), H5T_CSET_UTF8), w);
  const Id s = space(H5Screate(H5S_SCALAR), w);
  const Id a = attribute(H5Acreate2(obj, name, t.get(), s.get(), H5P_DEFAULT, H5P_DEFAULT), w);
  std::string padded = text;
  if (padded.empty()) padded.push_back('\0');
  check(H5Awrite(a.get(), t.get(), padded.data()), w);
}

Id newGroup(hid_t parent, const std::string& name) {
  const std::string w = "cannot create group " + name;
  const Id gcpl = plist(H5Pcreate(H5P_GROUP_CREATE), w);
  check(H5Pset_obj_track_times(gcpl.get(), 0), w);
  return group(H5Gcreate2(parent, name.c_str(), H5P_DEFAULT, gcpl.get(), H5P_DEFAULT), w);
}

std::size_t levelSide(std::size_t n, std::size_t level) { return ((n - 1) >> level) + 1; }

/// Copies every chunk of dataset `from` (rows × cols) into dataset `to` at row offset `row0`,
/// encoded bytes and filter mask as they are.
void copyChunks(hid_t from, hid_t to, std::size_t row0, const std::string& what) {
  const Id s = space(H5Dget_space(from), "cannot shape " + what);
  std::array<hsize_t, 2> dims{};
  check(H5Sget_simple_extent_dims(s.get(), dims.data(), nullptr), "cannot shape " + what);
  const Id dcpl = plist(H5Dget_create_plist(from), "cannot read the layout of " + what);
  std::array<hsize_t, 2> chunk{};
  check(H5Pget_chunk(dcpl.get(), 2, chunk.data()), "cannot read the chunks of " + what);
  std::vector<unsigned char> bytes;
  for (hsize_t r = 0; r < dims[0]; r += chunk[0]) {
    for (hsize_t c = 0; c < dims[1]; c += chunk[1]) {
      const std::array<hsize_t, 2> at{r, c}, dest{r + row0, c};
      hsize_t size = 0;
      check(H5Dget_chunk_storage_size(from, at.data(), &size), "cannot size a chunk of " + what);
      bytes.resize(size);
      std::uint32_t mask = 0;
      check(H5Dread_chunk(from, H5P_DEFAULT, at.data(), &mask, bytes.data()),
            "cannot read a chunk of " + what);
      check(H5Dwrite_chunk(to, H5P_DEFAULT, mask, dest.data(), size, bytes.data()),
            "cannot write a chunk of " + what);
    }
  }
}

/// A new level dataset rows × cols laid out (chunks, filters, fill value) as `like`.
Id levelLike(hid_t parent, const std::string& name, hid_t like, std::size_t rows,
             std::size_t cols) {
  const std::string w = "cannot create dataset " + name;
  const Id dcpl = plist(H5Dget_create_plist(like), w);
  const std::array<hsize_t, 2> dims{rows, cols};
  const Id s = space(H5Screate_simple(2, dims.data(), nullptr), w);
  const Id dapl = plist(H5Pcreate(H5P_DATASET_ACCESS), w);
  check(H5Pset_chunk_cache(dapl.get(), 0, 0, 1.0), w);
  Id d = dataset(H5Dcreate2(parent, name.c_str(), H5T_IEEE_F32LE, s.get(), H5P_DEFAULT, dcpl.get(),
                            dapl.get()),
                 w);
  copyAttributes(like, d.get(), name);
  return d;
}

/// Level `level` of the whole grid, read from the parts (heights, NaN where missing): the
/// level 0 of the store that computes the levels above the parts'.
class PartsLevel : public topo::SampleSource {
 public:
  PartsLevel(const Assembly& a, std::size_t level) : a_(a), level_(level) {
    for (const auto& p : a.parts) stores_.push_back(store::Store::open(p));
  }
  [[nodiscard]] std::size_t rows() const noexcept override { return levelSide(a_.rows, level_); }
  [[nodiscard]] std::size_t cols() const noexcept override { return levelSide(a_.cols, level_); }
  [[nodiscard]] float sample(std::size_t row, std::size_t col) const override {
    float v = 0.0F;
    readWindow(row, col, 1, 1, std::span<float>(&v, 1));
    return v;
  }
  void readWindow(std::size_t row0, std::size_t col0, std::size_t nrows, std::size_t ncols,
                  std::span<float> out) const override {
    for (std::size_t i = 0; i < stores_.size(); ++i) {
      const std::size_t p0 = a_.plan.parts[i].row0 >> level_;
      const std::size_t p1 = p0 + levelSide(a_.plan.parts[i].row1 - a_.plan.parts[i].row0, level_);
      const std::size_t r0 = std::max(row0, p0), r1 = std::min(row0 + nrows, p1);
      if (r0 >= r1) continue;
      stores_[i].readWindow(a_.grid, level_, r0 - p0, col0, r1 - r0, ncols,
                            out.subspan((r0 - row0) * ncols, (r1 - r0) * ncols));
    }
  }

 private:
  const Assembly& a_;
  std::size_t level_;
  std::vector<store::Store> stores_;
};

/// Writes the levels above the parts' (partTop + 1 …) into a store of their own, whose level 0
/// is level partTop of the grid: the same writer, so the same means and the same chunks.
std::filesystem::path writeCoarseLevels(const Assembly& a) {
  const std::size_t top = a.plan.partTop;
  const store::Store first = store::Store::open(a.parts.front());
  store::GridSource src;
  src.info = first.grid(a.grid);
  src.info.rows = levelSide(a.rows, top);
  src.info.cols = levelSide(a.cols, top);
  src.info.spacingX *= std::ldexp(1.0, static_cast<int>(top));
  src.info.spacingY *= std::ldexp(1.0, static_cast<int>(top));
  src.info.provenance.clear();
  src.samples = std::make_shared<PartsLevel>(a, top);
  store::WriteOptions o;
  o.patchRows = a.patchRows;
  o.patchCols = a.patchCols;
  o.levels = a.levels - top;
  o.threads = a.threads;
  o.memoryBudgetBytes = 0;
  o.durability = core::Durability::Scratch;  // deleted once joined
  // Codec and level: the first part's level datasets carry them; read them back from it.
  const Id f = file(H5Fopen(a.parts.front().c_str(), H5F_ACC_RDONLY, H5P_DEFAULT),
                    "cannot open " + a.parts.front().string());
  const std::string levelName = "/grids/" + a.grid + "/level" + std::to_string(top);
  const Id d = dataset(H5Dopen2(f.get(), levelName.c_str(), H5P_DEFAULT),
                       "cannot open " + levelName + " of " + a.parts.front().string());
  const Id dcpl = plist(H5Dget_create_plist(d.get()), "cannot read the filters of " + levelName);
  const int filters = H5Pget_nfilters(dcpl.get());
  for (int i = 0; i < filters; ++i) {
    unsigned flags = 0;
    std::size_t n = 8;
    std::array<unsigned, 8> values{};
    std::array<char, 64> name{};
    const H5Z_filter_t id = H5Pget_filter2(dcpl.get(), static_cast<unsigned>(i), &flags, &n,
                                           values.data(), name.size(), name.data(), nullptr);
    if (id == H5Z_FILTER_DEFLATE) o.deflate = static_cast<int>(values[0]);
    if (id == store::kZfpFilterId) o.codec = store::Codec::Zfp;
  }
  std::filesystem::path coarse = a.scratch / "coarse.h5";
  store::writeStore(coarse, std::span<const store::GridSource>(&src, 1), o);
  return coarse;
}

}  // namespace

JoinSeconds assemble(const Assembly& a) {
  JoinSeconds js;
  auto lapStart = std::chrono::steady_clock::now();
  const auto lap = [&lapStart]() {
    const auto now = std::chrono::steady_clock::now();
    return std::chrono::duration<double>(now - std::exchange(lapStart, now)).count();
  };
  const bool tiled = !a.partTiles.empty();
  const std::size_t top = a.plan.partTop;
  std::filesystem::path coarse;
  if (a.levels > top + 1) coarse = writeCoarseLevels(a);
  js.coarse = lap();
  const bool grow = a.growFirst && !tiled;
  std::vector<Id> parts;  // grow: the first stays closed, to become the store
  for (std::size_t p = 0; p < a.parts.size(); ++p) {
    if (grow && p == 0) {
      parts.emplace_back();
      continue;
    }
    parts.push_back(file(H5Fopen(a.parts[p].c_str(), H5F_ACC_RDONLY, H5P_DEFAULT),
                         "cannot open " + a.parts[p].string()));
  }
  const std::string gridPath = "/grids/" + a.grid;
  const auto write = [&](const std::filesystem::path& tmp) {
    const std::string w = "cannot create " + tmp.string();
    const Id fapl = plist(H5Pcreate(H5P_FILE_ACCESS), w);
    check(H5Pset_libver_bounds(fapl.get(), H5F_LIBVER_V18, H5F_LIBVER_V18), w);
    Id out, g;
    if (grow) {
      // The first part's root and grid attributes are the store's (its band starts at row 0);
      // those that depend on the whole grid are set below.
      std::error_code ec;
      std::filesystem::rename(a.parts.front(), tmp, ec);
      if (ec) {
        throw store::StoreError("regolith-mpi: assemble: cannot move " + a.parts.front().string() +
                                " to " + tmp.string() + ": " + ec.message());
      }
      out = file(H5Fopen(tmp.c_str(), H5F_ACC_RDWR, fapl.get()), "cannot open " + tmp.string());
      g = group(H5Gopen2(out.get(), gridPath.c_str(), H5P_DEFAULT),
                "cannot open " + gridPath + " of " + tmp.string());
    } else {
      out = file(H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()), w);
      {
        const Id from = group(H5Gopen2(parts.front().get(), "/", H5P_DEFAULT), w);
        const Id to = group(H5Gopen2(out.get(), "/", H5P_DEFAULT), w);
        copyAttributes(from.get(), to.get(), "the root group");
      }
      const Id grids = newGroup(out.get(), "grids");
      g = newGroup(grids.get(), a.grid);
      const Id from = group(H5Gopen2(parts.front().get(), gridPath.c_str(), H5P_DEFAULT),
                            "cannot open " + gridPath + " of " + a.parts.front().string());
      copyAttributes(from.get(), g.get(), gridPath);
    }
    const std::string what = "grid '" + a.grid + "'";
    setScalar<std::uint64_t>(g.get(), "rows", H5T_NATIVE_UINT64, a.rows, what);
    setScalar<std::uint64_t>(g.get(), "cols", H5T_NATIVE_UINT64, a.cols, what);
    setScalar<std::uint64_t>(g.get(), "levels", H5T_NATIVE_UINT64, a.levels, what);
    // Level 0's statistics: the blocks added in row-major order, as the writer adds them.
    double mn = std::numeric_limits<double>::infinity(), mx = -mn, sum = 0.0, count = 0.0;
    for (const store::BlockStatistics& b : a.blocks) {
      mn = std::min(mn, b.min);
      mx = std::max(mx, b.max);
      sum += b.sum;
      count += static_cast<double>(b.count);
    }
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const bool none = count == 0.0;
    if (H5Aexists(g.get(), "valid_samples") > 0) {
      setScalar<double>(g.get(), "height_min", H5T_NATIVE_DOUBLE, none ? nan : mn, what);
      setScalar<double>(g.get(), "height_max", H5T_NATIVE_DOUBLE, none ? nan : mx, what);
      setScalar<double>(g.get(), "height_mean", H5T_NATIVE_DOUBLE, none ? nan : sum / count, what);
      setScalar<std::uint64_t>(g.get(), "valid_samples", H5T_NATIVE_UINT64,
                               static_cast<std::uint64_t>(count), what);
    }
    if (!a.provenance.empty()) setText(g.get(), "provenance", a.provenance, what);
    if (tiled) {
      setScalar<std::uint64_t>(g.get(), "tile_count", H5T_NATIVE_UINT64, a.tileCount, what);
      const Id tiles = newGroup(g.get(), "tiles");
      // Tiles in their global order; each copied whole from its part (H5Ocopy copies the
      // encoded chunks as they are), its row0 moved to the grid's.
      std::vector<std::pair<std::size_t, std::size_t>> where(a.tileCount);  // (part, local)
      for (std::size_t p = 0; p < a.partTiles.size(); ++p) {
        for (std::size_t j = 0; j < a.partTiles[p].size(); ++j) where[a.partTiles[p][j]] = {p, j};
      }
      for (std::size_t i = 0; i < a.tileCount; ++i) {
        const auto [p, j] = where[i];
        std::string from = gridPath;
        from += "/tiles/";
        from += std::to_string(j);
        const std::string name = std::to_string(i);
        check(H5Ocopy(parts[p].get(), from.c_str(), tiles.get(), name.c_str(), H5P_DEFAULT,
                      H5P_DEFAULT),
              "cannot copy " + from + " of " + a.parts[p].string());
        const Id t =
            group(H5Gopen2(tiles.get(), name.c_str(), H5P_DEFAULT), "cannot open tile " + name);
        std::uint64_t row0 = 0;
        {
          const Id r = attribute(H5Aopen(t.get(), "row0", H5P_DEFAULT), "cannot open tile row0");
          check(H5Aread(r.get(), H5T_NATIVE_UINT64, &row0), "cannot read tile row0");
        }
        setScalar<std::uint64_t>(t.get(), "row0", H5T_NATIVE_UINT64, row0 + a.plan.parts[p].row0,
                                 "tile " + name);
      }
    }
    // Levels 0 (1 when tiled) … top: every part's chunks at its rows.
    for (std::size_t k = tiled ? 1 : 0; k <= top && k < a.levels; ++k) {
      const std::string name = "level" + std::to_string(k);
      std::string from = gridPath;
      from += '/';
      from += name;
      // grow: the first part's dataset is the store's own, so its source stays empty.
      const std::size_t firstCopied = grow ? 1 : 0;
      std::vector<Id> sources(parts.size());
      for (std::size_t p = firstCopied; p < parts.size(); ++p) {
        sources[p] = dataset(H5Dopen2(parts[p].get(), from.c_str(), H5P_DEFAULT),
                             "cannot open " + from + " of " + a.parts[p].string());
      }
      Id d;
      if (grow) {
        // The first part's dataset, its maximum rows the grid's: grown to the grid's rows.
        d = dataset(H5Dopen2(g.get(), name.c_str(), H5P_DEFAULT),
                    "cannot open " + from + " of " + tmp.string());
        const std::array<hsize_t, 2> dims{levelSide(a.rows, k), levelSide(a.cols, k)};
        check(H5Dset_extent(d.get(), dims.data()),
              "cannot extend " + from + " of " + tmp.string() + " to " + std::to_string(dims[0]) +
                  "x" + std::to_string(dims[1]) + " (was the first part written with room?)");
      } else {
        d = levelLike(g.get(), name, sources.front().get(), levelSide(a.rows, k),
                      levelSide(a.cols, k));
      }
      for (std::size_t p = firstCopied; p < parts.size(); ++p) {
        copyChunks(sources[p].get(), d.get(), a.plan.parts[p].row0 >> k,
                   from + " of " + a.parts[p].string());
      }
    }
    // Levels top + 1 …: from the coarse store's levels 1 ….
    if (!coarse.empty()) {
      const Id c = file(H5Fopen(coarse.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT),
                        "cannot open " + coarse.string());
      for (std::size_t k = top + 1; k < a.levels; ++k) {
        const std::string from = gridPath + "/level" + std::to_string(k - top);
        const Id s = dataset(H5Dopen2(c.get(), from.c_str(), H5P_DEFAULT),
                             "cannot open " + from + " of " + coarse.string());
        const Id d = levelLike(g.get(), "level" + std::to_string(k), s.get(), levelSide(a.rows, k),
                               levelSide(a.cols, k));
        copyChunks(s.get(), d.get(), 0, from + " of " + coarse.string());
      }
    }
    js.copies = lap();
    if (a.lateProvenance) {
      // The chunks reach the disk while the provenance is awaited; the sync after the rename
      // then writes little more than the attribute.
      check(H5Fflush(out.get(), H5F_SCOPE_GLOBAL), "cannot flush " + tmp.string());
      core::syncFile(tmp, "regolith-mpi import");
      js.sync = lap();
      const std::string provenance = a.lateProvenance();
      js.wait = lap();
      setText(g.get(), "provenance", provenance, what);
    }
    check(H5Fflush(out.get(), H5F_SCOPE_GLOBAL), "cannot flush " + tmp.string());
  };
  core::writeFileAtomically(a.out, write, "regolith-mpi import");
  if (!coarse.empty()) std::filesystem::remove(coarse);
  js.finish = lap();
  return js;
}

}  // namespace regolith::tools::mpi
