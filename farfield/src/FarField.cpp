#include <regolith/core/Error.hpp>
#include <regolith/farfield/FarField.hpp>

#include <utility>

namespace regolith::farfield {

namespace {

const HeightLayers& require(const std::shared_ptr<const HeightLayers>& layers) {
  if (!layers) throw InvalidArgument("farfield::FarField(): layers is null, expected layers");
  return *layers;
}

}  // namespace

FarField::FarField(std::shared_ptr<const HeightLayers> layers, PgmOptions options)
    : layers_(std::move(layers)), pgm_(require(layers_), options) {}

FarField::~FarField() = default;

FarFieldFrame FarField::draw(const gl::RenderTarget& target, const clod::Camera& camera,
                             const glm::dvec3& sun, bool keepDrawn) {
  FarFieldFrame frame;
  frame.pgm = pgm_.draw(target, camera, sun, keepDrawn);
  frame.mode = frame.pgm.drawn ? FarFieldMode::Pgm : FarFieldMode::None;
  return frame;
}

}  // namespace regolith::farfield
