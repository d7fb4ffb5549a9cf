#include "AtomicFile.hpp"

#include <regolith/topo/Error.hpp>

#include <unistd.h>

#include <fstream>
#include <string>

namespace regolith::tools {

void writeFileAtomically(const std::filesystem::path& path,
                         const std::function<void(std::ostream&)>& write, bool binary) {
  namespace fs = std::filesystem;
  const fs::path tmp = path.string() + ".tmp-" + std::to_string(::getpid());
  try {
    if (path.has_parent_path()) fs::create_directories(path.parent_path());
    {
      std::ofstream out(tmp, binary ? std::ios::binary | std::ios::trunc : std::ios::trunc);
      if (!out) throw Error("writeFileAtomically(): " + tmp.string() + ": cannot create file");
      write(out);
      out.flush();
      if (!out)
        throw Error("writeFileAtomically(): " + tmp.string() + ": write failed (disk full?)");
    }
    fs::rename(tmp, path);
  } catch (const fs::filesystem_error& e) {
    std::error_code ignore;
    fs::remove(tmp, ignore);
    throw Error("writeFileAtomically(): " + path.string() + ": " + e.code().message());
  } catch (...) {
    std::error_code ignore;
    fs::remove(tmp, ignore);
    throw;
  }
}

}  // namespace regolith::tools
