#pragma once
// Self-collision pairs the figure's joints keep apart ("only the pairs that can touch"): computed once
// per figure, by RagdollAsset.
#include <utility>
#include <vector>

#include "afb/figure/Figure.h"

namespace afb::bullet::detail {

/// How much worse than its limits a running figure may get before a pruned pair could touch: limits overshot by
/// up to `angleRad` per joint and the bodies kept at least `distanceM` apart.
struct PruneSlack {
    double angleRad = 10.0 * 3.14159265358979323846 / 180.0;
    double distanceM = 0.02;
};

/// The pairs of figure::selfCollisionPairs(figure) that cannot come within `slack.distanceM` of each other while
/// every joint on a path between them stays within its limit (widened by `slack.angleRad`), ascending. A bound,
/// never a guess: along the joint path from one body to the other, the set of places a body can reach relative to
/// the next is enclosed in a convex set (a cone about the joint's limit axis, a sphere about the anchor for a free
/// joint, the hinge's sampled sweep plus its sagitta), hop by hop; a pair is pruned when, for some body on the
/// path held still, the two enclosures are farther apart than the slack (GJK). Paths through sliders, springs or
/// the world are not followed.
std::vector<std::pair<int, int>> unreachablePairs(const figure::Figure& figure, const PruneSlack& slack = {});

} // namespace afb::bullet::detail
