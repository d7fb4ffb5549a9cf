#pragma once
/// \file
/// The legend of a frame's effects: the height colour bar with its values and the lat/lon
/// line spacing, as a small image (drawn into a render or saved beside it) and as JSON.

#include <regolith/clod/Camera.hpp>
#include <regolith/clod/Effects.hpp>
#include <regolith/gl/Image.hpp>

#include <optional>
#include <string>

namespace regolith::clod {

class ClipmapTerrain;

/// A legend. The image is a dark panel: a vertical colour bar (the height ramp, highest
/// height at the top) labelled with its top, middle and bottom heights in metres, and a line
/// "LAT/LON <spacing>°" when lat/lon lines are drawn. Labels use a built-in 3 × 5 pixel font
/// scaled 2×. Value type.
class Legend {
 public:
  Legend(std::optional<HeightColours> heights, std::optional<double> latLonSpacingDegrees);
  /// The legend of what `terrain` draws for `camera` (its declared height colours and the
  /// lat/lon spacing that camera gets). Empty if neither effect is declared.
  static Legend of(const ClipmapTerrain& terrain, const Camera& camera);

  [[nodiscard]] bool empty() const noexcept { return !heights_ && !latLon_; }
  /// The legend alone (1 × 1 transparent if empty).
  [[nodiscard]] gl::RgbaImage image() const;
  /// Copies image() into `target` at its top-right corner, 8 pixels in (clipped).
  void drawInto(gl::RgbaImage& target) const;
  /// JSON: {"heightColours": {"min": m, "max": m, "stops": [[r, g, b], ...]},
  ///        "latLonSpacingDegrees": d} (members present only for declared effects).
  [[nodiscard]] std::string json() const;
  /// Writes json() to `path` crash-safely (temporary name, then rename); throws
  /// regolith::Error naming the path on failure.
  void writeJson(const std::string& path) const;

  /// The colour bar in image(): columns [x0, x1), rows [y0, y1); row y0 is maxHeight.
  struct Bar {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  };
  [[nodiscard]] Bar bar() const noexcept;
  /// Height shown at bar row y (its centre), metres.
  [[nodiscard]] double heightAtRow(int y) const;

  [[nodiscard]] const std::optional<HeightColours>& heights() const noexcept { return heights_; }
  [[nodiscard]] const std::optional<double>& latLonSpacing() const noexcept { return latLon_; }

 private:
  std::optional<HeightColours> heights_;
  std::optional<double> latLon_;
};

}  // namespace regolith::clod
