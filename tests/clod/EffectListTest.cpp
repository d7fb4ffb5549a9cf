// clod::EffectList: effect names, parameters and defaults as the command line and Python give
// them; messages word for word.
#include <regolith/clod/EffectList.hpp>
#include <regolith/clod/HeightPyramid.hpp>
#include <regolith/core/Error.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <vector>

namespace regolith::clod {
namespace {

std::string messageOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const regolith::Error& e) {
    return e.what();
  }
  return "(no error)";
}

EffectRequest parsed(std::string_view list) {
  EffectRequest r;
  addEffectList(r, list, "render", kCommandLineEffectOptions);
  return r;
}

TEST(EffectListTest, ListsDeclareExactlyTheNamedEffects) {
  const EffectRequest none;
  EXPECT_FALSE(none.any());
  EXPECT_EQ(none.names(), "");
  const EffectRequest r = parsed(" noise ,latlon");
  EXPECT_TRUE(r.noise && r.latLon && !r.tracks && !r.heightColours);
  EXPECT_EQ(r.names(), "latlon,noise");  // kEffectNames order
  EXPECT_EQ(parsed("tracks,height-colours,latlon,noise").names(),
            "tracks,height-colours,latlon,noise");
  EXPECT_EQ(parsed("noise,noise").names(), "noise");
}

TEST(EffectListTest, UnknownAndEmptyNamesAreRefusedWithTheKnownOnes) {
  EXPECT_EQ(messageOf([] { (void)parsed("noise,Noise"); }),
            "render: --effects 'Noise' is not an effect, expected one of tracks, "
            "height-colours, latlon, noise");
  EXPECT_EQ(messageOf([] { (void)parsed(""); }),
            "render: --effects '' has an empty name, expected names separated by commas, each "
            "one of tracks, height-colours, latlon, noise");
  EXPECT_EQ(messageOf([] { (void)parsed("latlon,"); }),
            "render: --effects 'latlon,' has an empty name, expected names separated by "
            "commas, each one of tracks, height-colours, latlon, noise");
  EffectRequest r;
  EXPECT_EQ(messageOf([&] { addEffectName(r, "heightColours", "op", kPythonEffectOptions); }),
            "op: effects 'heightColours' is not an effect, expected one of tracks, "
            "height-colours, latlon, noise");
}

TEST(EffectListTest, NothingNamedMakesNoEffects) {
  int calls = 0;
  EffectDefaults d;
  d.heightRange = [&] {
    ++calls;
    return std::optional<std::array<double, 2>>(std::array<double, 2>{0.0, 1.0});
  };
  const Effects e = effectsOf(EffectRequest{}, d, "render", kCommandLineEffectOptions);
  EXPECT_TRUE(e.declared().empty());
  EXPECT_EQ(calls, 0);  // the terrain's range is not even looked at
}

TEST(EffectListTest, DefaultsComeFromTheTerrain) {
  EffectDefaults d;
  d.heightRange = [] {
    return std::optional<std::array<double, 2>>(std::array<double, 2>{-80.5, 20.25});
  };
  d.gridSpacing = 2.0;
  d.metresPerGridUnit = 1.0;
  const Effects e =
      effectsOf(parsed("height-colours,latlon,noise"), d, "render", kCommandLineEffectOptions);
  ASSERT_TRUE(e.heightColours && e.latLon && e.noise);
  EXPECT_EQ(e.heightColours->minHeight, -80.5F);
  EXPECT_EQ(e.heightColours->maxHeight, 20.25F);
  EXPECT_FALSE(e.heightColours->shaded);
  EXPECT_EQ(e.latLon->spacingDegrees, 0.0);  // adaptive
  EXPECT_EQ(e.noise->wavelength, 8.0);       // 4 spacings
  EXPECT_EQ(e.noise->amplitude, 0.5);        // a quarter spacing
  EXPECT_EQ(e.noise->octaves, 4);
  EXPECT_FALSE(e.tracks);  // the caller stamps a layer
  // A planet: spacing in degrees, amplitude in metres.
  d.gridSpacing = 0.25;
  d.metresPerGridUnit = 59274.7;
  const Effects p = effectsOf(parsed("noise"), d, "render", kCommandLineEffectOptions);
  EXPECT_EQ(p.noise->wavelength, 1.0);
  EXPECT_DOUBLE_EQ(p.noise->amplitude, 0.25 * 0.25 * 59274.7);
  // A flat terrain gets a metre around its one height; none at all is refused.
  d.heightRange = [] {
    return std::optional<std::array<double, 2>>(std::array<double, 2>{7.0, 7.0});
  };
  const Effects flat = effectsOf(parsed("height-colours"), d, "render", kCommandLineEffectOptions);
  EXPECT_EQ(flat.heightColours->minHeight, 6.5F);
  EXPECT_EQ(flat.heightColours->maxHeight, 7.5F);
  d.heightRange = [] { return std::optional<std::array<double, 2>>(); };
  EXPECT_EQ(messageOf([&] {
              (void)effectsOf(parsed("height-colours"), d, "render", kCommandLineEffectOptions);
            }),
            "render: height-colours, expected --height-range (the terrain has no valid height "
            "to take a range from)");
}

TEST(EffectListTest, GivenParametersAreCheckedAndNamedAsTheFrontEndSpellsThem) {
  const EffectDefaults d;
  const auto refusal = [&](EffectRequest r, const EffectOptionNames& spelling) {
    return messageOf([&] { (void)effectsOf(r, d, "op", spelling); });
  };
  EffectRequest r = parsed("height-colours,latlon,noise");
  r.heightRange = std::array<double, 2>{1.0, std::numeric_limits<double>::quiet_NaN()};
  EXPECT_EQ(refusal(r, kCommandLineEffectOptions),
            "op: --height-range is 1,nan m, expected low,high finite and within [-1e+06, "
            "1e+06] m");
  r.heightRange = std::array<double, 2>{1.0, 1.0 + 1e-9};  // equal as floats
  EXPECT_EQ(refusal(r, kPythonEffectOptions),
            "op: height_range is 1,1.000000001 m, expected low < high (as 32-bit floats)");
  r.heightRange = std::array<double, 2>{-1.0, 2.0};
  r.latLonSpacing = -1.0;
  EXPECT_EQ(refusal(r, kPythonEffectOptions),
            "op: effects['latlon']['spacing'] is -1 deg, expected 0 (adapts to the view) or "
            "finite and within [1e-06, 90] deg");
  r.latLonSpacing = 15.0;
  r.noiseAmplitude = std::numeric_limits<double>::infinity();
  EXPECT_EQ(refusal(r, kCommandLineEffectOptions),
            "op: --noise-amplitude is inf m, expected finite and within [0, 10000] m");
  r.noiseAmplitude = 0.0;  // albedo variation only: allowed
  r.noiseWavelength = 0.0;
  EXPECT_EQ(refusal(r, kCommandLineEffectOptions),
            "op: --noise-wavelength is 0, expected finite and within [1e-06, 1e+07] grid units "
            "(metres on a DEM, degrees on a planet)");
  r.noiseWavelength = 3.0;
  r.noiseOctaves = 0;
  EXPECT_EQ(refusal(r, kPythonEffectOptions),
            "op: effects['noise']['octaves'] is 0, expected 1 to 8");
  r.noiseOctaves = 8;
  const Effects e = effectsOf(r, d, "op", kPythonEffectOptions);
  EXPECT_EQ(e.heightColours->minHeight, -1.0F);
  EXPECT_EQ(e.latLon->spacingDegrees, 15.0);
  EXPECT_EQ(e.noise->amplitude, 0.0);
  EXPECT_EQ(e.noise->wavelength, 3.0);
  EXPECT_EQ(e.noise->octaves, 8);
}

TEST(EffectListTest, ParametersOfEffectsNotNamedAreRefused) {
  const EffectDefaults d;
  EffectRequest r = parsed("noise");
  r.heightRange = std::array<double, 2>{0.0, 1.0};
  EXPECT_EQ(messageOf([&] { (void)effectsOf(r, d, "render", kCommandLineEffectOptions); }),
            "render: --height-range sets a parameter of height-colours, which --effects does "
            "not name");
  r = parsed("height-colours");
  r.noiseWavelength = 1.0;
  EXPECT_EQ(messageOf([&] { (void)effectsOf(r, d, "op", kPythonEffectOptions); }),
            "op: effects['noise']['wavelength'] sets a parameter of noise, which effects does "
            "not name");
}

TEST(EffectListTest, HeightRangeOfSkipsNodataAndReadsASmallLevel) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const topo::TopoGrid grid(4, 4, 0.0, 3.0, 1.0, 1.0, -9999.0F);
  const std::vector<float> v = {1,     2,  3,   4,   //
                                -9999, 6,  nan, 8,   //
                                9,     10, 11,  12,  //
                                13,    14, 15,  -40};
  const auto samples = std::make_shared<topo::InMemorySamples>(4, 4, v);
  const auto p = HeightPyramid::fromSamples(grid, samples, SurfaceKind::Plane);
  const auto all = heightRangeOf(p);
  ASSERT_TRUE(all);
  EXPECT_EQ((*all)[0], -40.0);
  EXPECT_EQ((*all)[1], 15.0);
  // At most 4 samples: level 1, the means of the valid samples of each 2 × 2 block: 3, 5,
  // 11.5 and -0.5, a narrower range.
  const auto coarse = heightRangeOf(p, 4);
  ASSERT_TRUE(coarse);
  EXPECT_EQ((*coarse)[0], -0.5);
  EXPECT_EQ((*coarse)[1], 11.5);
  const std::vector<float> holes(16, nan);
  const auto empty = HeightPyramid::fromSamples(
      grid, std::make_shared<topo::InMemorySamples>(4, 4, holes), SurfaceKind::Plane);
  EXPECT_FALSE(heightRangeOf(empty));
}

}  // namespace
}  // namespace regolith::clod
