// regolith-mpi: `mpirun -np N regolith-mpi import SOURCES... --out STORE` builds one store on
// N ranks (docs/scale.md, "Beyond one machine: MPI"; docs/cli.md). MPI coordinates only: each
// rank imports a band of level-0 rows with the ordinary writer (serial HDF5) into a part
// store, and rank 0 joins the parts' encoded chunks as they are and computes the levels above.
#include <regolith/core/Error.hpp>
#include <regolith/core/Executor.hpp>
#include <regolith/store/Import.hpp>

#include "Assemble.hpp"
#include "MpiPlan.hpp"

#include <CLI/CLI.hpp>
#include <cpl_json.h>
#include <mpi.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace fs = std::filesystem;
using namespace regolith;
using namespace regolith::tools::mpi;

namespace {

struct Args {
  std::vector<std::string> sources;
  std::string out, grid, body, compression = "deflate";
  std::size_t patch = 256, levels = 0, memoryMb = 1024;
  int deflate = 0;
  unsigned threads = 0;
  double nodata = 0.0;
  bool hasNodata = false, strict = false;
};

// ---- cleanup when the job is killed ---------------------------------------------------------
// mpirun ends the other ranks with SIGTERM when one dies. The handler replaces the process by
// `sh -c 'rm -rf ...'` (execv is async-signal-safe): the parts folder and rank 0's temporary
// of the target go (any rank removes them: rank 0 may be the one that died); the target is
// never renamed into place.
std::string gPartsDir, gOut, gPid;

extern "C" void onTerminate(int /*signal*/) {
  if (gPartsDir.empty()) _exit(1);
  const char* argv[] = {"sh",
                        "-c",
                        "rm -rf -- \"$1\" \"$2\".tmp-\"$3\"-*",
                        "sh",
                        gPartsDir.c_str(),
                        gOut.c_str(),
                        gPid.c_str(),
                        nullptr};
  execv("/bin/sh",
        const_cast<char* const*>(argv));  // NOLINT(cppcoreguidelines-pro-type-const-cast)
  _exit(1);
}

// ---- MPI helpers ----------------------------------------------------------------------------

/// Every rank's bytes, on rank 0 (empty elsewhere).
std::vector<std::string> gather(const std::string& mine, int rank, int size) {
  const int n = static_cast<int>(mine.size());
  std::vector<int> counts(static_cast<std::size_t>(size)), displs(static_cast<std::size_t>(size));
  MPI_Gather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
  std::string all;
  if (rank == 0) {
    int total = 0;
    for (int i = 0; i < size; ++i) {
      displs[static_cast<std::size_t>(i)] = total;
      total += counts[static_cast<std::size_t>(i)];
    }
    all.resize(static_cast<std::size_t>(total));
  }
  MPI_Gatherv(mine.data(), n, MPI_CHAR, all.data(), counts.data(), displs.data(), MPI_CHAR, 0,
              MPI_COMM_WORLD);
  std::vector<std::string> out;
  if (rank == 0) {
    for (int i = 0; i < size; ++i) {
      out.push_back(all.substr(static_cast<std::size_t>(displs[static_cast<std::size_t>(i)]),
                               static_cast<std::size_t>(counts[static_cast<std::size_t>(i)])));
    }
  }
  return out;
}

/// Completes `request` without spinning: OpenMPI's blocking calls poll, which would take a
/// core from the ranks still working when ranks share a node.
void waitGently(MPI_Request& request) {
  for (int done = 0; MPI_Test(&request, &done, MPI_STATUS_IGNORE) == MPI_SUCCESS && done == 0;) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

/// Sends `text` to `to` (tag `tag`) and waits for it gently.
void sendString(const std::string& text, int to, int tag) {
  MPI_Request r = MPI_REQUEST_NULL;
  MPI_Isend(text.data(), static_cast<int>(text.size()), MPI_CHAR, to, tag, MPI_COMM_WORLD, &r);
  waitGently(r);
}

/// Receives a string from `from` (tag `tag`), waiting for it gently.
std::string receiveString(int from, int tag) {
  MPI_Status status{};
  for (int flag = 0;
       MPI_Iprobe(from, tag, MPI_COMM_WORLD, &flag, &status) == MPI_SUCCESS && flag == 0;) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  int n = 0;
  MPI_Get_count(&status, MPI_CHAR, &n);
  std::string text(static_cast<std::size_t>(std::max(n, 0)), '\0');
  MPI_Recv(text.data(), n, MPI_CHAR, from, tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  return text;
}

int broadcastInt(int v) {
  MPI_Bcast(&v, 1, MPI_INT, 0, MPI_COMM_WORLD);
  return v;
}

std::string broadcastString(std::string s, int rank) {
  int n = static_cast<int>(s.size());
  MPI_Bcast(&n, 1, MPI_INT, 0, MPI_COMM_WORLD);
  if (rank != 0) s.resize(static_cast<std::size_t>(n));
  MPI_Bcast(s.data(), n, MPI_CHAR, 0, MPI_COMM_WORLD);
  return s;
}

/// This process's CPU seconds so far (user + system, all its threads).
double cpuSeconds() {
  rusage u{};
  if (getrusage(RUSAGE_SELF, &u) != 0) return 0.0;
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec) * 1e-6;
}

double seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// ---- the plan: which rows (and tiles) each part holds ---------------------------------------

struct Layout {
  std::string grid;
  std::size_t rows = 0, cols = 0, levels = 0;
  SplitPlan plan;
  // Tiles: each tile's rows [row0, row0 + rows) and columns in the mosaic.
  struct Tile {
    std::size_t row0 = 0, rows = 0, col0 = 0, cols = 0;
  };
  std::vector<Tile> tiles;
  std::vector<std::vector<std::size_t>> partTiles;
  /// Why there is one part only, where not for the grid's size.
  std::string onePart;
};

/// Whether tiles make a mosaic whose geometry store::importTiles() snaps only as a whole:
/// a geographic one 180° high, an equirectangular one 360° wide (within a pixel). Its parts
/// would carry the unsnapped geometry; such a mosaic is not split (docs/scale.md).
bool globalMosaic(const store::GridInfo& first, std::size_t rows, std::size_t cols) {
  constexpr double kDeg = 57.29577951308232;
  if (first.kind == store::GridKind::Planet) {
    return static_cast<double>(rows + 1) * first.spacingY >= 180.0;
  }
  const store::PlacementInfo& pl = first.placement;
  if (pl.kind != store::PlacementInfo::Kind::Equirectangular || pl.projectionRadius <= 0.0) {
    return false;
  }
  const double cosTs = std::cos(pl.latTrueScaleDeg.value_or(0.0) / kDeg);
  const double dlon = first.spacingX / (pl.projectionRadius * cosTs) * kDeg;
  return static_cast<double>(cols + 1) * dlon >= 360.0;
}

Layout planImport(const Args& a, const store::ImportOptions& o, int ranks) {
  Layout l;
  const std::vector<fs::path> sources(a.sources.begin(), a.sources.end());
  const store::GridInfo first = store::describeRaster(sources.front(), o);
  l.grid = o.gridName.empty() ? first.name : o.gridName;
  if (sources.size() == 1) {
    l.rows = first.rows;
    l.cols = first.cols;
  } else {
    // As store::importTiles() places them: whole-sample offsets from the first tile.
    std::vector<std::pair<long long, long long>> at;
    long long minRow = 0, minCol = 0;
    for (const fs::path& s : sources) {
      const store::GridInfo g = store::describeRaster(s, o);
      const long long dr = std::llround((first.y0 - g.y0) / first.spacingY);
      const long long dc = std::llround((g.x0 - first.x0) / first.spacingX);
      at.emplace_back(dr, dc);
      minRow = std::min(minRow, dr);
      minCol = std::min(minCol, dc);
      l.tiles.push_back({0, g.rows, 0, g.cols});
    }
    for (std::size_t i = 0; i < l.tiles.size(); ++i) {
      l.tiles[i].row0 = static_cast<std::size_t>(at[i].first - minRow);
      l.tiles[i].col0 = static_cast<std::size_t>(at[i].second - minCol);
      l.rows = std::max(l.rows, l.tiles[i].row0 + l.tiles[i].rows);
      l.cols = std::max(l.cols, l.tiles[i].col0 + l.tiles[i].cols);
    }
  }
  const std::size_t maxLevels = levelCount(l.rows, l.cols, 1, 1, 0);
  if (a.levels > maxLevels) {
    throw InvalidArgument("regolith-mpi import: --levels " + std::to_string(a.levels) +
                          ", but grid '" + l.grid + "' reaches 1x1 samples at " +
                          std::to_string(maxLevels) + " levels");
  }
  l.levels = levelCount(l.rows, l.cols, a.patch, a.patch, a.levels);
  if (l.tiles.empty()) {
    l.plan = splitRows(l.rows, a.patch, l.levels, static_cast<std::size_t>(ranks), nullptr);
  } else {
    // Cuts only at tile borders that no tile straddles.
    std::vector<std::size_t> cuts;
    for (const auto& t : l.tiles) {
      const bool straddled = std::any_of(l.tiles.begin(), l.tiles.end(), [&](const auto& u) {
        return u.row0 < t.row0 && t.row0 < u.row0 + u.rows;
      });
      if (!straddled && t.row0 > 0) cuts.push_back(t.row0);
    }
    l.plan = splitRows(l.rows, a.patch, l.levels, static_cast<std::size_t>(ranks), &cuts);
    // Every part must be a whole band: its tiles start at its first row and span every column.
    l.partTiles.assign(l.plan.parts.size(), {});
    bool whole = true;
    for (std::size_t p = 0; p < l.plan.parts.size(); ++p) {
      const PartRows& part = l.plan.parts[p];
      std::size_t r0 = l.rows, r1 = 0, c0 = l.cols, c1 = 0;
      for (std::size_t i = 0; i < l.tiles.size(); ++i) {
        const auto& t = l.tiles[i];
        if (t.row0 < part.row0 || t.row0 >= part.row1) continue;
        l.partTiles[p].push_back(i);
        r0 = std::min(r0, t.row0);
        r1 = std::max(r1, t.row0 + t.rows);
        c0 = std::min(c0, t.col0);
        c1 = std::max(c1, t.col0 + t.cols);
      }
      whole = whole && r0 == part.row0 && r1 == part.row1 && c0 == 0 && c1 == l.cols;
    }
    if (!whole) l.onePart = "the tiles make no whole bands of patches";
    if (globalMosaic(first, l.rows, l.cols)) {
      l.onePart = "a global mosaic, whose geometry only the whole mosaic gives";
    }
    if (!l.onePart.empty()) {
      l.plan = SplitPlan{{PartRows{0, l.rows}}, 0};
      l.partTiles.clear();
    }
  }
  return l;
}

/// Tiles: the grid's provenance as store::importTiles() writes it: the first tile's, with
/// every tile's files in `sources`, in the tiles' order. Each part's provenance lists its own
/// tiles' files; an entry whose path is a tile's starts that tile's files.
std::string mergedProvenance(const Layout& l, const std::vector<fs::path>& parts,
                             const std::vector<std::string>& sources) {
  std::vector<std::vector<std::string>> perTile(sources.size());
  CPLJSONDocument base;
  for (std::size_t p = 0; p < parts.size(); ++p) {
    CPLJSONDocument doc;
    const std::string text = store::Store::open(parts[p]).grid(l.grid).provenance;
    if (!doc.LoadMemory(text)) {
      throw store::StoreError("regolith-mpi import: " + parts[p].string() +
                              ": cannot read the part's provenance");
    }
    const CPLJSONArray files = doc.GetRoot().GetArray("sources");
    std::size_t local = 0;
    for (int k = 0; k < files.Size(); ++k) {
      const std::string path = files[k].GetString("path");
      for (std::size_t j = local + 1; j < l.partTiles[p].size(); ++j) {
        const std::string& tile = sources[l.partTiles[p][j]];
        std::error_code ec;
        if (fs::equivalent(path, tile, ec)) {
          local = j;
          break;
        }
      }
      perTile[l.partTiles[p][local]].push_back(files[k].Format(CPLJSONObject::PrettyFormat::Plain));
    }
    if (!l.partTiles[p].empty() && l.partTiles[p].front() == 0) {
      if (!base.LoadMemory(text)) {
        throw store::StoreError("regolith-mpi import: cannot read the provenance");
      }
    }
  }
  // The first part's document, member by member, its sources replaced in their place.
  CPLJSONArray files;
  for (const auto& tile : perTile) {
    for (const std::string& f : tile) {
      CPLJSONDocument e;
      if (e.LoadMemory(f)) files.Add(e.GetRoot());
    }
  }
  CPLJSONObject merged;
  for (const CPLJSONObject& child : base.GetRoot().GetChildren()) {
    if (child.GetName() == "sources") {
      merged.Add("sources", files);
    } else {
      merged.Add(child.GetName(), child);
    }
  }
  return merged.Format(CPLJSONObject::PrettyFormat::Plain);
}

std::string encodeBlocks(const std::vector<store::BlockStatistics>& b) {
  std::string s(b.size() * sizeof(store::BlockStatistics), '\0');
  if (!b.empty()) std::memcpy(s.data(), b.data(), s.size());
  return s;
}

void appendBlocks(const std::string& s, std::vector<store::BlockStatistics>& out) {
  const std::size_t n = s.size() / sizeof(store::BlockStatistics);
  const std::size_t at = out.size();
  out.resize(at + n);
  if (n > 0) std::memcpy(out.data() + at, s.data(), n * sizeof(store::BlockStatistics));
}

/// Part p's store in the parts' folder.
fs::path partPath(const fs::path& dir, std::size_t p) {
  return dir / ("part-" + std::to_string(p) + ".h5");
}

/// The part store of part p: levels 0 … partTop of its rows (a window of the one raster, or its
/// tiles), written with the ordinary import. Returns its level-0 blocks' statistics as the
/// writer summed them (none for tiles written with one level, as the writer).
std::vector<store::BlockStatistics> importPart(const Args& a, const store::ImportOptions& base,
                                               const Layout& l, std::size_t p,
                                               const fs::path& path) {
  std::vector<store::BlockStatistics> blocks;
  store::ImportOptions o = base;
  o.durability = core::Durability::Scratch;  // deleted once joined
  // One raster: its digests are taken once, on the digesting rank, beside the join.
  o.digestSources = !l.tiles.empty();
  o.levels = l.plan.partTop + 1;
  o.gridName = l.grid;
  o.blockStatistics = [&blocks](std::string_view, const store::BlockStatistics& b) {
    blocks.push_back(b);
  };
  const PartRows& part = l.plan.parts[p];
  if (l.tiles.empty()) {
    o.window = store::SampleWindow{part.row0, 0, part.row1 - part.row0, l.cols};
    // The first band becomes the store, grown to the whole grid by the join (Assembly).
    if (p == 0) o.reserveRows = l.rows;
    (void)store::importRaster(a.sources.front(), path, o);
  } else {
    std::vector<fs::path> tiles;
    for (const std::size_t i : l.partTiles[p]) tiles.emplace_back(a.sources[i]);
    (void)store::importTiles(tiles, path, o);
  }
  return blocks;
}

/// The digesting rank's reply to rank 0: "ok <seconds>" and the single raster's provenance
/// with its digests (store::rasterProvenance()), or "error" and the reason, a line each.
std::string digestSource(const Args& a, const store::ImportOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  try {
    if (std::getenv("REGOLITH_MPI_TEST_DIGEST_FAILS") != nullptr) {
      throw store::ImportError("test: the digests fail (REGOLITH_MPI_TEST_DIGEST_FAILS)");
    }
    const std::string provenance = store::rasterProvenance(a.sources.front(), o);
    std::ostringstream head;
    head << "ok " << seconds(t0) << "\n";
    return head.str() + provenance;
  } catch (const std::exception& e) {
    return std::string("error\n") + e.what();
  }
}

/// Before MPI_Init: where every rank of the job runs on this node (OpenMPI's launcher gives
/// OMPI_COMM_WORLD_LOCAL_SIZE and OMPI_COMM_WORLD_SIZE) and nobody chose a point-to-point layer
/// (OMPI_MCA_pml, which `mpirun --mca pml X` sets too), asks OpenMPI for ob1, whose
/// shared-memory transport (vader) carries one node's messages. Left to choose, Debian's
/// OpenMPI 4.1 first tries its cm layer, loading and probing the PSM, PSM2 and libfabric
/// fabrics: 0.2 s of every rank's MPI_Init on a node that has none (docs/scale.md, "Stop
/// 45"). Across nodes OpenMPI chooses, as before. Returns what the summary says of it.
std::string choosePointToPoint() {
  if (const char* chosen = std::getenv("OMPI_MCA_pml"); chosen != nullptr) {
    return std::string("pml ") + chosen + ", as OMPI_MCA_pml set it";
  }
  const char* local = std::getenv("OMPI_COMM_WORLD_LOCAL_SIZE");
  const char* world = std::getenv("OMPI_COMM_WORLD_SIZE");
  if (local == nullptr || world == nullptr)
    return "the MPI library's choice (not started by OpenMPI's mpirun)";
  if (std::strcmp(local, world) != 0) return "OpenMPI's choice (ranks on several nodes)";
  // Before MPI_Init, on the only thread; the variable is read by MPI_Init.
  if (setenv("OMPI_MCA_pml", "ob1", 0) != 0) return "OpenMPI's choice (setenv failed)";
  return "pml ob1 (every rank on one node)";
}

/// How MPI started: MPI_Init's seconds and the point-to-point layer (choosePointToPoint()).
struct MpiStart {
  double seconds = 0.0;
  std::string pointToPoint;
};

int run(const Args& a, int rank, int size, const MpiStart& started) {
  const auto t0 = std::chrono::steady_clock::now();
  // Threads per rank, unless --threads says: the cores this rank may run on (one where mpirun
  // binds each rank to a core, its default for two ranks or fewer), and at most its share of
  // the node's cores. hardware_concurrency() alone gave a rank bound to one core two threads
  // on it.
  MPI_Comm node = MPI_COMM_NULL;
  MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, rank, MPI_INFO_NULL, &node);
  int perNode = 1;
  MPI_Comm_size(node, &perNode);
  MPI_Comm_free(&node);
  store::ImportOptions o;
  o.gridName = a.grid;
  o.patchRows = o.patchCols = a.patch;
  o.levels = a.levels;
  o.deflate = a.deflate;
  o.codec = store::codecNamed(a.compression);
  o.threads =
      a.threads != 0
          ? a.threads
          : std::max(1U, std::min(core::availableCores(), std::thread::hardware_concurrency() /
                                                              static_cast<unsigned>(perNode)));
  o.memoryBudgetBytes = a.memoryMb == 0 ? 0 : a.memoryMb * (std::size_t{1} << 20U);
  if (a.hasNodata) o.nodata = a.nodata;
  o.body = a.body;
  o.strict = a.strict;

  // The plan: every rank computes it from the sources' metadata (the same on every rank).
  Layout l;
  std::string planError;
  try {
    l = planImport(a, o, size);
  } catch (const std::exception& e) {
    planError = e.what();
  }
  if (!planError.empty()) {
    if (rank == 0) std::cerr << "regolith-mpi import: " << planError << "\n";
    return 1;
  }
  const std::size_t parts = l.plan.parts.size();
  const fs::path out = fs::absolute(a.out);
  // The parts' folder beside the target, named by rank 0's process id.
  const std::string pid = broadcastString(std::to_string(getpid()), rank);
  const fs::path dir = out.parent_path() / (out.filename().string() + ".parts-" + pid);
  gPartsDir = dir.string();
  gOut = out.string();
  gPid = pid;  // the target's temporary is rank 0's: <out>.tmp-<rank 0's pid>-<n>
  (void)std::signal(SIGTERM, onTerminate);
  (void)std::signal(SIGINT, onTerminate);

  // One raster split into parts: its digests (reading all of it) are taken once, by the last
  // rank: while rank 0 joins the parts, or at once when that rank has no part. It sends rank 0
  // the grid's provenance (docs/scale.md, "Stop 42").
  const bool digestApart = parts > 1 && l.tiles.empty();
  const int digester = size - 1;
  constexpr int kProvenanceTag = 42;
  std::string digestReply;
  if (digestApart && rank == digester && static_cast<std::size_t>(rank) >= parts) {
    digestReply = digestSource(a, o);
  }

  std::string error, blocks;
  const auto tParts = std::chrono::steady_clock::now();
  const auto p = static_cast<std::size_t>(rank);
  try {
    if (parts == 1) {
      if (rank == 0) {  // no split possible: the single-process import, on rank 0
        store::ImportOptions one = o;
        one.threads = a.threads;
        if (a.sources.size() == 1) {
          (void)store::importRaster(a.sources.front(), out, one);
        } else {
          const std::vector<fs::path> tiles(a.sources.begin(), a.sources.end());
          (void)store::importTiles(tiles, out, one);
        }
      }
    } else if (p < parts) {
      fs::create_directories(dir);
      const fs::path part = partPath(dir, p);
      blocks = encodeBlocks(importPart(a, o, l, p, part));
      if (const char* kill = std::getenv("REGOLITH_MPI_TEST_KILL_RANK");
          kill != nullptr && std::to_string(rank) == kill) {
        (void)std::raise(SIGKILL);  // tests: a rank that dies with its part written
      }
    }
  } catch (const std::exception& e) {
    error = e.what();
    if (error.empty()) error = "failed";
  }
  const double partSeconds = seconds(tParts);
  // Wait for the slowest rank.
  MPI_Request arrived = MPI_REQUEST_NULL;
  MPI_Ibarrier(MPI_COMM_WORLD, &arrived);
  waitGently(arrived);
  std::ostringstream slow;
  slow << partSeconds << " " << cpuSeconds();
  const std::vector<std::string> errors = gather(error, rank, size);
  const std::vector<std::string> stats = gather(blocks, rank, size);
  const std::vector<std::string> times = gather(slow.str(), rank, size);

  int partsOk = 1;
  if (rank == 0) {
    partsOk = std::all_of(errors.begin(), errors.end(), [](const auto& e) { return e.empty(); });
  }
  partsOk = broadcastInt(partsOk);
  if (digestApart && rank == digester) {
    if (digestReply.empty() && partsOk != 0) digestReply = digestSource(a, o);
    if (partsOk != 0) sendString(digestReply, 0, kProvenanceTag);
  }

  int status = 0;
  if (rank == 0) {
    for (int r = 0; r < size; ++r) {
      const std::string& e = errors[static_cast<std::size_t>(r)];
      if (e.empty()) continue;
      status = 1;
      std::cerr << "regolith-mpi import: rank " << r;
      if (static_cast<std::size_t>(r) < parts) {
        const PartRows& pr = l.plan.parts[static_cast<std::size_t>(r)];
        std::cerr << " (level-0 rows " << pr.row0 << "-" << pr.row1 - 1 << ")";
      }
      std::cerr << " failed: " << e << "\n";
    }
    if (status == 0 && parts > 1) {
      const auto tJoin = std::chrono::steady_clock::now();
      std::string reply, digestSeconds;
      JoinSeconds joined;
      try {
        Assembly as;
        as.out = out;
        as.scratch = dir;
        as.grid = l.grid;
        for (std::size_t i = 0; i < parts; ++i) {
          as.parts.push_back(partPath(dir, i));
        }
        as.plan = l.plan;
        as.rows = l.rows;
        as.cols = l.cols;
        as.levels = l.levels;
        as.patchRows = as.patchCols = a.patch;
        as.partTiles = l.partTiles;
        as.tileCount = l.tiles.size();
        for (std::size_t i = 0; i < parts; ++i) appendBlocks(stats[i], as.blocks);
        if (!l.tiles.empty()) as.provenance = mergedProvenance(l, as.parts, a.sources);
        as.threads = a.threads;
        as.growFirst = l.tiles.empty();
        if (digestApart) {
          as.lateProvenance = [&]() {
            reply = receiveString(digester, kProvenanceTag);
            const std::size_t eol = reply.find('\n');
            const std::string head = reply.substr(0, eol);
            if (head.rfind("ok ", 0) != 0) {
              throw store::StoreError("the digests of " + a.sources.front() + " on rank " +
                                      std::to_string(digester) +
                                      " failed: " + reply.substr(std::min(eol + 1, reply.size())));
            }
            digestSeconds = head.substr(3);
            return reply.substr(eol + 1);
          };
        }
        joined = assemble(as);
      } catch (const std::exception& e) {
        status = 1;
        std::cerr << "regolith-mpi import: rank 0 (assembling " << out.string()
                  << ") failed: " << e.what() << "\n";
      }
      // The digesting rank's reply is taken even when the join failed before asking for it.
      if (digestApart && reply.empty()) (void)receiveString(digester, kProvenanceTag);
      if (status == 0) {
        double slowest = 0.0;
        std::ostringstream ranks;
        for (const std::string& t : times) {
          std::istringstream in(t);
          double wall = 0.0, cpu = 0.0;
          in >> wall >> cpu;
          slowest = std::max(slowest, wall);
          ranks << (ranks.tellp() > 0 ? ", " : "") << "part " << wall << " s, CPU " << cpu << " s";
        }
        std::cout << "Wrote " << out.string() << ": grid '" << l.grid << "', " << l.rows
                  << " rows x " << l.cols << " cols, " << l.levels << " levels, from "
                  << a.sources.size() << (a.sources.size() == 1 ? " file" : " files") << " on "
                  << size << (size == 1 ? " rank" : " ranks") << "\n";
        std::cout << "  parts:          " << parts << " (level-0 rows";
        for (const PartRows& pr : l.plan.parts) std::cout << " " << pr.row0 << "-" << pr.row1 - 1;
        std::cout << "), levels 0-" << l.plan.partTop << " by the ranks";
        if (l.plan.partTop + 1 < l.levels) {
          std::cout << ", " << l.plan.partTop + 1 << "-" << l.levels - 1 << " by rank 0";
        }
        std::cout << "\n  seconds:        " << seconds(t0) << " (parts " << slowest
                  << " on the slowest rank, joining " << seconds(tJoin) << ")\n";
        std::cout << "  joining:        coarse levels " << joined.coarse << " s, chunks "
                  << joined.copies << " s, sync " << joined.sync << " s, digest awaited "
                  << joined.wait << " s, last sync and rename " << joined.finish << " s\n";
        std::cout << "  ranks:          " << ranks.str() << " (rank 0's CPU before the join)\n";
        if (digestApart) {
          std::cout << "  digests:        on rank " << digester
                    << (static_cast<std::size_t>(digester) < parts ? " beside the join, "
                                                                   : " beside the parts, ")
                    << digestSeconds << " s\n";
        }
      }
    } else if (status == 0) {
      std::cout << "Wrote " << out.string() << ": grid '" << l.grid << "', one part ("
                << (size == 1           ? std::string("one rank")
                    : l.onePart.empty() ? std::string("too few rows for two bands of patches")
                                        : l.onePart)
                << "), on rank 0 alone, " << seconds(t0) << " seconds\n";
    }
    if (status == 0) {
      std::cout << "  MPI:            MPI_Init " << started.seconds << " s, "
                << started.pointToPoint << "\n";
    }
  }
  status = broadcastInt(status);
  // Each rank removes its own part at once (freeing a part's pages takes a while), then
  // rank 0 the folder with whatever is left in it.
  std::error_code ec;
  if (parts > 1 && p < parts) fs::remove(partPath(dir, p), ec);
  MPI_Request removed = MPI_REQUEST_NULL;
  MPI_Ibarrier(MPI_COMM_WORLD, &removed);
  waitGently(removed);
  if (rank == 0) fs::remove_all(dir, ec);
  return status;
}

}  // namespace

int main(int argc, char** argv) try {
  MpiStart started;
  started.pointToPoint = choosePointToPoint();
  const auto t0 = std::chrono::steady_clock::now();
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  started.seconds = seconds(t0);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  CLI::App app{
      "regolith-mpi: build one store on several MPI ranks (mpirun -np N regolith-mpi import "
      "...). docs/cli.md, docs/scale.md"};
  app.require_subcommand(1);
  Args a;
  auto* cmd = app.add_subcommand(
      "import",
      "Import GDAL rasters as one grid of a new store, as `regolith import` does, on every "
      "rank of the job: bit for bit the store `regolith import` writes");
  cmd->add_option("source", a.sources, "Raster file(s); several: tiles of one grid")->required();
  cmd->add_option("-o,--out", a.out, "Store file to write (replaced atomically if it exists)")
      ->required();
  cmd->add_option("--grid", a.grid, "Name of the grid (default: the first source's file stem)");
  cmd->add_option("--patch", a.patch, "Patch (HDF5 chunk) size in samples, square")
      ->check(CLI::Range(std::size_t{8}, std::size_t{8192}))
      ->capture_default_str();
  cmd->add_option("--levels", a.levels, "Pyramid levels including level 0 (0: until one patch)")
      ->check(CLI::Range(0, 40))
      ->capture_default_str();
  cmd->add_option("--deflate", a.deflate, "Deflate level 0-9 (0: uncompressed)")
      ->check(CLI::Range(0, 9))
      ->capture_default_str();
  cmd->add_option("--compression", a.compression, "deflate or zfp")
      ->check(CLI::IsMember({"deflate", "zfp"}))
      ->capture_default_str();
  cmd->add_option(
         "--threads", a.threads,
         "Threads per rank (0: the cores this rank may run on, at most its share of the node's)")
      ->capture_default_str();
  cmd->add_option("--memory-mb", a.memoryMb, "MiB each rank's writer may hold (0: no bound)")
      ->capture_default_str();
  auto* nodata = cmd->add_option("--nodata", a.nodata, "A further source value meaning missing");
  cmd->add_option("--body", a.body, "Name of the body, where the CRS does not say it");
  cmd->add_flag("--strict", a.strict, "Refuse implausible heights");
  int rc = 0;
  try {
    app.parse(argc, argv);
    a.hasNodata = nodata->count() > 0;
  } catch (const CLI::ParseError& e) {
    rc = rank == 0 ? app.exit(e) : (e.get_exit_code() == 0 ? 0 : 1);
    MPI_Finalize();
    return rc;
  }
  try {
    rc = run(a, rank, size, started);
  } catch (const std::exception& e) {
    std::cerr << "regolith-mpi import: rank " << rank << ": " << e.what() << "\n";
    MPI_Abort(MPI_COMM_WORLD, 1);
  }
  MPI_Finalize();
  return rc;
} catch (...) {
  std::cerr << "regolith-mpi: unexpected failure\n";
  return 1;
}
