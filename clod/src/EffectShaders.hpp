#pragma once
// Composes the clipmap program from the bare shaders (Shaders.hpp) and one snippet per
// declared effect. Private to clod.

#include <regolith/clod/Effects.hpp>
#include <regolith/gl/Program.hpp>

namespace regolith::clod {

/// What the declared effects need from the pipeline.
struct EffectNeeds {
  bool grid = false;    // fGrid: grid coordinates relative to the frame's grid origin
  bool height = false;  // fHeight
  bool body = false;    // fBody: body-fixed position (float); lat/lon lines, and grid effects
                        // on planets (grid point per fragment on the polar lattice)
  bool axes = false;    // uAxisX/uAxisY: scene vectors per grid unit (normal perturbation)
  static EffectNeeds of(const Effects& effects, bool planet) noexcept;
};

/// The clipmap program's sources for these effects: the bare sources (Shaders.hpp) with each
/// declared effect's declarations, varyings and code inserted at fixed anchors. No effect:
/// exactly the bare sources. `planet`: the terrain is a Planet pyramid. Throws GlError if an
/// anchor is missing (the bare shaders were edited without updating the composer).
[[nodiscard]] gl::ShaderSources composeClipmapSources(const Effects& effects, bool planet);

}  // namespace regolith::clod
