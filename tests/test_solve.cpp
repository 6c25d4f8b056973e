#include <doctest/doctest.h>

#include "common/json.hpp"
#include "solve/distributions.hpp"

TEST_SUITE("solve") {
  TEST_CASE("distribution functions match tabulated values") {
    // Tabulated critical values; the functions are accurate far beyond the 1e-9 asked here.
    CHECK(momentid::chi_square_upper_tail(3.84145882069412, 1) ==
          doctest::Approx(0.05).epsilon(1e-9));
    CHECK(momentid::chi_square_upper_tail(18.475306906582, 7) ==
          doctest::Approx(0.01).epsilon(1e-9));
    CHECK(momentid::chi_square_upper_tail(6, 6) == doctest::Approx(0.42319008112684).epsilon(1e-9));
    CHECK(momentid::chi_square_upper_tail(400, 7) > 0);  // far tails do not underflow to 0
    CHECK(momentid::chi_square_upper_tail(400, 7) < 1e-80);
    CHECK(momentid::student_t_quantile(0.975, 49) ==
          doctest::Approx(2.00957523712924).epsilon(1e-9));
    CHECK(momentid::student_t_quantile(0.975, 4) ==
          doctest::Approx(2.77644510519779).epsilon(1e-9));
    CHECK(momentid::student_t_cdf(1.0, 3) == doctest::Approx(0.80449889052271).epsilon(1e-9));
    CHECK(momentid::student_t_cdf(-1.0, 3) == doctest::Approx(1 - 0.80449889052271).epsilon(1e-9));
  }

  TEST_CASE("JSON strings escape quotes and control characters and stay valid UTF-8") {
    CHECK(momentid::json_string("a\"b\\c\nd\x01") == "\"a\\\"b\\\\c\\nd\\u0001\"");
    CHECK(momentid::json_string("\xc3\xa9t\xff") == "\"\xc3\xa9t\\ufffd\"");
  }
}
