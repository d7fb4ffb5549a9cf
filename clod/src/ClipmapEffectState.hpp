#pragma once
// GPU state of a ClipmapTerrain's declared effects. Private to clod.

#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/clod/TextureClipmap.hpp>
#include <regolith/gl/GlObjects.hpp>

#include "EffectShaders.hpp"

#include <cstdint>
#include <memory>

namespace regolith::clod {

struct ClipmapTerrain::EffectState {
  EffectNeeds needs;
  std::unique_ptr<TextureClipmap> albedo, overlay;
  // Tracks: an R32F window of the rover::TrackLayer, texels [tx0, tx0 + n) × [ty0, ty0 + n).
  gl::Texture tracks{0U};
  int trackWindow = 0;
  std::int64_t trackTx0 = 0, trackTy0 = 0;
  bool trackLoaded = false;
  std::uint64_t trackVersion = 0;
};

}  // namespace regolith::clod
