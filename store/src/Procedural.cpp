// The generated Mars as a PageSource (Procedural.hpp): one MarsPlanetGenerator per pyramid
// level, each at that level's rows, computing windows on the calling thread.
#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/store/Procedural.hpp>

#include <string>
#include <utility>
#include <vector>

namespace regolith::store {
namespace {

/// The pyramid levels the options ask for, checked against what the rows allow.
std::size_t levelsFor(const ProceduralMarsOptions& o, const GridInfo& info) {
  const auto halvings = [&](std::size_t levels) {
    // Level levels − 1 has rows / 2^(levels − 1) rows, exactly, and at least 2.
    const std::size_t k = levels - 1;
    return k < 63 && info.rows % (std::size_t{1} << k) == 0 && (info.rows >> k) >= 2;
  };
  if (o.levels != 0) {
    if (!halvings(o.levels)) {
      throw InvalidArgument(
          core::format({"store::proceduralMars()", "", "levels", core::number(o.levels),
                        "each level to halve rows " + core::number(info.rows) +
                            " exactly, leaving >= 2 (2^(levels-1) divides rows)"}));
    }
    return o.levels;
  }
  std::size_t levels = 1;
  while ((info.levelRows(levels - 1) > o.patchRows || info.levelCols(levels - 1) > o.patchCols) &&
         halvings(levels + 1)) {
    ++levels;
  }
  return levels;
}

class ProceduralMars final : public PageSource {
 public:
  explicit ProceduralMars(const ProceduralMarsOptions& o) {
    MarsPlanetOptions planet = o.planet;
    planet.threads = 1;  // computed on the calling thread: no pool per patch
    planet.write = WriteOptions{};
    const MarsPlanetGenerator level0(planet);
    info_ = level0.gridInfo();
    if (o.patchRows == 0 || o.patchCols == 0) {
      throw InvalidArgument(
          core::format({"store::proceduralMars()", "", "patch size",
                        core::number(o.patchRows) + "x" + core::number(o.patchCols), "> 0"}));
    }
    info_.patchRows = o.patchRows;
    info_.patchCols = o.patchCols;
    info_.levels = levelsFor(o, info_);
    levels_.reserve(info_.levels);
    for (std::size_t k = 0; k < info_.levels; ++k) {
      MarsPlanetOptions lo = planet;
      lo.rows = planet.rows >> k;
      levels_.push_back(std::make_shared<MarsPlanetGenerator>(lo)->samples());
    }
    name_ = "procedural Mars (seed " + core::number(planet.seed) + ", " +
            core::number(planet.rows) + " rows" + (planet.ellipsoid ? ", ellipsoid" : "") + ")";
  }

  std::vector<std::string> gridNames() const override { return {info_.name}; }

  const GridInfo& grid(std::string_view name) const override {
    if (name != info_.name) {
      throw StoreError(
          core::format({"store::proceduralMars()", name_, "grid '" + std::string(name) + "'", "",
                        "'" + info_.name + "'"}));
    }
    return info_;
  }

  void readWindow(std::string_view grid, std::size_t level, std::size_t row0, std::size_t col0,
                  std::size_t rows, std::size_t cols, std::span<float> out) const override {
    const GridInfo& info = this->grid(grid);
    if (level >= info.levels || row0 > info.levelRows(level) ||
        rows > info.levelRows(level) - row0 || col0 > info.levelCols(level) ||
        cols > info.levelCols(level) - col0 || out.size() != rows * cols) {
      throw StoreError(core::format({"store::proceduralMars(): readWindow()", name_,
                                     "window of level " + core::number(level),
                                     "rows " + core::number(row0) + "+" + core::number(rows) +
                                         ", cols " + core::number(col0) + "+" + core::number(cols),
                                     "inside the level, with rows*cols samples of output"}));
    }
    if (rows == 0 || cols == 0) return;
    levels_[level]->readWindow(row0, col0, rows, cols, out);
  }

  std::string name() const override { return name_; }

 private:
  GridInfo info_;
  std::vector<std::shared_ptr<const topo::SampleSource>> levels_;  // one generator per level
  std::string name_;
};

}  // namespace

std::shared_ptr<const PageSource> proceduralMars(const ProceduralMarsOptions& options) {
  return std::make_shared<ProceduralMars>(options);
}

Pager proceduralPager(const ProceduralMarsOptions& options, std::shared_ptr<PatchCache> cache) {
  return {proceduralMars(options), std::move(cache)};
}

}  // namespace regolith::store
