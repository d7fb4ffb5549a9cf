#pragma once
/// \file
/// A scene as plain data (docs/scene-format.md): bodies and their datasets, local DEMs with
/// their placements, objects (the rover), cameras, the light and the effects each terrain
/// declares. No GL: a description is read, checked and written without a context; Scene
/// (Scene.hpp) builds and renders one. Lengths in metres, angles in degrees.

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace regolith::scene {

/// One grid of heights (or of albedo or overlay values): read from a store, or computed by a
/// deterministic generator of store/Generate.hpp in memory. Exactly one of `store` and
/// `generate` is set.
struct DataSource {
  /// A store file as written in the scene (relative paths are relative to the scene file's
  /// folder, SceneDescription::folder) and the grid in it.
  std::string store;
  std::string grid;
  /// A generator: "mars-planet", "mars-cap", "mars-strip" or "victoria"; its options below
  /// (each generator reads only its own, docs/scene-format.md lists which).
  std::string generate;
  std::uint64_t seed = 1;
  std::size_t rows = 360;      ///< mars-planet: latitude samples pole to pole
  bool ellipsoid = true;       ///< mars-planet, -cap, -strip: the IAU ellipsoid (else sphere)
  double craterDensity = 1.0;  ///< mars-planet, -cap, -strip
  std::size_t size = 601;      ///< victoria: samples per side
  double spacing = 2.0;        ///< victoria, mars-cap, mars-strip: metres
  std::string pole = "north";  ///< mars-cap: "north" or "south"
  double minLatitude = 75.0;   ///< mars-cap: |latitude| ≥ this, degrees in (0, 90)
  double centreLat = 0.0;      ///< mars-strip: planetocentric, degrees
  double centreLon = 0.0;      ///< mars-strip: east, degrees
  double inclination = 60.0;   ///< mars-strip: degrees in [0, 180]
  double length = 300000.0;    ///< mars-strip: along the track, metres
  double width = 10000.0;      ///< mars-strip: across the track, metres
  double raggedness = 0.25;    ///< mars-strip: in [0, 0.9]
  /// Composition (several height datasets of a body, or DEMs composed into it): the border
  /// feather in metres, and a coverage mask feathered over this many samples from the grid's
  /// nodata border (compose::featherMask(); 0: none).
  double featherMetres = 0.0;
  double featherNodataSamples = 0.0;

  bool operator==(const DataSource&) const = default;
};

/// A texture draped over a terrain (albedo or overlay): one grey grid, values in [0, 1]. The
/// grid is a store's, or a generator's run in memory on the terrain's own kind of grid
/// ("mars-planet" over a body, "victoria" over a DEM): a generator gives heights in metres,
/// which `range` maps linearly onto [0, 1] (min → 0, max → 1, clamped).
struct DrapedSource {
  DataSource data;
  int window = 512;      ///< texels per side of each texture clipmap level, 64..4096
  double opacity = 1.0;  ///< overlays: blend factor in [0, 1]
  /// Generators only (required there): the values that become 0 and 1, min < max.
  std::optional<std::array<double, 2>> range;

  bool operator==(const DrapedSource&) const = default;
};

/// The effects a terrain declares (clod::Effects, docs/overlays.md). Only what is set is
/// built: no shader code, texture or pass for the rest.
struct EffectsDescription {
  /// Wheel tracks (DEMs only): the layer the scene's rovers on this DEM press their
  /// traverses into.
  bool tracks = false;
  struct HeightColours {
    double min = 0.0, max = 1.0;  ///< metres, min < max
    bool shaded = false;
    bool operator==(const HeightColours&) const = default;
  };
  std::optional<HeightColours> heightColours;
  struct LatLon {
    double spacing = 0.0;  ///< degrees between lines, ≥ 0 (0: adapts to the view)
    double minPixelSpacing = 80.0;
    std::array<double, 3> colour{1.0, 1.0, 1.0};
    double width = 1.5;  ///< pixels
    bool operator==(const LatLon&) const = default;
  };
  std::optional<LatLon> latLon;
  struct Noise {
    double amplitude = 0.05;  ///< metres
    double wavelength = 0.5;  ///< grid units (metres on a DEM, degrees on a planet)
    int octaves = 4;          ///< 1..8
    double albedoVariation = 0.15;
    bool operator==(const Noise&) const = default;
  };
  std::optional<Noise> noise;
  std::optional<DrapedSource> albedo, overlay;

  /// The declared effects' names in clod::Effects::declared() order.
  [[nodiscard]] std::vector<std::string> declared() const;
  bool operator==(const EffectsDescription&) const = default;
};

/// How a terrain is drawn: constant albedo (unless an albedo texture is declared), clipmap
/// size, effects.
struct TerrainLook {
  std::array<double, 3> colour{0.80, 0.52, 0.38};  ///< linear RGB in [0, 1]
  int clipmapSize = 127;                           ///< vertices per level side, odd, 15..1023
  EffectsDescription effects;
  bool operator==(const TerrainLook&) const = default;
};

/// A body (a planet): its radii (or its first heights store's), its height datasets (several
/// are composed through compose::Catalogue, the first being the global grid), where it is,
/// and how it is drawn. Planets are drawn by clipmaps near the camera and by the far field
/// beyond.
struct Body {
  std::string name;
  /// Equatorial and polar radius, metres; unset: the body of the first heights dataset.
  std::optional<std::array<double, 2>> radii;
  /// The global planet grid first, then the datasets that refine it. Empty (with `radii`):
  /// the reference ellipsoid without relief, on a grid of 3° cells (kSmoothBodyCellDeg).
  std::vector<DataSource> heights;
  /// Where the body is in the scene's root frame (e.g. heliocentric, the ecliptic its x-y
  /// plane): its centre `position` (metres) and its body-fixed frame turned by `obliquity`
  /// about the root's x axis, then by `spin` about its own pole (degrees). Unset: the root's
  /// frame itself (position 0, no rotation).
  struct Pose {
    std::array<double, 3> position{0.0, 0.0, 0.0};
    double obliquity = 0.0;  ///< degrees in [-180, 180]
    double spin = 0.0;       ///< degrees in [-360, 360]
    bool operator==(const Pose&) const = default;
  };
  std::optional<Pose> pose;
  TerrainLook look;
  bool farField = true;
  /// Compose the body's DEMs into its surface too (each with its heights' featherMetres):
  /// the planet then shows the DEMs at its resolution and each DEM blends into the planet
  /// over its feather instead of meeting it at a step (the demo's composition).
  bool composeDems = false;
  bool operator==(const Body&) const = default;
};

/// A local DEM on a body: a local tangent plane at a planetodetic origin with a heading
/// (clockwise from north). `surfaceHeight` puts the origin on the body's surface (its first
/// heights grid, bilinear); else `height` (metres above the reference surface). A DEM from a
/// store without `placement` takes the store's own placement.
struct Dem {
  std::string name;
  std::string body;
  DataSource heights;
  struct Placement {
    double lat = 0.0, lon = 0.0;  ///< planetodetic latitude, east longitude, degrees
    double height = 0.0;
    bool surfaceHeight = true;
    double heading = 0.0;
    bool operator==(const Placement&) const = default;
  };
  std::optional<Placement> placement;
  TerrainLook look{{0.55, 0.75, 0.45}, 127, {}};
  bool operator==(const Dem&) const = default;
};

/// An object on a DEM. Today one kind: "rover" (render::roverMesh()), standing at `pose`
/// (grid x, y on the surface; heading clockwise from +y) or where a traverse of `waypoints`
/// (rover::runTraverse over the DEM) stops; its tracks are pressed into the DEM's tracks
/// layer if the DEM declares one.
struct Object {
  std::string name;
  std::string type = "rover";
  std::string dem;
  struct Pose {
    double x = 0.0, y = 0.0, heading = 0.0;
    bool operator==(const Pose&) const = default;
  };
  std::optional<Pose> pose;
  struct Traverse {
    std::vector<std::array<double, 2>> waypoints;
    double speed = 1.0;   ///< m/s
    double step = 0.001;  ///< s
    bool operator==(const Traverse&) const = default;
  };
  std::optional<Traverse> traverse;
  std::array<double, 3> colour{0.85, 0.85, 0.80};
  bool operator==(const Object&) const = default;
};

/// A camera in a named frame (a body, a DEM or an object: a camera in an object's frame
/// follows it): eye and look-at point in that frame, up (default +z). Rendered with `focus`
/// as the origin of the render list (default: the frame itself if it is a terrain, else the
/// DEM the object stands on).
struct Camera {
  std::string name;
  std::string frame;
  std::array<double, 3> eye{0.0, 0.0, 10.0}, lookAt{0.0, 0.0, 0.0}, up{0.0, 0.0, 1.0};
  double fovY = 45.0;  ///< degrees in (0, 180)
  double near = 0.1;   ///< metres, > 0
  int width = 960, height = 540;
  /// Viewport (x, y, width, height) in the image, GL convention (y up); unset: the image.
  std::optional<std::array<int, 4>> viewport;
  std::string focus;
  bool operator==(const Camera&) const = default;
};

/// The light: a direction in a named frame, as elevation above its x-y plane and azimuth
/// clockwise from +y (for a DEM: above the horizon, clockwise from north), or as a vector;
/// or the direction of a frame's origin (`from`: a sun).
struct Light {
  std::string frame;  ///< empty: the first DEM, else the first body
  double elevation = 35.0, azimuth = 90.0;
  std::optional<std::array<double, 3>> direction;
  /// A light at the origin of this frame (the root: the Sun of a heliocentric scene), far
  /// away: in every frame the light comes from that origin. Excludes the other keys.
  std::string from;
  bool operator==(const Light&) const = default;
};

/// A whole scene. `folder` is where relative store paths resolve (the scene file's folder;
/// not written to the file).
struct SceneDescription {
  int version = 1;
  /// The name of the root frame, the one the bodies' poses are given in ("sun" in a
  /// heliocentric scene, where a light may come `from` it).
  std::string root = "root";
  std::vector<Body> bodies;
  std::vector<Dem> dems;
  std::vector<Object> objects;
  std::vector<Camera> cameras;
  Light light;
  std::filesystem::path folder;

  /// The store path of a dataset, resolved against `folder`.
  [[nodiscard]] std::filesystem::path resolve(const std::string& store) const;
  [[nodiscard]] const Camera* camera(const std::string& name) const;
  bool operator==(const SceneDescription&) const = default;
};

/// The current scene format version.
inline constexpr int kSceneVersion = 1;

/// The grid cell of a body without heights (its reference ellipsoid, no relief): 3° in
/// latitude and longitude, 60 × 120 samples.
inline constexpr double kSmoothBodyCellDeg = 3.0;

/// Reads and checks a scene file. Throws InvalidArgument naming the file, the JSON pointer of
/// the key and the expectation (`scene.json: /cameras/1/fovY: 190 is not in (0, 180)`) for
/// bad JSON, unknown keys (listing the allowed ones), wrong types, numbers out of range or
/// not finite, duplicate names, references to names that do not exist, stores that do not
/// exist and bodies placed inside one another (for bodies whose radii the file gives; Scene
/// checks the rest when it is built); IoError if the file cannot be read.
[[nodiscard]] SceneDescription readScene(const std::filesystem::path& path);
/// Parses scene JSON text; `file` names it in messages and `folder` resolves its paths.
[[nodiscard]] SceneDescription parseScene(const std::string& text, const std::string& file,
                                          const std::filesystem::path& folder);
/// The JSON of a scene (every key written, defaults included; relative store paths relative
/// to `folder`).
[[nodiscard]] std::string sceneJson(const SceneDescription& scene,
                                    const std::filesystem::path& folder);
/// Writes a scene crash-safely (core::writeFileAtomically()). Relative store paths are
/// rewritten relative to the new file's folder. Checks the description first (as readScene
/// would, stores excepted): InvalidArgument naming the path.
void writeScene(const SceneDescription& scene, const std::filesystem::path& path);

/// A summary for `regolith info --json`: bodies, datasets, DEMs, objects, cameras and the
/// effects each terrain declares, as JSON text.
[[nodiscard]] std::string sceneInfoJson(const SceneDescription& scene);

}  // namespace regolith::scene
