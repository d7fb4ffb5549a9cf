#pragma once
// Catalogue files (compose::readCatalogueFile(), docs/composition.md) on the command line:
// how `info` and `query` tell one from a store, and what `info` prints about one.

#include <filesystem>
#include <iosfwd>

namespace regolith::tools {

/// True if `path` is a regular file that is not HDF5 and whose first character, after
/// white space and a UTF-8 byte-order mark, is '{': a JSON object, which is what a catalogue
/// file is. Does not parse it (readCatalogueFile() does, with its own errors).
[[nodiscard]] bool isCatalogueFile(const std::filesystem::path& path);

/// `regolith info` on a catalogue file: its body, rules and datasets (name, kind, placement,
/// size and spacing, role, priority, feather, mask, height range, extent and body-fixed
/// bounds), as text or as JSON (keys in docs/cli.md). Reads the file and opens its stores;
/// throws what compose::readCatalogueFile() throws.
void printCatalogueInfo(const std::filesystem::path& path, bool json, std::ostream& out);

}  // namespace regolith::tools
