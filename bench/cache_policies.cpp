// Eviction policies of store::PatchCache replayed on traces of patch requests
// (docs/cache-policies.md).
//
// A trace is the sequence of PatchKeys a user would ask the cache for. The traces come
// from simulated rover traverses over a large grid (131,072 x 131,072 samples at 1 m,
// 256 x 256-sample patches, pyramid levels of 512 m, 1 km, ... patches), regenerated
// deterministically on every run (fixed paths, fixed seeds, std::mt19937_64 whose output
// the standard fixes). --write-traces DIR also records them as binary files, and
// --read-traces DIR replays recorded files instead (for example traces logged by a pager).
//
// The rover: 6 wheels (3 axles 1.5 m apart, track 1.5 m), each wheel's patch asked for at
// 1 kHz, driving at --speed m/s (default 4 m/s, 80 times a real rover's 5 cm/s, so that a
// run covers kilometres in seconds; the patch-level pattern is the same, with fewer
// repeats per patch).
//
//   straight       4 km in a straight line (heading 30 deg)
//   loop           a circle of 300 m radius driven 3 times (5.65 km)
//   back-forth     800 m out and back, 3 times (4.8 km)
//   random         1,000,000 requests uniform over a 16 x 16-patch site (4 km x 4 km)
//   loop+user      the loop, plus a second user asking for a random patch of the site
//                  at 20 Hz
//   loop+window    the loop, plus a lazy-load window: every 100 ms the 3 x 3 patches
//                  around the rover at levels 1-4 (36 requests)
//
// Each trace is replayed twice:
//   raw        every request reaches the cache (6,000 requests a second from the wheels);
//   fast-path  behind a one-entry "last patch" per stream, as store::Pager does per
//              thread: a request reaches the cache only when its stream (the rover, the
//              window, the second user) moves to another patch.
//
// For each trace, capacity (in patches of 256 x 256 floats, as bytes) and policy, the
// program replays the trace on a fresh single-threaded PatchCache whose loader returns a
// pre-built patch (so the time is the cache's own) and reports the hit rate, loads (=
// misses), evictions and ns per request (fastest of --reps replays, std::chrono). Belady's
// offline optimum (evict the patch needed furthest in the future) is the reference: no
// online policy can load fewer patches.
//
// A last table times hits alone: n patches resident, 2^21 requests either for one patch
// (the patch under the wheels) or rotating over all n (every hit re-ranks a patch).

#include <regolith/store/PatchCache.hpp>

#include "JsonRows.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>
#include <numbers>
#include <queue>
#include <random>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace {

using regolith::store::CachePolicy;
using regolith::store::Patch;
using regolith::store::PatchCache;
using regolith::store::PatchKey;
using regolith::store::PatchKeyHash;

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;

constexpr double kExtent = 131072.0;  // metres (level 0: 131,072 samples at 1 m)
constexpr std::uint32_t kPatchSamples = 256;
constexpr std::uint32_t kLevels = 5;  // 0 (256 m patches) ... 4 (4,096 m patches)
constexpr double kDt = 0.001;         // s: 1 kHz queries

// The site: 16 x 16 level-0 patches, 4 km x 4 km; the loop and the random users live here.
constexpr std::uint32_t kSitePatch0 = 160;  // first patch row and column
constexpr std::uint32_t kSitePatches = 16;

constexpr std::array<CachePolicy, 3> kAllPolicies{CachePolicy::HitCount, CachePolicy::Lru,
                                                  CachePolicy::DecayingHitCount};

// Streams: who asks. The fast-path filter keeps one last patch per stream.
enum Stream : std::uint32_t { kRover = 0, kWindow = 1, kUser = 2, kStreams = 3 };

/// `count` consecutive requests for one key from one stream.
struct Run {
  PatchKey key;
  std::uint32_t count = 0;
  std::uint32_t stream = kRover;
};

struct Trace {
  std::string name;
  std::vector<Run> runs;
  [[nodiscard]] std::uint64_t requests() const {
    std::uint64_t n = 0;
    for (const Run& r : runs) n += r.count;
    return n;
  }
  [[nodiscard]] std::size_t distinctKeys() const {
    std::unordered_map<PatchKey, int, PatchKeyHash> seen;
    for (const Run& r : runs) seen.emplace(r.key, 0);
    return seen.size();
  }
  void push(const PatchKey& k, std::uint32_t stream) {
    if (!runs.empty() && runs.back().key == k && runs.back().stream == stream &&
        runs.back().count < std::numeric_limits<std::uint32_t>::max()) {
      ++runs.back().count;
    } else {
      runs.push_back({k, 1, stream});
    }
  }
};

PatchKey keyAt(std::uint32_t level, double x, double y) {
  const double size = kPatchSamples * std::ldexp(1.0, static_cast<int>(level));  // metres
  const auto index = [size](double metres) {
    return static_cast<std::uint32_t>(std::clamp(std::floor(metres / size), 0.0, kExtent / size));
  };
  return PatchKey{0, level, index(kExtent - y), index(x)};  // row 0 is north
}

PatchKey randomSiteKey(std::mt19937_64& rng) {
  const auto r = static_cast<std::uint32_t>(rng() % kSitePatches);
  const auto c = static_cast<std::uint32_t>(rng() % kSitePatches);
  return PatchKey{0, 0, kSitePatch0 + r, kSitePatch0 + c};
}

struct Pose {
  double x = 0.0, y = 0.0, heading = 0.0;  // metres, radians from east
};
using Path = std::function<Pose(double)>;  // arc length (m) -> pose

Path straightPath(double x0, double y0, double headingDeg) {
  const double h = headingDeg * kDeg;
  return [=](double s) { return Pose{x0 + s * std::cos(h), y0 + s * std::sin(h), h}; };
}

Path loopPath(double cx, double cy, double radius) {
  return [=](double s) {
    const double a = s / radius;
    return Pose{cx + radius * std::cos(a), cy + radius * std::sin(a), a + 0.5 * kPi};
  };
}

Path backAndForthPath(double x0, double y0, double headingDeg, double leg) {
  const double h = headingDeg * kDeg;
  return [=](double s) {
    const double u = std::fmod(s, 2.0 * leg);
    const double along = u < leg ? u : 2.0 * leg - u;
    return Pose{x0 + along * std::cos(h), y0 + along * std::sin(h), u < leg ? h : h + kPi};
  };
}

struct RoverOptions {
  double distance = 0.0;  // metres
  double speed = 4.0;     // m/s
  bool window = false;    // lazy-load window at levels 1-4 every 100 ms
  bool user = false;      // a second user at 20 Hz
};

void pushWheels(Trace& t, const Pose& p) {
  // 3 axles 1.5 m apart, track 1.5 m: (forward, left) in metres.
  constexpr std::array<std::array<double, 2>, 6> kWheels{
      {{1.5, 0.75}, {1.5, -0.75}, {0.0, 0.75}, {0.0, -0.75}, {-1.5, 0.75}, {-1.5, -0.75}}};
  const double c = std::cos(p.heading);
  const double s = std::sin(p.heading);
  for (const auto& [f, l] : kWheels)
    t.push(keyAt(0, p.x + f * c - l * s, p.y + f * s + l * c), kRover);
}

void pushWindow(Trace& t, const Pose& p) {
  for (std::uint32_t level = 1; level < kLevels; ++level) {
    const PatchKey centre = keyAt(level, p.x, p.y);
    for (std::uint32_t dr = 0; dr < 3; ++dr) {
      for (std::uint32_t dc = 0; dc < 3; ++dc) {
        t.push(PatchKey{0, level, centre.row + dr - 1, centre.col + dc - 1}, kWindow);
      }
    }
  }
}

Trace roverTrace(std::string name, const Path& path, const RoverOptions& o, std::uint64_t seed) {
  Trace t{std::move(name), {}};
  std::mt19937_64 rng(seed);
  const auto steps = static_cast<std::uint64_t>(std::llround(o.distance / (o.speed * kDt)));
  for (std::uint64_t i = 0; i < steps; ++i) {
    const Pose p = path(static_cast<double>(i) * o.speed * kDt);
    pushWheels(t, p);
    if (o.window && i % 100 == 0) pushWindow(t, p);
    if (o.user && i % 50 == 25) t.push(randomSiteKey(rng), kUser);
  }
  return t;
}

Trace randomTrace(std::uint64_t n, std::uint64_t seed) {
  Trace t{"random", {}};
  std::mt19937_64 rng(seed);
  for (std::uint64_t i = 0; i < n; ++i) t.push(randomSiteKey(rng), kUser);
  return t;
}

/// The requests that get past a one-entry last-patch cache per stream.
Trace behindFastPath(const Trace& raw) {
  Trace t{raw.name, {}};
  std::array<PatchKey, kStreams> last{};
  std::array<bool, kStreams> any{};
  for (const Run& r : raw.runs) {
    const std::uint32_t s = std::min<std::uint32_t>(r.stream, kStreams - 1);
    if (any[s] && last[s] == r.key) continue;
    any[s] = true;
    last[s] = r.key;
    t.push(r.key, s);
  }
  return t;
}

std::vector<Trace> generateTraces(double speed, double scale) {
  const double site0 = kSitePatch0 * 256.0;                   // west / south edge, m
  const double siteMid = site0 + kSitePatches * 256.0 / 2.0;  // a patch corner
  const double yMid = kExtent - siteMid;                      // the same corner in y
  std::vector<Trace> traces;
  traces.push_back(roverTrace("straight", straightPath(40000.3, 40100.7, 30.0),
                              {4000.0 * scale, speed, false, false}, 1));
  traces.push_back(roverTrace("loop", loopPath(siteMid, yMid, 300.0),
                              {3.0 * 2.0 * kPi * 300.0 * scale, speed, false, false}, 2));
  traces.push_back(roverTrace("back-forth",
                              backAndForthPath(siteMid + 92.5, yMid - 108.2, 10.0, 800.0),
                              {6.0 * 800.0 * scale, speed, false, false}, 3));
  traces.push_back(randomTrace(static_cast<std::uint64_t>(1e6 * scale), 4));
  traces.push_back(roverTrace("loop+user", loopPath(siteMid, yMid, 300.0),
                              {3.0 * 2.0 * kPi * 300.0 * scale, speed, false, true}, 5));
  traces.push_back(roverTrace("loop+window", loopPath(siteMid, yMid, 300.0),
                              {3.0 * 2.0 * kPi * 300.0 * scale, speed, true, false}, 6));
  return traces;
}

// ---- trace files: "RGLTRACE", u32 version 1, u32 0, u64 run count, then per run six u32:
// grid, level, row, col, count, stream (all little-endian, as on x86-64 and arm64) ----------

constexpr std::array<char, 8> kMagic{'R', 'G', 'L', 'T', 'R', 'A', 'C', 'E'};

void writeTrace(const Trace& t, const std::filesystem::path& file) {
  std::ofstream out(file, std::ios::binary);
  const std::array<std::uint32_t, 2> version{1, 0};
  const std::uint64_t n = t.runs.size();
  out.write(kMagic.data(), kMagic.size());
  out.write(reinterpret_cast<const char*>(version.data()), sizeof(version));
  out.write(reinterpret_cast<const char*>(&n), sizeof(n));
  for (const Run& r : t.runs) {
    const std::array<std::uint32_t, 6> rec{r.key.grid, r.key.level, r.key.row,
                                           r.key.col,  r.count,     r.stream};
    out.write(reinterpret_cast<const char*>(rec.data()), sizeof(rec));
  }
  if (!out) throw std::runtime_error("cache_policies: cannot write " + file.string());
}

Trace readTrace(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::array<char, 8> magic{};
  std::array<std::uint32_t, 2> version{};
  std::uint64_t n = 0;
  in.read(magic.data(), magic.size());
  in.read(reinterpret_cast<char*>(version.data()), sizeof(version));
  in.read(reinterpret_cast<char*>(&n), sizeof(n));
  if (!in || magic != kMagic || version[0] != 1) {
    throw std::runtime_error("cache_policies: " + file.string() + " is not a version 1 trace");
  }
  Trace t{file.stem().string(), {}};
  t.runs.reserve(n);
  for (std::uint64_t i = 0; i < n; ++i) {
    std::array<std::uint32_t, 6> rec{};
    in.read(reinterpret_cast<char*>(rec.data()), sizeof(rec));
    if (!in) throw std::runtime_error("cache_policies: " + file.string() + " is truncated");
    t.runs.push_back({PatchKey{rec[0], rec[1], rec[2], rec[3]}, rec[4], rec[5]});
  }
  return t;
}

// ---- replay -------------------------------------------------------------------------------

/// Loads Belady's MIN makes with room for `capacity` equal patches (repeats within a run
/// are hits for every policy, so the run sequence suffices).
std::uint64_t beladyLoads(const Trace& t, std::size_t capacity) {
  constexpr std::size_t kNever = std::numeric_limits<std::size_t>::max();
  const std::size_t n = t.runs.size();
  std::vector<std::size_t> next(n, kNever);
  {
    std::unordered_map<PatchKey, std::size_t, PatchKeyHash> seen;
    for (std::size_t i = n; i-- > 0;) {
      const auto it = seen.find(t.runs[i].key);
      if (it != seen.end()) {
        next[i] = it->second;
        it->second = i;
      } else {
        seen.emplace(t.runs[i].key, i);
      }
    }
  }
  std::unordered_map<PatchKey, std::size_t, PatchKeyHash> resident;  // key -> next use
  std::priority_queue<std::pair<std::size_t, PatchKey>,
                      std::vector<std::pair<std::size_t, PatchKey>>,
                      decltype([](const auto& a, const auto& b) { return a.first < b.first; })>
      furthest;  // stale entries are skipped
  std::uint64_t loads = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const PatchKey& k = t.runs[i].key;
    if (const auto it = resident.find(k); it != resident.end()) {
      it->second = next[i];
    } else {
      ++loads;
      if (capacity == 0) continue;
      while (resident.size() >= capacity) {
        const auto [use, victim] = furthest.top();
        furthest.pop();
        if (const auto v = resident.find(victim); v != resident.end() && v->second == use) {
          resident.erase(v);
        }
      }
      resident.emplace(k, next[i]);
    }
    furthest.emplace(next[i], k);
  }
  return loads;
}

struct Result {
  regolith::store::CacheStats stats;
  double nsPerRequest = 0.0;
};

Result replay(const Trace& t, CachePolicy policy, std::size_t capacityBytes,
              std::uint64_t decayPeriod, int reps, const std::shared_ptr<const Patch>& patch) {
  const PatchCache::Loader loader = [&patch](const PatchKey&) { return patch; };
  std::vector<double> ns;
  Result r;
  for (int rep = 0; rep < reps; ++rep) {
    PatchCache cache(capacityBytes, policy, decayPeriod);
    std::size_t sink = 0;
    const auto start = std::chrono::steady_clock::now();
    for (const Run& run : t.runs) {
      for (std::uint32_t i = 0; i < run.count; ++i) sink += cache.get(run.key, loader)->rows;
    }
    const auto stop = std::chrono::steady_clock::now();
    if (sink == 0) std::puts("");  // keeps the loop from being optimised away
    ns.push_back(std::chrono::duration<double, std::nano>(stop - start).count() /
                 static_cast<double>(std::max<std::uint64_t>(t.requests(), 1)));
    r.stats = cache.stats();
  }
  // The fastest replay: the machine is shared, and interference only ever adds time.
  r.nsPerRequest = *std::min_element(ns.begin(), ns.end());
  return r;
}

// ---- report -------------------------------------------------------------------------------

struct Options {
  double speed = 4.0;
  double scale = 1.0;
  int reps = 3;
  std::uint64_t decayPeriod = 4096;
  std::vector<std::size_t> capacities{4, 16, 64};
  std::vector<CachePolicy> policies{kAllPolicies.begin(), kAllPolicies.end()};
  std::string writeDir, readDir;
  std::string jsonPath;
};

/// Rows for --json: one per (replay mode, trace, capacity, policy), and one per hit-cost cell.
std::vector<regolith::bench::JsonRow> gJsonRows;

void report(const std::vector<Trace>& traces, const Options& o, const char* title,
            const char* mode) {
  auto patch = std::make_shared<Patch>();
  patch->rows = kPatchSamples;
  patch->cols = kPatchSamples;
  patch->samples.assign(std::size_t{kPatchSamples} * kPatchSamples, 0.0F);
  const std::size_t patchBytes = patch->bytes();

  std::printf("\n### %s\n\n", title);
  std::printf("Each policy cell: hit rate / loads / evictions.\n\n");
  std::printf("| trace | requests | distinct | cap | Belady loads |");
  for (CachePolicy p : o.policies) std::printf(" %s |", std::string(toString(p)).c_str());
  std::printf("\n|---|---:|---:|---:|---:|");
  for (std::size_t i = 0; i < o.policies.size(); ++i) std::printf("---:|");
  std::printf("\n");
  std::vector<std::vector<std::vector<double>>> ns(traces.size());
  for (std::size_t ti = 0; ti < traces.size(); ++ti) {
    const Trace& t = traces[ti];
    const std::uint64_t requests = t.requests();
    const std::size_t distinct = t.distinctKeys();
    for (const std::size_t cap : o.capacities) {
      const std::uint64_t belady = beladyLoads(t, cap);
      std::printf("| %s | %llu | %zu | %zu | %llu |", t.name.c_str(),
                  static_cast<unsigned long long>(requests), distinct, cap,
                  static_cast<unsigned long long>(belady));
      std::vector<double> row;
      for (const CachePolicy policy : o.policies) {
        const Result r = replay(t, policy, cap * patchBytes, o.decayPeriod, o.reps, patch);
        const double hitRate = 100.0 * static_cast<double>(r.stats.hits) /
                               static_cast<double>(std::max<std::uint64_t>(requests, 1));
        std::printf(" %.4f %% / %llu / %llu |", hitRate,
                    static_cast<unsigned long long>(r.stats.loads),
                    static_cast<unsigned long long>(r.stats.evictions));
        row.push_back(r.nsPerRequest);
        gJsonRows.push_back(
            regolith::bench::JsonRow{std::string("cache/") + mode + "/" + t.name + "/cap:" +
                                         std::to_string(cap) + "/" + std::string(toString(policy)),
                                     {},
                                     {}}
                .label("mode", mode)
                .label("trace", t.name)
                .label("policy", std::string(toString(policy)))
                .set("capacity_patches", static_cast<double>(cap))
                .set("capacity_MiB", static_cast<double>(cap * patchBytes) / (1024.0 * 1024.0))
                .set("hit_rate", static_cast<double>(r.stats.hits) /
                                     static_cast<double>(std::max<std::uint64_t>(requests, 1)))
                .set("loads", static_cast<double>(r.stats.loads))
                .set("belady_loads", static_cast<double>(belady))
                .set("requests", static_cast<double>(requests))
                .set("ns_per_request", r.nsPerRequest));
      }
      ns[ti].push_back(row);
      std::printf("\n");
      std::fflush(stdout);
    }
  }
  std::printf("\nns per request (fastest of %d replays):\n\n| trace | cap |", o.reps);
  for (CachePolicy p : o.policies) std::printf(" %s |", std::string(toString(p)).c_str());
  std::printf("\n|---|---:|");
  for (std::size_t i = 0; i < o.policies.size(); ++i) std::printf("---:|");
  std::printf("\n");
  for (std::size_t ti = 0; ti < traces.size(); ++ti) {
    for (std::size_t ci = 0; ci < o.capacities.size(); ++ci) {
      std::printf("| %s | %zu |", traces[ti].name.c_str(), o.capacities[ci]);
      for (double v : ns[ti][ci]) std::printf(" %.1f |", v);
      std::printf("\n");
    }
  }
}

/// ns per hit with `n` patches resident: requests for one patch, or rotating over all n.
double hitCost(CachePolicy policy, std::size_t n, bool rotating, const Options& o,
               const std::shared_ptr<const Patch>& patch) {
  constexpr std::uint32_t kRequests = 1U << 21U;
  const PatchCache::Loader loader = [&patch](const PatchKey&) { return patch; };
  double best = std::numeric_limits<double>::infinity();
  for (int rep = 0; rep < o.reps; ++rep) {
    PatchCache cache(n * patch->bytes(), policy, o.decayPeriod);
    std::vector<PatchKey> keys;
    for (std::uint32_t i = 0; i < n; ++i) keys.push_back(PatchKey{0, 0, 100, 100 + i});
    for (const PatchKey& k : keys) (void)cache.get(k, loader);
    std::size_t sink = 0;
    const auto start = std::chrono::steady_clock::now();
    for (std::uint32_t i = 0; i < kRequests; ++i) {
      sink += cache.get(keys[rotating ? i % n : 0], loader)->rows;
    }
    const auto stop = std::chrono::steady_clock::now();
    if (sink == 0 || cache.stats().loads != n) std::puts("hitCost: unexpected misses");
    best = std::min(best, std::chrono::duration<double, std::nano>(stop - start).count() /
                              static_cast<double>(kRequests));
  }
  return best;
}

void reportHitCost(const Options& o) {
  auto patch = std::make_shared<Patch>();
  patch->rows = kPatchSamples;
  patch->cols = kPatchSamples;
  patch->samples.assign(std::size_t{kPatchSamples} * kPatchSamples, 0.0F);
  std::printf("\n### Hits only: ns per hit (fastest of %d runs of 2^21 hits)\n\n", o.reps);
  std::printf("| resident | requests |");
  for (CachePolicy p : o.policies) std::printf(" %s |", std::string(toString(p)).c_str());
  std::printf("\n|---:|---|");
  for (std::size_t i = 0; i < o.policies.size(); ++i) std::printf("---:|");
  std::printf("\n");
  for (const std::size_t n : o.capacities) {
    for (const bool rotating : {false, true}) {
      std::printf("| %zu | %s |", n, rotating ? "rotating over all" : "one patch");
      for (const CachePolicy p : o.policies) {
        const double ns = hitCost(p, n, rotating, o, patch);
        std::printf(" %.1f |", ns);
        gJsonRows.push_back(regolith::bench::JsonRow{
            std::string("cache/hit/") + (rotating ? "rotating" : "one") +
                "/resident:" + std::to_string(n) + "/" + std::string(toString(p)),
            {},
            {}}.label("policy", std::string(toString(p)))
                                .set("resident_patches", static_cast<double>(n))
                                .set("ns_per_hit", ns));
      }
      std::printf("\n");
      std::fflush(stdout);
    }
  }
}

void usage(std::FILE* out) {
  std::fputs(
      "usage: cache_policies [--speed M_PER_S] [--scale F] [--reps N] [--decay-period N]\n"
      "                      [--capacities A,B,...] [--policies P,...]\n"
      "                      [--write-traces DIR] [--read-traces DIR] [--json FILE]\n"
      "  --speed          rover speed, m/s (default 4)\n"
      "  --scale          multiply every trace's length (default 1; 0.1 for a quick run)\n"
      "  --reps           timed replays per cell, the fastest is reported (default 3)\n"
      "  --decay-period   DecayingHitCount's period in requests (default 4096)\n"
      "  --capacities     cache sizes in 256x256-float patches (default 4,16,64)\n"
      "  --policies       any of HitCount,Lru,DecayingHitCount (default all three)\n"
      "  --write-traces   also write the generated traces to DIR/<name>.trace\n"
      "  --read-traces    replay DIR/*.trace instead of generating traces\n"
      "  --json           also write every cell as JSON rows to FILE (regolith report)\n",
      out);
}

std::vector<std::string> splitList(const std::string& list) {
  std::vector<std::string> items;
  for (std::size_t pos = 0; pos < list.size();) {
    const std::size_t comma = std::min(list.find(',', pos), list.size());
    items.push_back(list.substr(pos, comma - pos));
    pos = comma + 1;
  }
  return items;
}

CachePolicy policyNamed(const std::string& name) {
  for (const CachePolicy p : kAllPolicies) {
    if (toString(p) == name) return p;
  }
  throw std::invalid_argument("unknown policy " + name);
}

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
      return argv[++i];
    };
    if (a == "--speed") {
      o.speed = std::stod(value());
    } else if (a == "--scale") {
      o.scale = std::stod(value());
    } else if (a == "--reps") {
      o.reps = std::max(1, std::stoi(value()));
    } else if (a == "--decay-period") {
      o.decayPeriod = std::stoull(value());
    } else if (a == "--capacities") {
      o.capacities.clear();
      for (const std::string& item : splitList(value())) o.capacities.push_back(std::stoull(item));
    } else if (a == "--policies") {
      o.policies.clear();
      for (const std::string& item : splitList(value())) o.policies.push_back(policyNamed(item));
    } else if (a == "--write-traces") {
      o.writeDir = value();
    } else if (a == "--read-traces") {
      o.readDir = value();
    } else if (a == "--json") {
      o.jsonPath = value();
    } else if (a == "--help" || a == "-h") {
      usage(stdout);
      std::exit(0);
    } else {
      throw std::invalid_argument("unknown option " + a);
    }
  }
  if (!(o.speed > 0.0) || !(o.scale > 0.0))
    throw std::invalid_argument("speed and scale must be > 0");
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  try {
    o = parse(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cache_policies: %s\n", e.what());
    usage(stderr);
    return 2;
  }
  try {
    std::vector<Trace> traces;
    if (o.readDir.empty()) {
      traces = generateTraces(o.speed, o.scale);
    } else {
      std::vector<std::filesystem::path> files;
      for (const auto& e : std::filesystem::directory_iterator(o.readDir)) {
        if (e.path().extension() == ".trace") files.push_back(e.path());
      }
      std::sort(files.begin(), files.end());
      for (const auto& f : files) traces.push_back(readTrace(f));
    }
    if (!o.writeDir.empty()) {
      std::filesystem::create_directories(o.writeDir);
      for (const Trace& t : traces)
        writeTrace(t, std::filesystem::path(o.writeDir) / (t.name + ".trace"));
    }
    std::printf(
        "cache_policies: speed %.3g m/s, scale %.3g, decay period %llu, %d reps, %s traces\n",
        o.speed, o.scale, static_cast<unsigned long long>(o.decayPeriod), o.reps,
        o.readDir.empty() ? "generated" : "recorded");
    report(traces, o, "Raw: every request reaches the cache", "raw");
    std::vector<Trace> filtered;
    filtered.reserve(traces.size());
    for (const Trace& t : traces) filtered.push_back(behindFastPath(t));
    report(filtered, o, "Fast path: only changes of patch per stream reach the cache", "fast-path");
    reportHitCost(o);
    if (!o.jsonPath.empty())
      regolith::bench::writeJsonRows(o.jsonPath, "cache_policies", gJsonRows);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cache_policies: %s\n", e.what());
    return 1;
  }
  return 0;
}
