// gdal::Raster: one GDAL raster analysed into a GridInfo (docs/import.md has the rules) and
// read as heights in metres.
#include "GdalRaster.hpp"

#include <regolith/core/Error.hpp>
#include <regolith/core/FileIdentity.hpp>
#include <regolith/topo/Placement.hpp>
#include <regolith/topo/TopoPlanet.hpp>

#include "ImportChecks.hpp"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_json.h>
#include <cpl_string.h>
#include <cpl_vsi.h>
#include <ogr_srs_api.h>
#include <openssl/evp.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>

namespace regolith::store::gdal {

namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;
constexpr float kNan = std::numeric_limits<float>::quiet_NaN();
/// ISIS's float special pixels (NULL, LRS, LIS, HIS, HRS: 0xFF7FFFFB…0xFF7FFFFF) lie below
/// its VALID_MIN4 (0xFF7FFFFA, about −3.4028225e38); no height does.
constexpr double kIsisSpecialBelow = -3.40282255e38;

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

// The most samples one of the checks at open (rows beyond a pole, repeated columns) reads
// at once: 4 MiB of float32, whatever a header declares.
constexpr std::size_t kReadPieceSamples = std::size_t{1} << 20;

std::string number(double v) {
  std::ostringstream o;
  o.precision(12);
  o << v;
  return o.str();
}

/// The first string of a metadata domain (a label as JSON or XML), or "".
std::string metadataText(GDALDatasetH ds, const char* domain) {
  char** md = GDALGetMetadata(ds, domain);
  return md != nullptr && md[0] != nullptr ? std::string(md[0]) : std::string();
}

std::string colourName(GDALColorInterp c) { return lower(GDALGetColorInterpretationName(c)); }

/// "Mars" from "GCS_Mars", "Earth" for a terrestrial ellipsoid, else the datum's name.
std::string bodyName(OGRSpatialReferenceH srs, double semiMajor) {
  if (semiMajor > 6.35e6 && semiMajor < 6.4e6) return "Earth";
  const char* geogcs = OSRGetAttrValue(srs, "GEOGCS", 0);
  std::string name = geogcs != nullptr ? geogcs : "";
  if (name.rfind("GCS_", 0) == 0) name = name.substr(4);
  if (name.empty() || lower(name) == "unknown") {
    const char* datum = OSRGetAttrValue(srs, "DATUM", 0);
    name = datum != nullptr ? datum : "";
    if (name.rfind("D_", 0) == 0) name = name.substr(2);
  }
  if (name.empty() || lower(name) == "unknown") name = "unknown";
  return name;
}

double projParm(OGRSpatialReferenceH srs, const char* name, double fallback) {
  OGRErr err = OGRERR_NONE;
  const double v = OSRGetProjParm(srs, name, fallback, &err);
  return err == OGRERR_NONE ? v : fallback;
}

/// A label value: a number, a numeric string, or an object {"value": ..., "unit": ...} whose
/// unit, if any, is per degree.
std::optional<double> perDegree(const CPLJSONObject& o) {
  if (!o.IsValid()) return std::nullopt;
  if (o.GetType() == CPLJSONObject::Type::Object) {
    const std::string unit = lower(o.GetString("unit"));
    if (!unit.empty() && unit.find("deg") == std::string::npos) return std::nullopt;
    return perDegree(o.GetObj("value"));
  }
  double v = 0.0;
  switch (o.GetType()) {
    case CPLJSONObject::Type::Integer:
    case CPLJSONObject::Type::Long:
    case CPLJSONObject::Type::Double: v = o.ToDouble(); break;
    case CPLJSONObject::Type::String: v = CPLAtof(o.ToString().c_str()); break;
    default: return std::nullopt;
  }
  return std::isfinite(v) && v > 0.0 ? std::optional<double>(v) : std::nullopt;
}

/// The label's map resolution in pixels per degree: PDS3 IMAGE_MAP_PROJECTION.MAP_RESOLUTION,
/// ISIS3 IsisCube.Mapping.Scale (GDAL gives both labels as JSON).
std::optional<double> labelPixelsPerDegree(GDALDatasetH ds) {
  const std::pair<const char*, const char*> fields[] = {
      {"json:PDS", "IMAGE_MAP_PROJECTION/MAP_RESOLUTION"},
      {"json:ISIS3", "IsisCube/Mapping/Scale"}};
  for (const auto& [domain, path] : fields) {
    const std::string text = metadataText(ds, domain);
    if (text.empty()) continue;
    CPLJSONDocument doc;
    if (!doc.LoadMemory(text)) continue;
    if (auto v = perDegree(doc.GetRoot().GetObj(path))) return v;
  }
  return std::nullopt;
}

/// How far (pixels) a planet grid's pixel extent reaches beyond its farther pole (≤ 0 inside).
double poleOverhang(const GridInfo& i) {
  const double north = i.y0 + 0.5 * i.spacingY;
  const double south = i.y0 - (static_cast<double>(i.rows) - 0.5) * i.spacingY;
  return std::max(north - 90.0, -90.0 - south) / i.spacingY;
}

std::string rowsText(std::size_t first, std::size_t last) {
  return first == last ? "row " + std::to_string(first)
                       : "rows " + std::to_string(first) + "-" + std::to_string(last);
}

}  // namespace

double shiftOntoPoles(GridInfo& i) {
  // A pole-to-pole grid (rows × spacing = 180°) whose offsets, through a rounded map scale,
  // place it up to 0.9 pixel beyond a pole: its edges are the poles.
  if (i.kind != GridKind::Planet ||
      std::abs(static_cast<double>(i.rows) * i.spacingY - 180.0) > 1e-9 * 180.0) {
    return 0.0;
  }
  const double over = poleOverhang(i);
  if (!(over > topo::kPoleOverhangPixels && over <= 0.9)) return 0.0;
  const double y0 = 90.0 - 0.5 * i.spacingY;
  const double shift = (i.y0 - y0) / i.spacingY;
  i.y0 = y0;
  return shift;
}

void requireWithinPoles(const GridInfo& i, const std::string& prefix) {
  if (i.kind == GridKind::Planet && poleOverhang(i) > topo::kPoleOverhangPixels) {
    throw ImportError(prefix + ": georeferencing places the grid's edges at latitudes " +
                      number(i.y0 + 0.5 * i.spacingY) + " to " +
                      number(i.y0 - (static_cast<double>(i.rows) - 0.5) * i.spacingY) +
                      " deg, beyond a pole; expected within -90 to 90");
  }
}

bool globalToPlanet(GridInfo& info, std::optional<double> labelPixelsPerDegree) {
  const PlacementInfo& pl = info.placement;
  if (info.kind != GridKind::Dem || pl.kind != PlacementInfo::Kind::Equirectangular) return false;
  const double a = pl.projectionRadius;
  const double rows = static_cast<double>(info.rows), cols = static_cast<double>(info.cols);
  const double cosTs = std::cos(pl.latTrueScaleDeg.value_or(0.0) / kRadToDeg);
  const double dlon = info.spacingX / (a * cosTs) * kRadToDeg;
  const double dlat = info.spacingY / a * kRadToDeg;
  // The label's own resolution is the truth where it exists and agrees with the (rounded)
  // map scale. Labels print it rounded, and GDAL's writers derive it from the metres, so a
  // value within 1e-6 of 180°/rows is that value.
  std::optional<double> res;
  if (labelPixelsPerDegree && std::abs(1.0 / *labelPixelsPerDegree - dlat) <= 0.01 * dlat) {
    res = 1.0 / *labelPixelsPerDegree;
  }
  const double lonStep = res ? *res / cosTs : dlon;
  if (std::abs(cols * lonStep - 360.0) > 0.5 * lonStep) return false;
  // Global: a linear longitude/latitude grid at its exact resolution, every longitude once
  // (360°/cols), placed by the samples' offsets from the projection's origin (the map scale
  // in metres may be rounded).
  const double sx = 360.0 / cols;
  double sy = dlat;
  if (res) {
    sy = std::abs(rows * *res - 180.0) <= 1e-6 * 180.0 ? 180.0 / rows : *res;
  } else if (std::abs(rows * dlat - 180.0) <= 0.5 * dlat) {
    sy = 180.0 / rows;
  }
  info.x0 = pl.lonCentreDeg + info.x0 / info.spacingX * sx;
  info.y0 = pl.latOriginDeg + info.y0 / info.spacingY * sy;
  const bool snapped = sx != dlon || sy != dlat;
  info.spacingX = sx;
  info.spacingY = sy;
  info.kind = GridKind::Planet;
  info.placement = {};
  return snapped;
}

void registerOnce() {
  static std::once_flag once;
  std::call_once(once, [] { GDALAllRegister(); });
}

// ---- ErrorCapture ----------------------------------------------------------------------------

ErrorCapture::ErrorCapture() { CPLPushErrorHandlerEx(&ErrorCapture::handler, this); }

ErrorCapture::~ErrorCapture() { CPLPopErrorHandler(); }

std::string ErrorCapture::messages() const { return messages_; }

void ErrorCapture::handler(CPLErr cls, CPLErrorNum /*num*/, const char* msg) {
  if (cls != CE_Failure && cls != CE_Fatal) return;  // warnings and debug output are dropped
  auto* self = static_cast<ErrorCapture*>(CPLGetErrorHandlerUserData());
  if (self == nullptr || msg == nullptr) return;
  if (!self->messages_.empty()) self->messages_ += "; ";
  self->messages_ += msg;
}

// ---- Raster ----------------------------------------------------------------------------------

Raster::Raster(const std::filesystem::path& path, const ImportOptions& options,
               std::string operation, bool mosaicTile)
    : path_(path), prefix_(std::move(operation) + ": " + path.string()), tile_(mosaicTile) {
  registerOnce();
  open(options, false);
}

Raster::~Raster() = default;

void Raster::open(const ImportOptions& options, bool pdsShift) {
  ErrorCapture errors;
  // GDAL's PDS3 driver reads SAMPLE/LINE_PROJECTION_OFFSET in one of two conventions; its
  // documented options select the other one (thread-local, restored after the open).
  const char* keys[] = {"PDS_SampleProjOffset_Shift", "PDS_LineProjOffset_Shift"};
  std::string saved[2];
  bool had[2] = {false, false};
  if (pdsShift) {
    for (int i = 0; i < 2; ++i) {
      const char* v = CPLGetThreadLocalConfigOption(keys[i], nullptr);
      had[i] = v != nullptr;
      if (had[i]) saved[i] = v;
      CPLSetThreadLocalConfigOption(keys[i], "-0.5");
    }
  }
  GDALDatasetH ds =
      GDALOpenEx(path_.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY | GDAL_OF_VERBOSE_ERROR, nullptr,
                 nullptr, nullptr);
  if (pdsShift) {
    for (int i = 0; i < 2; ++i) {
      CPLSetThreadLocalConfigOption(keys[i], had[i] ? saved[i].c_str() : nullptr);
    }
  }
  if (ds == nullptr) {
    const std::string why = core::pathProblem(path_).value_or(
        "GDAL cannot open it as a raster" +
        (errors.messages().empty() ? std::string() : " (GDAL: " + errors.messages() + ")"));
    throw ImportError(prefix_ + ": " + why);
  }
  ds_.reset(ds);
  analyse(options);
  checkGeoreferencing(layout_.info, prefix_);
  // A planet grid reaching half a pixel or more beyond a pole: a PDS3 label in the other
  // offset convention (GDAL puts the MOLA MEGDR one pixel north and west).
  const GridInfo& i = layout_.info;
  if (!pdsShift && layout_.driver == "PDS" && i.kind == GridKind::Planet &&
      poleOverhang(i) >= 0.5) {
    ds_.reset();
    open(options, true);
    layout_.offsetCorrected = true;
    return;
  }
  resolvePoles();
  dropRepeatedColumns();
  applyWindow(options);
}

void Raster::applyWindow(const ImportOptions& options) {
  GridInfo& i = layout_.info;
  if (!options.body.empty()) i.bodyName = options.body;
  if (!options.window && !options.bbox) return;
  if (options.window && options.bbox) {
    throw ImportError(prefix_ + ": both a window and a bounding box given; expected one");
  }
  const SampleWindow w = options.window ? *options.window : windowOfBox(*options.bbox);
  if (w.rows == 0 || w.cols == 0 || w.row0 + w.rows > i.rows || w.col0 + w.cols > i.cols) {
    throw ImportError(prefix_ + ": window of " + std::to_string(w.rows) + " rows x " +
                      std::to_string(w.cols) + " cols from row " + std::to_string(w.row0) +
                      ", col " + std::to_string(w.col0) + " is empty or leaves the grid of " +
                      std::to_string(i.rows) + " rows x " + std::to_string(i.cols) +
                      " cols; expected a non-empty window inside it");
  }
  layout_.rowOffset += w.row0;
  layout_.colOffset += w.col0;
  i.x0 += static_cast<double>(w.col0) * i.spacingX;
  i.y0 -= static_cast<double>(w.row0) * i.spacingY;
  i.rows = w.rows;
  i.cols = w.cols;
  layout_.window = w;
}

SampleWindow Raster::windowOfBox(const std::array<double, 4>& box) const {
  const GridInfo& i = layout_.info;
  const auto [west, south, east, north] = box;
  const std::string text =
      number(west) + ", " + number(south) + ", " + number(east) + ", " + number(north);
  if (!(std::isfinite(west) && std::isfinite(east) && west < east && east - west <= 360.0 &&
        south < north && south >= -90.0 && north <= 90.0)) {
    throw ImportError(prefix_ + ": bounding box " + text +
                      " is not west < east (at most 360 deg apart), -90 <= south < north <= 90");
  }
  // The box in fractional grid columns (u) and rows (v).
  double u0 = 0.0, u1 = 0.0, v0 = 0.0, v1 = 0.0;
  if (i.kind == GridKind::Planet) {
    // West brought into the grid's 360° from its western edge; the box may not run past it.
    const double edge = i.x0 - 0.5 * i.spacingX;
    const double w = edge + (west - edge - 360.0 * std::floor((west - edge) / 360.0));
    u0 = (w - i.x0) / i.spacingX;
    u1 = (w + (east - west) - i.x0) / i.spacingX;
    const bool global = std::abs(static_cast<double>(i.cols) * i.spacingX - 360.0) <= 1e-9;
    if (global && u1 > static_cast<double>(i.cols) - 0.5) {
      throw ImportError(prefix_ + ": bounding box " + text + " crosses the grid's seam at " +
                        number(edge) + " deg longitude; expected a box within " + number(edge) +
                        " to " + number(edge + 360.0) + " (import the two sides apart)");
    }
    v0 = (i.y0 - north) / i.spacingY;
    v1 = (i.y0 - south) / i.spacingY;
  } else {
    // The box's outline through the placement: its rectangle in grid metres.
    const topo::Placement pl = placementOf(i);
    double xMin = std::numeric_limits<double>::infinity(), xMax = -xMin, yMin = xMin, yMax = -xMin;
    constexpr int kSteps = 64;
    for (int k = 0; k <= kSteps; ++k) {
      const double t = static_cast<double>(k) / kSteps;
      const double lon = west + t * (east - west), lat = south + t * (north - south);
      for (const auto& [la, lo] : {std::pair{south, lon}, std::pair{north, lon},
                                   std::pair{lat, west}, std::pair{lat, east}}) {
        glm::dvec3 p{};
        try {
          p = pl.fromGeodetic({la, lo, 0.0});
        } catch (const Error&) {
          continue;  // outside the projection's domain (the far side of a polar projection)
        }
        if (!(std::isfinite(p.x) && std::isfinite(p.y))) continue;
        xMin = std::min(xMin, p.x);
        xMax = std::max(xMax, p.x);
        yMin = std::min(yMin, p.y);
        yMax = std::max(yMax, p.y);
      }
    }
    u0 = (xMin - i.x0) / i.spacingX;
    u1 = (xMax - i.x0) / i.spacingX;
    v0 = (i.y0 - yMax) / i.spacingY;
    v1 = (i.y0 - yMin) / i.spacingY;
  }
  // Samples whose centres lie in the box (to 1e-9 of a sample), clipped to the grid.
  const double c0 = std::max(0.0, std::ceil(u0 - 1e-9));
  const double c1 = std::min(static_cast<double>(i.cols) - 1.0, std::floor(u1 + 1e-9));
  const double r0 = std::max(0.0, std::ceil(v0 - 1e-9));
  const double r1 = std::min(static_cast<double>(i.rows) - 1.0, std::floor(v1 + 1e-9));
  if (!(c0 <= c1 && r0 <= r1)) {
    throw ImportError(prefix_ + ": bounding box " + text +
                      " holds no sample centre of the grid; expected one that overlaps it");
  }
  return {static_cast<std::size_t>(r0), static_cast<std::size_t>(c0),
          static_cast<std::size_t>(r1 - r0) + 1, static_cast<std::size_t>(c1 - c0) + 1};
}

void Raster::resolvePoles() {
  GridInfo& i = layout_.info;
  const bool planet = i.kind == GridKind::Planet;
  const bool eqc = i.kind == GridKind::Dem &&
                   i.placement.kind == PlacementInfo::Kind::Equirectangular &&
                   i.placement.projectionRadius > 0.0;
  if (!planet && !eqc) return;  // other projections have no rows beyond a pole
  const double tol = topo::kPoleOverhangPixels;
  // A tile's edges are checked with the mosaic's (importTiles()), not tile by tile.
  if (!tile_) layout_.poleShiftPixels = shiftOntoPoles(i);
  // Latitude (degrees) of the centre of row r, and the pole tolerance in degrees.
  const double degPerY = planet ? 1.0 : kRadToDeg / i.placement.projectionRadius;
  const double lat0 = planet ? 0.0 : i.placement.latOriginDeg;
  const auto lat = [&](std::size_t r) {
    return lat0 + (i.y0 - static_cast<double>(r) * i.spacingY) * degPerY;
  };
  const double tolDeg = tol * i.spacingY * degPerY;
  std::size_t north = 0, south = 0;
  while (north < i.rows && lat(north) > 90.0 + tolDeg) ++north;
  while (south < i.rows - north && lat(i.rows - 1 - south) < -90.0 - tolDeg) ++south;
  if (north + south == i.rows) {
    throw ImportError(prefix_ + ": every row's centre lies beyond a pole (latitudes " +
                      number(lat(0)) + " to " + number(lat(i.rows - 1)) +
                      " deg); expected within -90 to 90");
  }
  // Rows beyond a pole are dropped when wholly missing (padding), and refused otherwise.
  const auto refuse = [&](std::size_t first, std::size_t last, const char* pole) {
    throw ImportError(prefix_ + ": " + rowsText(first, last) + " (centre latitude " +
                      number(lat(first)) + (first == last ? "" : " to " + number(lat(last))) +
                      " deg) lie beyond the " + pole +
                      " pole and hold valid samples; expected within -90 to 90 (wholly "
                      "missing rows beyond a pole are dropped)");
  };
  const std::size_t r0 = layout_.rowOffset, c0 = layout_.colOffset;
  if (north > 0 && !allMissing(r0, north, c0, i.cols)) refuse(0, north - 1, "north");
  if (south > 0 && !allMissing(r0 + i.rows - south, south, c0, i.cols)) {
    refuse(i.rows - south, i.rows - 1, "south");
  }
  layout_.rowOffset += north;
  layout_.droppedNorthRows += north;
  layout_.droppedSouthRows += south;
  i.y0 -= static_cast<double>(north) * i.spacingY;
  i.rows -= north + south;
  // What is left of a planet grid must lie within the poles as TopoPlanet requires.
  if (!tile_) requireWithinPoles(i, prefix_);
}

void Raster::dropRepeatedColumns() {
  GridInfo& i = layout_.info;
  if (i.kind != GridKind::Planet) return;
  const double span = static_cast<double>(i.cols) * i.spacingX;
  if (span <= 360.0 + 1e-9) return;  // TopoPlanet's bound
  // More than 360° of longitude: the columns from n on repeat the longitudes of 0… (360°
  // must be a whole number n of columns), and are dropped if they repeat their values too.
  const auto n = static_cast<std::size_t>(std::llround(360.0 / i.spacingX));
  const std::string spans = "grid spans " + number(span) + " deg of longitude in " +
                            std::to_string(i.cols) + " columns of " + number(i.spacingX) + " deg";
  if (n == 0 || n >= i.cols || std::abs(static_cast<double>(n) * i.spacingX - 360.0) > 1e-9) {
    throw ImportError(prefix_ + ": " + spans +
                      ", and no whole number of columns spans 360 deg; expected at most 360");
  }
  const std::size_t extra = i.cols - n;
  // Bands of up to 64 rows, and of fewer columns than kReadPieceSamples: the extra columns
  // of a hostile header can be 10^9 wide.
  const std::size_t width = std::min(extra, kReadPieceSamples);
  const std::size_t band =
      std::max<std::size_t>(1, std::min<std::size_t>(64, kReadPieceSamples / width));
  std::vector<float> head, tail;
  for (std::size_t r = 0; r < i.rows; r += band) {
    for (std::size_t c0 = 0; c0 < extra; c0 += width) {
      const std::size_t nr = std::min(band, i.rows - r), nc = std::min(width, extra - c0);
      head.resize(nr * nc);
      tail.resize(nr * nc);
      (void)readSource(layout_.rowOffset + r, layout_.colOffset + c0, nr, nc, head);
      (void)readSource(layout_.rowOffset + r, layout_.colOffset + n + c0, nr, nc, tail);
      for (std::size_t k = 0; k < head.size(); ++k) {
        const bool same = head[k] == tail[k] || (std::isnan(head[k]) && std::isnan(tail[k]));
        if (!same) {
          const std::size_t row = r + k / nc, col = n + c0 + k % nc;
          throw ImportError(prefix_ + ": " + spans + "; column " + std::to_string(col) +
                            " repeats the longitude of column " + std::to_string(col - n) +
                            " with another value (row " + std::to_string(row) + ": " +
                            number(static_cast<double>(tail[k])) + " vs " +
                            number(static_cast<double>(head[k])) +
                            " m); expected at most 360 deg, or repeated columns equal to the "
                            "first ones");
        }
      }
    }
  }
  layout_.droppedColumns = extra;
  i.cols = n;
}

bool Raster::allMissing(std::size_t row0, std::size_t nrows, std::size_t col0,
                        std::size_t ncols) const {
  // Row by row, in pieces of at most kReadPieceSamples: a header can declare rows of 10^9
  // samples (fuzz_import, stop 31: one read of the rows beyond a pole asked for 4 GB).
  std::vector<float> v;
  for (std::size_t r = 0; r < nrows; ++r) {
    for (std::size_t c = 0; c < ncols; c += kReadPieceSamples) {
      const std::size_t n = std::min(kReadPieceSamples, ncols - c);
      v.resize(n);
      if (readSource(row0 + r, col0 + c, 1, n, v) != n) return false;
    }
  }
  return true;
}

namespace {

/// Band 1 of a single-band raster of real numbers: what an elevation model is. Anything else
/// (several bands, a palette, complex samples) is refused, naming what the file holds.
GDALRasterBandH elevationBand(GDALDatasetH ds, const std::string& p) {
  const int bands = GDALGetRasterCount(ds);
  if (bands != 1) {
    std::string names;
    for (int b = 1; b <= bands; ++b) {
      names += (b > 1 ? ", " : "") +
               colourName(GDALGetRasterColorInterpretation(GDALGetRasterBand(ds, b)));
    }
    throw ImportError(p + ": has " + std::to_string(bands) + " bands" +
                      (bands > 0 ? " (" + names + ")" : std::string()) +
                      ", expected one elevation band" +
                      (bands >= 3 ? " (an RGB image is not a DEM)" : ""));
  }
  GDALRasterBandH band = GDALGetRasterBand(ds, 1);
  const GDALColorInterp ci = GDALGetRasterColorInterpretation(band);
  if (ci == GCI_PaletteIndex || GDALGetRasterColorTable(band) != nullptr) {
    throw ImportError(p + ": band 1 is a palette (colour-indexed) image, expected elevations");
  }
  const GDALDataType type = GDALGetRasterDataType(band);
  if (type == GDT_Unknown || GDALDataTypeIsComplex(type) != 0) {
    throw ImportError(p + ": band 1 has data type " + GDALGetDataTypeName(type) +
                      ", expected real numbers");
  }
  // GDAL reads a whole block to read any sample of it. A header of a few bytes can declare
  // rows of 10^9 samples in one block each (a fuzzed NOAA NGS geoid grid, 48 bytes, asked
  // for 4.5 GB), so the size of a block is refused before any read. Real products' blocks
  // are a row or a tile: a row of 1M float64 samples is 8 MiB.
  constexpr double kMaxBlockBytes = 256.0 * 1024 * 1024;
  int bx = 0, by = 0;
  GDALGetBlockSize(band, &bx, &by);
  const double blockBytes = static_cast<double>(bx) * static_cast<double>(by) *
                            static_cast<double>(GDALGetDataTypeSizeBytes(type));
  if (!(bx > 0 && by > 0 && blockBytes <= kMaxBlockBytes)) {
    throw ImportError(p + ": band 1 is stored in blocks of " + std::to_string(bx) + " x " +
                      std::to_string(by) + " samples of " + GDALGetDataTypeName(type) + " (" +
                      number(blockBytes / (1024.0 * 1024.0)) +
                      " MiB), expected at most 256 MiB per block (GDAL reads whole blocks)");
  }
  return band;
}

/// The band's heights: unit (m or km), scale and offset in metres, nodata, mask.
void analyseHeights(GDALRasterBandH band, const ImportOptions& options, Layout& l,
                    const std::string& p) {
  const std::string unit = lower(GDALGetRasterUnitType(band));
  double unitFactor = 1.0;
  if (unit == "km" || unit == "kilometer" || unit == "kilometers" || unit == "kilometre" ||
      unit == "kilometres") {
    unitFactor = 1000.0;
  } else if (!(unit.empty() || unit == "m" || unit == "meter" || unit == "meters" ||
               unit == "metre" || unit == "metres")) {
    throw ImportError(p + ": band 1 has unit '" + unit + "', expected metres (m) or km");
  }
  int ok = 0;
  const double scale = GDALGetRasterScale(band, &ok);
  l.scale = (ok != 0 ? scale : 1.0) * unitFactor;
  const double offset = GDALGetRasterOffset(band, &ok);
  l.offset = (ok != 0 ? offset : 0.0) * unitFactor;
  if (!(std::isfinite(l.scale) && l.scale != 0.0 && std::isfinite(l.offset))) {
    throw ImportError(p + ": band 1 has scale " + number(l.scale) + " and offset " +
                      number(l.offset) + ", expected a finite non-zero scale and finite offset");
  }
  int hasNodata = 0;
  const double nd = GDALGetRasterNoDataValue(band, &hasNodata);
  if (hasNodata != 0) l.declaredNodata = nd;
  l.extraNodata = options.nodata;
  const int maskFlags = GDALGetMaskFlags(band);
  l.readMask = (maskFlags & GMF_ALL_VALID) == 0 && maskFlags != GMF_NODATA;
  // The int16 void marker of SRTM-style DEMs, when the file declares no nodata at all.
  l.voidMarker = hasNodata == 0 && !l.readMask && !options.nodata;
}

/// The dataset's geotransform, which must be north-up: no rotation, dx > 0, dy < 0.
std::array<double, 6> northUpGeotransform(GDALDatasetH ds, const std::string& p) {
  std::array<double, 6> gt{};
  if (GDALGetGeoTransform(ds, gt.data()) != CE_None) {
    throw ImportError(p + ": has no geotransform, expected a georeferenced raster");
  }
  if (!std::all_of(gt.begin(), gt.end(), [](double v) { return std::isfinite(v); })) {
    throw ImportError(p + ": geotransform has a non-finite term (origin " + number(gt[0]) + ", " +
                      number(gt[3]) + ", pixel size " + number(gt[1]) + " x " + number(gt[5]) +
                      ", rotation " + number(gt[2]) + ", " + number(gt[4]) +
                      "), expected finite numbers");
  }
  if (gt[2] != 0.0 || gt[4] != 0.0) {
    throw ImportError(p + ": geotransform is rotated (terms " + number(gt[2]) + ", " +
                      number(gt[4]) + "), expected north-up");
  }
  if (!(gt[1] > 0.0 && gt[5] < 0.0)) {
    throw ImportError(p + ": geotransform has pixel size " + number(gt[1]) + " x " + number(gt[5]) +
                      ", expected north-up (dx > 0, dy < 0)");
  }
  return gt;
}

/// The body of the CRS: its radii (which must be positive), its name and the latitude type,
/// as the label declares it, else planetocentric on a sphere and planetodetic (geodetic) on
/// an ellipsoid.
void analyseBody(GDALDatasetH ds, OGRSpatialReferenceH srs, GridInfo& info, const std::string& p) {
  OGRErr err = OGRERR_NONE;
  const double a = OSRGetSemiMajor(srs, &err);
  const double b = OSRGetSemiMinor(srs, &err);
  if (!(a > 0.0 && b > 0.0)) {
    throw ImportError(p + ": CRS has ellipsoid radii " + number(a) + " / " + number(b) +
                      " m, expected > 0");
  }
  info.equatorialRadius = a;
  info.polarRadius = b;
  info.bodyName = bodyName(srs, a);
  const std::string label = lower(metadataText(ds, "json:ISIS3") + metadataText(ds, "json:PDS") +
                                  metadataText(ds, "xml:PDS4"));
  const bool detic = label.find("planetographic") != std::string::npos ||
                     label.find("planetodetic") != std::string::npos;
  const bool centric = !detic && (label.find("planetocentric") != std::string::npos || a == b);
  info.latitudeType =
      centric ? topo::LatitudeType::Planetocentric : topo::LatitudeType::Planetodetic;
}

/// A geographic CRS: a planet grid in degrees, its spacing snapped onto 360°/cols and
/// 180°/rows when the grid spans the globe to within half a sample.
void placeGeographic(OGRSpatialReferenceH srs, const std::array<double, 6>& gt, Layout& l) {
  GridInfo& info = l.info;
  const double rows = static_cast<double>(info.rows), cols = static_cast<double>(info.cols);
  const double f = OSRGetAngularUnits(srs, nullptr) * kRadToDeg;  // degrees per unit
  const double pm = OSRGetPrimeMeridian(srs, nullptr);
  double dx = gt[1] * f, dy = -gt[5] * f;
  if (std::abs(cols * dx - 360.0) <= 0.5 * dx && cols * dx != 360.0) {
    dx = 360.0 / cols;
    l.spacingSnapped = true;
  }
  if (std::abs(rows * dy - 180.0) <= 0.5 * dy && rows * dy != 180.0) {
    dy = 180.0 / rows;
    l.spacingSnapped = true;
  }
  info.kind = GridKind::Planet;
  info.spacingX = dx;
  info.spacingY = dy;
  info.x0 = pm + (gt[0] / gt[1] + 0.5) * dx;
  info.y0 = (gt[3] / -gt[5] - 0.5) * dy;
}

/// A projected CRS: a DEM in the projection's map coordinates, with an analytic placement
/// for the projections topo has (equirectangular on a sphere, polar stereographic, transverse
/// Mercator) and one through PROJ for the others. A global equirectangular grid that is not
/// a mosaic's tile becomes a planet grid. Sets the report's projection: "<CRS> (<method>)".
void placeProjected(OGRSpatialReferenceH srs, const std::array<double, 6>& gt, Layout& l,
                    const std::string& crs, bool tile, const std::string& p) {
  GridInfo& info = l.info;
  const double a = info.equatorialRadius, b = info.polarRadius;
  const char* m = OSRGetAttrValue(srs, "PROJECTION", 0);
  const std::string method = m != nullptr ? m : "unknown";
  l.projection = crs + " (" + method + ")";
  const double lf = OSRGetLinearUnits(srs, nullptr);  // metres per unit
  const double dxM = gt[1] * lf, dyM = -gt[5] * lf;
  const double fe = projParm(srs, SRS_PP_FALSE_EASTING, 0.0) * lf;
  const double fn = projParm(srs, SRS_PP_FALSE_NORTHING, 0.0) * lf;
  const double lon0 = projParm(srs, SRS_PP_CENTRAL_MERIDIAN, 0.0);
  const double lat0 = projParm(srs, SRS_PP_LATITUDE_OF_ORIGIN, 0.0);
  PlacementInfo& pl = info.placement;
  if (method == SRS_PT_EQUIRECTANGULAR && a == b) {
    const double latTs = projParm(srs, SRS_PP_STANDARD_PARALLEL_1, 0.0);
    info.kind = GridKind::Dem;
    pl.kind = PlacementInfo::Kind::Equirectangular;
    pl.projectionRadius = a;
    pl.latTrueScaleDeg = latTs;
    pl.lonCentreDeg = lon0;
    pl.latOriginDeg = lat0;
    info.spacingX = dxM;
    info.spacingY = dyM;
    info.x0 = gt[0] * lf + 0.5 * dxM - fe;
    info.y0 = gt[3] * lf - 0.5 * dyM - fn;
    // A mosaic's tiles: the mosaic as a whole becomes a planet grid (importTiles()).
    if (!tile) l.spacingSnapped = globalToPlanet(info, l.labelPixelsPerDegree);
  } else if (method == SRS_PT_POLAR_STEREOGRAPHIC ||
             ((method == SRS_PT_STEREOGRAPHIC || method == SRS_PT_OBLIQUE_STEREOGRAPHIC) &&
              std::abs(lat0) == 90.0)) {
    info.kind = GridKind::Dem;
    pl.kind = PlacementInfo::Kind::PolarStereographic;
    pl.pole = lat0 >= 0.0 ? 1 : -1;
    if (std::abs(lat0) == 90.0) {
      pl.scaleFactor = projParm(srs, SRS_PP_SCALE_FACTOR, 1.0);
    } else {
      pl.latTrueScaleDeg = lat0;  // variant B: latitude_of_origin is the true-scale latitude
    }
    pl.lonCentreDeg = lon0;
    pl.falseEasting = fe;
    pl.falseNorthing = fn;
    info.spacingX = dxM;
    info.spacingY = dyM;
    info.x0 = gt[0] * lf + 0.5 * dxM;
    info.y0 = gt[3] * lf - 0.5 * dyM;
  } else if (method == SRS_PT_TRANSVERSE_MERCATOR) {
    // Transverse Mercator (EPSG 9807), UTM zones north and south among them; x, y stay the
    // file's map coordinates, false easting/northing included, as for polar stereographic.
    info.kind = GridKind::Dem;
    pl.kind = PlacementInfo::Kind::TransverseMercator;
    pl.lonCentreDeg = lon0;
    pl.latOriginDeg = lat0;
    pl.scaleFactor = projParm(srs, SRS_PP_SCALE_FACTOR, 1.0);
    pl.falseEasting = fe;
    pl.falseNorthing = fn;
    info.spacingX = dxM;
    info.spacingY = dyM;
    info.x0 = gt[0] * lf + 0.5 * dxM;
    info.y0 = gt[3] * lf - 0.5 * dyM;
  } else {
    placeThroughProj(srs, gt, lf, info, p, l.projection);  // anything else PROJ knows
  }
}

}  // namespace

void Raster::analyse(const ImportOptions& options) {
  GDALDatasetH ds = ds_.get();
  const std::string& p = prefix_;
  Layout l;
  l.driver = GDALGetDriverShortName(GDALGetDatasetDriver(ds));
  band_ = elevationBand(ds, p);
  GridInfo& info = l.info;
  info.rows = static_cast<std::size_t>(GDALGetRasterYSize(ds));
  info.cols = static_cast<std::size_t>(GDALGetRasterXSize(ds));
  info.patchRows = options.patchRows;
  info.patchCols = options.patchCols;
  info.name = options.gridName.empty() ? path_.stem().string() : options.gridName;
  analyseHeights(band_, options, l, p);
  // No CRS: a height map placed by the caller, or refused naming the options (HeightMap.cpp).
  if (GDALGetSpatialRef(ds) == nullptr || options.heightMap) {
    placeHeightMap(ds, options, l, p);
    layout_ = std::move(l);
    return;  // heights by definition: no look for radii
  }

  const std::array<double, 6> gt = northUpGeotransform(ds, p);
  OGRSpatialReferenceH srs = GDALGetSpatialRef(ds);
  if (srs == nullptr) {
    throw ImportError(p + ": has no coordinate reference system");
  }
  l.srs = srs;
  analyseBody(ds, srs, info, p);
  l.labelPixelsPerDegree = labelPixelsPerDegree(ds);
  const char* crsName = OSRGetName(srs);
  const std::string crs = crsName != nullptr ? crsName : "unnamed CRS";
  if (OSRIsGeographic(srs) != 0) {
    placeGeographic(srs, gt, l);
    l.projection = crs + " (geographic)";
  } else if (OSRIsProjected(srs) != 0) {
    placeProjected(srs, gt, l, crs, tile_, p);
  } else {
    throw ImportError(p + ": CRS '" + crs + "' is neither geographic nor projected");
  }
  layout_ = std::move(l);
  detectRadii();
}

void Raster::detectRadii() {
  // A look at about 16×16 samples (nearest) of the values after scale/offset, taken from at
  // most 16 of the file's blocks: up to 4×4 blocks spread over the raster (16 strips of a
  // striped file), up to 4×4 samples spread over each. A look spread evenly over the raster
  // reads a block per sample: 256 tiles of a tiled GeoTIFF, 64 MiB of an 8192² float one and
  // 0.3 s at every open (docs/scale.md, "Stop 42").
  int blockX = 0, blockY = 0;
  GDALGetBlockSize(band_, &blockX, &blockY);
  const std::size_t w = cols(), h = rows();
  const std::size_t bw =
      std::clamp<std::size_t>(static_cast<std::size_t>(std::max(blockX, 1)), 1, w);
  const std::size_t bh =
      std::clamp<std::size_t>(static_cast<std::size_t>(std::max(blockY, 1)), 1, h);
  const std::size_t nbx = (w + bw - 1) / bw, nby = (h + bh - 1) / bh;
  std::size_t kc = std::min<std::size_t>(nbx, 4);
  const std::size_t kr = std::min<std::size_t>(nby, 16 / kc);
  kc = std::min<std::size_t>(nbx, 16 / kr);
  // The k of n blocks: the first, the last and evenly between (the middle one when k is 1).
  const auto spread = [](std::size_t i, std::size_t k, std::size_t n) {
    return k == 1 ? (n - 1) / 2 : i * (n - 1) / (k - 1);
  };
  std::vector<double> v, block;
  std::vector<unsigned char> m, blockMask;
  ErrorCapture errors;
  for (std::size_t i = 0; i < kr; ++i) {
    for (std::size_t j = 0; j < kc; ++j) {
      const std::size_t y0 = spread(i, kr, nby) * bh, x0 = spread(j, kc, nbx) * bw;
      const std::size_t ww = std::min(bw, w - x0), hh = std::min(bh, h - y0);
      const std::size_t sc = std::min(ww, 16 / kc), sr = std::min(hh, 16 / kr);
      block.assign(sr * sc, 0.0);
      blockMask.assign(sr * sc, 1);
      const auto at = [](std::size_t n) { return static_cast<int>(n); };
      if (GDALRasterIO(band_, GF_Read, at(x0), at(y0), at(ww), at(hh), block.data(), at(sc), at(sr),
                       GDT_Float64, 0, 0) != CE_None ||
          (layout_.readMask &&
           GDALRasterIO(GDALGetMaskBand(band_), GF_Read, at(x0), at(y0), at(ww), at(hh),
                        blockMask.data(), at(sc), at(sr), GDT_Byte, 0, 0) != CE_None)) {
        throw ImportError(prefix_ + ": cannot read band 1 (GDAL: " + errors.messages() + ")");
      }
      v.insert(v.end(), block.begin(), block.end());
      m.insert(m.end(), blockMask.begin(), blockMask.end());
    }
  }
  double lo = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < v.size(); ++i) {
    const double raw = v[i];
    if (m[i] == 0 || std::isnan(raw) || raw < kIsisSpecialBelow ||
        (layout_.declaredNodata && raw == *layout_.declaredNodata) ||
        (layout_.extraNodata && raw == *layout_.extraNodata) ||
        (layout_.voidMarker && raw == -32768.0)) {
      continue;
    }
    lo = std::min(lo, layout_.offset + layout_.scale * raw);
  }
  const GridInfo& info = layout_.info;
  // With no valid sample in that look, the offset decides (ISIS radii carry Base = radius).
  if (!std::isfinite(lo)) lo = layout_.offset;
  if (lo > 0.5 * info.equatorialRadius) {
    if (info.equatorialRadius != info.polarRadius) {
      throw ImportError(prefix_ + ": values (from " + number(lo) +
                        " m) are radii, but the CRS's body is an ellipsoid; radii are supported "
                        "on a sphere only");
    }
    layout_.radiusReference = info.equatorialRadius;
  }
}

float Raster::sample(std::size_t row, std::size_t col) const {
  float v = 0.0F;
  readWindow(row, col, 1, 1, {&v, 1});
  return v;
}

void Raster::readWindow(std::size_t row0, std::size_t col0, std::size_t nrows, std::size_t ncols,
                        std::span<float> out) const {
  std::size_t voids = 0;
  missing_ +=
      readSource(row0 + layout_.rowOffset, col0 + layout_.colOffset, nrows, ncols, out, &voids);
  voids_ += voids;
}

std::size_t Raster::readSource(std::size_t row0, std::size_t col0, std::size_t nrows,
                               std::size_t ncols, std::span<float> out, std::size_t* voids) const {
  const std::size_t n = nrows * ncols;
  const Layout& l = layout_;
  const double base = l.offset - l.radiusReference;
  // Float32 heights in metres as they are: read straight into `out` (the same values as
  // through double, without the conversion).
  const bool direct = GDALGetRasterDataType(band_) == GDT_Float32 && l.scale == 1.0 && base == 0.0;
  thread_local std::vector<double> values;
  thread_local std::vector<unsigned char> mask;
  if (!direct) values.resize(n);
  if (l.readMask) mask.resize(n);
  {
    // Only GDAL's reads are serialised; the conversion below runs on the caller's thread.
    const std::lock_guard lock(mutex_);
    ErrorCapture errors;
    const auto x = static_cast<int>(col0), y = static_cast<int>(row0);
    const auto w = static_cast<int>(ncols), h = static_cast<int>(nrows);
    const CPLErr rc =
        direct ? GDALRasterIO(band_, GF_Read, x, y, w, h, out.data(), w, h, GDT_Float32, 0, 0)
               : GDALRasterIO(band_, GF_Read, x, y, w, h, values.data(), w, h, GDT_Float64, 0, 0);
    if (rc != CE_None) {
      throw ImportError(prefix_ + ": cannot read rows " + std::to_string(row0) + "-" +
                        std::to_string(row0 + nrows - 1) + ", cols " + std::to_string(col0) + "-" +
                        std::to_string(col0 + ncols - 1) + " (GDAL: " + errors.messages() + ")");
    }
    if (l.readMask && GDALRasterIO(GDALGetMaskBand(band_), GF_Read, x, y, w, h, mask.data(), w, h,
                                   GDT_Byte, 0, 0) != CE_None) {
      throw ImportError(prefix_ + ": cannot read the mask of rows " + std::to_string(row0) + "-" +
                        std::to_string(row0 + nrows - 1) + " (GDAL: " + errors.messages() + ")");
    }
  }
  std::size_t missing = 0, voidCount = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double raw = direct ? static_cast<double>(out[i]) : values[i];
    const bool isVoid = l.voidMarker && raw == -32768.0;
    voidCount += isVoid ? 1 : 0;
    const bool isMissing =
        isVoid || std::isnan(raw) || raw < kIsisSpecialBelow || (l.readMask && mask[i] == 0) ||
        (l.declaredNodata && raw == *l.declaredNodata) || (l.extraNodata && raw == *l.extraNodata);
    if (isMissing) {
      out[i] = kNan;
      ++missing;
    } else if (!direct) {
      // Offset and radius first: a radius of 1737400 m and a height of 0.5 m meet in double.
      out[i] = static_cast<float>(base + l.scale * raw);
    }
  }
  if (voids != nullptr) *voids = voidCount;
  return missing;
}

}  // namespace regolith::store::gdal

namespace regolith::store::gdal {

namespace {

struct DigestCloser {
  void operator()(EVP_MD_CTX* c) const noexcept { EVP_MD_CTX_free(c); }
};

/// Size and SHA-256 (lower-case hex) of a file read through GDAL's virtual file layer.
std::pair<std::uint64_t, std::string> sizeAndSha256(const std::string& path,
                                                    const std::string& prefix) {
  VSILFILE* f = VSIFOpenL(path.c_str(), "rb");
  if (f == nullptr) throw ImportError(prefix + ": cannot read " + path + " to record its digest");
  std::unique_ptr<EVP_MD_CTX, DigestCloser> ctx(EVP_MD_CTX_new());
  bool ok = ctx && EVP_DigestInit_ex(ctx.get(), EVP_sha256(), nullptr) == 1;
  std::vector<unsigned char> buf(std::size_t{1} << 20);
  std::uint64_t bytes = 0;
  while (ok) {
    const std::size_t n = VSIFReadL(buf.data(), 1, buf.size(), f);
    if (n == 0) break;
    bytes += n;
    ok = EVP_DigestUpdate(ctx.get(), buf.data(), n) == 1;
  }
  VSIFCloseL(f);
  std::array<unsigned char, EVP_MAX_MD_SIZE> md{};
  unsigned len = 0;
  if (!ok || EVP_DigestFinal_ex(ctx.get(), md.data(), &len) != 1) {
    throw ImportError(prefix + ": cannot compute the SHA-256 digest of " + path);
  }
  static constexpr char kHex[] = "0123456789abcdef";
  std::string hex;
  for (unsigned i = 0; i < len; ++i) {
    hex += kHex[md[i] >> 4];
    hex += kHex[md[i] & 15];
  }
  return {bytes, hex};
}

/// Size of a file through GDAL's virtual file layer.
std::uint64_t fileSize(const std::string& path, const std::string& prefix) {
  VSIStatBufL st{};
  if (VSIStatL(path.c_str(), &st) != 0) {
    throw ImportError(prefix + ": cannot read " + path + " to record its size");
  }
  return static_cast<std::uint64_t>(st.st_size);
}

}  // namespace

std::vector<std::filesystem::path> Raster::files() const {
  const std::lock_guard lock(mutex_);
  std::vector<std::filesystem::path> out{path_};
  char** files = GDALGetFileList(ds_.get());
  for (char** f = files; f != nullptr && *f != nullptr; ++f) out.emplace_back(*f);
  CSLDestroy(files);
  return out;
}

std::string Raster::provenance(bool digests) const {
  const std::lock_guard lock(mutex_);
  GDALDatasetH ds = ds_.get();
  CPLJSONObject root;
  CPLJSONArray sources;
  char** files = GDALGetFileList(ds);
  for (char** f = files; f != nullptr && *f != nullptr; ++f) {
    CPLJSONObject s;
    s.Add("file", std::filesystem::path(*f).filename().string());
    s.Add("path", std::string(*f));
    if (digests) {
      const auto [bytes, sha] = sizeAndSha256(*f, prefix_);
      s.Add("bytes", static_cast<GInt64>(bytes));
      s.Add("sha256", sha);
    } else {
      s.Add("bytes", static_cast<GInt64>(fileSize(*f, prefix_)));
    }
    sources.Add(s);
  }
  CSLDestroy(files);
  root.Add("sources", sources);
  root.Add("gdal_driver", layout_.driver);
  root.Add("gdal_version", std::string(GDALVersionInfo("RELEASE_NAME")));
  // The label fields that decided the georeferencing.
  const std::pair<const char*, const char*> groups[] = {{"json:PDS", "IMAGE_MAP_PROJECTION"},
                                                        {"json:ISIS3", "IsisCube/Mapping"}};
  for (const auto& [domain, path] : groups) {
    const std::string text = metadataText(ds, domain);
    CPLJSONDocument doc;
    if (text.empty() || !doc.LoadMemory(text)) continue;
    const CPLJSONObject group = doc.GetRoot().GetObj(path);
    if (group.IsValid()) root.Add("label", group);
  }
  CPLJSONArray gt;
  std::array<double, 6> g{};
  if (GDALGetGeoTransform(ds, g.data()) == CE_None) {
    for (const double v : g) gt.Add(v);
  }
  root.Add("geotransform", gt);
  char* wkt = nullptr;
  const char* options[] = {"FORMAT=WKT2_2019", nullptr};
  if (layout_.srs != nullptr && OSRExportToWktEx(layout_.srs, &wkt, options) == OGRERR_NONE) {
    root.Add("crs_wkt", std::string(wkt));
  }
  CPLFree(wkt);
  return root.Format(CPLJSONObject::PrettyFormat::Plain);
}

}  // namespace regolith::store::gdal
