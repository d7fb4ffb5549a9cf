#include <regolith/core/Error.hpp>
#include <regolith/farfield/FarField.hpp>
#include <regolith/gl/Gl.hpp>
#include <regolith/gl/Image.hpp>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

namespace regolith::farfield {

namespace {

const HeightLayers& require(const std::shared_ptr<const HeightLayers>& layers) {
  if (!layers) throw InvalidArgument("farfield::FarField(): layers is null, expected layers");
  return *layers;
}

/// PGM's albedo over the equirectangular layer, north row first (RayCastGlobe's texture).
gl::RgbaImage albedoImage(const HeightLayers& layers, const PgmOptions& o) {
  gl::RgbaImage img;
  img.width = layers.equirectWidth();
  img.height = layers.equirectHeight();
  img.rgba.resize(static_cast<std::size_t>(img.width) * static_cast<std::size_t>(img.height) * 4);
  const double range = layers.maxHeight() - layers.minHeight();
  for (int j = 0; j < img.height; ++j) {
    const int row = img.height - 1 - j;  // the layer's row 0 is in the south
    for (int i = 0; i < img.width; ++i) {
      const double h =
          layers.equirect()[static_cast<std::size_t>(row) * static_cast<std::size_t>(img.width) +
                            static_cast<std::size_t>(i)];
      const float t =
          range > 1.0 ? static_cast<float>(std::clamp((h - layers.minHeight()) / range, 0.0, 1.0))
                      : 0.5F;
      const glm::vec3 c = o.heightColours ? glm::mix(o.low, o.high, t) : o.high;
      std::uint8_t* p =
          img.rgba.data() + 4 * (static_cast<std::size_t>(j) * static_cast<std::size_t>(img.width) +
                                 static_cast<std::size_t>(i));
      for (int k = 0; k < 3; ++k) {
        p[k] = static_cast<std::uint8_t>(std::lround(std::clamp(c[k], 0.0F, 1.0F) * 255.0F));
      }
      p[3] = 255;
    }
  }
  return img;
}

GlobeOptions globeOptions(const PgmOptions& o) {
  GlobeOptions g;
  g.ambient = o.ambient;
  return g;
}

}  // namespace

FarField::FarField(std::shared_ptr<const HeightLayers> layers, PgmOptions options)
    : layers_(std::move(layers)),
      pgm_(require(layers_), options),
      globe_(globeOptions(options)),
      albedo_(makeEquirectangularTexture(albedoImage(*layers_, options), true)) {}

FarField::~FarField() = default;

FarFieldFrame FarField::draw(const gl::RenderTarget& target, const clod::Camera& camera,
                             const glm::dvec3& sun, bool keepDrawn) {
  FarFieldFrame frame;
  // The impostor is the bare ellipsoid: its screen error is at most the relief over the
  // distance, seen from the nearest point the body can have (d - r_max; the limb is farther).
  const double d = glm::length(camera.position);
  const double relief = std::max(std::abs(layers_->minHeight()), std::abs(layers_->maxHeight()));
  frame.reliefPixels = d > pgm_.maxRadius() ? relief / (d - pgm_.maxRadius()) * camera.focalPixels()
                                            : std::numeric_limits<double>::infinity();
  // (A camera not of the target's size goes on to PGM, which refuses it.)
  if (keepDrawn && camera.width == target.width() && camera.height == target.height() &&
      !emptyTest_.anyEmpty(target)) {
    // The near field drew every pixel: nothing to fill in. PGM's lagged primary sphere
    // would come from a view long past when it next draws, so it starts again from the
    // lowest radius.
    pgm_.restart();
    frame.mode = FarFieldMode::Covered;
    return frame;
  }
  const double limit = pgm_.options().impostorReliefPixels;
  if (!(limit > 0.0 && frame.reliefPixels <= limit)) {
    frame.pgm = pgm_.draw(target, camera, sun, keepDrawn);
    if (frame.pgm.drawn) {
      frame.mode = FarFieldMode::Pgm;
      return frame;
    }
  }
  // Too far for PGM: the impostor.
  if (keepDrawn) {
    if (depthWidth_ != target.width() || depthHeight_ != target.height()) {
      drawnDepth_ = gl::Texture();
      glTextureStorage2D(drawnDepth_.id(), 1, GL_DEPTH_COMPONENT32F, target.width(),
                         target.height());
      depthWidth_ = target.width();
      depthHeight_ = target.height();
    }
    glCopyImageSubData(target.depthTexture(), GL_TEXTURE_2D, 0, 0, 0, 0, drawnDepth_.id(),
                       GL_TEXTURE_2D, 0, 0, 0, 0, target.width(), target.height(), 1);
  }
  GlobeBody body;
  body.a = layers_->body().equatorialRadius();
  body.b = layers_->body().polarRadius();
  body.albedoTexture = albedo_.id();
  body.colour = glm::vec3(1.0F);
  target.bind();
  frame.globe = globe_.draw(camera, body, sun, keepDrawn ? drawnDepth_.id() : 0);
  frame.mode = frame.globe.drawn ? FarFieldMode::Impostor : FarFieldMode::None;
  return frame;
}

}  // namespace regolith::farfield
