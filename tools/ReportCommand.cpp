// `regolith report --out DIR [--full] [--from RUN.json]`: the accuracy-versus-time report
// (docs/accuracy-vs-time.md). Runs the benchmark programs of bench/ (quick filters by
// default), gathers their JSON with the machine and the command into DIR/run.json, and has
// scripts/report.py (Python with numpy and matplotlib) draw DIR/*.png and DIR/index.html.
#include <regolith/core/AtomicFile.hpp>
#include <regolith/core/Error.hpp>

#include "Commands.hpp"
#include "OutputFolder.hpp"

#include <CLI/CLI.hpp>
#include <fcntl.h>
#include <nlohmann/json.hpp>
#include <spawn.h>
#include <sys/utsname.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

// Paths configured at build time (tools/CMakeLists.txt); empty when not built.
#ifndef REGOLITH_BENCH_DIR
#define REGOLITH_BENCH_DIR ""
#endif
#ifndef REGOLITH_REPORT_SCRIPT
#define REGOLITH_REPORT_SCRIPT ""
#endif
#ifndef REGOLITH_REPORT_PYTHON
#define REGOLITH_REPORT_PYTHON ""
#endif

extern char** environ;  // NOLINT(readability-redundant-declaration): posix_spawn's environment

namespace regolith::tools {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr const char* kCommand = "regolith report";

/// One benchmark program run: its arguments in quick and full mode. Google Benchmark
/// programs get --benchmark_out=<json>; the others (accuracy_table, cache_policies) get
/// --json <json>.
struct Step {
  const char* program;
  const char* what;
  bool googleBenchmark;
  std::vector<std::string> quick;
  std::vector<std::string> full;
};

/// Every knob where accuracy costs time, and the program that measures it.
std::vector<Step> steps() {
  return {
      {"accuracy_table",
       "interpolation kernels: error against an analytic surface, ns/query",
       false,
       {"--points", "20000"},
       {}},
      {"topo_bench",
       "interpolation kernels: ns per height() query on a 2048² DEM",
       true,
       {"--benchmark_filter=^dem/height/(nearest|bilinear|bicubic)/", "--benchmark_min_time=0.02"},
       {"--benchmark_filter=^dem/(height|heights_batch|surface_grid)/", "--benchmark_min_time=0.2",
        "--benchmark_repetitions=3", "--benchmark_report_aggregates_only=true"}},
      {"store_bench",
       "pyramid against strided coarse reads, codecs, traverse against cache budget",
       true,
       {"--benchmark_filter=^store/(coarse|codec|rover/paged_heights(/|_4)|rover/survey/)",
        "--benchmark_min_time=0.02"},
       {"--benchmark_filter=^store/(coarse|codec|rover/paged_heights(/|_4)|rover/survey/)",
        "--benchmark_min_time=0.5"}},
      {"cache_policies",
       "cache policy and budget: hit rate and ns per request on rover traces",
       false,
       {"--scale", "0.3", "--reps", "1", "--capacities", "4,16,64"},
       {"--capacities", "2,4,8,16,32,64,128"}},
      {"precision_bench",
       "float, double and re-rooted positions: error against distance",
       true,
       {"--benchmark_min_time=0.01"},
       {"--benchmark_min_time=0.1"}},
      {"clod_bench",
       "clipmap level size: screen-space error and frame time (GL)",
       true,
       {"--benchmark_filter=^clod/(clipmap|mesh)/dem:2048/", "--benchmark_min_time=0.01"},
       {"--benchmark_filter=^clod/(clipmap|mesh)/", "--benchmark_min_time=0.5"}},
      {"farfield_bench",
       "far-field PGM grid size: screen-space error and frame time (GL)",
       true,
       {"--benchmark_filter=^pgm/low/grid:(256|512|1024|2048)/screen:512/",
        "--benchmark_min_time=0.01"},
       {"--benchmark_filter=^pgm/.*/screen:1024/", "--benchmark_min_time=0.5"}},
      {"effects_bench",
       "the cost of each scene-declared effect (GL)",
       true,
       {"--pairs=12"},
       {"--pairs=300"}},
      {"import_bench",
       "import codecs on an 8192² raster: size and time (full only)",
       true,
       {},
       {"--benchmark_min_time=0"}},
  };
}

/// Whether `step` runs in this mode (import_bench is too long for the quick report).
bool runs(const Step& step, bool full) { return full || !step.quick.empty(); }

/// Runs `argv` with stdout and stderr appended to `log`; returns its exit status (or 128 +
/// signal). Throws IoError if it cannot be started.
int runProgram(const std::vector<std::string>& argv, const fs::path& log) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  const std::unique_ptr<posix_spawn_file_actions_t, int (*)(posix_spawn_file_actions_t*)> guard(
      &actions, posix_spawn_file_actions_destroy);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(),
                                   O_WRONLY | O_CREAT | O_APPEND, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  std::vector<char*> args;
  args.reserve(argv.size() + 1);
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = 0;
  if (const int rc = posix_spawn(&pid, args[0], &actions, nullptr, args.data(), environ); rc != 0) {
    throw IoError(std::string(kCommand) + ": cannot run " + argv[0] + ": " + std::strerror(rc));
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) throw IoError(std::string(kCommand) + ": waitpid failed");
  }
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  return 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
}

/// The CPU model of /proc/cpuinfo ("unknown CPU" without one).
std::string cpuModel() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.starts_with("model name")) {
      const auto colon = line.find(':');
      if (colon != std::string::npos) return line.substr(line.find_first_not_of(' ', colon + 1));
    }
  }
  return "unknown CPU";
}

std::string utcNow() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

json machine() {
  utsname u{};
  uname(&u);
  return {{"cpu", cpuModel()},
          {"cores", std::thread::hardware_concurrency()},
          {"os", std::string(u.sysname) + " " + u.release + " " + u.machine},
          {"host_kind", "see docs/accuracy-vs-time.md for the reference machine"}};
}

json readJson(const fs::path& path, const char* what) {
  std::ifstream in(path);
  if (!in) throw IoError(std::string(kCommand) + ": " + path.string() + ": cannot read " + what);
  try {
    return json::parse(in);
  } catch (const json::exception& e) {
    throw InvalidArgument(std::string(kCommand) + ": " + path.string() + ": " + what +
                          " is not valid JSON: " + e.what());
  }
}

struct Args {
  std::string out;
  std::string from;
  std::string benchDir = REGOLITH_BENCH_DIR;
  bool full = false;
  std::vector<std::string> only;
};

/// The bench program's path, or InvalidArgument naming what is missing and how to build it.
fs::path benchProgram(const Args& a, const char* program) {
  if (a.benchDir.empty()) {
    throw InvalidArgument(std::string(kCommand) +
                          ": this regolith was built without the benchmark programs; configure "
                          "with -DREGOLITH_BUILD_BENCH=ON (or pass --bench-dir DIR)");
  }
  fs::path p = fs::path(a.benchDir) / program;
  if (!fs::exists(p)) {
    throw InvalidArgument(std::string(kCommand) + ": " + p.string() +
                          ": no such program; build it with `ninja -C <build> " + program +
                          "` (configured with -DREGOLITH_BUILD_BENCH=ON)");
  }
  return p;
}

std::string commandLine(const Args& a) {
  std::ostringstream s;
  s << kCommand << " --out " << a.out;
  if (a.full) s << " --full";
  if (!a.from.empty()) s << " --from " << a.from;
  for (const std::string& o : a.only) s << " --only " << o;
  return s.str();
}

/// Runs the benchmark programs into `dir`/raw and returns the run document.
json runBenchmarks(const Args& a, const fs::path& dir) {
  const fs::path raw = dir / "raw";
  fs::create_directories(raw);
  std::vector<const Step*> chosen;
  const std::vector<Step> all = steps();
  for (const Step& s : all) {
    if (!runs(s, a.full)) continue;
    if (!a.only.empty() && std::find(a.only.begin(), a.only.end(), s.program) == a.only.end())
      continue;
    chosen.push_back(&s);
  }
  // Check every program before running any (a missing one fails at once, not after minutes).
  for (const Step* s : chosen) (void)benchProgram(a, s->program);

  json doc;
  doc["report_format"] = 1;
  doc["mode"] = a.full ? "full" : "quick";
  doc["command"] = commandLine(a);
  doc["date"] = utcNow();
  doc["machine"] = machine();
  doc["runs"] = json::array();
  const auto start = std::chrono::steady_clock::now();
  std::size_t i = 0;
  for (const Step* s : chosen) {
    ++i;
    const fs::path program = benchProgram(a, s->program);
    const fs::path out = raw / (std::string(s->program) + ".json");
    const fs::path log = raw / (std::string(s->program) + ".log");
    fs::remove(log);
    std::vector<std::string> argv{program.string()};
    const std::vector<std::string>& extra = a.full ? s->full : s->quick;
    argv.insert(argv.end(), extra.begin(), extra.end());
    if (s->googleBenchmark) {
      argv.push_back("--benchmark_out=" + out.string());
      argv.push_back("--benchmark_out_format=json");
    } else {
      argv.push_back("--json");
      argv.push_back(out.string());
    }
    std::ostringstream shown;
    shown << s->program;
    for (std::size_t k = 1; k < argv.size(); ++k) shown << ' ' << argv[k];
    std::cerr << kCommand << ": [" << i << "/" << chosen.size() << "] " << s->what << "\n  "
              << shown.str() << std::endl;
    const auto t0 = std::chrono::steady_clock::now();
    const int rc = runProgram(argv, log);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (rc != 0) {
      throw IoError(std::string(kCommand) + ": " + s->program + " failed with exit status " +
                    std::to_string(rc) + "; its output is in " + log.string());
    }
    char took[64];
    std::snprintf(took, sizeof took, "%.1f", seconds);
    std::cerr << "  done in " << took << " s" << std::endl;
    json entry{{"program", s->program},
               {"what", s->what},
               {"command", shown.str()},
               {"seconds", seconds},
               {"output", readJson(out, "benchmark output")}};
    doc["runs"].push_back(std::move(entry));
  }
  doc["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return doc;
}

void plot(const fs::path& runJson, const fs::path& dir, const std::string& replot) {
  const std::string python = REGOLITH_REPORT_PYTHON;
  const std::string script = REGOLITH_REPORT_SCRIPT;
  if (python.empty()) {
    throw InvalidArgument(
        std::string(kCommand) +
        ": no Python with numpy and matplotlib was found when regolith was "
        "configured; on Debian: apt-get install python3-matplotlib "
        "python3-numpy, or configure with -DREGOLITH_REPORT_PYTHON=/path/to/python3");
  }
  if (script.empty() || !fs::exists(script)) {
    throw InvalidArgument(std::string(kCommand) + ": the plotting script '" + script +
                          "' does not exist (scripts/report.py of the source tree regolith was "
                          "built from)");
  }
  std::cerr << kCommand << ": plotting into " << dir.string() << std::endl;
  std::vector<std::string> argv{python, script, "--run", runJson.string(), "--out", dir.string()};
  if (!replot.empty()) {
    argv.push_back("--replot-command");
    argv.push_back(replot);
  }
  const fs::path log = dir / "raw" / "report.py.log";
  fs::create_directories(log.parent_path());
  fs::remove(log);
  if (const int rc = runProgram(argv, log); rc != 0) {
    std::ifstream in(log);
    std::ostringstream text;
    text << in.rdbuf();
    throw IoError(std::string(kCommand) + ": " + script + " failed with exit status " +
                  std::to_string(rc) + ":\n" + text.str());
  }
}

void run(const Args& a) {
  requireFolderToWrite(kCommand, a.out);
  const fs::path dir(a.out);
  fs::create_directories(dir);
  const fs::path runJson = dir / "run.json";
  if (!a.from.empty()) {
    // Re-plot an earlier run: nothing is run, the run's own command and machine stay.
    const json doc = readJson(a.from, "report run");
    if (!doc.contains("runs") || !doc.contains("machine") || !doc.contains("command")) {
      throw InvalidArgument(std::string(kCommand) + ": " + a.from +
                            ": not a report run (expected the keys runs, machine and command, "
                            "as in the run.json of an earlier `regolith report`)");
    }
    if (!fs::exists(runJson) || !fs::equivalent(runJson, a.from)) {
      core::writeStreamAtomically(
          runJson, [&](std::ostream& o) { o << doc.dump(1) << '\n'; }, "regolith report");
    }
    plot(runJson, dir, commandLine(a));
  } else {
    const json doc = runBenchmarks(a, dir);
    core::writeStreamAtomically(
        runJson, [&](std::ostream& o) { o << doc.dump(1) << '\n'; }, "regolith report");
    plot(runJson, dir, "");
    char took[64];
    std::snprintf(took, sizeof took, "%.1f", doc["seconds"].get<double>());
    std::cerr << kCommand << ": benchmarks took " << took << " s" << std::endl;
  }
  std::cout << "Wrote " << (dir / "index.html").string() << " (raw run: " << runJson.string()
            << ")\n";
}

}  // namespace

void addReportCommand(CLI::App& app) {
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "report",
      "The accuracy-versus-time report: runs the benchmark programs (quick by default), saves "
      "their JSON in --out/run.json and writes --out/index.html with PNG plots "
      "(docs/accuracy-vs-time.md)");
  cmd->add_option("--out", a->out, "Folder for index.html, the plots and run.json")->required();
  auto* full = cmd->add_flag(
      "--full", a->full,
      "The long runs (tens of minutes) instead of the quick ones (about two minutes)");
  cmd->add_option("--from", a->from,
                  "Re-plot the run.json of an earlier report without running anything")
      ->check(CLI::ExistingFile)
      ->excludes(full);
  cmd->add_option("--bench-dir", a->benchDir,
                  "Folder of the benchmark programs (default: the build's bench/ folder)");
  cmd->add_option("--only", a->only,
                  "Run only these programs (e.g. --only precision_bench); the page shows what ran");
  cmd->callback([a] { run(*a); });
}

}  // namespace regolith::tools
