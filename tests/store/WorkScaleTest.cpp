// tests/support/WorkScale.hpp: the share of their work the long store tests do under the
// sanitizers (scripts/test-all.sh sets REGOLITH_TEST_WORK_SCALE=0.25 there).
#include "support/WorkScale.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <optional>
#include <stdexcept>
#include <string>

namespace {

/// Sets REGOLITH_TEST_WORK_SCALE for one scope and puts the old value back.
class ScaleSetting {
 public:
  explicit ScaleSetting(const char* value) {
    if (const char* old = std::getenv(kName)) old_ = old;
    if (value == nullptr) {
      ::unsetenv(kName);
    } else {
      ::setenv(kName, value, 1);
    }
  }
  ScaleSetting(const ScaleSetting&) = delete;
  ScaleSetting& operator=(const ScaleSetting&) = delete;
  ~ScaleSetting() {
    if (old_) {
      ::setenv(kName, old_->c_str(), 1);
    } else {
      ::unsetenv(kName);
    }
  }

 private:
  static constexpr const char* kName = "REGOLITH_TEST_WORK_SCALE";
  std::optional<std::string> old_;
};

}  // namespace

TEST(WorkScale, WholeWorkUnlessSetAndAShareRoundedUpWithAFloor) {
  using regolith::test::scaledWork;
  {
    const ScaleSetting unset(nullptr);
    EXPECT_EQ(scaledWork(3000), 3000U);
  }
  {
    const ScaleSetting quarter("0.25");
    EXPECT_EQ(scaledWork(3000), 750U);
    EXPECT_EQ(scaledWork(301), 76U);  // rounded up
    EXPECT_EQ(scaledWork(2), 1U);
    EXPECT_EQ(scaledWork(2, 5), 5U);  // the floor
  }
  {
    const ScaleSetting whole("1");
    EXPECT_EQ(scaledWork(1500), 1500U);
  }
}

TEST(WorkScale, AValueOutsideZeroToOneOrNotANumberIsRefusedNamingIt) {
  using regolith::test::scaledWork;
  for (const char* bad : {"0", "-0.5", "1.5", "quarter", "0.25x", "nan"}) {
    const ScaleSetting setting(bad);
    try {
      (void)scaledWork(100);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()), std::string("REGOLITH_TEST_WORK_SCALE: '") + bad +
                                           "', expected a number in (0, 1]");
    }
  }
}
