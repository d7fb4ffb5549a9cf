#pragma once
// Text shared by the commands that describe grids and imports (info, import).

#include <regolith/store/Import.hpp>

#include <string>
#include <vector>

namespace regolith::tools {

/// Shortest text that reads back as the same double ("nan" for NaN).
[[nodiscard]] std::string shortestNumber(double v);

/// The corrections an import applied to what GDAL reports, one phrase each (empty: none):
/// the PDS3 projection-offset correction, the snapped global spacing, the assumed -32768
/// void marker, the subtracted radius reference.
[[nodiscard]] std::vector<std::string> appliedCorrections(const store::ImportReport& r);

}  // namespace regolith::tools
