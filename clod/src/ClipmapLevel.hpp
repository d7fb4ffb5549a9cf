#pragma once
// One clipmap level: an n × n window of one pyramid level around the focus, held in a
// toroidally addressed RGBA32F texture (xyz: scene position relative to the level's double
// anchor, w: height or NaN for nodata). Private to clod.

#include <regolith/clod/HeightPyramid.hpp>
#include <regolith/gl/GlObjects.hpp>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace regolith::clod {

class ClipmapLevel {
 public:
  /// n: vertices per side (odd). `level` indexes the pyramid.
  ClipmapLevel(const HeightPyramid& pyramid, std::size_t level, int n);

  /// Moves the window so that its centre sample is the one nearest to grid point (gx, gy),
  /// uploading only rows and columns that enter the window (all of it on the first call, or
  /// when the window jumps by n or more, or drifts n samples from the anchor). Returns the
  /// number of texels uploaded. `polar` (planets on global grids) selects the lattice: 0
  /// latitude/longitude rows and columns, +1/−1 a polar stereographic lattice about the
  /// north/south pole; a change re-uploads the level.
  std::size_t moveTo(double gx, double gy, int polar = 0);

  /// A move split in three for background loading: plan() (render thread, no I/O) says
  /// which regions enter the window; fetch() (any thread) reads the samples and computes
  /// the texels in double; apply() (render thread) uploads them and moves the window.
  struct Plan {
    struct Region {
      std::int64_t r0, r1, c0, c1;
      std::vector<float> texels;  // RGBA per sample, row-major
    };
    std::int64_t row0 = 0, col0 = 0;
    bool full = false;
    int polar = 0;
    double polarStep = 0.0;
    std::int64_t anchorRow = 0, anchorCol = 0;
    glm::dvec3 anchor{0.0};
    std::vector<Region> regions;
    [[nodiscard]] bool empty() const noexcept;
    [[nodiscard]] std::size_t texels() const noexcept;
  };
  [[nodiscard]] Plan plan(double gx, double gy, int polar) const;
  /// Reads only the pyramid and the plan: safe on a worker thread while the level draws.
  void fetch(Plan& plan) const;
  std::size_t apply(const Plan& plan);
  /// Hints the ring `margin` samples wide around the plan's window, clipped to the grid, to
  /// the level's source (topo::SampleSource::prefetch()), so a paged source loads the
  /// patches of the next moves in the background. Lat/lon lattices only; any thread.
  void prefetch(const Plan& plan, int margin) const;

  /// This level's window as a rectangle (i0, j0, i1, j1) in `coarser`'s window vertex
  /// coordinates (i along columns, j along rows).
  [[nodiscard]] glm::dvec4 footprintIn(const ClipmapLevel& coarser) const;
  /// True if this level's window covers the centre hole (half-width `hole` cells) of the
  /// next coarser level, in the same lattice.
  [[nodiscard]] bool covers(const ClipmapLevel& coarser, int hole) const;

  /// Window origin: virtual (row, col) of its top-left sample; may lie outside the grid.
  [[nodiscard]] std::int64_t row0() const noexcept { return row0_; }
  [[nodiscard]] std::int64_t col0() const noexcept { return col0_; }
  [[nodiscard]] bool valid() const noexcept { return valid_; }
  /// The lattice: 0 latitude/longitude (or plane) rows and columns, ±1 polar stereographic.
  [[nodiscard]] int polar() const noexcept { return polar_; }
  [[nodiscard]] const glm::dvec3& anchor() const noexcept { return anchor_; }
  [[nodiscard]] gl::Id texture() const noexcept { return texture_.id(); }
  /// Scene position of the window's centre sample at height 0.
  [[nodiscard]] glm::dvec3 centre() const;
  /// Sample spacing in grid units (x, y).
  [[nodiscard]] double spacingX() const noexcept { return grid().spacingX(); }
  [[nodiscard]] double spacingY() const noexcept { return grid().spacingY(); }
  /// Largest distance in metres between neighbouring samples near the window centre.
  [[nodiscard]] double cellMetres() const;
  /// A sphere holding every vertex the level can draw: its window's samples from `below`
  /// metres under the lowest height (the skirts) up to the highest, in scene coordinates.
  /// Conservative (the window's angular extent about its centre on a planet, its rectangle
  /// on a plane, sampled through a placement); for culling whole levels.
  struct Bound {
    glm::dvec3 centre{0.0};
    double radius = 0.0;
  };
  [[nodiscard]] Bound bound(double below) const;
  /// Lowest and highest valid height in the window (0, 0 if none is valid).
  [[nodiscard]] float minHeight() const noexcept { return minH_; }
  [[nodiscard]] float maxHeight() const noexcept { return maxH_; }
  /// Texel (x, y) in the texture of window sample (row0 + j, col0 + i).
  [[nodiscard]] int texelX(std::int64_t i) const noexcept;
  [[nodiscard]] int texelY(std::int64_t j) const noexcept;

 private:
  [[nodiscard]] const topo::TopoGrid& grid() const noexcept;
  /// Grid point (longitude/x, latitude/y) of window lattice point (vr, vc).
  [[nodiscard]] glm::dvec2 lattice(double vr, double vc) const;
  [[nodiscard]] glm::dvec2 lattice(double vr, double vc, int polar, double step) const;
  /// This level's window centre as a fractional (col, row) index of `coarser`'s lattice.
  [[nodiscard]] glm::dvec2 centreIndexIn(const ClipmapLevel& coarser) const;
  [[nodiscard]] glm::dvec2 indexIn(const ClipmapLevel& coarser, double r, double c) const;
  void fill(const Plan& plan, Plan::Region& region) const;
  /// Calls fn(i, r, c, len) for each run of consecutive real samples in virtual row vr,
  /// columns [c0, c0 + w): window columns i … i + len − 1 are real samples (r, c … c + len − 1).
  void forEachRun(
      std::int64_t vr, std::int64_t c0, std::size_t w,
      const std::function<void(std::size_t, std::size_t, std::size_t, std::size_t)>& fn) const;
  /// The real samples a lat/lon or plane region reads, as windows (fill()'s runs, rows
  /// with the same run joined).
  void appendWindows(const Plan::Region& region,
                     std::vector<topo::SampleSource::Window>& out) const;
  /// Height at a grid point by bilinear interpolation (polar frames), NaN near nodata.
  [[nodiscard]] float interpolate(const glm::dvec2& g) const;
  [[nodiscard]] float sampleAt(std::int64_t vr, std::int64_t vc) const;
  /// Maps a virtual (row, col) to a real sample, wrapping longitude and reflecting over a
  /// pole on global planet grids. False if outside the data.
  bool realIndex(std::int64_t vr, std::int64_t vc, std::size_t& r, std::size_t& c) const;
  void updateRange();

  const HeightPyramid& pyramid_;
  std::size_t level_;
  int n_;
  bool wrapLon_ = false, crossPoles_ = false;
  // Lattice: 0 latitude/longitude rows and columns; +1/−1 polar stereographic about the
  // north/south pole, where lat/lon cells collapse. Heights are then interpolated.
  int polar_ = 0;
  double polarStep_ = 0.0;  // lattice step in projected metres
  bool valid_ = false;
  std::int64_t row0_ = 0, col0_ = 0;
  std::int64_t anchorRow_ = 0, anchorCol_ = 0;
  glm::dvec3 anchor_{0.0};
  std::vector<float> heights_;  // CPU mirror of w, toroidal like the texture
  float minH_ = 0.0F, maxH_ = 0.0F;
  gl::Texture texture_;
};

}  // namespace regolith::clod
