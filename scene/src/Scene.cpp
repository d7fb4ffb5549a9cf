#include <regolith/compose/Catalogue.hpp>
#include <regolith/compose/ComposedPyramid.hpp>
#include <regolith/compose/FromStore.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/gl/HeadlessContext.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/scene/Scene.hpp>
#include <regolith/scene/SceneParts.hpp>
#include <regolith/scenegraph/SitePose.hpp>
#include <regolith/store/Generate.hpp>
#include <regolith/store/GridInfo.hpp>
#include <regolith/store/Pager.hpp>
#include <regolith/store/Store.hpp>
#include <regolith/topo/Projection.hpp>

#include "BodyPlacement.hpp"

#include <EGL/egl.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <optional>
#include <sstream>
#include <utility>

namespace regolith::scene {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr std::size_t kMaxDemsPerBody = 4;  // render::SceneRenderer::addCutOut()

glm::dvec3 vec(const std::array<double, 3>& a) { return {a[0], a[1], a[2]}; }
glm::vec3 colour(const std::array<double, 3>& a) {
  return {static_cast<float>(a[0]), static_cast<float>(a[1]), static_cast<float>(a[2])};
}

/// One grid of a data source, as the scene needs it.
struct Grid {
  std::shared_ptr<const clod::HeightPyramid> pyramid;
  store::GridInfo info;                               // its store's or generator's description
  std::shared_ptr<const topo::SampleSource> samples;  // level 0 (for TopoDem)
  std::shared_ptr<const store::Pager> pager;          // set for stores
};

}  // namespace

struct Scene::Impl {
  SceneDescription d;
  SceneOptions options;
  std::shared_ptr<store::PatchCache> cache;
  std::shared_ptr<core::Executor> loader;  // SceneOptions::loader, or one of the scene's
  std::map<std::string, std::shared_ptr<const store::Pager>> pagers;  // by resolved path
  scenegraph::SceneGraph graph{"root"};

  struct Terrain {
    std::string name;
    int key = -1;
    scenegraph::NodeId node = 0;
    std::shared_ptr<const clod::HeightPyramid> pyramid;
    clod::ClipmapOptions options;
    bool planet = false;
    std::shared_ptr<const farfield::HeightLayers> farField;    // planets with a far field
    std::shared_ptr<const compose::ComposedSurface> composed;  // planets composed
    topo::Geodetic origin{};                                   // DEMs: the tangent plane's
    double heading = 0.0;
    glm::vec3 albedo{0.0F};
    std::string body;                  // DEMs: the body they sit on
    std::optional<topo::TopoDem> dem;  // DEMs: for traverses
  };
  std::vector<Terrain> terrains;
  struct Thing {
    std::string name;
    int key = -1;
    scenegraph::NodeId node = 0;
    glm::dvec4 pose{0.0};
    glm::vec3 colour{0.0F};
  };
  std::vector<Thing> objects;
  std::map<std::string, scenegraph::NodeId> cameras;
  std::size_t traversesDriven = 0;
  scenegraph::NodeId lightFrame = 0;
  glm::dvec3 lightDirection{0.0, 0.0, 1.0};
  bool lightFromOrigin = false;  // Light::from: the light is at lightFrame's origin

  /// The direction towards the light in `frame`: a direction given in the light's frame,
  /// or towards the origin of the light's frame (a sun: as far as a heliocentric scene's
  /// Sun, the direction varies by 2e-5 rad across Mars, so the frame's origin stands for
  /// every point of it).
  [[nodiscard]] glm::dvec3 lightIn(scenegraph::NodeId frame) const {
    const scenegraph::Pose p = graph.relative(frame, lightFrame);
    if (!lightFromOrigin) return p.applyVector(lightDirection);
    const glm::dvec3 towards = p.apply(glm::dvec3(0.0));
    if (!(glm::length(towards) > 0.0)) return lightDirection;  // the frame is the light's own
    return glm::normalize(towards);
  }

  [[noreturn]] void fail(const std::string& ptr, const std::string& what) const {
    throw InvalidArgument("Scene: " + ptr + ": " + what);
  }

  const store::Pager& pager(const std::string& path) {
    const std::filesystem::path p = d.resolve(path);
    auto& slot = pagers[p.string()];
    if (!slot) {
      slot = std::make_shared<const store::Pager>(
          std::make_shared<const store::Store>(store::Store::open(p)), cache);
    }
    return *slot;
  }

  Grid fromStore(const DataSource& s) {
    const store::Pager& pg = pager(s.store);
    Grid g;
    g.info = pg.grid(s.grid);
    g.pyramid = std::make_shared<const clod::HeightPyramid>(pg.pyramid(s.grid, loader));
    g.samples = pg.source(s.grid);
    g.pager = pagers[d.resolve(s.store).string()];
    return g;
  }

  static store::PlanetOf planetOf(const DataSource& s) {
    return store::PlanetOf{s.seed, s.ellipsoid, s.craterDensity};
  }

  /// A generator's grid in memory (its pyramid by 2×2 means, computed once).
  static Grid generated(const DataSource& s, double originHeight) {
    Grid g;
    clod::SurfaceKind kind = clod::SurfaceKind::Plane;
    std::optional<topo::Body> body;
    if (s.generate == "mars-planet") {
      store::MarsPlanetOptions o;
      o.rows = s.rows;
      o.seed = s.seed;
      o.ellipsoid = s.ellipsoid;
      o.craterDensity = s.craterDensity;
      const store::MarsPlanetGenerator gen(o);
      g.info = gen.gridInfo();
      g.samples = gen.samples();
      kind = clod::SurfaceKind::Planet;
      body = store::bodyOf(g.info);
    } else if (s.generate == "victoria") {
      store::VictoriaOptions o;
      o.size = s.size;
      o.spacing = s.spacing;
      o.seed = s.seed;
      o.originHeight = originHeight;
      const store::VictoriaGenerator gen(o);
      g.info = gen.gridInfo();
      g.samples = gen.samples();
    } else if (s.generate == "mars-cap") {
      store::PolarCapOptions o;
      o.pole = s.pole == "south" ? store::PolarCapOptions::Pole::South
                                 : store::PolarCapOptions::Pole::North;
      o.minLatitudeDeg = s.minLatitude;
      o.spacing = s.spacing;
      o.planet = planetOf(s);
      const store::PolarCapGenerator gen(o);
      g.info = gen.gridInfo();
      g.samples = gen.samples();
    } else {  // mars-strip (readScene() admits no other)
      store::StripOptions o;
      o.centreLatDeg = s.centreLat;
      o.centreLonDeg = s.centreLon;
      o.inclinationDeg = s.inclination;
      o.length = s.length;
      o.width = s.width;
      o.spacing = s.spacing;
      o.raggedness = s.raggedness;
      o.planet = planetOf(s);
      const store::StripGenerator gen(o);
      g.info = gen.gridInfo();
      g.samples = gen.samples();
    }
    g.pyramid = std::make_shared<const clod::HeightPyramid>(clod::HeightPyramid::fromSamples(
        store::topoGridOf(g.info), g.samples, kind, body, g.info.latitudeType));
    return g;
  }

  Grid grid(const DataSource& s, double originHeight = 0.0) {
    return s.store.empty() ? generated(s, originHeight) : fromStore(s);
  }

  std::optional<clod::DrapedTexture> draped(const std::optional<DrapedSource>& s,
                                            const std::string& ptr) {
    if (!s) return std::nullopt;
    clod::DrapedTexture t;
    if (s->data.store.empty()) {
      // A generator's heights mapped onto [0, 1] over `range` (readScene() requires it),
      // on the generator's own grid, its pyramid by 2×2 means of the mapped values.
      if (!s->range) fail(ptr + "/range", "missing, expected [min, max] for a generator");
      const Grid g = generated(s->data, 0.0);
      const double lo = (*s->range)[0], span = (*s->range)[1] - lo;
      const std::size_t rows = g.samples->rows(), cols = g.samples->cols();
      std::vector<float> values(rows * cols);
      for (std::size_t r = 0; r < rows; ++r)
        for (std::size_t c = 0; c < cols; ++c)
          values[r * cols + c] = static_cast<float>(
              std::clamp((static_cast<double>(g.samples->sample(r, c)) - lo) / span, 0.0, 1.0));
      t.channels.push_back(
          std::make_shared<const clod::HeightPyramid>(clod::HeightPyramid::fromSamples(
              store::topoGridOf(g.info),
              std::make_shared<topo::InMemorySamples>(rows, cols, std::move(values)),
              g.pyramid->kind(), g.pyramid->body(), g.info.latitudeType)));
    } else {
      t.channels.push_back(fromStore(s->data).pyramid);
    }
    t.window = s->window;
    t.opacity = static_cast<float>(s->opacity);
    return t;
  }

  clod::Effects effects(const EffectsDescription& e, const std::string& ptr) {
    clod::Effects out;
    out.albedo = draped(e.albedo, ptr + "/albedo");
    out.overlay = draped(e.overlay, ptr + "/overlay");
    if (e.tracks) out.tracks = std::make_shared<rover::TrackLayer>(rover::RoverRuts::kTexelMetres);
    if (e.heightColours) {
      out.heightColours =
          clod::HeightColours{static_cast<float>(e.heightColours->min),
                              static_cast<float>(e.heightColours->max), e.heightColours->shaded};
    }
    if (e.latLon) {
      clod::LatLonLines l;
      l.spacingDegrees = e.latLon->spacing;
      l.minPixelSpacing = e.latLon->minPixelSpacing;
      l.colour = colour(e.latLon->colour);
      l.widthPixels = static_cast<float>(e.latLon->width);
      out.latLon = l;
    }
    if (e.noise) {
      clod::StructuredNoise n;
      n.amplitude = e.noise->amplitude;
      n.wavelength = e.noise->wavelength;
      n.octaves = e.noise->octaves;
      n.albedoVariation = static_cast<float>(e.noise->albedoVariation);
      out.noise = n;
    }
    return out;
  }

  Terrain& terrainNamed(const std::string& name) {
    for (Terrain& t : terrains)
      if (t.name == name) return t;
    throw InvalidArgument("Scene: no body or DEM named '" + name + "'");
  }

  /// A body without heights: its reference ellipsoid (the description's radii) with no
  /// relief, on a global grid of kSmoothBodyCellDeg cells.
  static Grid smooth(const Body& b) {
    const auto rows = static_cast<std::size_t>(std::lround(180.0 / kSmoothBodyCellDeg));
    const std::size_t cols = 2 * rows;
    const double half = 0.5 * kSmoothBodyCellDeg;
    const topo::TopoGrid g(rows, cols, -180.0 + half, 90.0 - half, kSmoothBodyCellDeg,
                           kSmoothBodyCellDeg);
    const topo::Body body = topo::Body::ellipsoid(b.name, (*b.radii)[0], (*b.radii)[1]);
    Grid out;
    out.samples =
        std::make_shared<topo::InMemorySamples>(rows, cols, std::vector<float>(rows * cols, 0.0F));
    out.info.name = b.name;
    out.pyramid = std::make_shared<const clod::HeightPyramid>(
        clod::HeightPyramid::fromSamples(g, out.samples, clod::SurfaceKind::Planet, body));
    return out;
  }

  /// A body's frame in the root's: Body::pose (translation, then the obliquity about x, then
  /// the spin about the pole).
  static scenegraph::Pose bodyPose(const Body& b) {
    if (!b.pose) return scenegraph::Pose::identity();
    return scenegraph::bodyPose(vec(b.pose->position), b.pose->obliquity, b.pose->spin);
  }

  void buildBody(std::size_t i) {
    const Body& b = d.bodies[i];
    const std::string ptr = "/bodies/" + std::to_string(i);
    if (b.heights.empty() && !b.radii)
      fail(ptr + "/heights", "empty and no radii, expected at least one dataset");
    Grid planet = b.heights.empty() ? smooth(b) : grid(b.heights[0]);
    if (planet.pyramid->kind() != clod::SurfaceKind::Planet)
      fail(ptr + "/heights/0", "grid '" + planet.info.name + "' is not a planet grid");
    const topo::Body& body = *planet.pyramid->body();
    if (b.radii && (std::abs((*b.radii)[0] - body.equatorialRadius()) > 1.0 ||
                    std::abs((*b.radii)[1] - body.polarRadius()) > 1.0)) {
      std::ostringstream what;
      what << '[' << core::number((*b.radii)[0]) << ", " << core::number((*b.radii)[1])
           << "] differ from the heights' [" << core::number(body.equatorialRadius()) << ", "
           << core::number(body.polarRadius()) << "] by more than 1 m";
      fail(ptr + "/radii", what.str());
    }
    Terrain t;
    t.name = b.name;
    t.planet = true;
    t.pyramid = planet.pyramid;
    t.albedo = colour(b.look.colour);
    t.options.size = b.look.clipmapSize;
    t.options.albedo = t.albedo;
    t.options.effects = effects(b.look.effects, ptr + "/effects");
    t.key = static_cast<int>(terrains.size());
    t.node = graph.add(graph.root(), b.name, bodyPose(b), scenegraph::NodeKind::Terrain, t.key);
    terrains.push_back(std::move(t));
  }

  /// Every body's place, now that every body's radii are known (detail::checkBodiesApart()).
  void checkBodiesApart() const {
    std::vector<double> radius;
    for (const Body& b : d.bodies)
      for (const Terrain& t : terrains)
        if (t.planet && t.name == b.name) radius.push_back(t.pyramid->body()->equatorialRadius());
    if (const auto e = detail::checkBodiesApart(d.bodies, radius)) fail(e->pointer, e->what);
  }

  /// A body with several height datasets, or whose DEMs are composed into it: one composed
  /// surface (docs/composition.md) that the planet draws on its own lattice and each
  /// composed DEM on its own (its samples there are the composed heights). The catalogue
  /// holds the planet grid, then the DEMs, then the further datasets (the demo's order).
  void composeBody(std::size_t i) {
    const Body& b = d.bodies[i];
    Terrain& t = terrainNamed(b.name);
    const std::shared_ptr<const clod::HeightPyramid> planet = t.pyramid;
    std::shared_ptr<const compose::ComposedSurface> composed;
    if (b.heights.size() > 1 || b.composeDems) {
      const topo::Body& body = *planet->body();
      auto catalogue = std::make_shared<compose::Catalogue>(body);
      compose::DatasetOptions po;
      po.name = b.name;
      catalogue->add(compose::Dataset::planet(levelsOf(*planet), po));
      std::vector<std::pair<Terrain*, std::shared_ptr<const compose::Dataset>>> dems;
      if (b.composeDems) {
        for (std::size_t k = 0; k < d.dems.size(); ++k) {
          if (d.dems[k].body != b.name) continue;
          Terrain& dem = terrainNamed(d.dems[k].name);
          compose::DatasetOptions o;
          o.name = dem.name;
          o.featherMetres = d.dems[k].heights.featherMetres;
          auto data = compose::Dataset::dem(levelsOf(*dem.pyramid), dem.dem->placement(), o);
          catalogue->add(data);
          dems.emplace_back(&dem, std::move(data));
        }
      }
      for (std::size_t k = 1; k < b.heights.size(); ++k) {
        const DataSource& s = b.heights[k];
        compose::DatasetOptions o;
        o.featherMetres = s.featherMetres;
        if (!s.store.empty()) {
          const store::Pager& pg = pager(s.store);
          if (s.featherNodataSamples > 0.0) {
            o.mask = compose::featherMask(store::topoGridOf(pg.grid(s.grid)), *pg.source(s.grid),
                                          s.featherNodataSamples);
          }
          catalogue->add(compose::datasetFromStore(pg, s.grid, o, loader));
        } else {
          const Grid g = generated(s, 0.0);
          o.name = g.info.name;
          if (s.featherNodataSamples > 0.0) {
            o.mask =
                compose::featherMask(store::topoGridOf(g.info), *g.samples, s.featherNodataSamples);
          }
          catalogue->add(
              compose::Dataset::dem(levelsOf(*g.pyramid), store::placementOf(g.info), o));
        }
      }
      composed = std::make_shared<const compose::ComposedSurface>(catalogue->snapshot());
      t.composed = composed;
      t.pyramid = std::make_shared<const clod::HeightPyramid>(compose::composedPlanetPyramid(
          composed, planet->level(0).grid, planet->latitudeType(), planet->levelCount()));
      for (auto& [dem, own] : dems) {
        dem->pyramid = std::make_shared<const clod::HeightPyramid>(
            compose::composedDemPyramid(composed, dem->pyramid->level(0).grid,
                                        dem->dem->placement(), dem->pyramid->levelCount(), own)
                .levels,
            clod::SurfaceKind::Plane);
      }
    }
    t.options.levels = b.farField ? planetLevelsWithFarField(*t.pyramid, b.look.clipmapSize) : 0;
    if (b.farField) t.farField = farFieldLayers(*t.pyramid, composed.get());
  }

  void buildDem(std::size_t i) {
    const Dem& dm = d.dems[i];
    const std::string ptr = "/dems/" + std::to_string(i);
    Terrain& bodyTerrain = terrainNamed(dm.body);
    const topo::Body& body = *bodyTerrain.pyramid->body();
    std::size_t onBody = 0;
    for (const Dem& other : d.dems) onBody += other.body == dm.body ? 1U : 0U;
    if (onBody > kMaxDemsPerBody)
      fail(ptr + "/body", std::to_string(onBody) + " DEMs on '" + dm.body + "', expected at most " +
                              std::to_string(kMaxDemsPerBody));
    topo::Geodetic origin;
    double heading = 0.0;
    if (dm.placement) {
      origin = {dm.placement->lat, dm.placement->lon, dm.placement->height};
      if (dm.placement->surfaceHeight) origin.height = planetHeightAt(*bodyTerrain.pyramid, origin);
      heading = dm.placement->heading;
    }
    Grid g = grid(dm.heights, origin.height);
    if (g.pyramid->kind() != clod::SurfaceKind::Plane)
      fail(ptr + "/heights", "grid '" + g.info.name + "' is not a DEM");
    if (!dm.placement) {
      if (g.info.placement.kind != store::PlacementInfo::Kind::LocalTangentPlane)
        fail(ptr + "/placement",
             "missing, and grid '" + g.info.name + "' is not on a local tangent plane");
      origin = {g.info.placement.originLatDeg, g.info.placement.originLonDeg,
                g.info.placement.originHeight};
      heading = g.info.placement.headingDeg;
    }
    Terrain t;
    t.name = dm.name;
    t.body = dm.body;
    t.pyramid = g.pyramid;
    t.albedo = colour(dm.look.colour);
    t.options.size = dm.look.clipmapSize;
    t.options.levels = 0;
    t.options.albedo = t.albedo;
    t.options.effects = effects(dm.look.effects, ptr + "/effects");
    if (const auto given = options.tracks.find(dm.name); given != options.tracks.end()) {
      if (!dm.look.effects.tracks)
        fail(ptr + "/effects/tracks",
             "not declared, but SceneOptions::tracks gives a layer for '" + dm.name + "'");
      if (!given->second) fail(ptr + "/effects/tracks", "SceneOptions::tracks gives a null layer");
      t.options.effects.tracks = given->second;
    }
    t.origin = origin;
    t.heading = heading;
    const topo::Placement placement(topo::LocalTangentPlane(body, origin, heading));
    t.dem.emplace(store::topoGridOf(g.info), placement, g.samples);
    t.key = static_cast<int>(terrains.size());
    t.node =
        graph.add(bodyTerrain.node, dm.name, scenegraph::tangentPlanePose(body, origin, heading),
                  scenegraph::NodeKind::Terrain, t.key);
    terrains.push_back(std::move(t));
  }

  void buildObject(std::size_t i) {
    const Object& o = d.objects[i];
    const Terrain& dem = terrainNamed(o.dem);
    Thing th;
    th.name = o.name;
    th.colour = colour(o.colour);
    double x = 0.0, y = 0.0, heading = 0.0;
    if (o.pose) {
      x = o.pose->x;
      y = o.pose->y;
      heading = o.pose->heading;
    } else if (const auto given = options.driven.find(o.name); given != options.driven.end()) {
      x = given->second.x;  // driven by the caller (SceneOptions::driven)
      y = given->second.y;
      heading = given->second.heading * 180.0 / std::numbers::pi;
    } else {
      ++traversesDriven;
      rover::TraverseOptions to;
      for (const auto& w : o.traverse->waypoints) to.path.emplace_back(w[0], w[1]);
      to.speed = o.traverse->speed;
      to.step = o.traverse->step;
      const TraverseEnd end = driveAndPress(*dem.dem, to, dem.options.effects.tracks.get());
      x = end.last.x;
      y = end.last.y;
      heading = end.last.heading * 180.0 / std::numbers::pi;
    }
    const double z = demHeightAt(*dem.pyramid, x, y);
    th.pose = {x, y, z, heading};
    th.key = static_cast<int>(terrains.size() + objects.size());
    th.node = graph.add(dem.node, o.name, scenegraph::roverPose({x, y, z}, heading),
                        scenegraph::NodeKind::Object, th.key);
    objects.push_back(std::move(th));
  }

  void build() {
    for (const auto& [name, layer] : options.tracks) {
      bool found = false;
      for (const Dem& dm : d.dems) found = found || dm.name == name;
      if (!found)
        throw InvalidArgument("Scene: SceneOptions::tracks: '" + name +
                              "' is not a DEM of the scene");
    }
    for (const auto& entry : options.driven) {
      const std::string& name = entry.first;
      const auto it = std::find_if(d.objects.begin(), d.objects.end(),
                                   [&](const Object& o) { return o.name == name; });
      if (it == d.objects.end() || !it->traverse)
        throw InvalidArgument("Scene: SceneOptions::driven: '" + name +
                              "' is not an object of the scene with a traverse");
      const auto dem = std::find_if(d.dems.begin(), d.dems.end(),
                                    [&](const Dem& m) { return m.name == it->dem; });
      if (dem != d.dems.end() && dem->look.effects.tracks && !options.tracks.count(it->dem))
        fail("/objects/" + std::to_string(it - d.objects.begin()) + "/traverse",
             "driven by the caller (SceneOptions::driven), but SceneOptions::tracks gives no "
             "layer for its DEM '" +
                 it->dem + "', which declares tracks");
    }
    for (std::size_t i = 0; i < d.bodies.size(); ++i) buildBody(i);
    checkBodiesApart();
    for (std::size_t i = 0; i < d.dems.size(); ++i) buildDem(i);
    for (std::size_t i = 0; i < d.bodies.size(); ++i) composeBody(i);
    for (std::size_t i = 0; i < d.objects.size(); ++i) buildObject(i);
    for (Terrain& t : terrains) t.options.executor = loader;
    for (const Camera& c : d.cameras) {
      cameras[c.name] = graph.add(graph.at(c.frame), c.name,
                                  scenegraph::Pose::lookAt(vec(c.eye), vec(c.lookAt), vec(c.up)),
                                  scenegraph::NodeKind::Camera);
    }
    const std::string lightFrameName = !d.light.from.empty()    ? d.light.from
                                       : !d.light.frame.empty() ? d.light.frame
                                       : !d.dems.empty()        ? d.dems.front().name
                                                                : d.bodies.front().name;
    lightFrame = graph.at(lightFrameName);
    lightFromOrigin = !d.light.from.empty();
    if (d.light.direction) {
      lightDirection = glm::normalize(vec(*d.light.direction));
    } else {
      const double e = d.light.elevation * kDeg, a = d.light.azimuth * kDeg;
      lightDirection = {std::cos(e) * std::sin(a), std::cos(e) * std::cos(a), std::sin(e)};
    }
  }

  std::string focusOf(const Camera& c) const {
    if (!c.focus.empty()) return c.focus;
    for (const Terrain& t : terrains)
      if (t.name == c.frame) return t.name;
    for (const Object& o : d.objects)
      if (o.name == c.frame) return o.dem;
    return d.bodies.front().name;
  }
};

Scene::Scene(SceneDescription description, const SceneOptions& options)
    : impl_(std::make_unique<Impl>()) {
  impl_->d = std::move(description);
  impl_->graph = scenegraph::SceneGraph(impl_->d.root);
  impl_->options = options;
  impl_->cache = std::make_shared<store::PatchCache>(options.cacheBytes);
  impl_->loader =
      options.loader ? options.loader
                     : std::make_shared<core::ThreadPool>(std::max(1U, core::availableCores() - 1));
  impl_->build();
}

Scene Scene::load(const std::filesystem::path& path, const SceneOptions& options) {
  return Scene(readScene(path), options);
}

Scene::Scene(Scene&&) noexcept = default;
Scene& Scene::operator=(Scene&&) noexcept = default;
Scene::~Scene() = default;

const SceneDescription& Scene::description() const noexcept { return impl_->d; }
const scenegraph::SceneGraph& Scene::graph() const noexcept { return impl_->graph; }

const clod::HeightPyramid& Scene::terrain(const std::string& name) const {
  for (const Impl::Terrain& t : impl_->terrains)
    if (t.name == name) return *t.pyramid;
  throw InvalidArgument("Scene::terrain(): no body or DEM named '" + name + "'");
}

const clod::ClipmapOptions& Scene::terrainOptions(const std::string& name) const {
  for (const Impl::Terrain& t : impl_->terrains)
    if (t.name == name) return t.options;
  throw InvalidArgument("Scene::terrainOptions(): no body or DEM named '" + name + "'");
}

scenegraph::SceneGraph& Scene::graph() noexcept { return impl_->graph; }

std::vector<SceneTerrain> Scene::terrains() const {
  std::vector<SceneTerrain> out;
  for (const Impl::Terrain& t : impl_->terrains) {
    out.push_back({t.name, t.planet, t.body, t.key, t.node, t.pyramid, t.options, t.farField,
                   t.composed, t.origin, t.heading});
  }
  return out;
}

std::vector<SceneObject> Scene::objects() const {
  std::vector<SceneObject> out;
  for (const Impl::Thing& o : impl_->objects) out.push_back({o.name, o.key, o.node, o.colour});
  return out;
}

scenegraph::NodeId Scene::cameraNode(const std::string& camera) const {
  const auto it = impl_->cameras.find(camera);
  if (it == impl_->cameras.end()) {
    throw InvalidArgument("Scene::cameraNode(): no camera named '" + camera + "'");
  }
  return it->second;
}

std::shared_ptr<const store::PatchCache> Scene::cache() const noexcept { return impl_->cache; }
std::shared_ptr<core::Executor> Scene::loader() const noexcept { return impl_->loader; }

double Scene::demHeight(const std::string& dem, double x, double y) const {
  for (const Impl::Terrain& t : impl_->terrains)
    if (t.name == dem && !t.planet) return demHeightAt(*t.pyramid, x, y);
  throw InvalidArgument("Scene::demHeight(): no DEM named '" + dem + "'");
}

glm::dvec4 Scene::objectPose(const std::string& object) const {
  for (const Impl::Thing& o : impl_->objects)
    if (o.name == object) return o.pose;
  throw InvalidArgument("Scene::objectPose(): no object named '" + object + "'");
}

glm::dvec3 Scene::lightIn(const std::string& frame) const {
  return impl_->lightIn(impl_->graph.at(frame));
}

std::size_t Scene::traversesDriven() const noexcept { return impl_->traversesDriven; }

std::string Scene::focusOf(const std::string& camera) const {
  const Camera* c = impl_->d.camera(camera);
  if (!c) throw InvalidArgument("Scene::focusOf(): no camera named '" + camera + "'");
  return impl_->focusOf(*c);
}

gl::RgbaImage Scene::render(const std::string& camera) const {
  const Impl& s = *impl_;
  const Camera* c = s.d.camera(camera);
  if (!c) {
    std::ostringstream names;
    for (std::size_t i = 0; i < s.d.cameras.size(); ++i)
      names << (i == 0 ? "" : ", ") << s.d.cameras[i].name;
    throw InvalidArgument("Scene::render(): no camera named '" + camera +
                          "', expected one of: " + (s.d.cameras.empty() ? "none" : names.str()));
  }
  render::SceneView view;
  view.fovYDegrees = c->fovY;
  view.near = c->near;
  view.width = c->width;
  view.height = c->height;
  if (c->viewport) {
    view.x = (*c->viewport)[0];
    view.y = (*c->viewport)[1];
    view.width = (*c->viewport)[2];
    view.height = (*c->viewport)[3];
  }
  return render(s.cameras.at(camera), s.graph.at(focusOf(camera)), view, c->width, c->height);
}

void Scene::registerWith(render::SceneRenderer& renderer) const {
  const Impl& s = *impl_;
  for (const Impl::Terrain& t : s.terrains) renderer.addTerrain(t.key, t.pyramid, t.options);
  for (const Impl::Terrain& t : s.terrains) {
    if (t.planet) continue;
    for (const Impl::Terrain& b : s.terrains)
      if (b.name == t.body) renderer.addCutOut(b.key, t.key);
  }
  for (const Impl::Thing& o : s.objects) renderer.addMesh(o.key, render::roverMesh(), o.colour);
  for (const Impl::Terrain& t : s.terrains)
    if (t.farField) renderer.addFarField(t.key, t.farField, planetFarFieldOptions(t.albedo));
}

gl::RgbaImage Scene::render(scenegraph::NodeId camera, scenegraph::NodeId focus,
                            render::SceneView view, int width, int height) const {
  const Impl& s = *impl_;
  std::unique_ptr<gl::HeadlessContext> context;
  if (eglGetCurrentContext() == EGL_NO_CONTEXT) context = std::make_unique<gl::HeadlessContext>();
  gl::RgbaImage image;
  {
    render::SceneRenderer renderer;
    registerWith(renderer);
    gl::RenderTarget target(width, height);
    view.lightInFocus = s.lightIn(focus);
    target.clear({0.02F, 0.02F, 0.04F, 1.0F});
    const scenegraph::RenderList list = s.graph.renderList(focus, camera);
    renderer.prepare(list, view);        // waits: the headless frame does not depend on read speed
    renderer.draw(list, view, &target);  // the far fields too
    image = target.readColor();
  }  // GL objects go before the context
  return image;
}

}  // namespace regolith::scene
