#pragma once
// Commands that write a store refuse an output whose folder does not exist before doing any
// work (a long import or generation should not fail at the very end).

#include <string>
#include <string_view>

namespace regolith::tools {

/// Throws InvalidArgument "<command>: --out <out>: folder <dir> does not exist" unless the
/// folder of `out` (the current folder for a bare name) is an existing directory.
void requireOutputFolder(std::string_view command, const std::string& out);

}  // namespace regolith::tools
