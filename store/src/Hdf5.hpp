#pragma once
/// \file
/// Private HDF5 plumbing of the store: move-only RAII handles for hid_t, the process-wide
/// lock that serialises HDF5 calls, the scoped silencing of HDF5's automatic error printing,
/// and the translation of HDF5's error stack into StoreError (tier 3 → tier 2,
/// docs/store-format.md). No hid_t leaves store/src.

#include <regolith/store/Store.hpp>

#include <hdf5.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <mutex>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace regolith::store::hdf5 {

/// The one process-wide mutex that serialises every HDF5 call Regolith makes. HDF5 keeps
/// global state (its identifier tables, its free lists, the per-file metadata caches); even
/// the thread-safe build takes one global lock inside. This is the only global in the store
/// module, and it is unavoidable: two Store objects on different files still share HDF5's
/// library state. Recursive so that a handle may be closed while the lock is held.
std::recursive_mutex& mutex();

/// Holds mutex() for a scope and silences HDF5's automatic error printing on this thread
/// for that scope (HDF5 keeps the setting per thread in its thread-safe build); the previous
/// setting is restored on exit, so an application's own HDF5 error handler survives.
class Lock {
 public:
  Lock();
  ~Lock();
  Lock(const Lock&) = delete;
  Lock& operator=(const Lock&) = delete;
  Lock(Lock&&) = delete;
  Lock& operator=(Lock&&) = delete;

 private:
  std::unique_lock<std::recursive_mutex> lock_;
  H5E_auto2_t oldFunc_ = nullptr;
  void* oldData_ = nullptr;
};

/// A move-only owner of one HDF5 identifier, closed with Close (taking the lock) on
/// destruction. An empty handle holds H5I_INVALID_HID.
template <herr_t (*Close)(hid_t)>
class Handle {
 public:
  Handle() noexcept = default;
  explicit Handle(hid_t id) noexcept : id_(id) {}
  Handle(Handle&& other) noexcept : id_(std::exchange(other.id_, H5I_INVALID_HID)) {}
  Handle& operator=(Handle&& other) noexcept {
    if (this != &other) {
      reset();
      id_ = std::exchange(other.id_, H5I_INVALID_HID);
    }
    return *this;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  ~Handle() { reset(); }

  [[nodiscard]] hid_t get() const noexcept { return id_; }
  [[nodiscard]] bool valid() const noexcept { return id_ >= 0; }
  /// Gives up ownership (the caller closes the identifier and checks the result).
  [[nodiscard]] hid_t release() noexcept { return std::exchange(id_, H5I_INVALID_HID); }
  /// Closes the identifier now (errors from the close are ignored: nothing can be done
  /// about them, and a write path flushes explicitly before closing).
  void reset() noexcept {
    if (id_ >= 0) {
      try {
        const Lock lock;
        (void)Close(id_);
      } catch (...) {  // NOLINT(bugprone-empty-catch): a failed close cannot be reported
      }
      id_ = H5I_INVALID_HID;
    }
  }

 private:
  hid_t id_ = H5I_INVALID_HID;
};

using File = Handle<H5Fclose>;
using Group = Handle<H5Gclose>;
using Dataset = Handle<H5Dclose>;
using Attribute = Handle<H5Aclose>;
using Dataspace = Handle<H5Sclose>;
using Datatype = Handle<H5Tclose>;
using PropertyList = Handle<H5Pclose>;
using Object = Handle<H5Oclose>;

/// HDF5's error stack of this thread as one line: its outermost entry (what failed) and its
/// innermost one (why), each condensed by condenseErrorDescription():
/// "H5Fopen(): unable to open file; ...; H5F__super_read(): truncated file: eof = 100000, ...".
/// Clears the stack. Empty if there is none.
[[nodiscard]] std::string takeErrorStack();

/// One HDF5 error description on one line: line breaks and runs of blanks become one space,
/// and a file driver's "file write failed: time = ..., filename = ..., errno = 28, error
/// message = 'No space left on device', ..." becomes "file write failed: No space left on
/// device (errno 28)" (the file, often a temporary, is named by the message around it).
[[nodiscard]] std::string condenseErrorDescription(std::string_view desc);

/// The context of one operation, for messages: "store::open(): /path/x.h5".
struct Context {
  std::string prefix;
  Context(std::string_view operation, const std::filesystem::path& path);
};

/// Throws StoreError("<prefix>: <what>").
[[noreturn]] void fail(const Context& ctx, const std::string& what);
/// Throws StoreError("<prefix>: <what> [HDF5: <error stack>]"), taking the stack.
[[noreturn]] void failHdf5(const Context& ctx, const std::string& what);

/// Returns id if it is valid, else throws failHdf5(ctx, what).
hid_t check(hid_t id, const Context& ctx, const std::string& what);
/// Throws failHdf5(ctx, what) if status < 0.
void check(herr_t status, const Context& ctx, const std::string& what);

/// Why filter `id` is not available and what to do about it, for messages: HDF5's plugin
/// directories and, for the H5Z-ZFP filter, the Debian package that installs it. Call with
/// the HDF5 lock held.
[[nodiscard]] std::string missingFilterHint(int id);

// ---- attributes ----------------------------------------------------------------------------
// Readers take the object's description for messages ("grid 'victoria'" or "the root group")
// and throw StoreError naming the attribute when it is missing or of the wrong class/shape.

[[nodiscard]] bool hasAttribute(hid_t obj, const char* name, const Context& ctx);
/// One number (integer or float class, one element), converted to double.
[[nodiscard]] double readNumber(hid_t obj, const char* name, const Context& ctx,
                                const std::string& owner);
/// Exactly n numbers (integer or float class), converted to double.
[[nodiscard]] std::vector<double> readNumbers(hid_t obj, const char* name, std::size_t n,
                                              const Context& ctx, const std::string& owner);
/// A non-negative integer (integer class, one element).
[[nodiscard]] std::size_t readCount(hid_t obj, const char* name, const Context& ctx,
                                    const std::string& owner);
/// Exactly n integers (integer class).
[[nodiscard]] std::vector<long long> readIntegers(hid_t obj, const char* name, std::size_t n,
                                                  const Context& ctx, const std::string& owner);
/// A variable-length string attribute read in a child process under a timeout (the
/// global heap it lives in has no checksum; see the definition). Call with the HDF5 lock
/// held; `mem` is a variable-length C string type.
[[nodiscard]] std::string readVariableStringBounded(hid_t attr, hid_t mem, const Context& ctx,
                                                    const std::string& owner, const char* name);
/// A string (fixed or variable length, one element). A variable-length one is answered by
/// the innermost VariableStringBatch of this thread that read it, else read on its own by
/// readVariableStringBounded().
[[nodiscard]] std::string readString(hid_t obj, const char* name, const Context& ctx,
                                     const std::string& owner);

/// Reads several variable-length string attributes of one object (a store before format
/// 1.4) in one child process under one 10 s watchdog, instead of one child per attribute:
/// a fork() is the main cost of opening an old store (7 per grid). While the batch lives,
/// readString() on this thread answers those attributes of `obj` from it: their text, or the
/// error the attribute's own bounded read would have given (HDF5's error, a crash, a timeout,
/// text over 16 MiB), named after the attribute that was being read when the child failed.
/// Attributes the child did not reach, and names that are missing, of another class or
/// shape, or fixed-length strings, are left to readString() (its own checks and messages).
/// Does nothing for fewer than two such attributes. Call with `obj` open for the batch's
/// life; the batch takes the HDF5 lock while it reads. Not copyable or movable; one thread.
class VariableStringBatch {
 public:
  VariableStringBatch(hid_t obj, std::initializer_list<const char*> names, const Context& ctx);
  ~VariableStringBatch();
  VariableStringBatch(const VariableStringBatch&) = delete;
  VariableStringBatch& operator=(const VariableStringBatch&) = delete;
  VariableStringBatch(VariableStringBatch&&) = delete;
  VariableStringBatch& operator=(VariableStringBatch&&) = delete;

  /// What the read of one attribute gave: its text, or (failed) the end of its error
  /// message after "cannot read <owner> attribute '<name>'".
  struct Outcome {
    bool failed = false;
    std::string text;
  };
  /// The outcome of attribute `name` of `obj` in this thread's innermost batch of `obj`, or
  /// nullptr if no batch of this thread read it.
  [[nodiscard]] static const Outcome* find(hid_t obj, std::string_view name);

 private:
  static std::vector<std::pair<std::string, Outcome>> read(hid_t obj,
                                                           std::initializer_list<const char*> names,
                                                           const Context& ctx);

  hid_t obj_;
  std::vector<std::pair<std::string, Outcome>> outcomes_;
  VariableStringBatch* outer_;
};

void writeDouble(hid_t obj, const char* name, double v, const Context& ctx);
void writeDoubles(hid_t obj, const char* name, const std::vector<double>& v, const Context& ctx);
void writeFloat(hid_t obj, const char* name, float v, const Context& ctx);
void writeUInt64(hid_t obj, const char* name, std::uint64_t v, const Context& ctx);
void writeUInt64s(hid_t obj, const char* name, const std::vector<std::uint64_t>& v,
                  const Context& ctx);
void writeInt32(hid_t obj, const char* name, int v, const Context& ctx);
void writeInt32s(hid_t obj, const char* name, const std::vector<int>& v, const Context& ctx);
/// A scalar variable-length UTF-8 string (h5py reads it as str).
void writeString(hid_t obj, const char* name, const std::string& v, const Context& ctx);

/// A short name of a datatype's class for messages: "string", "compound", "int16", ...
[[nodiscard]] std::string describeType(hid_t type);

}  // namespace regolith::store::hdf5
