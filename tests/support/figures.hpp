#pragma once
// Figures that docs/stability.md quotes, written by the test that measures them.
//
// A figure is a doctest MESSAGE line `figure <key> = <value>`; scripts/stability_figures.py runs
// the tests, collects these lines and splices each value into the doc between
// `<!-- figure:<key> -->` and `<!-- /figure -->` (and the ctest stability_figures_in_docs fails
// when the doc's values differ). Values are printed with 3 significant digits, as the doc reads them.

#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <type_traits>

namespace krs_test {

// 3 significant digits, exponent without leading zeros or '+': 2.99e-7, 0.99995 -> 1, 0 -> 0.
inline std::string figure_text(double v)
{
    char buffer[32];
    if (v == 0 || (std::abs(v) >= 1e-3 && std::abs(v) < 1e6))
        std::snprintf(buffer, sizeof buffer, "%.3g", v);
    else
        std::snprintf(buffer, sizeof buffer, "%.2e", v);
    std::string s = buffer;
    if (const auto e = s.find('e'); e != std::string::npos) {
        std::string mantissa = s.substr(0, e), exponent = s.substr(e + 1);
        // Trailing zeros of the mantissa carry no information here: 3.00e-7 -> 3e-7.
        if (mantissa.find('.') != std::string::npos) {
            while (mantissa.back() == '0') mantissa.pop_back();
            if (mantissa.back() == '.') mantissa.pop_back();
        }
        const bool negative = exponent[0] == '-';
        std::size_t digits = exponent.find_first_not_of("+-0");
        s = mantissa + "e" + (negative ? "-" : "") + (digits == std::string::npos ? "0" : exponent.substr(digits));
    }
    return s;
}
// More digits where 3 would hide the point (a Lipschitz constant of 0.99995 is not 1).
inline std::string figure_digits(double v, int digits)
{
    char buffer[40];
    std::snprintf(buffer, sizeof buffer, "%.*g", digits, v);
    return buffer;
}
inline std::string figure_text(long long v) { return std::to_string(v); }
inline std::string figure_text(int v) { return std::to_string(v); }
inline std::string figure_text(const std::string& v) { return v; }
inline std::string figure_text(const char* v) { return v; }

} // namespace krs_test

#define KRS_FIGURE(key, value) MESSAGE("figure " << (key) << " = " << krs_test::figure_text(value))
