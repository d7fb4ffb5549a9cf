#include "Hdf5.hpp"

#include <array>
#include <charconv>

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

herr_t collectError(unsigned /*n*/, const H5E_error2_t* err, void* data) {
  auto* out = static_cast<std::string*>(data);
  if (!out->empty()) out->append("; ");
  out->append(err->func_name != nullptr ? err->func_name : "?");
  out->append("(): ");
  out->append(err->desc != nullptr ? err->desc : "");
  return 0;
}

}  // namespace

std::string takeErrorStack() {
  const Lock lock;
  std::string out;
  (void)H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, collectError, &out);
  (void)H5Eclear2(H5E_DEFAULT);
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
  const Datatype mem(check(H5Tcopy(H5T_C_S1), ctx, what));
  check(H5Tset_cset(mem.get(), H5Tget_cset(a.type.get())), ctx, what);
  if (variable > 0) {
    check(H5Tset_size(mem.get(), H5T_VARIABLE), ctx, what);
    char* p = nullptr;
    check(H5Aread(a.attr.get(), mem.get(), static_cast<void*>(&p)), ctx, what);
    std::string s = p != nullptr ? std::string(p) : std::string();
    H5free_memory(p);
    return s;
  }
  const std::size_t size = H5Tget_size(a.type.get());
  if (size == 0) failHdf5(ctx, what);
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
  const Lock lock;
  const std::string what = std::string("cannot write attribute '") + name + "'";
  const Datatype type(check(H5Tcopy(H5T_C_S1), ctx, what));
  check(H5Tset_size(type.get(), H5T_VARIABLE), ctx, what);
  check(H5Tset_cset(type.get(), H5T_CSET_UTF8), ctx, what);
  const char* p = v.c_str();
  writeAttribute(obj, name, type.get(), type.get(), static_cast<const void*>(&p), 1, true, ctx);
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
