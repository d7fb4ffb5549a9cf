#pragma once
// `regolith query CATALOGUE [points...]`: composed heights and normals of a catalogue file's
// datasets (compose::ComposedSurface, docs/cli.md), or with --explain each point's shares.

#include <regolith/topo/Query.hpp>

#include "PointsCsv.hpp"

#include <cstddef>
#include <span>
#include <string>

namespace regolith::tools {

/// What a query on a catalogue file needs besides its points.
struct CatalogueQueryOptions {
  std::string file;  ///< the catalogue file (JSON)
  topo::NormalFrame frame = topo::NormalFrame::Grid;
  bool explain = false;  ///< print each point's shares instead of heights and normals
  std::size_t cacheMb = 256;
};

/// Reads the catalogue file (compose::readCatalogueFile(), its errors as they are), refuses a
/// standard output that is one of its stores, then prints CSV for `points` (lon, lat in
/// degrees, planetodetic latitude; already checked finite and within ±90°) on stdout.
void runCatalogueQuery(const CatalogueQueryOptions& options, std::span<const Point> points);

}  // namespace regolith::tools
