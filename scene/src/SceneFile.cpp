// The scene file: JSON in and out, every key checked (docs/scene-format.md).
#include <regolith/clod/Effects.hpp>
#include <regolith/core/AtomicFile.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/scene/SceneDescription.hpp>

#include "BodyPlacement.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace regolith::scene {

namespace {

using json = nlohmann::ordered_json;
namespace fs = std::filesystem;

constexpr double kInf = std::numeric_limits<double>::infinity();

/// A closed or open interval, and how messages write it.
struct Range {
  double lo = -kInf, hi = kInf;
  bool loOpen = false, hiOpen = false;
  [[nodiscard]] bool holds(double v) const {
    return (loOpen ? v > lo : v >= lo) && (hiOpen ? v < hi : v <= hi);
  }
  [[nodiscard]] std::string text() const {
    if (hi == kInf) return (loOpen ? "> " : ">= ") + core::number(lo);
    return std::string(loOpen ? "(" : "[") + core::number(lo) + ", " + core::number(hi) +
           (hiOpen ? ")" : "]");
  }
};
constexpr Range kAny{};
constexpr Range kPositive{0.0, kInf, true, false};
constexpr Range kNonNegative{0.0, kInf, false, false};
constexpr Range kUnit{0.0, 1.0, false, false};

std::string typeName(const json& j) {
  if (j.is_null()) return "null";
  if (j.is_boolean()) return "a boolean";
  if (j.is_number()) return "a number";
  if (j.is_string()) return "a string";
  if (j.is_array()) return "an array";
  return "an object";
}

std::string joined(const std::vector<std::string>& names) {
  std::ostringstream out;
  for (std::size_t i = 0; i < names.size(); ++i) out << (i == 0 ? "" : ", ") << names[i];
  return names.empty() ? "none" : out.str();
}

/// Reads one scene document, naming `file` and the JSON pointer in every error.
class Reader {
 public:
  Reader(std::string file, fs::path folder, bool checkStores)
      : file_(std::move(file)), folder_(std::move(folder)), checkStores_(checkStores) {}

  [[noreturn]] void fail(const std::string& ptr, const std::string& what) const {
    throw InvalidArgument(file_ + ": " + (ptr.empty() ? "/" : ptr) + ": " + what);
  }

  /// `j` must be an object whose keys are all in `allowed`.
  void object(const json& j, const std::string& ptr,
              const std::vector<std::string>& allowed) const {
    if (!j.is_object()) fail(ptr, "expected an object, got " + typeName(j));
    for (const auto& item : j.items()) {
      if (std::find(allowed.begin(), allowed.end(), item.key()) == allowed.end())
        fail(ptr + "/" + item.key(), "unknown key, expected one of: " + joined(allowed));
    }
  }

  const json* member(const json& j, const std::string& key) const {
    const auto it = j.find(key);
    return it == j.end() ? nullptr : &*it;
  }

  double number(const json& j, const std::string& ptr, const std::string& key, double fallback,
                const Range& range = kAny, bool required = false) const {
    const json* v = member(j, key);
    const std::string p = ptr + "/" + key;
    if (!v) {
      if (required) fail(p, "missing, expected a number");
      return fallback;
    }
    return numberAt(*v, p, range);
  }

  double numberAt(const json& v, const std::string& p, const Range& range = kAny) const {
    if (!v.is_number()) fail(p, "expected a number, got " + typeName(v));
    const double x = v.get<double>();
    if (!std::isfinite(x)) fail(p, core::number(x) + " is not finite");
    if (!range.holds(x)) fail(p, core::number(x) + " is not in " + range.text());
    return x;
  }

  long long integer(const json& j, const std::string& ptr, const std::string& key,
                    long long fallback, long long lo, long long hi) const {
    const json* v = member(j, key);
    if (!v) return fallback;
    const std::string p = ptr + "/" + key;
    if (!v->is_number_integer())
      fail(p, "expected an integer, got " +
                  (v->is_number() ? core::number(v->get<double>()) : typeName(*v)));
    const long long x =
        v->is_number_unsigned()
            ? static_cast<long long>(std::min<std::uint64_t>(
                  v->get<std::uint64_t>(),
                  static_cast<std::uint64_t>(std::numeric_limits<long long>::max())))
            : v->get<long long>();
    if (x < lo || x > hi)
      fail(p, std::to_string(x) + " is not in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                  "]");
    return x;
  }

  std::uint64_t seed(const json& j, const std::string& ptr) const {
    const json* v = member(j, "seed");
    if (!v) return 1;
    if (!v->is_number_unsigned())
      fail(ptr + "/seed", "expected an integer >= 0, got " +
                              (v->is_number() ? core::number(v->get<double>()) : typeName(*v)));
    return v->get<std::uint64_t>();
  }

  std::string string(const json& j, const std::string& ptr, const std::string& key, bool required,
                     const std::string& fallback = {}) const {
    const json* v = member(j, key);
    const std::string p = ptr + "/" + key;
    if (!v) {
      if (required) fail(p, "missing, expected a string");
      return fallback;
    }
    if (!v->is_string()) fail(p, "expected a string, got " + typeName(*v));
    std::string s = v->get<std::string>();
    if (s.empty()) fail(p, "empty, expected a non-empty string");
    return s;
  }

  bool boolean(const json& j, const std::string& ptr, const std::string& key, bool fallback) const {
    const json* v = member(j, key);
    if (!v) return fallback;
    if (!v->is_boolean()) fail(ptr + "/" + key, "expected true or false, got " + typeName(*v));
    return v->get<bool>();
  }

  template <std::size_t N>
  std::array<double, N> numbers(const json& v, const std::string& p,
                                const Range& range = kAny) const {
    if (!v.is_array() || v.size() != N)
      fail(p, "expected an array of " + std::to_string(N) + " numbers, got " +
                  (v.is_array() ? "an array of " + std::to_string(v.size()) : typeName(v)));
    std::array<double, N> out{};
    for (std::size_t i = 0; i < N; ++i) out[i] = numberAt(v[i], p + "/" + std::to_string(i), range);
    return out;
  }

  template <std::size_t N>
  std::array<double, N> numbers(const json& j, const std::string& ptr, const std::string& key,
                                const std::array<double, N>& fallback,
                                const Range& range = kAny) const {
    const json* v = member(j, key);
    return v ? numbers<N>(*v, ptr + "/" + key, range) : fallback;
  }

  const json& array(const json& j, const std::string& ptr, const std::string& key,
                    bool required) const {
    static const json kEmpty = json::array();
    const json* v = member(j, key);
    if (!v) {
      if (required) fail(ptr + "/" + key, "missing, expected an array");
      return kEmpty;
    }
    if (!v->is_array()) fail(ptr + "/" + key, "expected an array, got " + typeName(*v));
    return *v;
  }

  DataSource source(const json& j, const std::string& ptr) const {
    if (!j.is_object()) fail(ptr, "expected an object, got " + typeName(j));
    DataSource s;
    if (j.contains("store") == j.contains("generate"))
      fail(ptr, "expected exactly one of \"store\" and \"generate\"");
    if (j.contains("store")) {
      object(j, ptr, {"store", "grid", "featherMetres", "featherNodataSamples"});
      s.store = string(j, ptr, "store", true);
      s.grid = string(j, ptr, "grid", true);
      s.featherMetres = number(j, ptr, "featherMetres", 0.0, kNonNegative);
      s.featherNodataSamples = number(j, ptr, "featherNodataSamples", 0.0, kNonNegative);
      if (checkStores_ && !fs::exists(resolve(s.store))) fail(ptr + "/store", "no such file");
      return s;
    }
    s.generate = string(j, ptr, "generate", true);
    if (s.generate == "mars-planet") {
      object(j, ptr, {"generate", "seed", "rows", "ellipsoid", "craterDensity", "featherMetres"});
      s.rows = static_cast<std::size_t>(integer(j, ptr, "rows", 360, 4, 1 << 20));
    } else if (s.generate == "victoria") {
      object(j, ptr, {"generate", "seed", "size", "spacing", "featherMetres"});
      s.size = static_cast<std::size_t>(integer(j, ptr, "size", 601, 2, 1 << 16));
      s.spacing = number(j, ptr, "spacing", 2.0, kPositive);
    } else if (s.generate == "mars-cap") {
      object(j, ptr,
             {"generate", "seed", "pole", "minLatitude", "spacing", "ellipsoid", "craterDensity",
              "featherMetres"});
      s.pole = string(j, ptr, "pole", false, "north");
      if (s.pole != "north" && s.pole != "south")
        fail(ptr + "/pole", "\"" + s.pole + "\" is not one of: north, south");
      s.minLatitude = number(j, ptr, "minLatitude", 75.0, {0.0, 90.0, true, true});
      s.spacing = number(j, ptr, "spacing", 1000.0, kPositive);
    } else if (s.generate == "mars-strip") {
      object(j, ptr,
             {"generate", "seed", "centreLat", "centreLon", "inclination", "length", "width",
              "spacing", "raggedness", "ellipsoid", "craterDensity", "featherMetres",
              "featherNodataSamples"});
      s.centreLat = number(j, ptr, "centreLat", 0.0, {-89.0, 89.0, true, true});
      s.centreLon = number(j, ptr, "centreLon", 0.0, {-180.0, 360.0});
      s.inclination = number(j, ptr, "inclination", 60.0, {0.0, 180.0});
      s.length = number(j, ptr, "length", 300000.0, kPositive);
      s.width = number(j, ptr, "width", 10000.0, kPositive);
      s.spacing = number(j, ptr, "spacing", 50.0, kPositive);
      s.raggedness = number(j, ptr, "raggedness", 0.25, {0.0, 0.9});
    } else {
      fail(ptr + "/generate",
           "\"" + s.generate + "\" is not one of: mars-planet, mars-cap, mars-strip, victoria");
    }
    s.seed = seed(j, ptr);
    if (s.generate != "victoria") {
      s.ellipsoid = boolean(j, ptr, "ellipsoid", true);
      s.craterDensity = number(j, ptr, "craterDensity", 1.0, kNonNegative);
    }
    s.featherMetres = number(j, ptr, "featherMetres", 0.0, kNonNegative);
    if (s.generate == "mars-cap" || s.generate == "mars-strip")
      s.featherNodataSamples = number(j, ptr, "featherNodataSamples", 0.0, kNonNegative);
    return s;
  }

  DrapedSource draped(const json& j, const std::string& ptr, bool dem) const {
    object(j, ptr, {"data", "window", "opacity", "range"});
    DrapedSource d;
    const json* data = member(j, "data");
    if (!data) fail(ptr + "/data", "missing, expected a dataset ({\"store\", \"grid\"})");
    const json* range = member(j, "range");
    const bool store = data->is_object() && data->contains("store");
    if (store && range)  // before the store is looked for: the key is wrong either way
      fail(ptr + "/range",
           "given for a store's data, expected it only with a generator (a store's values are "
           "drawn as they are, in [0, 1])");
    d.data = source(*data, ptr + "/data");
    d.window = static_cast<int>(integer(j, ptr, "window", 512, 64, 4096));
    d.opacity = number(j, ptr, "opacity", 1.0, kUnit);
    if (d.data.generate.empty()) {
      if (range)
        fail(ptr + "/range",
             "given for a store's data, expected it only with a generator (a store's values are "
             "drawn as they are, in [0, 1])");
      return d;
    }
    // A generator's grid must be the terrain's kind of grid: the texture is draped in the
    // terrain's grid frame.
    const char* own = dem ? "victoria" : "mars-planet";
    if (d.data.generate != own)
      fail(ptr + "/data/generate", "\"" + d.data.generate + "\" is not draped over a " +
                                       (dem ? "DEM" : "body") + ", expected " + own);
    if (!range)
      fail(ptr + "/range",
           "missing, expected [min, max]: the generator's heights (metres) that become 0 and 1");
    d.range = numbers<2>(*range, ptr + "/range");
    if (!((*d.range)[1] > (*d.range)[0]))
      fail(ptr + "/range/1",
           core::number((*d.range)[1]) + " is not > min (" + core::number((*d.range)[0]) + ")");
    return d;
  }

  EffectsDescription effects(const json& j, const std::string& ptr, bool dem) const {
    EffectsDescription e;
    object(j, ptr,
           dem ? std::vector<std::string>{"tracks", "heightColours", "latLon", "noise", "albedo",
                                          "overlay"}
               : std::vector<std::string>{"heightColours", "latLon", "noise", "albedo", "overlay"});
    e.tracks = boolean(j, ptr, "tracks", false);
    if (const json* h = member(j, "heightColours")) {
      const std::string p = ptr + "/heightColours";
      object(*h, p, {"min", "max", "shaded"});
      EffectsDescription::HeightColours c;
      c.min = number(*h, p, "min", 0.0, kAny, true);
      c.max = number(*h, p, "max", 0.0, kAny, true);
      if (!(c.max > c.min))
        fail(p + "/max", core::number(c.max) + " is not > min (" + core::number(c.min) + ")");
      c.shaded = boolean(*h, p, "shaded", false);
      e.heightColours = c;
    }
    if (const json* l = member(j, "latLon")) {
      const std::string p = ptr + "/latLon";
      object(*l, p, {"spacing", "minPixelSpacing", "colour", "width"});
      EffectsDescription::LatLon c;
      c.spacing = number(*l, p, "spacing", 0.0, {0.0, 90.0});
      c.minPixelSpacing = number(*l, p, "minPixelSpacing", 80.0, kPositive);
      c.colour = numbers<3>(*l, p, "colour", c.colour, kUnit);
      c.width = number(*l, p, "width", 1.5, kPositive);
      e.latLon = c;
    }
    if (const json* n = member(j, "noise")) {
      const std::string p = ptr + "/noise";
      object(*n, p, {"amplitude", "wavelength", "octaves", "albedoVariation"});
      EffectsDescription::Noise c;
      c.amplitude = number(*n, p, "amplitude", 0.05, kNonNegative);
      c.wavelength = number(*n, p, "wavelength", 0.5, kPositive);
      c.octaves = static_cast<int>(integer(*n, p, "octaves", 4, 1, 8));
      c.albedoVariation = number(*n, p, "albedoVariation", 0.15, kUnit);
      e.noise = c;
    }
    if (const json* a = member(j, "albedo")) e.albedo = draped(*a, ptr + "/albedo", dem);
    if (const json* o = member(j, "overlay")) e.overlay = draped(*o, ptr + "/overlay", dem);
    return e;
  }

  void look(const json& j, const std::string& ptr, TerrainLook& look, bool dem) const {
    look.colour = numbers<3>(j, ptr, "colour", look.colour, kUnit);
    look.clipmapSize = static_cast<int>(integer(j, ptr, "clipmapSize", look.clipmapSize, 15, 1023));
    if (look.clipmapSize % 2 == 0)
      fail(ptr + "/clipmapSize", std::to_string(look.clipmapSize) + " is not odd");
    if (const json* e = member(j, "effects")) look.effects = effects(*e, ptr + "/effects", dem);
  }

  SceneDescription scene(const json& doc) const {
    SceneDescription s;
    s.folder = folder_;
    object(doc, "", {"version", "root", "bodies", "dems", "objects", "cameras", "light"});
    s.root = string(doc, "", "root", false);
    if (s.root.empty()) s.root = "root";
    s.version = static_cast<int>(integer(doc, "", "version", -1, kSceneVersion, kSceneVersion));
    if (s.version < 0) fail("/version", "missing, expected " + std::to_string(kSceneVersion));
    const json& bodies = array(doc, "", "bodies", true);
    if (bodies.empty()) fail("/bodies", "empty, expected at least one body");
    for (std::size_t i = 0; i < bodies.size(); ++i) {
      const std::string p = "/bodies/" + std::to_string(i);
      const json& b = bodies[i];
      object(b, p,
             {"name", "radii", "heights", "pose", "colour", "clipmapSize", "effects", "farField",
              "composeDems"});
      Body body;
      body.name = string(b, p, "name", true);
      if (const json* r = member(b, "radii")) body.radii = numbers<2>(*r, p + "/radii", kPositive);
      if (!body.radii && !member(b, "heights"))
        fail(p + "/heights",
             "missing, expected an array of datasets (or \"radii\": a body without relief)");
      const json& heights = array(b, p, "heights", false);
      if (heights.empty() && member(b, "heights"))
        fail(p + "/heights",
             "empty, expected at least one dataset (leave it out, with \"radii\", for a body "
             "without relief)");
      for (std::size_t k = 0; k < heights.size(); ++k)
        body.heights.push_back(source(heights[k], p + "/heights/" + std::to_string(k)));
      if (!body.heights.empty() && !body.heights[0].generate.empty() &&
          body.heights[0].generate != "mars-planet")
        fail(p + "/heights/0/generate",
             "\"" + body.heights[0].generate + "\" is not a global grid, expected mars-planet");
      for (std::size_t k = 1; k < body.heights.size(); ++k) {
        if (body.heights[k].generate == "mars-planet" || body.heights[k].generate == "victoria")
          fail(p + "/heights/" + std::to_string(k) + "/generate",
               "\"" + body.heights[k].generate +
                   "\" cannot refine a body, expected mars-cap or mars-strip (DEMs go in /dems)");
      }
      if (const json* pose = member(b, "pose")) {
        const std::string q = p + "/pose";
        object(*pose, q, {"position", "obliquity", "spin"});
        if (!member(*pose, "position"))
          fail(q + "/position", "missing, expected [x, y, z] in metres");
        Body::Pose bp;
        bp.position = numbers<3>(*pose, q, "position", bp.position);
        bp.obliquity = number(*pose, q, "obliquity", 0.0, {-180.0, 180.0});
        bp.spin = number(*pose, q, "spin", 0.0, {-360.0, 360.0});
        body.pose = bp;
      }
      look(b, p, body.look, false);
      body.farField = boolean(b, p, "farField", true);
      body.composeDems = boolean(b, p, "composeDems", false);
      s.bodies.push_back(std::move(body));
    }
    const json& dems = array(doc, "", "dems", false);
    for (std::size_t i = 0; i < dems.size(); ++i) {
      const std::string p = "/dems/" + std::to_string(i);
      const json& d = dems[i];
      object(d, p, {"name", "body", "heights", "placement", "colour", "clipmapSize", "effects"});
      Dem dem;
      dem.name = string(d, p, "name", true);
      dem.body = string(d, p, "body", true);
      const json* h = member(d, "heights");
      if (!h) fail(p + "/heights", "missing, expected a dataset");
      dem.heights = source(*h, p + "/heights");
      if (!dem.heights.generate.empty() && dem.heights.generate != "victoria")
        fail(p + "/heights/generate",
             "\"" + dem.heights.generate + "\" is not a DEM generator, expected victoria");
      if (const json* pl = member(d, "placement")) {
        const std::string q = p + "/placement";
        object(*pl, q, {"lat", "lon", "height", "heading"});
        Dem::Placement placement;
        placement.lat = number(*pl, q, "lat", 0.0, {-90.0, 90.0}, true);
        placement.lon = number(*pl, q, "lon", 0.0, {-180.0, 360.0}, true);
        placement.heading = number(*pl, q, "heading", 0.0, {-360.0, 360.0});
        const json* hh = member(*pl, "height");
        if (hh && hh->is_string()) {
          if (hh->get<std::string>() != "surface")
            fail(q + "/height",
                 "\"" + hh->get<std::string>() + "\" is not a number or \"surface\"");
        } else if (hh) {
          placement.height = numberAt(*hh, q + "/height");
          placement.surfaceHeight = false;
        }
        dem.placement = placement;
      } else if (dem.heights.store.empty()) {
        fail(p + "/placement", "missing, expected a placement for a generated DEM");
      }
      look(d, p, dem.look, true);
      s.dems.push_back(std::move(dem));
    }
    const json& objects = array(doc, "", "objects", false);
    for (std::size_t i = 0; i < objects.size(); ++i) {
      const std::string p = "/objects/" + std::to_string(i);
      const json& o = objects[i];
      object(o, p, {"name", "type", "dem", "pose", "traverse", "colour"});
      Object obj;
      obj.name = string(o, p, "name", true);
      obj.type = string(o, p, "type", false, "rover");
      if (obj.type != "rover") fail(p + "/type", "\"" + obj.type + "\" is not one of: rover");
      obj.dem = string(o, p, "dem", true);
      if (o.contains("pose") == o.contains("traverse"))
        fail(p, "expected exactly one of \"pose\" and \"traverse\"");
      if (const json* pose = member(o, "pose")) {
        const std::string q = p + "/pose";
        object(*pose, q, {"x", "y", "heading"});
        obj.pose = Object::Pose{number(*pose, q, "x", 0.0, kAny, true),
                                number(*pose, q, "y", 0.0, kAny, true),
                                number(*pose, q, "heading", 0.0, {-360.0, 360.0})};
      }
      if (const json* t = member(o, "traverse")) {
        const std::string q = p + "/traverse";
        object(*t, q, {"waypoints", "speed", "step"});
        Object::Traverse tr;
        const json& w = array(*t, q, "waypoints", true);
        if (w.size() < 2)
          fail(q + "/waypoints", std::to_string(w.size()) + " waypoints, expected at least 2");
        for (std::size_t k = 0; k < w.size(); ++k)
          tr.waypoints.push_back(numbers<2>(w[k], q + "/waypoints/" + std::to_string(k)));
        tr.speed = number(*t, q, "speed", 1.0, kPositive);
        tr.step = number(*t, q, "step", 0.001, kPositive);
        obj.traverse = tr;
      }
      obj.colour = numbers<3>(o, p, "colour", obj.colour, kUnit);
      s.objects.push_back(std::move(obj));
    }
    const json& cameras = array(doc, "", "cameras", false);
    for (std::size_t i = 0; i < cameras.size(); ++i) {
      const std::string p = "/cameras/" + std::to_string(i);
      const json& c = cameras[i];
      object(c, p,
             {"name", "frame", "eye", "lookAt", "up", "fovY", "near", "width", "height", "viewport",
              "focus"});
      Camera cam;
      cam.name = string(c, p, "name", true);
      cam.frame = string(c, p, "frame", true);
      if (!member(c, "eye")) fail(p + "/eye", "missing, expected an array of 3 numbers");
      if (!member(c, "lookAt")) fail(p + "/lookAt", "missing, expected an array of 3 numbers");
      cam.eye = numbers<3>(c, p, "eye", cam.eye);
      cam.lookAt = numbers<3>(c, p, "lookAt", cam.lookAt);
      cam.up = numbers<3>(c, p, "up", cam.up);
      const auto d = std::array<double, 3>{cam.lookAt[0] - cam.eye[0], cam.lookAt[1] - cam.eye[1],
                                           cam.lookAt[2] - cam.eye[2]};
      if (d[0] == 0.0 && d[1] == 0.0 && d[2] == 0.0)
        fail(p + "/lookAt", "equals the eye, expected a point the camera looks at");
      const double cx = d[1] * cam.up[2] - d[2] * cam.up[1],
                   cy = d[2] * cam.up[0] - d[0] * cam.up[2],
                   cz = d[0] * cam.up[1] - d[1] * cam.up[0];
      if (cx == 0.0 && cy == 0.0 && cz == 0.0)
        fail(p + "/up", "parallel to the view direction, expected a direction across it");
      cam.fovY = number(c, p, "fovY", 45.0, {0.0, 180.0, true, true});
      cam.near = number(c, p, "near", 0.1, kPositive);
      cam.width = static_cast<int>(integer(c, p, "width", 960, 1, 16384));
      cam.height = static_cast<int>(integer(c, p, "height", 540, 1, 16384));
      if (const json* v = member(c, "viewport")) {
        const std::array<double, 4> vp = numbers<4>(*v, p + "/viewport", kNonNegative);
        std::array<int, 4> iv{};
        for (std::size_t k = 0; k < 4; ++k) {
          if (vp[k] != std::floor(vp[k]))
            fail(p + "/viewport/" + std::to_string(k), core::number(vp[k]) + " is not an integer");
          iv[k] = static_cast<int>(vp[k]);
        }
        if (iv[2] < 1 || iv[3] < 1 || iv[0] + iv[2] > cam.width || iv[1] + iv[3] > cam.height)
          fail(p + "/viewport", "[" + std::to_string(iv[0]) + ", " + std::to_string(iv[1]) + ", " +
                                    std::to_string(iv[2]) + ", " + std::to_string(iv[3]) +
                                    "] is not a non-empty rectangle inside the " +
                                    std::to_string(cam.width) + "x" + std::to_string(cam.height) +
                                    " image");
        cam.viewport = iv;
      }
      cam.focus = string(c, p, "focus", false);
      s.cameras.push_back(std::move(cam));
    }
    if (const json* l = member(doc, "light")) {
      object(*l, "/light", {"frame", "elevation", "azimuth", "direction", "from"});
      s.light.frame = string(*l, "/light", "frame", false);
      s.light.from = string(*l, "/light", "from", false);
      if (l->contains("from") && l->size() > 1)
        fail("/light",
             "expected \"from\" alone (a light at a frame's origin has no direction of its own)");
      if (l->contains("direction") && (l->contains("elevation") || l->contains("azimuth")))
        fail("/light", "expected \"direction\" or \"elevation\" and \"azimuth\", not both");
      s.light.elevation = number(*l, "/light", "elevation", 35.0, {-90.0, 90.0});
      s.light.azimuth = number(*l, "/light", "azimuth", 90.0, {-360.0, 360.0});
      if (const json* d = member(*l, "direction")) {
        const auto v = numbers<3>(*d, "/light/direction");
        if (v[0] == 0.0 && v[1] == 0.0 && v[2] == 0.0)
          fail("/light/direction", "is zero, expected a direction");
        s.light.direction = v;
      }
    }
    references(s);
    // Bodies apart: those whose radii the file gives (Scene checks the rest when built).
    std::vector<double> radius;
    for (const Body& b : s.bodies)
      radius.push_back(b.radii ? (*b.radii)[0] : std::numeric_limits<double>::quiet_NaN());
    if (const auto e = detail::checkBodiesApart(s.bodies, radius)) fail(e->pointer, e->what);
    return s;
  }

  /// Names are unique across bodies, DEMs, objects and cameras (they name scene-graph
  /// nodes), and every reference names something of the right kind.
  void references(const SceneDescription& s) const {
    std::map<std::string, std::string> seen;  // name → pointer of its first use
    const auto unique = [&](const std::string& name, const std::string& ptr) {
      const auto [it, fresh] = seen.emplace(name, ptr);
      if (!fresh) fail(ptr, "\"" + name + "\" is already the name of " + it->second);
    };
    std::vector<std::string> bodies, terrains, frames, cameras;
    unique(s.root, "/root");
    for (std::size_t i = 0; i < s.bodies.size(); ++i) {
      unique(s.bodies[i].name, "/bodies/" + std::to_string(i) + "/name");
      bodies.push_back(s.bodies[i].name);
    }
    for (std::size_t i = 0; i < s.dems.size(); ++i) {
      unique(s.dems[i].name, "/dems/" + std::to_string(i) + "/name");
      terrains.push_back(s.dems[i].name);
    }
    for (std::size_t i = 0; i < s.objects.size(); ++i)
      unique(s.objects[i].name, "/objects/" + std::to_string(i) + "/name");
    for (std::size_t i = 0; i < s.cameras.size(); ++i) {
      unique(s.cameras[i].name, "/cameras/" + std::to_string(i) + "/name");
      cameras.push_back(s.cameras[i].name);
    }
    terrains.insert(terrains.begin(), bodies.begin(), bodies.end());
    frames = terrains;
    for (const Object& o : s.objects) frames.push_back(o.name);
    const auto known = [&](const std::string& name, const std::vector<std::string>& names,
                           const std::string& ptr, const std::string& kinds) {
      if (std::find(names.begin(), names.end(), name) == names.end())
        fail(ptr, "\"" + name + "\" names no " + kinds + " (there are: " + joined(names) + ")");
    };
    std::vector<std::string> dems(terrains.begin() + static_cast<std::ptrdiff_t>(bodies.size()),
                                  terrains.end());
    for (std::size_t i = 0; i < s.dems.size(); ++i)
      known(s.dems[i].body, bodies, "/dems/" + std::to_string(i) + "/body", "body");
    for (std::size_t i = 0; i < s.objects.size(); ++i)
      known(s.objects[i].dem, dems, "/objects/" + std::to_string(i) + "/dem", "DEM");
    for (std::size_t i = 0; i < s.cameras.size(); ++i) {
      known(s.cameras[i].frame, frames, "/cameras/" + std::to_string(i) + "/frame",
            "body, DEM or object");
      if (!s.cameras[i].focus.empty())
        known(s.cameras[i].focus, terrains, "/cameras/" + std::to_string(i) + "/focus",
              "body or DEM");
    }
    if (!s.light.frame.empty()) known(s.light.frame, frames, "/light/frame", "body, DEM or object");
    frames.insert(frames.begin(), s.root);
    if (!s.light.from.empty())
      known(s.light.from, frames, "/light/from", "root, body, DEM or object");
  }

  fs::path resolve(const std::string& store) const {
    const fs::path p(store);
    return p.is_absolute() ? p : folder_ / p;
  }

 private:
  std::string file_;
  fs::path folder_;
  bool checkStores_;
};

// ---- writing ---------------------------------------------------------------------------

json sourceJson(const DataSource& s, const fs::path& from, const fs::path& to) {
  json j;
  if (!s.store.empty()) {
    fs::path p(s.store);
    if (p.is_relative() && from != to) {
      const fs::path abs = fs::absolute(from / p).lexically_normal();
      const fs::path rel = abs.lexically_relative(fs::absolute(to).lexically_normal());
      p = rel.empty() ? abs : rel;
    }
    j["store"] = p.generic_string();
    j["grid"] = s.grid;
  } else {
    j["generate"] = s.generate;
    j["seed"] = s.seed;
    if (s.generate == "mars-planet") {
      j["rows"] = s.rows;
    } else if (s.generate == "victoria") {
      j["size"] = s.size;
      j["spacing"] = s.spacing;
    } else if (s.generate == "mars-cap") {
      j["pole"] = s.pole;
      j["minLatitude"] = s.minLatitude;
      j["spacing"] = s.spacing;
    } else if (s.generate == "mars-strip") {
      j["centreLat"] = s.centreLat;
      j["centreLon"] = s.centreLon;
      j["inclination"] = s.inclination;
      j["length"] = s.length;
      j["width"] = s.width;
      j["spacing"] = s.spacing;
      j["raggedness"] = s.raggedness;
    }
    if (s.generate != "victoria") {
      j["ellipsoid"] = s.ellipsoid;
      j["craterDensity"] = s.craterDensity;
    }
  }
  j["featherMetres"] = s.featherMetres;
  if (s.generate.empty() || s.generate == "mars-cap" || s.generate == "mars-strip")
    j["featherNodataSamples"] = s.featherNodataSamples;
  return j;
}

json drapedJson(const DrapedSource& d, const fs::path& from, const fs::path& to) {
  json j = {{"data", sourceJson(d.data, from, to)}, {"window", d.window}, {"opacity", d.opacity}};
  if (d.range) j["range"] = *d.range;
  return j;
}

json effectsJson(const EffectsDescription& e, bool dem, const fs::path& from, const fs::path& to) {
  json j = json::object();
  if (dem) j["tracks"] = e.tracks;
  if (e.heightColours)
    j["heightColours"] = {{"min", e.heightColours->min},
                          {"max", e.heightColours->max},
                          {"shaded", e.heightColours->shaded}};
  if (e.latLon)
    j["latLon"] = {{"spacing", e.latLon->spacing},
                   {"minPixelSpacing", e.latLon->minPixelSpacing},
                   {"colour", e.latLon->colour},
                   {"width", e.latLon->width}};
  if (e.noise)
    j["noise"] = {{"amplitude", e.noise->amplitude},
                  {"wavelength", e.noise->wavelength},
                  {"octaves", e.noise->octaves},
                  {"albedoVariation", e.noise->albedoVariation}};
  if (e.albedo) j["albedo"] = drapedJson(*e.albedo, from, to);
  if (e.overlay) j["overlay"] = drapedJson(*e.overlay, from, to);
  return j;
}

json toJson(const SceneDescription& s, const fs::path& to) {
  const fs::path& from = s.folder;
  json doc;
  doc["version"] = s.version;
  if (s.root != "root") doc["root"] = s.root;
  doc["bodies"] = json::array();
  for (const Body& b : s.bodies) {
    json j;
    j["name"] = b.name;
    if (b.radii) j["radii"] = *b.radii;
    if (!b.heights.empty() || !b.radii) {  // none, with radii: a body without relief
      j["heights"] = json::array();
      for (const DataSource& d : b.heights) j["heights"].push_back(sourceJson(d, from, to));
    }
    if (b.pose)
      j["pose"] = {
          {"position", b.pose->position}, {"obliquity", b.pose->obliquity}, {"spin", b.pose->spin}};
    j["colour"] = b.look.colour;
    j["clipmapSize"] = b.look.clipmapSize;
    j["effects"] = effectsJson(b.look.effects, false, from, to);
    j["farField"] = b.farField;
    j["composeDems"] = b.composeDems;
    doc["bodies"].push_back(std::move(j));
  }
  doc["dems"] = json::array();
  for (const Dem& d : s.dems) {
    json j;
    j["name"] = d.name;
    j["body"] = d.body;
    j["heights"] = sourceJson(d.heights, from, to);
    if (d.placement) {
      j["placement"] = {
          {"lat", d.placement->lat}, {"lon", d.placement->lon}, {"heading", d.placement->heading}};
      if (d.placement->surfaceHeight) {
        j["placement"]["height"] = "surface";
      } else {
        j["placement"]["height"] = d.placement->height;
      }
    }
    j["colour"] = d.look.colour;
    j["clipmapSize"] = d.look.clipmapSize;
    j["effects"] = effectsJson(d.look.effects, true, from, to);
    doc["dems"].push_back(std::move(j));
  }
  doc["objects"] = json::array();
  for (const Object& o : s.objects) {
    json j{{"name", o.name}, {"type", o.type}, {"dem", o.dem}, {"colour", o.colour}};
    if (o.pose) j["pose"] = {{"x", o.pose->x}, {"y", o.pose->y}, {"heading", o.pose->heading}};
    if (o.traverse)
      j["traverse"] = {{"waypoints", o.traverse->waypoints},
                       {"speed", o.traverse->speed},
                       {"step", o.traverse->step}};
    doc["objects"].push_back(std::move(j));
  }
  doc["cameras"] = json::array();
  for (const Camera& c : s.cameras) {
    json j{{"name", c.name},     {"frame", c.frame}, {"eye", c.eye},
           {"lookAt", c.lookAt}, {"up", c.up},       {"fovY", c.fovY},
           {"near", c.near},     {"width", c.width}, {"height", c.height}};
    if (c.viewport) j["viewport"] = *c.viewport;
    if (!c.focus.empty()) j["focus"] = c.focus;
    doc["cameras"].push_back(std::move(j));
  }
  json light = json::object();
  if (!s.light.frame.empty() && s.light.from.empty()) light["frame"] = s.light.frame;
  if (!s.light.from.empty()) {
    light["from"] = s.light.from;
  } else if (s.light.direction) {
    light["direction"] = *s.light.direction;
  } else {
    light["elevation"] = s.light.elevation;
    light["azimuth"] = s.light.azimuth;
  }
  doc["light"] = light;
  return doc;
}

SceneDescription parse(const std::string& text, const std::string& file, const fs::path& folder,
                       bool checkStores) {
  json doc;
  try {
    doc = json::parse(text);
  } catch (const json::exception& e) {  // parse_error, and out_of_range for 1e999
    // nlohmann's message: "[json.exception.parse_error.101] parse error at line 3, ...".
    std::string what = e.what();
    const auto at = what.find("] ");
    throw InvalidArgument(file + ": not JSON (" +
                          (at == std::string::npos ? what : what.substr(at + 2)) + ")");
  }
  return Reader(file, folder, checkStores).scene(doc);
}

}  // namespace

std::vector<std::string> EffectsDescription::declared() const {
  return clod::declaredEffectNames(*this);
}

fs::path SceneDescription::resolve(const std::string& store) const {
  const fs::path p(store);
  return p.is_absolute() ? p : folder / p;
}

const Camera* SceneDescription::camera(const std::string& name) const {
  for (const Camera& c : cameras)
    if (c.name == name) return &c;
  return nullptr;
}

SceneDescription parseScene(const std::string& text, const std::string& file,
                            const fs::path& folder) {
  return parse(text, file, folder, true);
}

SceneDescription readScene(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError("readScene(): " + path.string() + ": cannot be read (no such file?)");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw IoError("readScene(): " + path.string() + ": read failed");
  return parseScene(text.str(), path.string(), path.parent_path());
}

std::string sceneJson(const SceneDescription& scene, const fs::path& folder) {
  return toJson(scene, folder).dump(2) + "\n";
}

void writeScene(const SceneDescription& scene, const fs::path& path) {
  // What JSON cannot carry (a NaN position would be written as null) is named first.
  std::vector<double> radius;
  for (const Body& b : scene.bodies)
    radius.push_back(b.radii ? (*b.radii)[0] : std::numeric_limits<double>::quiet_NaN());
  if (const auto e = detail::checkBodiesApart(scene.bodies, radius))
    throw InvalidArgument(path.string() + ": " + e->pointer + ": " + e->what);
  const std::string text = sceneJson(scene, path.parent_path());
  // What is written must read back: the same checks as readScene (stores may not exist yet).
  (void)parse(text, path.string(), path.parent_path(), false);
  core::writeStreamAtomically(
      path, [&](std::ostream& os) { os << text; }, "writeScene()");
}

std::string sceneInfoJson(const SceneDescription& s) {
  json doc;
  const auto dataset = [&](const DataSource& d) {
    json j;
    if (!d.store.empty()) {
      j["store"] = s.resolve(d.store).string();
      j["grid"] = d.grid;
    } else {
      j["generate"] = d.generate;
      j["seed"] = d.seed;
    }
    return j;
  };
  const auto declared = [](const EffectsDescription& e) {
    json j = json::array();
    for (const std::string& n : e.declared()) j.push_back(n);
    return j;
  };
  doc["version"] = s.version;
  doc["bodies"] = json::array();
  for (const Body& b : s.bodies) {
    json j{{"name", b.name}, {"farField", b.farField}, {"effects", declared(b.look.effects)}};
    if (b.radii) j["radii"] = *b.radii;
    if (b.pose) j["position"] = b.pose->position;
    j["datasets"] = json::array();
    for (const DataSource& d : b.heights) {
      json dj = dataset(d);
      dj["role"] = "heights";
      j["datasets"].push_back(dj);
    }
    for (const auto* t : {&b.look.effects.albedo, &b.look.effects.overlay}) {
      if (!*t) continue;
      json dj = dataset((*t)->data);
      dj["role"] = t == &b.look.effects.albedo ? "albedo" : "overlay";
      j["datasets"].push_back(dj);
    }
    doc["bodies"].push_back(j);
  }
  doc["dems"] = json::array();
  for (const Dem& d : s.dems) {
    json j{{"name", d.name},
           {"body", d.body},
           {"heights", dataset(d.heights)},
           {"effects", declared(d.look.effects)}};
    if (d.placement) {
      j["placement"] = {
          {"lat", d.placement->lat}, {"lon", d.placement->lon}, {"heading", d.placement->heading}};
      j["placement"]["height"] =
          d.placement->surfaceHeight ? json("surface") : json(d.placement->height);
    } else {
      j["placement"] = "from the store";
    }
    doc["dems"].push_back(j);
  }
  doc["objects"] = json::array();
  for (const Object& o : s.objects) {
    json j{{"name", o.name}, {"type", o.type}, {"dem", o.dem}};
    j["placed"] = o.traverse
                      ? "traverse of " + std::to_string(o.traverse->waypoints.size()) + " waypoints"
                      : std::string("pose");
    doc["objects"].push_back(j);
  }
  doc["cameras"] = json::array();
  for (const Camera& c : s.cameras) {
    doc["cameras"].push_back({{"name", c.name},
                              {"frame", c.frame},
                              {"fovY", c.fovY},
                              {"width", c.width},
                              {"height", c.height}});
  }
  return doc.dump(2) + "\n";
}

}  // namespace regolith::scene
