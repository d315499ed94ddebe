#pragma once

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <type_traits>

namespace bvhlab {

/// A number as a message shows it: the fewest digits, from six, that read back as the same value
/// of its type ("-1", "0.25", "64.00001", "1e+20", "nan"), where std::to_string prints six
/// decimals ("-1.000000", "0.000000" for 1e-7, 1e20 in 27 digits) and %g alone rounds to six
/// digits (a refused 64.00001 read "got 64"). Nine digits always read back a float, 17 a double.
template <class T>
std::string number_text(T x) {
    static_assert(std::is_floating_point_v<T>);
    constexpr int most = std::is_same_v<T, float> ? 9 : 17;
    char text[32];
    for (int digits = 6; digits <= most; ++digits) {
        std::snprintf(text, sizeof text, "%.*g", digits, double(x));
        if (!std::isfinite(x) || T(std::strtod(text, nullptr)) == x) break;
    }
    return text;
}

}  // namespace bvhlab
