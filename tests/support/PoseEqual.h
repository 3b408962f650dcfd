#pragma once
// Bit-for-bit comparison of figure transforms and skeleton poses, for tests that demand exactly one side of a blend
// (not a tolerance).
#include "afb/figure/Transform.h"
#include "afb/pose/SkeletonDriver.h"

namespace afb::test {

/// Rotation and position equal entry by entry.
inline bool bitEqual(const figure::Transform& a, const figure::Transform& b) {
    return a.rotation == b.rotation && a.position == b.position;
}

/// The entity and every joint's model and local transform equal entry by entry.
inline bool bitEqual(const pose::SkeletonPose& a, const pose::SkeletonPose& b) {
    if (!bitEqual(a.entity, b.entity) || a.model.size() != b.model.size() || a.local.size() != b.local.size())
        return false;
    for (std::size_t j = 0; j < a.model.size(); ++j)
        if (!bitEqual(a.model[j], b.model[j]) || !bitEqual(a.local[j], b.local[j])) return false;
    return true;
}

} // namespace afb::test
