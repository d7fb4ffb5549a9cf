#include "Hdf5.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <optional>

// A sanitized build (GCC's -fsanitize=address or thread, or clang's) can move the reports of
// the child processes that read old stores' texts out of the test log; see readInChild().
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define REGOLITH_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define REGOLITH_SANITIZED 1
#endif
#endif
#ifdef REGOLITH_SANITIZED
#include <sanitizer/common_interface_defs.h>
#endif

namespace regolith::store::hdf5 {

std::recursive_mutex& mutex() {
  // The one process-wide HDF5 lock (see Hdf5.hpp), built on first use and deliberately never
  // destroyed: a Store held in some other static may close its handles during static
  // destruction, after a function-local mutex object would already be gone.
  static auto* const m = new std::recursive_mutex;
  return *m;
}

namespace {
// How many Locks this thread holds. Only the outermost one touches HDF5's printing setting:
// H5Eget_auto2() clears the thread's error stack, which a nested Lock taken while an error is
// being reported (takeErrorStack) must not do.
thread_local int lockDepth = 0;
}  // namespace

Lock::Lock() : lock_(mutex()) {
  if (lockDepth++ == 0) {
    (void)H5Eget_auto2(H5E_DEFAULT, &oldFunc_, &oldData_);
    (void)H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  }
}

Lock::~Lock() {
  if (--lockDepth == 0) (void)H5Eset_auto2(H5E_DEFAULT, oldFunc_, oldData_);
}

namespace {

/// One entry of HDF5's error stack: "function(): description".
struct StackEntry {
  std::string func;
  std::string desc;
};

herr_t collectError(unsigned /*n*/, const H5E_error2_t* err, void* data) {
  static_cast<std::vector<StackEntry>*>(data)->push_back(
      {err->func_name != nullptr ? err->func_name : "?", err->desc != nullptr ? err->desc : ""});
  return 0;
}

}  // namespace

std::string condenseErrorDescription(std::string_view desc) {
  // A failed read or write of HDF5's file drivers reads "file write failed: time = <ctime(),
  // which ends in a line break>, filename = '<the file, perhaps a temporary>', file
  // descriptor = 5, errno = 28, error message = 'No space left on device', buf = ...": the
  // cause is the system's message and errno.
  std::string out(desc);
  const std::string_view timeKey = ": time = ", errnoKey = "errno = ",
                         messageKey = "error message = '";
  const std::size_t time = desc.find(timeKey), message = desc.find(messageKey);
  if (time != std::string_view::npos && message != std::string_view::npos) {
    const std::size_t from = message + messageKey.size(), to = desc.find('\'', from);
    out = std::string(desc.substr(0, time)) + ": " +
          std::string(desc.substr(from, to == std::string_view::npos ? to : to - from));
    const std::size_t e = desc.find(errnoKey);
    if (e != std::string_view::npos) {
      const std::size_t digits = e + errnoKey.size();
      std::size_t end = digits;
      while (end < desc.size() && desc[end] >= '0' && desc[end] <= '9') ++end;
      if (end > digits) out += " (errno " + std::string(desc.substr(digits, end - digits)) + ")";
    }
  }
  // One line: line breaks and runs of blanks become one space.
  std::string line;
  line.reserve(out.size());
  for (const char ch : out) {
    const bool blank = ch == ' ' || ch == '\n' || ch == '\r' || ch == '\t';
    if (blank && (line.empty() || line.back() == ' ')) continue;
    line += blank ? ' ' : ch;
  }
  while (!line.empty() && line.back() == ' ') line.pop_back();
  return line;
}

std::string takeErrorStack() {
  const Lock lock;
  std::vector<StackEntry> entries;
  (void)H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, collectError, &entries);
  (void)H5Eclear2(H5E_DEFAULT);
  if (entries.empty()) return {};
  // The outermost call (what failed) and the innermost one (why); the frames between them
  // repeat the failure on its way up.
  const auto text = [](const StackEntry& e) {
    return e.func + "(): " + condenseErrorDescription(e.desc);
  };
  std::string out = text(entries.front());
  if (entries.size() > 2) out += "; ...";
  if (entries.size() > 1) out += "; " + text(entries.back());
  return out;
}

Context::Context(std::string_view operation, const std::filesystem::path& path)
    : prefix(std::string(operation) + ": " + path.string()) {}

void fail(const Context& ctx, const std::string& what) {
  throw StoreError(ctx.prefix + ": " + what);
}

void failHdf5(const Context& ctx, const std::string& what) {
  std::string stack = takeErrorStack();
  if (stack.empty()) stack = "no error stack";
  throw StoreError(ctx.prefix + ": " + what + " [HDF5: " + stack + "]");
}

hid_t check(hid_t id, const Context& ctx, const std::string& what) {
  if (id < 0) failHdf5(ctx, what);
  return id;
}

void check(herr_t status, const Context& ctx, const std::string& what) {
  if (status < 0) failHdf5(ctx, what);
}

std::string missingFilterHint(int id) {
  std::string dirs;
  unsigned n = 0;
  if (H5PLsize(&n) >= 0) {
    for (unsigned i = 0; i < n; ++i) {
      std::array<char, 1024> buf{};
      if (H5PLget(i, buf.data(), buf.size()) <= 0) continue;
      if (!dirs.empty()) dirs += ':';
      dirs.append(buf.data());
    }
  }
  std::string hint = "HDF5 looks for filter plugins in " +
                     (dirs.empty() ? std::string("(none)") : dirs) +
                     " (HDF5_PLUGIN_PATH replaces that list)";
  if (id == 32013) hint += "; the ZFP filter (H5Z-ZFP) is Debian's hdf5-filter-plugin-zfp-serial";
  return hint;
}

// ---- attributes ----------------------------------------------------------------------------

bool hasAttribute(hid_t obj, const char* name, const Context& ctx) {
  const Lock lock;
  const htri_t e = H5Aexists(obj, name);
  if (e < 0) failHdf5(ctx, std::string("cannot look up attribute '") + name + "'");
  return e > 0;
}

namespace {

struct OpenedAttribute {
  Attribute attr;
  Datatype type;
  H5T_class_t cls = H5T_NO_CLASS;
  std::size_t elements = 0;
};

OpenedAttribute openAttribute(hid_t obj, const char* name, const Context& ctx,
                              const std::string& owner) {
  const Lock lock;
  if (!hasAttribute(obj, name, ctx)) {
    fail(ctx, owner + " has no attribute '" + name + "'");
  }
  OpenedAttribute a;
  const std::string what = owner + " attribute '" + name + "'";
  a.attr = Attribute(check(H5Aopen(obj, name, H5P_DEFAULT), ctx, "cannot open " + what));
  a.type = Datatype(check(H5Aget_type(a.attr.get()), ctx, "cannot read the type of " + what));
  a.cls = H5Tget_class(a.type.get());
  const Dataspace space(check(H5Aget_space(a.attr.get()), ctx, "cannot read the shape of " + what));
  const hssize_t n = H5Sget_simple_extent_npoints(space.get());
  if (n < 0) failHdf5(ctx, "cannot read the shape of " + what);
  a.elements = static_cast<std::size_t>(n);
  return a;
}

std::string className(H5T_class_t cls) {
  switch (cls) {
    case H5T_INTEGER: return "an integer";
    case H5T_FLOAT: return "a float";
    case H5T_STRING: return "a string";
    case H5T_COMPOUND: return "a compound";
    case H5T_ENUM: return "an enum";
    case H5T_ARRAY: return "an array";
    case H5T_VLEN: return "a variable-length sequence";
    default: return "of an unsupported class";
  }
}

void expectElements(const OpenedAttribute& a, std::size_t n, const char* name, const Context& ctx,
                    const std::string& owner) {
  if (a.elements != n) {
    fail(ctx, owner + " attribute '" + name + "' has " + std::to_string(a.elements) +
                  (a.elements == 1 ? " element" : " elements") + ", expected " + std::to_string(n));
  }
}

std::vector<double> readNumbersImpl(hid_t obj, const char* name, std::size_t n, const Context& ctx,
                                    const std::string& owner) {
  const Lock lock;
  const OpenedAttribute a = openAttribute(obj, name, ctx, owner);
  if (a.cls != H5T_INTEGER && a.cls != H5T_FLOAT) {
    fail(ctx, owner + " attribute '" + name + "' is " + className(a.cls) + ", expected a number");
  }
  expectElements(a, n, name, ctx, owner);
  std::vector<double> v(n);
  check(H5Aread(a.attr.get(), H5T_NATIVE_DOUBLE, v.data()), ctx,
        "cannot read " + owner + " attribute '" + name + "'");
  return v;
}

}  // namespace

double readNumber(hid_t obj, const char* name, const Context& ctx, const std::string& owner) {
  return readNumbersImpl(obj, name, 1, ctx, owner)[0];
}

std::vector<double> readNumbers(hid_t obj, const char* name, std::size_t n, const Context& ctx,
                                const std::string& owner) {
  return readNumbersImpl(obj, name, n, ctx, owner);
}

std::vector<long long> readIntegers(hid_t obj, const char* name, std::size_t n, const Context& ctx,
                                    const std::string& owner) {
  const Lock lock;
  const OpenedAttribute a = openAttribute(obj, name, ctx, owner);
  if (a.cls != H5T_INTEGER) {
    fail(ctx, owner + " attribute '" + name + "' is " + className(a.cls) + ", expected an integer");
  }
  expectElements(a, n, name, ctx, owner);
  std::vector<long long> v(n);
  check(H5Aread(a.attr.get(), H5T_NATIVE_LLONG, v.data()), ctx,
        "cannot read " + owner + " attribute '" + name + "'");
  return v;
}

std::size_t readCount(hid_t obj, const char* name, const Context& ctx, const std::string& owner) {
  const long long v = readIntegers(obj, name, 1, ctx, owner)[0];
  if (v < 0) {
    fail(ctx, owner + " has " + name + " " + std::to_string(v) + ", expected >= 0");
  }
  return static_cast<std::size_t>(v);
}

namespace {

/// The longest text attribute read (16 MiB: provenance JSON is a few kB).
constexpr std::size_t kMaxStringBytes = std::size_t{16} << 20;
/// How long a variable-length string read may take before it is taken for a hang.
constexpr int kStringReadTimeoutMs = 10000;

/// Writes all of `data` to fd (a pipe), or returns false.
bool writeAll(int fd, const char* data, std::size_t n) {
  while (n > 0) {
    const ssize_t w = ::write(fd, data, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return false;
    data += w;
    n -= static_cast<std::size_t>(w);
  }
  return true;
}

/// Reads from fd until end of file, maxBytes + 1 bytes, or the deadline; false on a timeout.
bool readUntilEof(int fd, std::string& out, std::size_t maxBytes,
                  std::chrono::steady_clock::time_point deadline) {
  std::array<char, 4096> buf{};
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return false;
    pollfd pfd{fd, POLLIN, 0};
    const int ready = ::poll(&pfd, 1, static_cast<int>(left.count()));
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0) return false;  // the deadline passed, or poll() failed
    const ssize_t r = ::read(fd, buf.data(), buf.size());
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) return true;
    out.append(buf.data(), static_cast<std::size_t>(r));
    if (out.size() > maxBytes) return true;
  }
}

}  // namespace

namespace {

const char* const kHeapNote =
    " (a variable-length string, kept in the file's global heap, which has no checksum: "
    "the heap is damaged)";

/// How a child that read variable-length strings ended, for messages: the end of "cannot
/// read <owner> attribute '<name>'" for the attribute it was reading.
std::string childFailure(bool finished, int status) {
  if (!finished) {
    return ": HDF5 did not finish reading it within " +
           std::to_string(kStringReadTimeoutMs / 1000) + " s" + kHeapNote;
  }
  if (WIFSIGNALED(status)) {
    return ": HDF5 crashed reading it (signal " + std::to_string(WTERMSIG(status)) + ")" +
           kHeapNote;
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 2) return kHeapNote;  // HDF5's error
  // A sanitizer's report exits non-zero.
  return ": HDF5 crashed reading it (exit status " + std::to_string(WEXITSTATUS(status)) + ")" +
         kHeapNote;
}

std::string tooLong() {
  return ": it is longer than " + std::to_string(kMaxStringBytes) + " bytes" + kHeapNote;
}

/// A forked child of the caller, which holds the HDF5 lock (so no other thread of this
/// process is inside HDF5 when it forks): `body(fd)` runs in the child, writing to a pipe,
/// then the child exits with its return value without running any destructor or atexit
/// handler. The parent reads the pipe until end of file, `maxBytes` + 1 bytes or the
/// watchdog's deadline (then kills the child), and reaps the child.
struct ChildRead {
  std::string bytes;
  bool finished = false;  // false: the deadline passed
  int status = 0;         // waitpid()'s
};

template <class Body>
ChildRead readInChild(Body&& body, std::size_t maxBytes, const Context& ctx,
                      const std::string& what) {
  std::array<int, 2> fds{};
  if (::pipe2(fds.data(), O_CLOEXEC) != 0) {
    fail(ctx, what + ": pipe(): " + std::strerror(errno));
  }
#ifdef REGOLITH_SANITIZED
  // HDF5 reading a damaged global heap in the child is a memory error inside HDF5 that the
  // child exists to contain (the parent reports it as a damaged heap); a sanitizer reports it
  // in the child. With REGOLITH_SANDBOX_REPORTS set, those reports go to
  // "<its value>.<pid of the child>" instead of stderr, so a log of the tests holds only
  // the reports of the processes that must have none (scripts/test-all.sh fails on any).
  // Read before fork(): the child only makes the call.
  const char* sandboxReports = std::getenv("REGOLITH_SANDBOX_REPORTS");
#endif
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::close(fds[0]);
#ifdef REGOLITH_SANITIZED
    if (sandboxReports != nullptr && *sandboxReports != '\0') {
      __sanitizer_set_report_path(sandboxReports);
    }
#endif
    ::_exit(body(fds[1]));
  }
  ::close(fds[1]);
  if (pid < 0) {
    ::close(fds[0]);
    fail(ctx, what + ": fork(): " + std::strerror(errno));
  }
  ChildRead r;
  r.finished = readUntilEof(
      fds[0], r.bytes, maxBytes,
      std::chrono::steady_clock::now() + std::chrono::milliseconds(kStringReadTimeoutMs));
  ::close(fds[0]);
  if (!r.finished) ::kill(pid, SIGKILL);
  while (::waitpid(pid, &r.status, 0) < 0 && errno == EINTR) {
  }
  return r;
}

}  // namespace

std::string readVariableStringBounded(hid_t attr, hid_t mem, const Context& ctx,
                                      const std::string& owner, const char* name) {
  // Why a child process: a variable-length string lives in HDF5's global heap, which has no
  // checksum, and HDF5 1.10 crashes (a huge object size, in H5HG_read) or loops forever (a
  // free-space entry of size 0) on a damaged one; no HDF5 call validates a heap first.
  // Stores since format 1.4 write fixed-length strings (inside checksummed object
  // headers), so only older stores come here. The child reads the attribute and writes the
  // text to a pipe.
  const std::string what = "cannot read " + owner + " attribute '" + name + "'";
  const ChildRead r = readInChild(
      [&](int fd) {
        char* p = nullptr;
        if (H5Aread(attr, mem, static_cast<void*>(&p)) < 0) return 2;
        return p == nullptr || writeAll(fd, p, std::strlen(p)) ? 0 : 3;
      },
      kMaxStringBytes, ctx, what);
  if (r.finished && r.bytes.size() > kMaxStringBytes) fail(ctx, what + tooLong());
  if (!r.finished || !WIFEXITED(r.status) || WEXITSTATUS(r.status) != 0) {
    fail(ctx, what + childFailure(r.finished, r.status));
  }
  return r.bytes;
}

namespace {

// The batch's records on the pipe, in the order read: 'B' and the attribute's index (4
// bytes) before a read; then 'V', the text's length (8 bytes) and the text; or 'F' (HDF5's
// error) or 'L' (longer than kMaxStringBytes).
constexpr char kBegin = 'B', kValue = 'V', kHdf5Error = 'F', kTooLong = 'L';

thread_local VariableStringBatch* tlInnermostBatch = nullptr;

}  // namespace

VariableStringBatch::VariableStringBatch(hid_t obj, std::initializer_list<const char*> names,
                                         const Context& ctx)
    : obj_(obj), outcomes_(read(obj, names, ctx)), outer_(tlInnermostBatch) {
  tlInnermostBatch = this;  // last: a constructor that throws has no destructor to undo it
}

std::vector<std::pair<std::string, VariableStringBatch::Outcome>> VariableStringBatch::read(
    hid_t obj, std::initializer_list<const char*> names, const Context& ctx) {
  std::vector<std::pair<std::string, Outcome>> outcomes;
  const Lock lock;
  struct Pending {
    std::string name;
    Attribute attr;
    Datatype mem;
  };
  std::vector<Pending> todo;
  for (const char* name : names) {
    // Only what readString() would read in a child: one element of a variable-length
    // string. Anything else (or any HDF5 error here) is left to readString().
    if (H5Aexists(obj, name) <= 0) continue;
    Attribute attr(H5Aopen(obj, name, H5P_DEFAULT));
    if (!attr.valid()) continue;
    const Datatype type(H5Aget_type(attr.get()));
    const Dataspace space(H5Aget_space(attr.get()));
    if (!type.valid() || !space.valid() || H5Tget_class(type.get()) != H5T_STRING ||
        H5Tis_variable_str(type.get()) <= 0 || H5Sget_simple_extent_npoints(space.get()) != 1) {
      continue;
    }
    Datatype mem(H5Tcopy(H5T_C_S1));
    if (!mem.valid() || H5Tset_cset(mem.get(), H5Tget_cset(type.get())) < 0 ||
        H5Tset_size(mem.get(), H5T_VARIABLE) < 0) {
      continue;
    }
    todo.push_back({name, std::move(attr), std::move(mem)});
  }
  (void)takeErrorStack();  // lookups that failed are readString()'s to report
  if (todo.size() < 2) return outcomes;
  ChildRead r;
  try {
    r = readInChild(
        [&](int fd) {
          for (std::size_t i = 0; i < todo.size(); ++i) {
            std::array<char, 5> begin{kBegin};
            const auto index = static_cast<std::uint32_t>(i);
            std::memcpy(begin.data() + 1, &index, 4);
            if (!writeAll(fd, begin.data(), begin.size())) return 3;
            char* p = nullptr;
            const char* tag = &kValue;
            std::uint64_t n = 0;
            if (H5Aread(todo[i].attr.get(), todo[i].mem.get(), static_cast<void*>(&p)) < 0) {
              tag = &kHdf5Error;
            } else if (p != nullptr) {
              n = std::strlen(p);
              if (n > kMaxStringBytes) tag = &kTooLong;
            }
            if (!writeAll(fd, tag, 1)) return 3;
            if (*tag != kValue) continue;
            if (!writeAll(fd, reinterpret_cast<const char*>(&n), 8)) return 3;
            if (n > 0 && !writeAll(fd, p, static_cast<std::size_t>(n))) return 3;
          }
          return 0;
        },
        todo.size() * (kMaxStringBytes + 16), ctx, "cannot read text attributes");
  } catch (const StoreError&) {
    return outcomes;  // no pipe or no fork: each attribute's own read reports it, by name
  }
  // Parse the records; a record cut short ends the parse (the child failed there).
  std::size_t pos = 0;
  std::optional<std::size_t> reading;  // begun, with no outcome yet
  const std::string& b = r.bytes;
  while (pos < b.size()) {
    const char tag = b[pos];
    if (tag == kBegin) {
      std::uint32_t index = 0;
      if (b.size() - pos < 5) break;
      std::memcpy(&index, b.data() + pos + 1, 4);
      if (index >= todo.size()) break;
      reading = index;
      pos += 5;
      continue;
    }
    if (!reading) break;
    Outcome o;
    if (tag == kValue) {
      std::uint64_t n = 0;
      if (b.size() - pos < 9) break;
      std::memcpy(&n, b.data() + pos + 1, 8);
      if (b.size() - pos - 9 < n) break;
      o.text = b.substr(pos + 9, static_cast<std::size_t>(n));
      pos += 9 + static_cast<std::size_t>(n);
    } else if (tag == kHdf5Error || tag == kTooLong) {
      o.failed = true;
      o.text = tag == kTooLong ? tooLong() : std::string(kHeapNote);
      pos += 1;
    } else {
      break;
    }
    outcomes.emplace_back(todo[*reading].name, std::move(o));
    reading.reset();
  }
  // The attribute being read when the child crashed, hung or was cut off.
  const bool clean = r.finished && WIFEXITED(r.status) && WEXITSTATUS(r.status) == 0;
  if (reading && !clean) {
    outcomes.emplace_back(todo[*reading].name, Outcome{true, childFailure(r.finished, r.status)});
  }
  return outcomes;
}

VariableStringBatch::~VariableStringBatch() { tlInnermostBatch = outer_; }

const VariableStringBatch::Outcome* VariableStringBatch::find(hid_t obj, std::string_view name) {
  for (const VariableStringBatch* b = tlInnermostBatch; b != nullptr; b = b->outer_) {
    if (b->obj_ != obj) continue;
    for (const auto& [n, o] : b->outcomes_) {
      if (n == name) return &o;
    }
    return nullptr;
  }
  return nullptr;
}

std::string readString(hid_t obj, const char* name, const Context& ctx, const std::string& owner) {
  const Lock lock;
  const OpenedAttribute a = openAttribute(obj, name, ctx, owner);
  if (a.cls != H5T_STRING) {
    fail(ctx, owner + " attribute '" + name + "' is " + className(a.cls) + ", expected a string");
  }
  expectElements(a, 1, name, ctx, owner);
  const std::string what = "cannot read " + owner + " attribute '" + name + "'";
  const htri_t variable = H5Tis_variable_str(a.type.get());
  if (variable < 0) failHdf5(ctx, what);
  if (variable > 0) {
    if (const VariableStringBatch::Outcome* o = VariableStringBatch::find(obj, name)) {
      if (o->failed) fail(ctx, what + o->text);
      return o->text;
    }
  }
  const Datatype mem(check(H5Tcopy(H5T_C_S1), ctx, what));
  check(H5Tset_cset(mem.get(), H5Tget_cset(a.type.get())), ctx, what);
  if (variable > 0) {
    check(H5Tset_size(mem.get(), H5T_VARIABLE), ctx, what);
    return readVariableStringBounded(a.attr.get(), mem.get(), ctx, owner, name);
  }
  const std::size_t size = H5Tget_size(a.type.get());
  if (size == 0) failHdf5(ctx, what);
  if (size > kMaxStringBytes) {
    fail(ctx, owner + " attribute '" + name + "' is a string of " + std::to_string(size) +
                  " bytes, expected at most " + std::to_string(kMaxStringBytes));
  }
  check(H5Tset_size(mem.get(), size), ctx, what);
  check(H5Tset_strpad(mem.get(), H5T_STR_NULLPAD), ctx, what);
  std::string s(size, '\0');
  check(H5Aread(a.attr.get(), mem.get(), s.data()), ctx, what);
  // Fixed-length strings may be NUL- or space-padded.
  const std::size_t end = s.find('\0');
  if (end != std::string::npos) s.resize(end);
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s;
}

namespace {

void writeAttribute(hid_t obj, const char* name, hid_t fileType, hid_t memType, const void* data,
                    std::size_t n, bool scalar, const Context& ctx) {
  const Lock lock;
  const std::string what = std::string("cannot write attribute '") + name + "'";
  const hsize_t dims[1] = {static_cast<hsize_t>(n)};
  const Dataspace space(
      check(scalar ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, dims, nullptr), ctx, what));
  const Attribute attr(
      check(H5Acreate2(obj, name, fileType, space.get(), H5P_DEFAULT, H5P_DEFAULT), ctx, what));
  check(H5Awrite(attr.get(), memType, data), ctx, what);
}

}  // namespace

void writeDouble(hid_t obj, const char* name, double v, const Context& ctx) {
  writeAttribute(obj, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &v, 1, true, ctx);
}

void writeDoubles(hid_t obj, const char* name, const std::vector<double>& v, const Context& ctx) {
  writeAttribute(obj, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, v.data(), v.size(), false, ctx);
}

void writeFloat(hid_t obj, const char* name, float v, const Context& ctx) {
  writeAttribute(obj, name, H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, &v, 1, true, ctx);
}

void writeUInt64(hid_t obj, const char* name, std::uint64_t v, const Context& ctx) {
  writeAttribute(obj, name, H5T_STD_U64LE, H5T_NATIVE_UINT64, &v, 1, true, ctx);
}

void writeUInt64s(hid_t obj, const char* name, const std::vector<std::uint64_t>& v,
                  const Context& ctx) {
  writeAttribute(obj, name, H5T_STD_U64LE, H5T_NATIVE_UINT64, v.data(), v.size(), false, ctx);
}

void writeInt32(hid_t obj, const char* name, int v, const Context& ctx) {
  writeAttribute(obj, name, H5T_STD_I32LE, H5T_NATIVE_INT, &v, 1, true, ctx);
}

void writeInt32s(hid_t obj, const char* name, const std::vector<int>& v, const Context& ctx) {
  writeAttribute(obj, name, H5T_STD_I32LE, H5T_NATIVE_INT, v.data(), v.size(), false, ctx);
}

void writeString(hid_t obj, const char* name, const std::string& v, const Context& ctx) {
  // Fixed length (format 1.4): the text lives in the checksummed object header. A
  // variable-length string lives in HDF5's global heap, which has no checksum, and a damaged
  // heap crashes or hangs HDF5 1.10 when the attribute is read (readString()).
  const Lock lock;
  const std::string what = std::string("cannot write attribute '") + name + "'";
  const Datatype type(check(H5Tcopy(H5T_C_S1), ctx, what));
  check(H5Tset_size(type.get(), std::max<std::size_t>(v.size(), 1)), ctx, what);
  check(H5Tset_strpad(type.get(), H5T_STR_NULLPAD), ctx, what);
  check(H5Tset_cset(type.get(), H5T_CSET_UTF8), ctx, what);
  const std::string padded = v.empty() ? std::string(1, '\0') : v;
  writeAttribute(obj, name, type.get(), type.get(), padded.data(), 1, true, ctx);
}

std::string describeType(hid_t type) {
  const Lock lock;
  const H5T_class_t cls = H5Tget_class(type);
  const std::size_t bits = 8 * H5Tget_size(type);
  switch (cls) {
    case H5T_INTEGER:
      return (H5Tget_sign(type) == H5T_SGN_NONE ? "uint" : "int") + std::to_string(bits);
    case H5T_FLOAT: return "float" + std::to_string(bits);
    case H5T_STRING: return "string";
    case H5T_COMPOUND: return "compound";
    case H5T_ENUM: return "enum";
    case H5T_ARRAY: return "array";
    case H5T_VLEN: return "variable-length sequence";
    case H5T_OPAQUE: return "opaque";
    case H5T_BITFIELD: return "bitfield";
    case H5T_REFERENCE: return "reference";
    default: return "unknown type";
  }
}

}  // namespace regolith::store::hdf5
