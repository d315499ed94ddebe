#pragma once

#include <cstdio>
#include <string>

namespace bvhlab {

/// A number as a message shows it, in %g's short form ("-1", "0.25", "1e+20", "nan"), where
/// std::to_string prints six decimals ("-1.000000", "0.000000" for 1e-7, 1e20 in 27 digits).
inline std::string number_text(double x) {
    char text[32];
    std::snprintf(text, sizeof text, "%g", x);
    return text;
}

}  // namespace bvhlab
