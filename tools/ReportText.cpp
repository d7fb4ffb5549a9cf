#include "ReportText.hpp"

#include <charconv>
#include <cmath>

namespace regolith::tools {

std::string shortestNumber(double v) {
  if (std::isnan(v)) return "nan";
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return {buf, r.ptr};
}

std::vector<std::string> appliedCorrections(const store::ImportReport& r) {
  std::vector<std::string> c;
  if (r.offsetCorrected) {
    c.emplace_back(
        "PDS3 projection offsets read in the other convention (GDAL's default "
        "put the grid beyond a pole)");
  }
  if (r.spacingSnapped) {
    c.emplace_back(
        "global spacing snapped to the label's resolution (or 360/cols, 180/rows degrees)");
  }
  if (r.poleShiftPixels != 0.0) {
    c.emplace_back("pole-to-pole grid moved " + shortestNumber(r.poleShiftPixels) +
                   " px onto the poles (rounded map scale)");
  }
  if (r.droppedNorthRows + r.droppedSouthRows > 0) {
    c.emplace_back(
        "wholly missing rows beyond a pole dropped: " + std::to_string(r.droppedNorthRows) +
        " north, " + std::to_string(r.droppedSouthRows) + " south");
  }
  if (r.droppedColumns > 0) {
    c.emplace_back(std::to_string(r.droppedColumns) +
                   " columns beyond 360 deg of longitude dropped (equal to the first ones)");
  }
  if (r.voidMarkerAssumed) c.emplace_back("-32768 taken as missing (no nodata declared)");
  if (r.radiusReference != 0.0) {
    c.emplace_back("values are radii: " + shortestNumber(r.radiusReference) +
                   " m subtracted to give heights");
  }
  return c;
}

}  // namespace regolith::tools
