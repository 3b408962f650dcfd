// Numbers in the stress runs' failure details and reports (Stress.cpp, StressReport.cpp).
#pragma once

#include <cstdio>
#include <string>

namespace afb::sim::detail {

/// `v` with `digits` decimals.
inline std::string fixed(double v, int digits) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", digits, v);
    return buf;
}

} // namespace afb::sim::detail
