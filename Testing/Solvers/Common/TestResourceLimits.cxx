// The size and number guards of Common/ResourceLimits.h (issue 21): memory
// estimates refused with a message naming the bytes and the override, the
// override lifting them, integer conversions range-checked, non-finite
// fields detected.

#include "ResourceLimits.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <vector>

namespace
{
using namespace translucency;

std::string MessageOf(const std::function<void()>& f)
{
  try
  {
    f();
  }
  catch (const Error& e)
  {
    return e.what();
  }
  return "(no error)";
}

TEST(ResourceLimits, CheckMemoryRefusesAboveTheLimitAndNamesTheOverride)
{
  const std::string m =
    MessageOf([] { CheckMemory("thing", 3.0 * (1 << 30), std::size_t(1) << 30, "use less"); });
  EXPECT_NE(m.find("thing needs about 3 GiB"), std::string::npos) << m;
  EXPECT_NE(m.find("the limit is 1 GiB"), std::string::npos) << m;
  EXPECT_NE(m.find("use less"), std::string::npos) << m;
  EXPECT_NE(m.find("--memory-limit"), std::string::npos) << m;
  EXPECT_NO_THROW(CheckMemory("thing", 3.0 * (1 << 30), std::size_t(4) << 30, "use less"));
  // An estimate that overflowed (inf, NaN) is refused, never let through.
  EXPECT_THROW(CheckMemory("thing", INFINITY, std::size_t(1) << 40, ""), Error);
  EXPECT_THROW(CheckMemory("thing", NAN, std::size_t(1) << 40, ""), Error);
  EXPECT_THROW(CheckMemory("thing", 1.0, 0, ""), Error);
}

TEST(ResourceLimits, DefaultMemoryLimitIsEightGiBAndCanBeRaised)
{
  EXPECT_EQ(GetDefaultMemoryLimit(), std::size_t(8) << 30);
  const double bytes = 10.0 * (1 << 30);
  EXPECT_THROW(CheckMemory("x", bytes, GetDefaultMemoryLimit(), ""), Error);
  SetDefaultMemoryLimit(std::size_t(16) << 30);
  EXPECT_NO_THROW(CheckMemory("x", bytes, GetDefaultMemoryLimit(), ""));
  EXPECT_THROW(SetDefaultMemoryLimit(0), Error);
  SetDefaultMemoryLimit(std::size_t(8) << 30);
}

TEST(ResourceLimits, CheckedIntegerRefusesWhatACastCannotHold)
{
  EXPECT_EQ(CheckedInteger<int>(1e6, "n"), 1000000);
  EXPECT_EQ(CheckedInteger<int>(2147483647.0, "n"), 2147483647);
  EXPECT_EQ(CheckedInteger<long long>(-9223372036854775808.0, "n"),
    std::numeric_limits<long long>::min());
  const double inf = std::numeric_limits<double>::infinity();
  for (double bad : { 2147483648.0, -2147483649.0, 1e30, 1e300, 2.5, std::nan(""), inf, -inf })
  {
    EXPECT_THROW(CheckedInteger<int>(bad, "n"), Error) << bad;
  }
  EXPECT_THROW(CheckedInteger<long long>(9223372036854775808.0, "n"), Error);
  EXPECT_THROW(CheckedInteger<unsigned>(-1.0, "n"), Error);
  EXPECT_THROW(CheckedInteger<int>(0.0, "n", 1), Error);
  EXPECT_THROW(CheckedInteger<int>(101.0, "n", 1, 100), Error);
  EXPECT_EQ(CheckedInteger<int>(100.0, "n", 1, 100), 100);
  const std::string m = MessageOf([] { CheckedInteger<int>(1e300, "\"max_iter\""); });
  EXPECT_NE(m.find("\"max_iter\": 1.0000000000000001e+300 is not a whole number"),
    std::string::npos)
    << m;
}

TEST(ResourceLimits, RequireFiniteNamesTheQuantityAndIndex)
{
  EXPECT_NO_THROW(RequireFinite(std::vector<double>{ 0.0, 1e308, 4.9e-324 }, "F", ""));
  const std::string m = MessageOf([] {
    RequireFinite(std::vector<double>{ 1.0, 2.0, NAN }, "Fluence", OverflowCause());
  });
  EXPECT_NE(m.find("Fluence is not finite (nan at index 2 of 3)"), std::string::npos) << m;
  EXPECT_NE(m.find("light power"), std::string::npos) << m;
  EXPECT_THROW(RequireFinite(std::vector<double>{ -INFINITY }, "B", ""), Error);
}

TEST(ResourceLimits, FormatNumberIsShort)
{
  EXPECT_EQ(FormatNumber(1e100), "1e+100");
  EXPECT_EQ(FormatNumber(0.5), "0.5");
}

} // namespace
