// The rover traverse (rover::runTraverse) from Python.
#include <regolith/core/Error.hpp>
#include <regolith/rover/Traverse.hpp>
#include <regolith/store/Pager.hpp>
#include <regolith/store/Store.hpp>

#include "Common.hpp"

#include <pybind11/functional.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <array>
#include <cmath>
#include <memory>
#include <optional>
#include <vector>

namespace regolith::python {

namespace {

std::vector<glm::dvec2> pathOf(const DoubleArray& a) {
  if (a.ndim() != 2 || a.shape(1) != 2) {
    throw InvalidArgument(
        "regolith.run_traverse(): path must be an (N, 2) array of grid (x, y) "
        "in metres, got " +
        std::to_string(a.ndim()) + " dimensions");
  }
  std::vector<glm::dvec2> p(static_cast<std::size_t>(a.shape(0)));
  for (std::size_t i = 0; i < p.size(); ++i) p[i] = {a.data()[2 * i], a.data()[2 * i + 1]};
  return p;
}

py::array_t<double> pathArray(const std::vector<glm::dvec2>& p) {
  py::array_t<double> a({static_cast<py::ssize_t>(p.size()), py::ssize_t{2}});
  for (std::size_t i = 0; i < p.size(); ++i) {
    a.mutable_data()[2 * i] = p[i].x;
    a.mutable_data()[2 * i + 1] = p[i].y;
  }
  return a;
}

/// Steps kept for Python: flat arrays grown as the traverse goes (no GIL needed).
struct Record {
  std::vector<double> step, time, ground, wheels, normals, chassis, position;
  void add(const rover::StepState& s) {
    step.push_back(static_cast<double>(s.step));
    time.push_back(s.time);
    ground.insert(ground.end(), {s.ground.x, s.ground.y, s.ground.heading});
    for (const auto& w : s.wheels) {
      wheels.insert(wheels.end(), {w.x, w.y, w.height});
      normals.insert(normals.end(), {w.normal.x, w.normal.y, w.normal.z});
    }
    const auto& c = s.chassis;
    chassis.insert(chassis.end(), {c.height, c.pitch, c.roll, c.residual});
    position.insert(position.end(), {c.position.x, c.position.y, c.position.z});
  }
};

py::array_t<double> array(const std::vector<double>& v, const std::vector<py::ssize_t>& shape) {
  py::array_t<double> a(shape);
  std::copy(v.begin(), v.end(), a.mutable_data());
  return a;
}

py::dict chassisDict(const rover::ChassisPose& p) {
  py::dict c;
  c["height"] = p.height;
  c["pitch"] = p.pitch;
  c["roll"] = p.roll;
  c["heading"] = p.heading;
  c["residual"] = p.residual;
  c["position"] = py::make_tuple(p.position.x, p.position.y, p.position.z);
  c["up"] = py::make_tuple(p.up.x, p.up.y, p.up.z);
  c["forward"] = py::make_tuple(p.forward.x, p.forward.y, p.forward.z);
  return c;
}

py::dict stateDict(const rover::StepState& s, const store::PatchCache& cache) {
  py::dict d;
  d["step"] = s.step;
  d["time"] = s.time;
  d["distance"] = s.distance;
  d["ground"] = py::make_tuple(s.ground.x, s.ground.y, s.ground.heading);
  py::array_t<double> w({py::ssize_t{6}, py::ssize_t{3}}), n({py::ssize_t{6}, py::ssize_t{3}});
  for (std::size_t i = 0; i < rover::kWheels; ++i) {
    const auto& c = s.wheels[i];
    w.mutable_data()[3 * i] = c.x, w.mutable_data()[3 * i + 1] = c.y;
    w.mutable_data()[3 * i + 2] = c.height;
    n.mutable_data()[3 * i] = c.normal.x, n.mutable_data()[3 * i + 1] = c.normal.y;
    n.mutable_data()[3 * i + 2] = c.normal.z;
  }
  d["wheels"] = w;
  d["normals"] = n;
  py::dict c;
  c["height"] = s.chassis.height;
  c["pitch"] = s.chassis.pitch;
  c["roll"] = s.chassis.roll;
  c["residual"] = s.chassis.residual;
  c["position"] = py::make_tuple(s.chassis.position.x, s.chassis.position.y, s.chassis.position.z);
  c["up"] = py::make_tuple(s.chassis.up.x, s.chassis.up.y, s.chassis.up.z);
  d["chassis"] = c;
  d["resident_bytes"] = cache.stats().residentBytes;
  return d;
}

void bindRoverClass(py::module_& m) {
  py::class_<rover::Rover>(
      m, "Rover",
      "Six-wheel rover kinematics (rover::Rover): axle offsets (front, middle, rear; metres "
      "along the heading), track width and clearance. Wheel i is on axle i // 2, side i % 2 "
      "(0 left, 1 right). Headings are radians clockwise from north (+y).")
      .def(py::init([](const std::array<double, 3>& axles, double track, double clearance) {
             rover::RoverGeometry g;
             g.axleOffsets = axles;
             g.trackWidth = track;
             g.clearance = clearance;
             return rover::Rover(g);
           }),
           py::arg("axle_offsets") = std::array<double, 3>{1.10, 0.0, -1.00},
           py::arg("track_width") = 2.20, py::arg("clearance") = 0.66)
      .def_property_readonly("reach", [](const rover::Rover& r) { return r.geometry().reach(); })
      .def(
          "wheel_positions",
          [](const rover::Rover& r, double x, double y, double heading) {
            const auto w = r.wheelPositions({x, y, heading});
            py::array_t<double> a({py::ssize_t{6}, py::ssize_t{2}});
            for (std::size_t i = 0; i < rover::kWheels; ++i) {
              a.mutable_data()[2 * i] = w[i].x;
              a.mutable_data()[2 * i + 1] = w[i].y;
            }
            return a;
          },
          py::arg("x"), py::arg("y"), py::arg("heading"),
          "Grid (x, y) of the six wheel contacts, a (6, 2) array.")
      .def(
          "settle",
          [](const rover::Rover& r, double x, double y, double heading,
             const DoubleArray& heights) {
            if (heights.ndim() != 1 || heights.shape(0) != 6) {
              throw InvalidArgument("Rover.settle(): heights must have shape (6,), got " +
                                    std::to_string(heights.size()) + " values");
            }
            const rover::GroundPose pose{x, y, heading};
            const auto w = r.wheelPositions(pose);
            std::array<rover::WheelContact, rover::kWheels> c{};
            for (std::size_t i = 0; i < rover::kWheels; ++i) {
              const double h = heights.data()[i];
              c[i] = {w[i].x, w[i].y, h, glm::dvec3(0.0, 0.0, 1.0),
                      std::isnan(h) ? topo::QueryStatus::Nodata : topo::QueryStatus::Ok};
            }
            return chassisDict(r.settle(pose, c));
          },
          py::arg("x"), py::arg("y"), py::arg("heading"), py::arg("heights"),
          "Settles the chassis on the terrain heights under the six wheels (at "
          "wheel_positions()): height, pitch, roll (radians), residual, position, up, forward. "
          "A NaN height raises DomainError.");
}

}  // namespace

void bindRover(py::module_& m) {
  bindRoverClass(m);
  m.def(
      "default_victoria_path",
      [](double scale) { return pathArray(rover::defaultVictoriaPath(scale)); },
      py::arg("scale") = 1.0,
      "The default traverse path across the Victoria-like DEM, an (N, 2) array of grid x, y "
      "(metres).");

  m.def(
      "run_traverse",
      [](const std::filesystem::path& storePath, const std::optional<DoubleArray>& path,
         const std::string& grid, std::size_t level, std::size_t cacheBytes,
         const std::string& policy, double speed, double step, std::size_t maxSteps,
         const std::string& interp, std::size_t recordEvery,
         const std::function<py::object(py::dict)>& callback, std::size_t callbackEvery,
         const std::optional<rover::Rover>& vehicle) {
        if (cacheBytes == 0) {
          throw InvalidArgument(
              "regolith.run_traverse(): cache_bytes is 0, expected a cache budget > 0 bytes");
        }
        rover::TraverseOptions o;
        if (vehicle) o.geometry = vehicle->geometry();
        o.path = path ? pathOf(*path) : rover::defaultVictoriaPath();
        o.speed = speed;
        o.step = step;
        o.maxSteps = maxSteps;
        o.interpolation = parseInterpolation(interp);
        if (callback && callbackEvery == 0) {
          throw InvalidArgument("regolith.run_traverse(): callback_every is 0, expected > 0");
        }
        // The DEM, paged from the store through a cache of cache_bytes that this call owns.
        auto file = std::make_shared<const store::Store>(store::Store::open(storePath));
        auto cache = std::make_shared<store::PatchCache>(cacheBytes, parsePolicy(policy));
        const topo::TopoDem dem = store::Pager(file, cache).dem(grid, level);
        Record rec;
        rover::TraverseResult r;
        {
          const py::gil_scoped_release release;
          r = rover::runTraverse(dem, o, [&](const rover::StepState& s) {
            if (recordEvery > 0 && s.step % recordEvery == 0) rec.add(s);
            if (!callback || s.step % callbackEvery != 0) return true;
            const py::gil_scoped_acquire acquire;
            const py::object ret = callback(stateDict(s, *cache));
            return ret.is_none() || ret.cast<bool>();
          });
        }
        const store::CacheStats stats = cache->stats();
        const store::ReadCounters reads = file->counters();
        py::dict d;
        d["steps"] = r.steps;
        d["queries"] = r.queries;
        d["distance"] = r.distance;
        d["query_seconds"] = r.querySeconds;
        d["total_seconds"] = r.totalSeconds;
        d["queries_per_second"] = r.queriesPerSecond;
        d["cache"] = statsDict(stats);
        d["reads"] = reads.reads;
        d["bytes_read"] = reads.bytesRead;
        d["peak_resident_bytes"] = stats.peakResidentBytes;
        d["budget_bytes"] = stats.capacityBytes;
        d["max_tilt"] = r.maxTilt;
        d["max_residual"] = r.maxResidual;
        if (recordEvery > 0) {
          const auto k = static_cast<py::ssize_t>(rec.step.size());
          py::dict t;
          t["step"] = array(rec.step, {k});
          t["time"] = array(rec.time, {k});
          t["ground"] = array(rec.ground, {k, 3});
          t["wheels"] = array(rec.wheels, {k, 6, 3});
          t["normals"] = array(rec.normals, {k, 6, 3});
          t["chassis"] = array(rec.chassis, {k, 4});
          t["position"] = array(rec.position, {k, 3});
          d["record"] = t;
        }
        return d;
      },
      py::arg("store"), py::arg("path") = py::none(), py::arg("grid") = "victoria",
      py::arg("level") = 0, py::arg("cache_bytes") = std::size_t{64} << 20,
      py::arg("policy") = "lru", py::arg("speed") = 1.0, py::arg("step") = 0.001,
      py::arg("max_steps") = 0, py::arg("interp") = "bilinear", py::arg("record_every") = 0,
      py::arg("callback") = nullptr, py::arg("callback_every") = 1, py::arg("rover") = py::none(),
      R"doc(Drives a six-wheel rover along `path` ((N, 2) grid x, y in metres; default:
default_victoria_path()) across a DEM of a store, paged through a cache of cache_bytes,
querying height and normal under each wheel every `step` seconds (rover::runTraverse).

Returns a dict: steps, queries, distance, query_seconds, total_seconds, queries_per_second,
cache (hits, misses, loads, evictions, bytes_loaded, resident_bytes, ...), reads, bytes_read,
peak_resident_bytes, budget_bytes, max_tilt, max_residual; with record_every=k > 0 also
'record': every k-th step's step, time, ground (x, y, heading), wheels (k, 6, 3: x, y, h),
normals (k, 6, 3), chassis (k, 4: height, pitch, roll, residual) and position (k, 3).
rover: a Rover (default: Rover()). callback(state) is called every callback_every steps with a dict (step, time, distance,
ground, wheels, normals, chassis, resident_bytes); returning False stops the traverse.
The GIL is released between callbacks. Raises InvalidArgument for bad options, StoreError for
a bad store, DomainError if a wheel lands on nodata.)doc");
}

}  // namespace regolith::python
