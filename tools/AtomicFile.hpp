#pragma once
// Crash-safe file writes: the content goes to a temporary file beside the target, is
// flushed, and is renamed over the target only when complete, so a crash or a full disk
// never leaves a truncated file under the real name.

#include <filesystem>
#include <functional>
#include <ostream>

namespace regolith::tools {

/// Calls write(stream) on a temporary file, then renames it to `path`. Throws
/// regolith::Error naming the path on any I/O failure; the temporary is removed.
void writeFileAtomically(const std::filesystem::path& path,
                         const std::function<void(std::ostream&)>& write, bool binary);

}  // namespace regolith::tools
