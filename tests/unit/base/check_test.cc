#include "common/base/check.h"

#include <gtest/gtest.h>

namespace microdex {
namespace {

TEST(CheckDeathTest, FailedCheckAbortsWithFileAndLine) {
  EXPECT_DEATH(MICRODEX_CHECK(1 + 1 == 3), "check failed: 1 \\+ 1 == 3 at .*check_test.cc:[0-9]+");
}

TEST(Check, PassingCheckDoesNothing) {
  int evaluated = 0;
  MICRODEX_CHECK(++evaluated == 1);
  EXPECT_EQ(evaluated, 1);
}

}  // namespace
}  // namespace microdex
