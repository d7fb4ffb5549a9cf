#pragma once
// GPU state of a ClipmapTerrain's declared effects. Private to clod.

#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/clod/TextureClipmap.hpp>
#include <regolith/core/Executor.hpp>
#include <regolith/gl/GlObjects.hpp>

#include "EffectShaders.hpp"

#include <cstdint>
#include <future>
#include <memory>

namespace regolith::clod {

/// The height of the coarsest pyramid level's sample nearest the focus, which lat/lon lines
/// that adapt to the view measure the camera's altitude from.
struct FocusGround {
  std::int64_t row = -1, col = -1;  ///< the sample (-1, -1: off the grid, height 0)
  double height = 0.0;              ///< metres; 0 over nodata or off the grid
  bool known = false;               ///< false until a focus was set

  [[nodiscard]] bool sameSample(const FocusGround& o) const noexcept {
    return known && o.known && row == o.row && col == o.col;
  }
};
/// The ground under grid point `o` of `pyramid`: the sample only, or (`read`) with its height.
[[nodiscard]] FocusGround focusGround(const HeightPyramid& pyramid, glm::dvec2 o, bool read);

struct ClipmapTerrain::EffectState {
  EffectNeeds needs;
  std::unique_ptr<TextureClipmap> albedo, overlay;
  // Tracks: an R32F window of the rover::TrackLayer, texels [tx0, tx0 + n) × [ty0, ty0 + n).
  gl::Texture tracks{0U};
  int trackWindow = 0;
  std::int64_t trackTx0 = 0, trackTy0 = 0;
  bool trackLoaded = false;
  std::uint64_t trackVersion = 0;
  // Lat/lon lines that adapt to the view (ClipmapTerrain::latLonSpacing()): the ground under
  // the focus. Read when the focus moves onto another sample: on the calling thread by
  // setFocus(), on the executor by requestFocus(); never in draw(), which uses the last
  // ground known.
  FocusGround ground;                  // the last one read (known: false before that)
  std::future<FocusGround> groundJob;  // requestFocus(): the read running on the executor
  std::shared_ptr<core::Executor> groundExecutor;
};

}  // namespace regolith::clod
