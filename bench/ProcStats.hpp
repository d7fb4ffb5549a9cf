#pragma once
// What Linux says of this process (/proc/self): its resident set and the bytes it read from
// the disk, for the scale benchmarks (docs/scale.md). Each is 0 where /proc is not there.
#include <cstdint>
#include <fstream>
#include <string>

namespace regolith::bench {

/// A field of /proc/self/file ("key: value ..." lines), its first number; 0 if absent.
inline double procField(const char* file, const std::string& key) {
  std::ifstream in(std::string("/proc/self/") + file);
  std::string k;
  while (in >> k) {
    if (k == key) {
      double v = 0.0;
      in >> v;
      return v;
    }
    in.ignore(4096, '\n');
  }
  return 0.0;
}

/// VmHWM (the peak resident set) or VmRSS (now), MiB.
inline double statusMiB(const std::string& field) { return procField("status", field) / 1024.0; }

/// Bytes this process made the kernel read from storage (read_bytes of /proc/self/io: page
/// cache hits are not counted, so a store read again from a warm page cache reads 0).
inline double diskReadBytes() { return procField("io", "read_bytes:"); }

}  // namespace regolith::bench
