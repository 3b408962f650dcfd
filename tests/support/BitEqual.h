#pragma once
// Bit-for-bit comparison of transforms, for tests that demand the same result from two paths (not a tolerance).
#include <LinearMath/btTransform.h>

namespace afb::test {

/// Every component of the origin and the basis equal (as floats compare: the same bits but for ±0).
inline bool bitEqual(const btTransform& a, const btTransform& b) {
    return a.getOrigin() == b.getOrigin() && a.getBasis() == b.getBasis();
}

} // namespace afb::test
