#pragma once
/// \file
/// Wheel tracks a traverse leaves on the terrain: a rut-depth field in the terrain's grid
/// frame, stamped on the CPU each rover step (no GL). clod::ClipmapTerrain draws it as
/// perturbed normals (docs/overlays.md).

#include <glm/vec2.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <span>
#include <unordered_map>
#include <vector>

namespace regolith::rover {

/// The ruts the project's rover presses (the main demo, the traverse examples, Python's
/// defaults): a 0.40 m wide wheel, 3 cm deep at its centre, into a layer of 5 cm texels,
/// one imprint of all wheels every 5 cm of travel.
struct RoverRuts {
  static constexpr double kWheelWidthMetres = 0.40;
  static constexpr double kDepthMetres = 0.03;
  static constexpr double kTexelMetres = 0.05;
  static constexpr double kSpacingMetres = 0.05;
};

/// One wheel's imprint on the ground, in the terrain's grid frame (x east, y north,
/// metres: a plane DEM or a DEM placed on a planet). Not WheelContact (Rover.hpp), which is
/// what the terrain answers under a wheel.
struct WheelImprint {
  glm::dvec2 gridXY{0.0};
  double wheelWidthMetres = 0.4;
  double depthMetres = 0.02;
};

/// The rut depth of a whole traverse, stored sparsely in square tiles of `texelMetres`
/// texels that are created as wheels touch them, so tracks persist along the whole
/// traverse however long it is (memory grows with the ground the wheels covered, 1 MiB per
/// tile of 512² texels).
///
/// A contact presses a rut with a smooth cross-section (depth·cos²(π·d / width), d the
/// distance from the wheel's path) into the field; where ruts overlap the deeper one wins,
/// so driving twice over the same track does not deepen it. stampSegment() presses a
/// wheel's whole path between two steps, so the rut is continuous whatever the step
/// length; stamp() presses one contact (a disc of the wheel's width).
///
/// Thread-safe: a traverse may stamp from its own thread while the render thread reads.
class TrackLayer {
 public:
  /// Texel size in metres (> 0 and finite, else InvalidArgument).
  explicit TrackLayer(double texelMetres = 0.02);

  /// One contact. Throws InvalidArgument for a non-finite position, a width ≤ 0 or a depth
  /// < 0 (or non-finite).
  void stamp(glm::dvec2 gridXY, double wheelWidthMetres, double depthMetres);
  /// The wheel's path from `from` to `to` (same checks).
  void stampSegment(glm::dvec2 from, glm::dvec2 to, double wheelWidthMetres, double depthMetres);
  /// A rover step: each wheel's path from its previous contact to this one (the previous
  /// contacts of the same wheel index, kept per layer; the first step stamps discs).
  void step(std::span<const WheelImprint> wheels);

  [[nodiscard]] double texelMetres() const noexcept { return texel_; }
  /// Rut depth (metres, ≥ 0) at a grid point, bilinear between texel centres. Throws
  /// InvalidArgument for a non-finite point.
  [[nodiscard]] double depthAt(glm::dvec2 gridXY) const;
  /// Depth of texel (tx, ty): the texel centred at ((tx + ½)·texel, (ty + ½)·texel).
  [[nodiscard]] float texel(std::int64_t tx, std::int64_t ty) const;
  /// Copies texels [tx0, tx0 + w) × [ty0, ty0 + h) into out (row ty0 first), 0 where
  /// nothing was stamped.
  void read(std::int64_t tx0, std::int64_t ty0, int w, int h, std::span<float> out) const;
  /// Increases with every stamp (a renderer re-uploads when it changed).
  [[nodiscard]] std::uint64_t version() const;
  /// Texel rectangle (tx0, ty0, tx1, ty1), half-open, touched since the version `since`
  /// (the union of the stamps' bounds; everything stamped if `since` is 0).
  [[nodiscard]] std::array<std::int64_t, 4> dirtySince(std::uint64_t since) const;
  /// Tiles allocated (each kTile² texels).
  [[nodiscard]] std::size_t tiles() const;
  /// Forgets every track.
  void clear();

  static constexpr int kTile = 512;

 private:
  void press(glm::dvec2 a, glm::dvec2 b, double width, double depth);
  float* tileFor(std::int64_t tx, std::int64_t ty);

  double texel_;
  mutable std::mutex mutex_;
  std::unordered_map<std::uint64_t, std::vector<float>> tiles_;
  std::vector<glm::dvec2> last_;  // previous contact per wheel (step())
  // Per stamp: version and its texel bounds, for dirtySince().
  struct Stamp {
    std::uint64_t version;
    std::array<std::int64_t, 4> rect;
  };
  std::vector<Stamp> history_;
  std::uint64_t version_ = 0;
};

}  // namespace regolith::rover
