#pragma once
/// \file
/// A texture clipmap: a draped texture of any size (albedo, science map) shown through one
/// fixed-size window per pyramid level, paged from its sources like the heights.

#include <regolith/clod/Effects.hpp>
#include <regolith/core/Executor.hpp>
#include <regolith/gl/GlObjects.hpp>

#include <glm/vec2.hpp>
#include <glm/vec4.hpp>

#include <cstddef>
#include <cstdint>
#include <future>
#include <optional>
#include <string>
#include <vector>

namespace regolith::clod {

/// Texture clipmap (Tanner, Migdal & Jones 1998, the JPL paper's future work): level l of the
/// texture pyramid is held as a `window` × `window` RGBA8 layer of one GL_TEXTURE_2D_ARRAY,
/// centred on the focus. The fragment shader picks per pixel the finest level whose texels
/// are at least as large as the pixel's footprint and whose window holds the point, so the
/// texture is drawn at the resolution the view needs while the GPU holds only
/// window² × levels texels, whatever the size of the source (16K wide and more, beyond the
/// GPU's maximum texture size).
///
/// Sources: DrapedTexture::channels, one HeightPyramid per channel (the store's pyramid
/// through store::Pager, or fromSamples()). Levels stop at the first one the window covers.
/// A window moves when the focus drifts a quarter window from its centre; the layer is then
/// read again and uploaded whole: on the calling thread (update()), or on the executor it is
/// given (request(), then poll() uploads on the render thread), while the old windows keep drawing
/// (a pixel outside every window falls back to the terrain's own albedo). Outside the source or
/// over NaN the alpha is 0 (the terrain's own albedo shows).
///
/// Needs a current GL 4.5 context; belongs to its thread.
class TextureClipmap {
 public:
  /// Background reads (request()) run on `executor`; null: a one-thread core::ThreadPool
  /// made at the first request. Throws InvalidArgument naming `name` if there are not 1, 3
  /// or 4 channels, a channel is null, channels' grids or level counts differ, or the window
  /// is outside 64..4096.
  TextureClipmap(const DrapedTexture& texture, std::string name,
                 std::shared_ptr<core::Executor> executor = nullptr);
  TextureClipmap(const TextureClipmap&) = delete;
  TextureClipmap& operator=(const TextureClipmap&) = delete;
  TextureClipmap(TextureClipmap&&) = delete;
  TextureClipmap& operator=(TextureClipmap&&) = delete;
  /// Waits for a background read still running (it reads this object's sources).
  ~TextureClipmap();

  /// Centres the windows on grid point `focus` (the terrain's grid coordinates). Returns the
  /// texels uploaded (0 if no window had to move).
  std::size_t update(glm::dvec2 focus);
  /// Background loading: reads the windows that must move on the executor and returns at
  /// once; a request while one is running is kept (the latest) and started after it.
  void request(glm::dvec2 focus);
  /// Uploads finished background reads (render thread); with `wait`, first blocks until the
  /// running read finishes. Returns the texels uploaded. Rethrows a read error (store I/O).
  std::size_t poll(bool wait = false);
  /// True while a background read is running or waiting.
  [[nodiscard]] bool loading() const noexcept { return job_.valid() || pending_.has_value(); }

  [[nodiscard]] gl::Id texture() const noexcept { return texture_.id(); }
  [[nodiscard]] int levels() const noexcept { return static_cast<int>(windows_.size()); }
  [[nodiscard]] int window() const noexcept { return window_; }
  /// Level-0 texel size along x, grid units.
  [[nodiscard]] double spacing0() const noexcept;
  /// Per level: (west edge, north edge, width, height) of its window in grid units, relative
  /// to `origin`.
  [[nodiscard]] std::vector<glm::vec4> windowRects(glm::dvec2 origin) const;
  /// Texels uploaded since construction.
  [[nodiscard]] std::size_t uploadedTexels() const noexcept { return uploaded_; }

 private:
  struct Window {
    std::int64_t row0 = 0, col0 = 0;
    bool loaded = false;
  };
  struct Layer {
    std::size_t level;
    std::int64_t row0, col0;
    std::vector<std::uint8_t> rgba;
  };
  /// Windows that must move for `focus`, not yet read.
  [[nodiscard]] std::vector<Layer> plan(glm::dvec2 focus) const;
  /// Reads a layer's texels from the sources (any thread: reads only the sources).
  void read(Layer& layer) const;
  void upload(const Layer& layer);

  DrapedTexture source_;
  std::string name_;
  int window_;
  std::vector<Window> windows_;
  gl::Texture texture_;
  std::size_t uploaded_ = 0;
  std::shared_ptr<core::Executor> executor_;
  std::future<std::vector<Layer>> job_;
  std::optional<glm::dvec2> pending_;
};

}  // namespace regolith::clod
