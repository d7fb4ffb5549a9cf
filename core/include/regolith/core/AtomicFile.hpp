#pragma once
/// \file
/// The one crash-safe file writer of Regolith. The content is written to a temporary file
/// beside the target, synced to the disk, renamed over the target, and the folder entry is
/// synced: after a crash, a kill or a full disk the target holds either its previous content
/// byte for byte or the complete new content, never a part.
///
/// The temporary is `<target>.tmp-<pid>-<n>`, with n a per-process counter, so two writers in
/// one process (threads) or in two processes never share one. It is removed whenever the
/// write fails or throws; only a process killed mid-write leaves it behind.
///
/// Thread-safety: any number of threads may write different targets at once.

#include <filesystem>
#include <functional>
#include <ostream>
#include <string_view>

namespace regolith::core {

/// The temporary name writeFileAtomically() will use next in this process for `target`
/// (`<target>.tmp-<pid>-<n>`). Each call returns a new name.
[[nodiscard]] std::filesystem::path temporaryPathFor(const std::filesystem::path& target);

/// Whether writeFileAtomically() makes the content durable.
enum class Durability {
  /// The temporary is synced before the rename and the folder after it (crash-safe).
  Durable,
  /// Renamed into place without syncing: for scratch files that a job deletes before it ends
  /// (regolith-mpi's part stores). A crash or power loss may leave one incomplete under its
  /// name; a target meant to outlive the job must never be written so.
  Scratch,
};

/// Calls write(temporary), where `temporary` is a fresh path beside `target` that does not
/// exist yet and that `write` creates and fills (for writers that take a file name: HDF5,
/// libpng through fopen). Then syncs the temporary, renames it over `target` and syncs the
/// folder. The folder of `target` must exist (IoError otherwise: a mistyped path is not a
/// new folder).
///
/// Throws regolith::IoError, whose message starts with `operation` and names the file and
/// the system's reason, when a step of the file system fails; an exception from `write`
/// passes through unchanged. The temporary is removed in both cases. Durability::Scratch skips
/// both syncs.
void writeFileAtomically(const std::filesystem::path& target,
                         const std::function<void(const std::filesystem::path&)>& write,
                         std::string_view operation, Durability durability = Durability::Durable);

/// fsync() of a file's data: for a writer that syncs its bulk early, while it waits for a
/// last detail, so that writeFileAtomically()'s own sync has little left to do (regolith-mpi's
/// join). Throws regolith::IoError starting with `operation` and naming the file.
void syncFile(const std::filesystem::path& file, std::string_view operation);

/// As above, for content written to a stream: write(stream) fills the temporary, opened in
/// binary mode. A stream that has failed after write() (a full disk) is an IoError.
void writeStreamAtomically(const std::filesystem::path& target,
                           const std::function<void(std::ostream&)>& write,
                           std::string_view operation);

}  // namespace regolith::core
