#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/topo/Body.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <cassert>
#include <charconv>
#include <cmath>
#include <limits>
#include <string>

namespace regolith::topo {

TopoGrid::TopoGrid(std::size_t rows, std::size_t cols, double x0, double y0, double dx, double dy,
                   std::optional<float> nodata)
    : rows_(rows), cols_(cols), x0_(x0), y0_(y0), dx_(dx), dy_(dy), nodata_(nodata) {
  constexpr const char* op = "TopoGrid()";
  if (rows == 0 || cols == 0) {
    throw InvalidArgument(std::string(op) + ": grid is " + core::number(rows) + "x" +
                          core::number(cols) + " samples, expected at least 1x1");
  }
  requireFinite(x0, op, "x0");
  requireFinite(y0, op, "y0");
  requireFinite(dx, op, "spacing x");
  requireFinite(dy, op, "spacing y");
  if (dx <= 0.0 || dy <= 0.0) {
    throw InvalidArgument(std::string(op) + ": spacing is (" + core::number(dx) + ", " +
                          core::number(dy) + "), expected both > 0");
  }
  if (!std::isnormal(dx) || !std::isnormal(dy)) {
    // A subnormal spacing makes every fractional index infinite: every point "outside".
    const auto shortest = [](double v) {
      std::array<char, 32> buf{};
      return std::string(buf.data(), std::to_chars(buf.data(), buf.data() + buf.size(), v).ptr);
    };
    throw InvalidArgument(std::string(op) + ": spacing is (" + shortest(dx) + ", " + shortest(dy) +
                          "), expected normal doubles (at least 2.2250738585072014e-308)");
  }
}

TopoGrid TopoGrid::fromGeoTransform(const std::array<double, 6>& gt, std::size_t rows,
                                    std::size_t cols, std::optional<float> nodata) {
  if (gt[2] != 0.0 || gt[4] != 0.0) {
    throw InvalidArgument("TopoGrid::fromGeoTransform(): rotation terms are (" +
                          core::number(gt[2]) + ", " + core::number(gt[4]) +
                          "), expected 0 (north-up rasters only)");
  }
  if (!(gt[1] > 0.0) || !(gt[5] < 0.0)) {
    throw InvalidArgument("TopoGrid::fromGeoTransform(): pixel size is (" + core::number(gt[1]) +
                          ", " + core::number(gt[5]) + "), expected dx > 0 and dy < 0 (north-up)");
  }
  const double dx = gt[1], dy = -gt[5];
  return TopoGrid(rows, cols, gt[0] + 0.5 * dx, gt[3] - 0.5 * dy, dx, dy, nodata);
}

std::array<double, 6> TopoGrid::geoTransform() const noexcept {
  return {x0_ - 0.5 * dx_, dx_, 0.0, y0_ + 0.5 * dy_, 0.0, -dy_};
}

glm::dvec2 TopoGrid::edgeSlack() const noexcept {
  constexpr double k = 4.0 * std::numeric_limits<double>::epsilon();
  const double mx = std::max({std::abs(x0_), std::abs(west()), std::abs(east())});
  const double my = std::max({std::abs(y0_), std::abs(north()), std::abs(south())});
  return {k * (mx / dx_ + static_cast<double>(cols_) + 1.0),
          k * (my / dy_ + static_cast<double>(rows_) + 1.0)};
}

bool TopoGrid::contains(double x, double y) const noexcept {
  const glm::dvec2 f = fractionalIndex(x, y);
  const glm::dvec2 e = edgeSlack();
  return f.x >= -0.5 - e.x && f.x <= static_cast<double>(cols_) - 0.5 + e.x && f.y >= -0.5 - e.y &&
         f.y <= static_cast<double>(rows_) - 0.5 + e.y;
}

void SampleSource::readWindow(std::size_t row0, std::size_t col0, std::size_t nrows,
                              std::size_t ncols, std::span<float> out) const {
  assert(out.size() >= nrows * ncols);
  for (std::size_t r = 0; r < nrows; ++r) {
    for (std::size_t c = 0; c < ncols; ++c) out[r * ncols + c] = sample(row0 + r, col0 + c);
  }
}

InMemorySamples::InMemorySamples(std::size_t rows, std::size_t cols, std::vector<float> data)
    : rows_(rows), cols_(cols), data_(std::move(data)) {
  std::size_t n = 0;
  if (rows == 0 || cols == 0 || __builtin_mul_overflow(rows, cols, &n) || data_.size() != n) {
    throw InvalidArgument("InMemorySamples(): " + core::number(data_.size()) + " samples for a " +
                          core::number(rows) + "x" + core::number(cols) +
                          " grid, expected rows*cols > 0");
  }
}

std::shared_ptr<InMemorySamples> InMemorySamples::fromFunction(
    std::size_t rows, std::size_t cols, const std::function<float(std::size_t, std::size_t)>& f) {
  std::size_t n = 0;
  if (__builtin_mul_overflow(rows, cols, &n)) {
    throw InvalidArgument("InMemorySamples::fromFunction(): a " + core::number(rows) + "x" +
                          core::number(cols) + " grid, expected rows*cols below 2^64");
  }
  std::vector<float> data(n);
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t c = 0; c < cols; ++c) data[r * cols + c] = f(r, c);
  }
  return std::make_shared<InMemorySamples>(rows, cols, std::move(data));
}

float InMemorySamples::sample(std::size_t row, std::size_t col) const {
  assert(row < rows_ && col < cols_);
  return data_[row * cols_ + col];
}

void InMemorySamples::readWindow(std::size_t row0, std::size_t col0, std::size_t nrows,
                                 std::size_t ncols, std::span<float> out) const {
  assert(row0 + nrows <= rows_ && col0 + ncols <= cols_ && out.size() >= nrows * ncols);
  for (std::size_t r = 0; r < nrows; ++r) {
    const float* src = data_.data() + (row0 + r) * cols_ + col0;
    std::copy(src, src + ncols, out.begin() + static_cast<std::ptrdiff_t>(r * ncols));
  }
}

}  // namespace regolith::topo
