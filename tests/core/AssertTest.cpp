// Compiled with REGOLITH_FORCE_ASSERTS (tests/CMakeLists.txt), so the assertion checks in
// Release builds too, as the option promises.
#include <regolith/core/Assert.hpp>

#include <gtest/gtest.h>

namespace {

int checkedIndex(int i, int size) {
  REGOLITH_ASSERT(i >= 0 && i < size, "index out of range");
  return i;
}

}  // namespace

TEST(AssertDeathTest, AFailedAssertionNamesTheConditionAndAborts) {
  static_assert(regolith::core::kAssertionsEnabled);
  EXPECT_EQ(checkedIndex(2, 3), 2);
  EXPECT_DEATH((void)checkedIndex(3, 3),
               "regolith: assertion failed: .*AssertTest.cpp:[0-9]+: i >= 0 && i < size: "
               "index out of range");
}
