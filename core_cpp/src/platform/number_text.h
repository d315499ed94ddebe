#pragma once

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace bvhlab {

/// A number as a message shows it: the fewest digits, from six, that read back as the same value
/// ("-1", "0.25", "64.00001", "1e+20", "nan"), where std::to_string prints six decimals
/// ("-1.000000", "0.000000" for 1e-7, 1e20 in 27 digits) and %g alone rounds to six digits (a
/// refused 64.00001 read "got 64").
inline std::string number_text(double x) {
    char text[32];
    for (int digits = 6; digits <= 17; ++digits) {
        std::snprintf(text, sizeof text, "%.*g", digits, x);
        if (!std::isfinite(x) || std::strtod(text, nullptr) == x) break;
    }
    return text;
}

/// The same for a float: the digits that read back as the same float.
inline std::string number_text(float x) {
    char text[32];
    for (int digits = 6; digits <= 9; ++digits) {
        std::snprintf(text, sizeof text, "%.*g", digits, double(x));
        if (!std::isfinite(x) || std::strtof(text, nullptr) == x) break;
    }
    return text;
}

}  // namespace bvhlab
