// Triangle-mesh export (OBJ and binary PLY) of grid regions.
#include <regolith/core/Error.hpp>
#include <regolith/topo/Mesh.hpp>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cstring>
#include <sstream>

using namespace regolith;
using namespace regolith::topo;

namespace {
TopoDem smallDem(bool hole) {
  const TopoGrid g(3, 4, 10.0, 20.0, 2.0, 2.0, -9999.0f);
  std::vector<float> v{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
  if (hole) v[5] = -9999.0f;  // sample (1, 1)
  return {g, Placement(LocalTangentPlane(Body::marsSphere(), {-2.05, -5.5, 0.0})),
          std::make_shared<InMemorySamples>(3, 4, v)};
}
}  // namespace

TEST(Mesh, GridMeshHasOneVertexPerSampleAndTwoUpFacingTrianglesPerCell) {
  const TriangleMesh m = buildMesh(smallDem(false), {});
  ASSERT_EQ(m.vertices.size(), 12u);
  ASSERT_EQ(m.triangles.size(), 2u * 2u * 3u);
  EXPECT_EQ(m.vertices[6], glm::dvec3(14.0, 18.0, 7.0));  // sample (1, 2)
  for (const auto& t : m.triangles) {
    const glm::dvec3 n =
        glm::cross(m.vertices[t[1]] - m.vertices[t[0]], m.vertices[t[2]] - m.vertices[t[0]]);
    EXPECT_GT(n.z, 0.0) << "counter-clockwise seen from above";
  }
}

TEST(Mesh, NodataLeavesAHoleNotASpike) {
  const TriangleMesh m = buildMesh(smallDem(true), {});
  EXPECT_EQ(m.vertices.size(), 11u);
  // Sample (1,1) touches 6 of the 12 triangles.
  EXPECT_EQ(m.triangles.size(), 6u);
  for (const auto& v : m.vertices) EXPECT_NE(v.z, -9999.0);
}

TEST(Mesh, BodyFixedMeshIsRelativeToItsOrigin) {
  const TopoDem dem = smallDem(false);
  const glm::dvec3 origin = dem.toBodyFixed(10.0, 20.0, 0.0);
  const TriangleMesh m = buildMesh(dem, {1, 1, 2, 2}, MeshFrame::BodyFixed, origin);
  ASSERT_EQ(m.vertices.size(), 4u);
  EXPECT_NEAR(glm::length(m.vertices[0] + origin - dem.samplePosition(1, 1)), 0.0, 1e-9);
  EXPECT_LT(glm::length(m.vertices[3]), 20.0);  // small numbers, safe to upload as float
}

TEST(Mesh, WindowsOutsideTheGridAreRejected) {
  EXPECT_THROW((void)buildMesh(smallDem(false), {2, 0, 2, 2}), InvalidArgument);
  EXPECT_THROW((void)buildMesh(smallDem(false), {0, 0, 1, 4}), InvalidArgument);
}

TEST(Mesh, ObjTextListsVerticesAndOneBasedFaces) {
  const TriangleMesh m = buildMesh(smallDem(false), {0, 0, 2, 2});
  std::ostringstream os;
  writeObj(os, m);
  std::istringstream is(os.str());
  std::string line;
  std::vector<glm::dvec3> vs;
  std::vector<std::array<int, 3>> fs;
  while (std::getline(is, line)) {
    std::istringstream ls(line);
    std::string tag;
    ls >> tag;
    if (tag == "v") {
      glm::dvec3 v;
      ls >> v.x >> v.y >> v.z;
      vs.push_back(v);
    } else if (tag == "f") {
      std::array<int, 3> f{};
      ls >> f[0] >> f[1] >> f[2];
      fs.push_back(f);
    }
  }
  ASSERT_EQ(vs.size(), m.vertices.size());
  ASSERT_EQ(fs.size(), m.triangles.size());
  for (std::size_t i = 0; i < vs.size(); ++i) EXPECT_EQ(vs[i], m.vertices[i]);
  for (std::size_t i = 0; i < fs.size(); ++i) {
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(static_cast<std::uint32_t>(fs[i][static_cast<std::size_t>(k)]),
                m.triangles[i][static_cast<std::size_t>(k)] + 1);
  }
}

TEST(Mesh, PlyIsBinaryLittleEndianWithDoubleVertices) {
  const TriangleMesh m = buildMesh(smallDem(false), {});
  std::ostringstream os;
  writePly(os, m);
  const std::string s = os.str();
  const std::size_t end = s.find("end_header\n");
  ASSERT_NE(end, std::string::npos);
  const std::string header = s.substr(0, end);
  EXPECT_NE(header.find("format binary_little_endian 1.0"), std::string::npos);
  EXPECT_NE(header.find("element vertex 12"), std::string::npos);
  EXPECT_NE(header.find("element face 12"), std::string::npos);
  const char* body = s.data() + end + std::strlen("end_header\n");
  EXPECT_EQ(s.size() - static_cast<std::size_t>(body - s.data()), 12u * 24u + 12u * 13u);
  double v7[3];
  std::memcpy(v7, body + 7 * 24, 24);
  EXPECT_EQ(glm::dvec3(v7[0], v7[1], v7[2]), m.vertices[7]);
  const char* face0 = body + 12 * 24;
  EXPECT_EQ(static_cast<unsigned char>(face0[0]), 3u);
  std::uint32_t idx[3];
  std::memcpy(idx, face0 + 1, 12);
  EXPECT_EQ(idx[0], m.triangles[0][0]);
  EXPECT_EQ(idx[2], m.triangles[0][2]);
}
