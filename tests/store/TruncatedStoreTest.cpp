// A store file truncated while it is open (issue 17, docs/reliability.md "Disk full and read
// errors"): every read path gives a regolith::Error naming the file, never a crash or a
// silent value. The file is truncated for real (std::filesystem::resize_file) after
// Store::open, so HDF5 holds the metadata it read and finds the chunks gone.
#include <regolith/core/Error.hpp>
#include <regolith/store/Prefetcher.hpp>

#include "store/PagerFixture.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

using namespace regolith;
using namespace regolith::store;
using namespace regolith::test;

namespace {

/// A copy of the pager fixture, opened, then cut to `keep` bytes.
struct Truncated {
  fs::path path;
  std::shared_ptr<const Store> store;
  std::shared_ptr<PatchCache> cache;
  std::shared_ptr<const Pager> pager;
};

Truncated openThenTruncate(const std::string& name, std::uintmax_t keep) {
  Truncated t;
  t.path = scratch(name);
  fs::copy_file(fixture().path, t.path, fs::copy_options::overwrite_existing);
  t.store = std::make_shared<const Store>(Store::open(t.path));
  t.cache = std::make_shared<PatchCache>(std::size_t{64} << 20);
  t.pager = std::make_shared<const Pager>(t.store, t.cache);
  fs::resize_file(t.path, keep);
  return t;
}

/// Runs f, which must throw a regolith::Error whose message names the file; prints it.
template <class F>
void expectErrorNaming(const fs::path& file, F&& f) {
  try {
    f();
    ADD_FAILURE() << "no error from a truncated " << file;
  } catch (const Error& e) {
    std::printf("error: %s\n", e.what());
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
  }
}

// Half the file (some chunks may survive) or only its first 4 KiB (none does: 0 below).
class TruncatedStore : public ::testing::TestWithParam<double> {
 protected:
  Truncated open(const std::string& name) const {
    const auto half =
        static_cast<std::uintmax_t>(GetParam() * double(fs::file_size(fixture().path)));
    return openThenTruncate(name, GetParam() > 0.0 ? half : 4096);
  }
};

}  // namespace

TEST_P(TruncatedStore, ReadWindowThrowsAnErrorNamingTheFile) {
  const Truncated t = open("window.h5");
  std::vector<float> out(700 * 900);
  expectErrorNaming(t.path, [&] { t.store->readWindow("dem", 0, 0, 0, 700, 900, out); });
  std::vector<float> planet(180 * 360);
  expectErrorNaming(t.path, [&] { t.store->readWindow("planet", 0, 0, 0, 180, 360, planet); });
}

TEST_P(TruncatedStore, PagedQueriesThrowAnErrorNamingTheFile) {
  const Truncated t = open("queries.h5");
  const TopoDem dem = t.pager->dem("dem");
  // Points spread over every patch of the DEM, so that a lost one is met.
  std::vector<double> xs, ys;
  for (double y = 399.0; y > -300.0; y -= 50.0)
    for (double x = -499.0; x < 400.0; x += 50.0) {
      xs.push_back(x);
      ys.push_back(y);
    }
  std::vector<double> h(xs.size());
  std::vector<glm::dvec3> n(xs.size());
  std::vector<QueryStatus> st(xs.size());
  expectErrorNaming(t.path, [&] { dem.heights(xs, ys, h, st); });
  expectErrorNaming(t.path, [&] { dem.surfaces(xs, ys, h, n, st); });
  expectErrorNaming(t.path, [&] {
    for (std::size_t i = 0; i < xs.size(); ++i) (void)dem.height(xs[i], ys[i]);
  });
  expectErrorNaming(t.path, [&] {
    for (std::size_t i = 0; i < xs.size(); ++i) (void)dem.surface(xs[i], ys[i]);
  });
  // A paged planet reads its pole rows when it is made: that read fails, or its queries do.
  expectErrorNaming(t.path, [&] {
    const TopoPlanet planet = t.pager->planet("planet");
    for (double lat = -89.0; lat < 90.0; lat += 10.0)
      for (double lon = -179.0; lon < 180.0; lon += 10.0) (void)planet.surface({lat, lon});
  });
}

TEST_P(TruncatedStore, ThePrefetcherCountsFailedLoadsAndKeepsTheError) {
  const Truncated t = open("prefetch.h5");
  Prefetcher pf(t.pager, 2);
  pf.wait(pf.request("dem", {LevelWindow{0, 0, 0, 700, 900}}));
  EXPECT_GT(pf.stats().failed, 0U);
  EXPECT_NE(pf.lastError().find(t.path.string()), std::string::npos) << pf.lastError();
  // What failed was not cached: a query still meets the error instead of a value.
  const TopoDem dem = t.pager->dem("dem");
  expectErrorNaming(t.path, [&] {
    for (double y = 399.0; y > -300.0; y -= 50.0)
      for (double x = -499.0; x < 400.0; x += 50.0) (void)dem.height(x, y);
  });
}

INSTANTIATE_TEST_SUITE_P(Cuts, TruncatedStore, ::testing::Values(0.5, 0.0), [](const auto& p) {
  return p.param == 0.5 ? std::string("Half") : "First4KiB";
});
