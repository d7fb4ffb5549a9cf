#include "MainDemo.hpp"

#include <regolith/rover/Traverse.hpp>
#include <regolith/store/Generate.hpp>
#include <regolith/store/Store.hpp>
#include <regolith/topo/Error.hpp>

#include "CancelOnSignal.hpp"
#include "TerminalProgress.hpp"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

namespace regolith::tools {

namespace {

namespace fs = std::filesystem;

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

/// True if `path` opens as a store holding grid `grid` (a stale or foreign file does not).
bool hasGrid(const fs::path& path, const std::string& grid) {
  if (!fs::exists(path)) return false;
  try {
    const store::Store s = store::Store::open(path);
    for (const std::string& n : s.gridNames())
      if (n == grid) return true;
  } catch (const Error&) {
  }
  return false;
}

store::WriteOptions writeOptions(TerminalProgress& progress) {
  store::WriteOptions w;
  w.deflate = 4;
  w.progress = progress.callback();
  w.cancel = CancelOnSignal::flag();
  return w;
}

/// The default stores: generated when absent, reused when present.
struct DefaultData {
  fs::path mars, victoria;
  std::string marsNote, victoriaNote;
};

DefaultData ensureData(const MainDemoOptions& o, const fs::path& dir, std::ostream& out) {
  fs::create_directories(dir);
  DefaultData d{dir / "mars.h5", dir / "victoria.h5", "", ""};
  const CancelOnSignal cancel;
  {
    store::MarsPlanetOptions m;
    m.rows = o.quick ? 256 : 1024;
    const auto t0 = Clock::now();
    if (hasGrid(d.mars, m.gridName)) {
      d.marsNote = "reused";
    } else {
      out << "  generating " << d.mars.string() << " (procedural Mars, " << m.rows << " x "
          << 2 * m.rows << " samples)..." << std::endl;
      TerminalProgress progress = TerminalProgress::forStderr();
      m.write = writeOptions(progress);
      store::MarsPlanetGenerator(m).write(d.mars);
      std::ostringstream s;
      s << std::fixed << std::setprecision(1) << "generated in " << secondsSince(t0) << " s";
      d.marsNote = s.str();
    }
  }
  {
    store::VictoriaOptions v;
    if (o.quick) {  // the same 1.2 km square at 3 m
      v.size = 401;
      v.spacing = 3.0;
    }
    const auto t0 = Clock::now();
    if (hasGrid(d.victoria, v.gridName)) {
      d.victoriaNote = "reused";
    } else {
      out << "  generating " << d.victoria.string() << " (Victoria-like crater, " << v.size << " x "
          << v.size << " samples at " << v.spacing << " m)..." << std::endl;
      TerminalProgress progress = TerminalProgress::forStderr();
      v.write = writeOptions(progress);
      store::VictoriaGenerator(v).write(d.victoria);
      std::ostringstream s;
      s << std::fixed << std::setprecision(1) << "generated in " << secondsSince(t0) << " s";
      d.victoriaNote = s.str();
    }
  }
  return d;
}

/// The traverse and what the renders need from it: the wheel contacts along the way.
struct TraverseRun {
  rover::TraverseResult result;
  std::vector<rover::WheelContact> trackContacts;  // every few centimetres of travel
  rover::ChassisPose last;                         // where the rover stopped
  rover::GroundPose lastGround;
};

TraverseRun runTraverse(const MainDemoOptions& o, const fs::path& victoria, std::ostream& out) {
  rover::TraverseOptions t;
  t.store = victoria;
  t.cacheBytes = o.cacheMb << 20U;
  t.path = rover::defaultVictoriaPath();
  TraverseRun run;
  double nextStamp = 0.0;
  double nextReport = 0.0;
  run.result = rover::runTraverse(t, [&](const rover::StepState& s) {
    if (s.distance >= nextStamp) {  // tracks: one imprint of all six wheels every 5 cm
      run.trackContacts.insert(run.trackContacts.end(), s.wheels.begin(), s.wheels.end());
      nextStamp = s.distance + 0.05;
    }
    if (s.distance >= nextReport) {
      out << "  " << std::fixed << std::setprecision(0) << std::setw(4) << s.distance << " m  x "
          << std::setw(6) << std::setprecision(1) << s.chassis.x << "  y " << std::setw(6)
          << s.chassis.y << "  height " << std::setw(7) << std::setprecision(2) << s.chassis.height
          << " m  pitch " << std::setw(5) << std::setprecision(1) << s.chassis.pitch * 180.0 / M_PI
          << "°  roll " << std::setw(5) << s.chassis.roll * 180.0 / M_PI << "°  cache "
          << s.cache.residentBytes / 1024 << " KiB\n";
      nextReport = s.distance + 100.0;
    }
    run.last = s.chassis;
    run.lastGround = s.ground;
    return true;
  });
  return run;
}

}  // namespace

void runMainDemo(const MainDemoOptions& o, std::ostream& out) {
  const auto start = Clock::now();
  fs::create_directories(o.outDir);
  const fs::path dataDir = o.dataDir.empty() ? o.outDir / "data" : o.dataDir;

  out << "[1/3] Default data in " << dataDir.string() << "\n";
  const DefaultData data = ensureData(o, dataDir, out);
  out << "  " << data.mars.string() << ": " << data.marsNote << "\n  " << data.victoria.string()
      << ": " << data.victoriaNote << "\n";

  out << "[2/3] Rover traverse across the crater (6 wheels, 1 ms steps, cache budget " << o.cacheMb
      << " MiB)\n";
  const auto t1 = Clock::now();
  const TraverseRun trav = runTraverse(o, data.victoria, out);
  const double traverseSeconds = secondsSince(t1);
  const rover::TraverseResult& r = trav.result;

  out << "[3/3] Renders: not yet wired\n";

  out << "\n==== Summary (" << std::fixed << std::setprecision(1) << secondsSince(start) << " s)\n";
  out << "Traverse: " << r.steps << " steps, " << std::setprecision(0) << r.distance
      << " m driven, " << r.queries << " wheel queries at " << std::setprecision(1)
      << r.queriesPerSecond / 1e6 << " M/s (queries only; whole loop " << traverseSeconds
      << " s)\n";
  out << "  cache: " << r.cache.hits << " hits, " << r.cache.misses << " misses, " << r.cache.loads
      << " patch loads, " << r.reads.bytesRead / 1024 << " KiB read; resident "
      << r.peakResidentBytes / 1024 << " KiB at most, budget " << r.budgetBytes / 1024 << " KiB\n";
  out << "  chassis: largest tilt " << std::setprecision(1) << r.maxTilt * 180.0 / M_PI
      << "°, largest contact residual " << std::setprecision(3) << r.maxResidual << " m\n";
}

}  // namespace regolith::tools
