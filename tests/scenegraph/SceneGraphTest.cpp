#include <regolith/core/Error.hpp>
#include <regolith/demo/PaperScene.hpp>
#include <regolith/scenegraph/SceneGraph.hpp>
#include <regolith/topo/Projection.hpp>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>

namespace regolith::scenegraph {
namespace {

using demo::buildPaperScene;
using demo::kDrawRover;
using demo::kDrawVictoria;
using demo::PaperSceneLayout;
using demo::PaperSceneNodes;

void expectNear(const glm::dvec3& a, const glm::dvec3& b, double tol) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

TEST(SceneGraphTest, AddFindAndErrors) {
  SceneGraph g("sun");
  const NodeId a = g.add(g.root(), "a", Pose{});
  EXPECT_EQ(g.find("a"), a);
  EXPECT_EQ(g.at("sun"), g.root());
  EXPECT_FALSE(g.find("b"));
  EXPECT_THROW(g.add(g.root(), "a", Pose{}), InvalidArgument);
  EXPECT_THROW(g.add(99, "c", Pose{}), InvalidArgument);
  EXPECT_THROW(g.add(a, "", Pose{}), InvalidArgument);
  Pose bad;
  bad.translation.x = std::nan("");
  EXPECT_THROW(g.add(a, "nan", bad), InvalidArgument);
  EXPECT_THROW(g.setLocal(g.root(), Pose{}), InvalidArgument);
  try {
    (void)g.at("nowhere");
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("'nowhere'"), std::string::npos);
  }
  EXPECT_THROW((void)g.renderList(g.root(), a), InvalidArgument);  // not a camera
}

TEST(SceneGraphTest, RelativePoseGoesThroughTheCommonAncestor) {
  SceneGraph g;
  Pose pa, pb, pc;
  pa.translation = {1e11, 0, 0};
  pa.rotation = glm::angleAxis(0.3, glm::dvec3(0, 0, 1));
  pb.translation = {0, 3e6, 0};
  pc.translation = {0, 0, 5};
  pc.rotation = glm::angleAxis(-0.2, glm::dvec3(1, 0, 0));
  const NodeId a = g.add(g.root(), "a", pa);
  const NodeId b = g.add(a, "b", pb);
  const NodeId c = g.add(a, "c", pc);
  EXPECT_EQ(g.commonAncestor(b, c), a);
  EXPECT_EQ(g.commonAncestor(b, g.root()), g.root());
  EXPECT_EQ(g.pathToRoot(b), (std::vector<NodeId>{b, a, g.root()}));
  // b and c meet at a: the result involves only the two small edges.
  const Pose bc = g.relative(b, c);
  const Pose expect = pb.inverse() * pc;
  expectNear(bc.translation, expect.translation, 1e-12);
  // Through the root the 1e11 m offset cancels and leaves ~1e-5 m of rounding.
  const Pose viaRoot = g.inRoot(b).inverse() * g.inRoot(c);
  expectNear(viaRoot.translation, expect.translation, 1e-3);
  // Re-rooting at b gives every node's pose relative to b.
  const auto poses = g.rerooted(b);
  for (NodeId n = 0; n < g.size(); ++n) {
    const Pose r = g.relative(b, n);
    const double tol = 1e-12 * (1.0 + glm::length(r.translation));
    expectNear(poses[n].translation, r.translation, tol);
    expectNear(poses[n].apply({1, 2, 3}) - poses[n].translation, r.apply({1, 2, 3}) - r.translation,
               1e-12);
  }
}

TEST(SceneGraphTest, PaperSceneHasTheRightTreeAndPlacement) {
  SceneGraph g("sun");
  const PaperSceneLayout layout;
  const PaperSceneNodes n = buildPaperScene(g, layout);
  EXPECT_EQ(g.node(n.victoria).parent, n.mars);
  EXPECT_EQ(g.node(n.rover).parent, n.victoria);
  EXPECT_EQ(g.node(n.mars).parent, n.sun);
  EXPECT_EQ(g.node(n.earth).parent, n.sun);
  EXPECT_EQ(g.node(n.mastCamera).kind, NodeKind::Camera);
  EXPECT_THROW(buildPaperScene(g, layout), InvalidArgument);  // not empty
  // The DEM origin in Mars's frame is the body-fixed point of 2.05°S 5.5°W (topo's geodesy).
  const glm::dvec3 origin = g.relative(n.mars, n.victoria).translation;
  expectNear(origin, layout.mars.toBodyFixed(layout.victoriaOrigin), 1e-6);
  const topo::Geodetic geo = layout.mars.toGeodetic(origin);
  EXPECT_NEAR(geo.latDeg, -2.05, 1e-9);
  EXPECT_NEAR(geo.lonDeg, -5.5, 1e-9);
  // The DEM's z axis is Mars's surface normal there, its y axis points north.
  const glm::dmat3 enu = layout.mars.enuFrame(-2.05, -5.5);
  const glm::dmat3 axes = g.relative(n.mars, n.victoria).matrix();
  expectNear(axes[2], enu[2], 1e-12);
  expectNear(axes[1], enu[1], 1e-12);
  // Mars is 1.52 AU from the Sun.
  EXPECT_NEAR(glm::length(g.inRoot(n.mars).translation), layout.marsDistance, 1.0);
}

TEST(SceneGraphTest, RenderListIsTheSameSceneWhateverTheFocus) {
  SceneGraph g("sun");
  const PaperSceneNodes n = buildPaperScene(g);
  const RenderList atVictoria = g.renderList(n.victoria, n.chaseCamera);
  const RenderList atMars = g.renderList(n.mars, n.chaseCamera);
  const RenderList atEarth = g.renderList(n.earth, n.chaseCamera);
  const RenderList atSun = g.renderList(n.sun, n.chaseCamera);
  ASSERT_EQ(atVictoria.items.size(), 4U);  // earth, mars, victoria, rover
  // The focus is at the origin: the Victoria item's pose in focus is the identity there.
  expectNear(atVictoria.findDrawable(kDrawVictoria)->inFocus.translation, glm::dvec3(0.0), 0.0);
  // The camera is near the focus when the focus is the DEM: coordinates stay small.
  EXPECT_LT(glm::length(atVictoria.cameraInFocus.translation), 1000.0);
  EXPECT_GT(glm::length(atSun.cameraInFocus.translation), 1e11);
  // Every item's pose relative to the camera agrees across foci. Re-rooted at Victoria or
  // Mars the rover is placed to 1e-9 m; through Earth or the Sun 1e11 m offsets cancel and
  // leave rounding of ~1e-5 m (still far below a pixel).
  for (const auto& item : atVictoria.items) {
    const glm::dvec3 ref = g.relative(n.chaseCamera, item.node).translation;
    const double scale = 1.0 + glm::length(ref);
    expectNear(item.inCamera.translation, ref, 1e-12 * scale + 1e-9);
    expectNear(atMars.find(item.node)->inCamera.translation, ref, 1e-12 * scale + 1e-8);
    expectNear(atEarth.find(item.node)->inCamera.translation, ref, 1e-4 + 1e-14 * scale);
    expectNear(atSun.find(item.node)->inCamera.translation, ref, 1e-4 + 1e-14 * scale);
  }
  // The rover stands 8 m in front of and 2.5 m below the chase camera... in its frame:
  // camera at (−8, 0, 3) looking at (0, 0, 0.5).
  const glm::dvec3 roverInEye = atVictoria.findDrawable(kDrawRover)->inCamera.translation;
  EXPECT_NEAR(glm::length(roverInEye), std::sqrt(64.0 + 9.0), 1e-9);
  EXPECT_LT(roverInEye.z, 0.0);
}

TEST(SceneGraphTest, MovingTheRoverOneMillimetreMovesItOneMillimetreInTheRenderList) {
  SceneGraph g("sun");
  const PaperSceneLayout layout;
  const PaperSceneNodes n = buildPaperScene(g, layout);
  const glm::dvec3 before =
      g.renderList(n.victoria, n.orbitCamera).findDrawable(kDrawRover)->inFocus.translation;
  g.setLocal(n.rover, roverPose(layout.roverInDem + glm::dvec3(0.001, 0.0, 0.0), 0.0));
  const glm::dvec3 after =
      g.renderList(n.victoria, n.orbitCamera).findDrawable(kDrawRover)->inFocus.translation;
  expectNear(after - before, {0.001, 0.0, 0.0}, 1e-12);
  // In the Sun's frame the same move is lost in the rounding of a 2e11 m coordinate (its
  // spacing there is 3e-5 m in double, 16 km in float).
  const glm::dvec3 sunA = g.inRoot(n.rover).translation;
  const glm::vec3 sunF(sunA);
  EXPECT_EQ(glm::vec3(sunA + glm::dvec3(0.001, 0, 0)), sunF);
}

}  // namespace
}  // namespace regolith::scenegraph
