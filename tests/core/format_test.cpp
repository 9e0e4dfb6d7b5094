// The one number format of messages and the one range-error grammar
// ("FIELD must be WHAT, got VALUE").
#include "terracut/core/format.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <string>

namespace terracut {
namespace {

TEST(FormatNumber, ShortestTextThatReadsBackTheSameDouble) {
  struct Case {
    double value;
    const char* text;
  };
  // Exact where %.6g would round (1234567, 1/3): the message shows the value
  // compared; short where a fixed precision would pad ("0.1").
  for (const Case& c : {Case{0.1, "0.1"}, Case{-0.2, "-0.2"}, Case{0.0, "0"}, Case{1000.0, "1000"},
                        Case{1e6, "1e+06"}, Case{1e-7, "1e-07"}, Case{1234567.0, "1234567"},
                        Case{2.0 / 3.0, "0.6666666666666666"}})
    EXPECT_EQ(format_number(c.value), c.text);
  for (double v : {1.0 / 3.0, 0.1 + 0.2, 2.0 / 7.0, -1e-300, 1.7976931348623157e308})
    EXPECT_EQ(std::stod(format_number(v)), v) << format_number(v);
}

TEST(FormatNumber, NonFiniteValues) {
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(format_number(inf), "inf");
  EXPECT_EQ(format_number(-inf), "-inf");
  EXPECT_EQ(format_number(nan), "nan");
  EXPECT_EQ(format_number(-nan), "nan");  // a NaN's sign means nothing in a message
  EXPECT_EQ(format_number(std::numeric_limits<float>::quiet_NaN()), "nan");
  EXPECT_EQ(format_number(-std::numeric_limits<float>::infinity()), "-inf");
}

TEST(FormatNumber, FloatsAreWrittenAsFloats) {
  // 0.1f is 0.100000001490116... as a double; as a float its shortest text is "0.1".
  EXPECT_EQ(format_number(0.1f), "0.1");
  EXPECT_EQ(format_number(-0.5f), "-0.5");
}

TEST(FormatNumber, WholeNumbersInDecimal) {
  EXPECT_EQ(format_number(0), "0");
  EXPECT_EQ(format_number(-3), "-3");
  EXPECT_EQ(format_number(65536), "65536");
  EXPECT_EQ(format_number(100000), "100000");  // not "1e+05", as the double would be
  EXPECT_EQ(format_number(std::int64_t(1) << 40), "1099511627776");
  EXPECT_EQ(format_number(std::size_t(12)), "12");
  EXPECT_EQ(format_number(std::numeric_limits<std::int64_t>::min()), "-9223372036854775808");
  EXPECT_EQ(format_number(std::numeric_limits<std::uint64_t>::max()), "18446744073709551615");
}

TEST(MustBe, FieldWhatGot) {
  EXPECT_EQ(must_be("rate_hz", "in (0, 1e6]", 0.0), "rate_hz must be in (0, 1e6], got 0");
  EXPECT_EQ(must_be("grid.cols", "in [1, 65536]", 70000),
            "grid.cols must be in [1, 65536], got 70000");
  EXPECT_EQ(must_be("size_m[1]", "in (0, 1000] metres", -0.2),
            "size_m[1] must be in (0, 1000] metres, got -0.2");
  const std::string field = "mass_kg";
  EXPECT_EQ(must_be(field, "finite and >= 0", std::numeric_limits<double>::quiet_NaN()),
            "mass_kg must be finite and >= 0, got nan");
  EXPECT_EQ(must_be("initial height", ">= 0", -0.1f), "initial height must be >= 0, got -0.1");
}

TEST(MustBe, WithoutTheField) {
  // For readers that put the field in front themselves ("FILE:LINE: field: ...").
  EXPECT_EQ(must_be("> 0", 0.0), "must be > 0, got 0");
  EXPECT_EQ(must_be("in [1, 65535]", 0), "must be in [1, 65535], got 0");
}

}  // namespace
}  // namespace terracut
