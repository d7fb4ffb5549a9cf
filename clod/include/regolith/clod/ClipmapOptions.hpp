#pragma once
/// \file
/// The settings of a ClipmapTerrain, apart from the class so that code which only configures
/// terrains (SceneRenderer::addTerrain(), scenes) needs no GL header.

#include <regolith/clod/Effects.hpp>
#include <regolith/core/Executor.hpp>

#include <glm/vec3.hpp>

#include <cstddef>
#include <memory>

namespace regolith::clod {

/// Settings of a ClipmapTerrain.
struct ClipmapOptions {
  /// Vertices per level side (odd, 15 ≤ size ≤ 2047).
  int size = 255;
  /// Levels used (0: every pyramid level). Level k reads pyramid level k.
  std::size_t levels = 0;
  /// A level draws only while its cells, at their nearest to the camera, span at least
  /// this many pixels; finer levels switch off and the next one draws its centre.
  double minCellPixels = 0.5;
  glm::vec3 lightDirection{0.4F, -0.3F, 0.866F};  ///< towards the light, scene frame
  glm::vec3 albedo{0.78F, 0.66F, 0.55F};
  float ambient = 0.2F;
  /// Background loading (requestFocus): after each level's window, the loader hints a ring
  /// this many cells wide around it to the level's source (topo::SampleSource::prefetch()),
  /// so a paged source loads the patches the next moves need in the background (a store's
  /// pyramid: its store::Prefetcher; the lazy-load window is the clipmap plus this margin).
  int prefetchMargin = 32;
  /// Where a coarser level overlaps a finer one, push the coarser surface's depth back by
  /// this fraction so the finer (more exact) surface wins the depth test there: fewer
  /// patches of coarse terrain showing through near level borders at grazing angles, but
  /// the depth buffer no longer holds the exact geometry in those bands (off by default;
  /// the viewer uses 0.02).
  float overlapDepthPush = 0.0F;
  /// Effects the scene declares (docs/overlays.md). Which ones are declared is fixed at
  /// construction (each is compiled into the program); their parameters may change through
  /// setOptions(). None: the bare pipeline.
  Effects effects;
  /// Tracks: GPU window of the rover::TrackLayer around the focus, texels per side (256..8192).
  int trackWindow = 2048;
  /// Compile in the cut-out test, so that DEMs drawn over this planet can win where they
  /// have data (SceneRenderer::addCutOut() rebuilds the planet's terrain with it). Inert until
  /// ClipmapTerrain::setCutOuts() names a DEM; fixed at construction like the effects.
  bool cutOuts = false;
  /// Leave out the levels the camera cannot see: a level whose bounding sphere (its window
  /// from the skirts' depth to its highest sample) lies outside the view frustum or, on a
  /// planet, wholly behind the body's horizon (hidden by a sphere below every height the
  /// clipmap holds). Culled triangles would have drawn no pixel; off draws them anyway, for
  /// the test that shows culling changes no pixel and for the benchmark of what it saves.
  bool cullLevels = true;
  /// Tracks: relative darkening of the albedo inside a rut (compacted soil).
  float trackDarkening = 0.15F;
  /// Where background reads run (requestFocus(): the levels' windows, one at a time,
  /// coarsest first; the draped textures' windows). Null: one-thread core::ThreadPools made
  /// at the first background read. Shared, so it outlives the terrain's last read.
  std::shared_ptr<core::Executor> executor;
};

}  // namespace regolith::clod
