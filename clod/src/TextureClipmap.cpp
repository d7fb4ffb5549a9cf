#include <regolith/clod/HeightPyramid.hpp>
#include <regolith/clod/TextureClipmap.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/gl/Gl.hpp>
#include <regolith/gl/GlError.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace regolith::clod {

namespace {

GLuint makeArray(int window, int layers) {
  GLuint id = 0;
  glCreateTextures(GL_TEXTURE_2D_ARRAY, 1, &id);
  glTextureStorage3D(id, 1, GL_RGBA8, window, window, layers);
  glTextureParameteri(id, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTextureParameteri(id, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTextureParameteri(id, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTextureParameteri(id, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  return id;
}

std::uint8_t unorm8(float v) {
  return static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0F, 1.0F) * 255.0F));
}

}  // namespace

TextureClipmap::~TextureClipmap() {
  if (job_.valid()) job_.wait();
}

TextureClipmap::TextureClipmap(const DrapedTexture& texture, std::string name,
                               std::shared_ptr<core::Executor> executor)
    : source_(texture),
      name_(std::move(name)),
      window_(texture.window),
      texture_(0U),
      executor_(std::move(executor)) {
  const auto fail = [&](const std::string& what) {
    throw InvalidArgument("TextureClipmap(): " + name_ + ": " + what);
  };
  const std::size_t nc = source_.channels.size();
  if (nc != 1 && nc != 3 && nc != 4)
    fail(std::to_string(nc) + " channels, expected 1 (grey), 3 (RGB) or 4 (RGBA)");
  for (std::size_t c = 0; c < nc; ++c)
    if (!source_.channels[c]) fail("channel " + std::to_string(c) + " is null");
  if (window_ < 64 || window_ > 4096)
    fail("window " + std::to_string(window_) + " texels, expected 64..4096");
  const HeightPyramid& p0 = *source_.channels[0];
  for (std::size_t c = 1; c < nc; ++c) {
    const HeightPyramid& p = *source_.channels[c];
    bool same = p.levelCount() == p0.levelCount();
    for (std::size_t l = 0; same && l < p.levelCount(); ++l) {
      const auto &a = p.level(l).grid, &b = p0.level(l).grid;
      same = a.rows() == b.rows() && a.cols() == b.cols() && a.x0() == b.x0() && a.y0() == b.y0() &&
             a.spacingX() == b.spacingX() && a.spacingY() == b.spacingY();
    }
    if (!same) fail("channel " + std::to_string(c) + " has other grids than channel 0");
  }
  // Levels up to the first one the window covers whole.
  std::size_t count = p0.levelCount();
  for (std::size_t l = 0; l < p0.levelCount(); ++l) {
    const auto& g = p0.level(l).grid;
    if (std::max(g.rows(), g.cols()) <= static_cast<std::size_t>(window_)) {
      count = l + 1;
      break;
    }
  }
  count = std::min<std::size_t>(count, 16);  // the shader's window array
  windows_.resize(count);
  texture_ = gl::Texture(makeArray(window_, static_cast<int>(count)));
  gl::checkGl("TextureClipmap()");
}

double TextureClipmap::spacing0() const noexcept {
  return source_.channels[0]->level(0).grid.spacingX();
}

std::vector<TextureClipmap::Layer> TextureClipmap::plan(glm::dvec2 focus) const {
  std::vector<Layer> out;
  const HeightPyramid& p0 = *source_.channels[0];
  for (std::size_t l = 0; l < windows_.size(); ++l) {
    const auto& g = p0.level(l).grid;
    const glm::dvec2 f = g.fractionalIndex(focus.x, focus.y);  // (col, row)
    const auto col0 = static_cast<std::int64_t>(std::lround(f.x)) - window_ / 2;
    const auto row0 = static_cast<std::int64_t>(std::lround(f.y)) - window_ / 2;
    const Window& w = windows_[l];
    const std::int64_t quarter = window_ / 4;
    if (w.loaded && std::llabs(row0 - w.row0) < quarter && std::llabs(col0 - w.col0) < quarter)
      continue;
    out.push_back(Layer{l, row0, col0, {}});
  }
  return out;
}

std::size_t TextureClipmap::update(glm::dvec2 focus) {
  poll(true);  // a background read finishes first, so windows never go back in time
  std::vector<Layer> layers = plan(focus);
  std::size_t count = 0;
  for (Layer& layer : layers) {
    read(layer);
    upload(layer);
    count += layer.rgba.size() / 4;
  }
  return count;
}

void TextureClipmap::request(glm::dvec2 focus) {
  if (job_.valid()) {
    pending_ = focus;
    return;
  }
  pending_.reset();
  std::vector<Layer> layers = plan(focus);
  if (layers.empty()) return;
  if (!executor_) executor_ = std::make_shared<core::ThreadPool>(1);
  job_ = core::submitTask(*executor_, [this, layers = std::move(layers)]() mutable {
    for (Layer& layer : layers) read(layer);
    return std::move(layers);
  });
}

std::size_t TextureClipmap::poll(bool wait) {
  if (!job_.valid()) return 0;
  if (!wait && job_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return 0;
  const std::vector<Layer> layers = job_.get();  // rethrows a read error
  std::size_t count = 0;
  for (const Layer& layer : layers) {
    upload(layer);
    count += layer.rgba.size() / 4;
  }
  if (pending_) request(*pending_);
  return count;
}

void TextureClipmap::read(Layer& layer) const {
  const std::size_t level = layer.level;
  const std::int64_t row0 = layer.row0, col0 = layer.col0;
  const auto n = static_cast<std::size_t>(window_);
  std::vector<std::uint8_t>& rgba = layer.rgba;
  rgba.assign(n * n * 4, 0);
  const std::size_t nc = source_.channels.size();
  const auto& g = source_.channels[0]->level(level).grid;
  // The part of the window inside the grid.
  const std::int64_t r0 = std::max<std::int64_t>(row0, 0);
  const std::int64_t c0 = std::max<std::int64_t>(col0, 0);
  const std::int64_t r1 =
      std::min<std::int64_t>(row0 + window_, static_cast<std::int64_t>(g.rows()));
  const std::int64_t c1 =
      std::min<std::int64_t>(col0 + window_, static_cast<std::int64_t>(g.cols()));
  if (r1 > r0 && c1 > c0) {
    const auto h = static_cast<std::size_t>(r1 - r0), w = static_cast<std::size_t>(c1 - c0);
    std::vector<float> values(h * w);
    for (std::size_t c = 0; c < nc; ++c) {
      const auto& lvl = source_.channels[c]->level(level);
      lvl.source->readWindow(static_cast<std::size_t>(r0), static_cast<std::size_t>(c0), h, w,
                             values);
      for (std::size_t y = 0; y < h; ++y)
        for (std::size_t x = 0; x < w; ++x) {
          const float v = values[y * w + x];
          const std::size_t at = ((static_cast<std::size_t>(r0 - row0) + y) * n +
                                  static_cast<std::size_t>(c0 - col0) + x) *
                                 4;
          const bool missing = lvl.grid.isNodata(v);
          if (nc == 1) {
            rgba[at] = rgba[at + 1] = rgba[at + 2] = missing ? 0 : unorm8(v);
            rgba[at + 3] = missing ? 0 : 255;
          } else {
            rgba[at + c] = missing ? 0 : unorm8(v);
            if (c == 0) rgba[at + 3] = missing ? 0 : 255;
            if (missing) rgba[at + 3] = 0;
          }
        }
    }
  }
}

void TextureClipmap::upload(const Layer& layer) {
  glTextureSubImage3D(texture_.id(), 0, 0, 0, static_cast<GLint>(layer.level), window_, window_, 1,
                      GL_RGBA, GL_UNSIGNED_BYTE, layer.rgba.data());
  gl::checkGl("TextureClipmap: upload");
  windows_[layer.level] = Window{layer.row0, layer.col0, true};
  uploaded_ += layer.rgba.size() / 4;
}

std::vector<glm::vec4> TextureClipmap::windowRects(glm::dvec2 origin) const {
  std::vector<glm::vec4> out;
  for (std::size_t l = 0; l < windows_.size(); ++l) {
    const auto& g = source_.channels[0]->level(l).grid;
    const auto& w = windows_[l];
    const double west = g.x0() + (static_cast<double>(w.col0) - 0.5) * g.spacingX();
    const double north = g.y0() - (static_cast<double>(w.row0) - 0.5) * g.spacingY();
    out.emplace_back(static_cast<float>(west - origin.x), static_cast<float>(north - origin.y),
                     static_cast<float>(window_ * g.spacingX()),
                     static_cast<float>(window_ * g.spacingY()));
  }
  return out;
}

}  // namespace regolith::clod
