#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/topo/Mesh.hpp>

#include <bit>
#include <cstring>
#include <functional>
#include <limits>
#include <ostream>
#include <string>

namespace regolith::topo {
namespace {

GridWindow resolve(const TopoGrid& g, GridWindow w, const char* op) {
  if (w.rows == 0 && w.row0 < g.rows()) w.rows = g.rows() - w.row0;
  if (w.cols == 0 && w.col0 < g.cols()) w.cols = g.cols() - w.col0;
  if (w.row0 + w.rows > g.rows() || w.col0 + w.cols > g.cols() || w.rows < 2 || w.cols < 2) {
    throw InvalidArgument(std::string(op) + ": window rows " + core::number(w.row0) + "+" +
                          core::number(w.rows) + ", cols " + core::number(w.col0) + "+" +
                          core::number(w.cols) + " does not fit the " + core::number(g.rows()) +
                          "x" + core::number(g.cols()) +
                          " grid, expected at least 2x2 samples inside it");
  }
  if (w.rows * w.cols > std::numeric_limits<std::uint32_t>::max()) {
    throw InvalidArgument(std::string(op) + ": window has " + core::number(w.rows * w.cols) +
                          " samples, expected fewer than 2^32 (uint32 indices)");
  }
  return w;
}

// vertexOf(r, c) returns the vertex position or NaN for nodata.
TriangleMesh build(const GridWindow& w, const glm::dvec3& origin,
                   const std::function<glm::dvec3(std::size_t, std::size_t)>& vertexOf) {
  TriangleMesh m;
  m.origin = origin;
  constexpr std::uint32_t none = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> index(w.rows * w.cols, none);
  for (std::size_t r = 0; r < w.rows; ++r) {
    for (std::size_t c = 0; c < w.cols; ++c) {
      const glm::dvec3 p = vertexOf(w.row0 + r, w.col0 + c);
      if (std::isnan(p.x)) continue;
      index[r * w.cols + c] = static_cast<std::uint32_t>(m.vertices.size());
      m.vertices.push_back(p - origin);
    }
  }
  auto tri = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    if (a != none && b != none && c != none) m.triangles.push_back({a, b, c});
  };
  for (std::size_t r = 0; r + 1 < w.rows; ++r) {
    for (std::size_t c = 0; c + 1 < w.cols; ++c) {
      // A = top-left, B = top-right, C = bottom-left, D = bottom-right (row 0 is north),
      // wound counter-clockwise seen from above.
      const std::uint32_t a = index[r * w.cols + c], b = index[r * w.cols + c + 1];
      const std::uint32_t cc = index[(r + 1) * w.cols + c], d = index[(r + 1) * w.cols + c + 1];
      tri(a, cc, d);
      tri(a, d, b);
    }
  }
  return m;
}

double sampleHeight(const TopoGrid& g, const SampleSource& s, std::size_t r, std::size_t c) {
  const float v = s.sample(r, c);
  return g.isNodata(v) ? std::numeric_limits<double>::quiet_NaN() : static_cast<double>(v);
}

template <class T>
void putLE(std::ostream& out, T v) {
  static_assert(std::endian::native == std::endian::little, "PLY writer assumes little-endian");
  char buf[sizeof(T)];
  std::memcpy(buf, &v, sizeof(T));
  out.write(buf, sizeof(T));
}

}  // namespace

TriangleMesh buildMesh(const TopoDem& dem, const GridWindow& window, MeshFrame frame,
                       const glm::dvec3& origin) {
  const TopoGrid& g = dem.grid();
  const GridWindow w = resolve(g, window, "buildMesh()");
  return build(w, origin, [&](std::size_t r, std::size_t c) {
    const double h = sampleHeight(g, dem.samples(), r, c);
    if (std::isnan(h)) return glm::dvec3(h);
    const glm::dvec2 xy = g.sampleCentre(static_cast<double>(r), static_cast<double>(c));
    return frame == MeshFrame::Grid ? glm::dvec3(xy, h) : dem.toBodyFixed(xy.x, xy.y, h);
  });
}

TriangleMesh buildMesh(const TopoPlanet& planet, const GridWindow& window,
                       const glm::dvec3& origin) {
  const TopoGrid& g = planet.grid();
  const GridWindow w = resolve(g, window, "buildMesh()");
  return build(w, origin, [&](std::size_t r, std::size_t c) {
    const double h = sampleHeight(g, planet.samples(), r, c);
    if (std::isnan(h)) return glm::dvec3(h);
    const glm::dvec2 ll = g.sampleCentre(static_cast<double>(r), static_cast<double>(c));
    return planet.toBodyFixed({ll.y, ll.x}, h);
  });
}

void writeObj(std::ostream& out, const TriangleMesh& mesh) {
  const auto old = out.precision(std::numeric_limits<double>::max_digits10);
  out << "# Regolith terrain mesh: " << mesh.vertices.size() << " vertices, "
      << mesh.triangles.size() << " triangles\n";
  out << "# origin " << mesh.origin.x << ' ' << mesh.origin.y << ' ' << mesh.origin.z << '\n';
  for (const auto& v : mesh.vertices) out << "v " << v.x << ' ' << v.y << ' ' << v.z << '\n';
  for (const auto& t : mesh.triangles) {
    out << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
  }
  out.precision(old);
}

void writePly(std::ostream& out, const TriangleMesh& mesh) {
  const auto old = out.precision(std::numeric_limits<double>::max_digits10);
  out << "ply\nformat binary_little_endian 1.0\n"
      << "comment Regolith terrain mesh\n"
      << "comment origin " << mesh.origin.x << ' ' << mesh.origin.y << ' ' << mesh.origin.z << '\n'
      << "element vertex " << mesh.vertices.size() << '\n'
      << "property double x\nproperty double y\nproperty double z\n"
      << "element face " << mesh.triangles.size() << '\n'
      << "property list uchar uint vertex_indices\nend_header\n";
  out.precision(old);
  for (const auto& v : mesh.vertices) {
    putLE(out, v.x);
    putLE(out, v.y);
    putLE(out, v.z);
  }
  for (const auto& t : mesh.triangles) {
    putLE(out, static_cast<std::uint8_t>(3));
    for (std::uint32_t i : t) putLE(out, i);
  }
}

}  // namespace regolith::topo
