#include <regolith/compose/Dataset.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace regolith::compose {

namespace {

/// Squared Euclidean distance transform of one line (Felzenszwalb and Huttenlocher 2012,
/// "Distance transforms of sampled functions": the lower envelope of parabolas). Written
/// here because no Debian library we already use has one: OpenCV would be a large new
/// dependency for 40 lines, and GDAL's proximity algorithm works on GDAL datasets, which
/// compose must not know.
void edt1d(const std::vector<double>& f, std::vector<double>& d, std::vector<std::size_t>& v,
           std::vector<double>& z) {
  const std::size_t n = f.size();
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::size_t k = 0;
  v[0] = 0;
  z[0] = -kInf;
  z[1] = kInf;
  for (std::size_t q = 1; q < n; ++q) {
    if (std::isinf(f[q])) continue;
    while (true) {
      const std::size_t p = v[k];
      if (std::isinf(f[p])) {  // the envelope so far is empty: q starts it
        v[k] = q;
        z[k] = -kInf;
        z[k + 1] = kInf;
        break;
      }
      const auto qd = static_cast<double>(q), pd = static_cast<double>(p);
      const double s = ((f[q] + qd * qd) - (f[p] + pd * pd)) / (2.0 * (qd - pd));
      if (s <= z[k]) {
        if (k == 0) {
          v[0] = q;
          z[0] = -kInf;
          z[1] = kInf;
          break;
        }
        --k;
        continue;
      }
      ++k;
      v[k] = q;
      z[k] = s;
      z[k + 1] = kInf;
      break;
    }
  }
  k = 0;
  for (std::size_t q = 0; q < n; ++q) {
    while (z[k + 1] < static_cast<double>(q)) ++k;
    const double diff = static_cast<double>(q) - static_cast<double>(v[k]);
    d[q] = std::isinf(f[v[k]]) ? kInf : diff * diff + f[v[k]];
  }
}

}  // namespace

std::shared_ptr<const topo::SampleSource> featherMask(const topo::TopoGrid& grid,
                                                      const topo::SampleSource& samples,
                                                      double widthSamples, bool includeGridEdge) {
  constexpr const char* op = "compose::featherMask()";
  if (!(std::isfinite(widthSamples) && widthSamples > 0.0)) {
    throw InvalidArgument(core::format({.operation = op,
                                        .field = "width",
                                        .value = core::number(widthSamples) + " samples",
                                        .expected = "finite, > 0"}));
  }
  const std::size_t rows = grid.rows(), cols = grid.cols();
  if (rows * cols > (std::size_t{1} << 28)) {
    throw InvalidArgument(
        core::format({.operation = op,
                      .field = "grid size",
                      .value = std::to_string(rows) + " x " + std::to_string(cols),
                      .expected = "at most 2^28 samples (an in-memory mask)"}));
  }
  std::vector<float> heights(rows * cols);
  samples.readWindow(0, 0, rows, cols, heights);
  // Distances are measured to the nearest missing sample; the grid edge counts as missing
  // one sample beyond the outermost row and column when includeGridEdge is set, so the
  // padded grid is (rows + 2) × (cols + 2).
  const std::size_t pad = includeGridEdge ? 1 : 0;
  const std::size_t pr = rows + 2 * pad, pc = cols + 2 * pad;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::vector<double> dist(pr * pc, includeGridEdge ? 0.0 : kInf);
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t c = 0; c < cols; ++c) {
      dist[(r + pad) * pc + c + pad] = grid.isNodata(heights[r * cols + c]) ? 0.0 : kInf;
    }
  }
  const std::size_t longest = std::max(pr, pc);
  std::vector<double> f(longest), d(longest), z(longest + 1);
  std::vector<std::size_t> v(longest);
  for (std::size_t c = 0; c < pc; ++c) {
    f.resize(pr);
    d.resize(pr);
    for (std::size_t r = 0; r < pr; ++r) f[r] = dist[r * pc + c];
    edt1d(f, d, v, z);
    for (std::size_t r = 0; r < pr; ++r) dist[r * pc + c] = d[r];
  }
  f.resize(pc);
  d.resize(pc);
  for (std::size_t r = 0; r < pr; ++r) {
    for (std::size_t c = 0; c < pc; ++c) f[c] = dist[r * pc + c];
    edt1d(f, d, v, z);
    for (std::size_t c = 0; c < pc; ++c) dist[r * pc + c] = d[c];
  }
  std::vector<float> mask(rows * cols);
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t c = 0; c < cols; ++c) {
      const double t =
          std::clamp(std::sqrt(dist[(r + pad) * pc + c + pad]) / widthSamples, 0.0, 1.0);
      mask[r * cols + c] = static_cast<float>(t * t * (3.0 - 2.0 * t));
    }
  }
  return std::make_shared<topo::InMemorySamples>(rows, cols, std::move(mask));
}

}  // namespace regolith::compose
