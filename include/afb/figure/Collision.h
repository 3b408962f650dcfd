#pragma once
// Which bodies of a figure collide (docs/format.md §6.2), and how far apart two bodies are at the load pose.
#include <utility>
#include <vector>

#include "afb/figure/Figure.h"

namespace afb::figure {

/// Gaps below this (metres) count as touching when a figure is checked at its load pose.
inline constexpr double kTouchToleranceM = 0.001;

/// Pairs (i < j) of bodies that collide with each other (docs/format.md §6.2): the figure's selfCollision is on, both
/// bodies' selfCollision flags are on, no non-spring constraint joins them directly, and each clipMask includes the
/// other's contents. Ascending order.
std::vector<std::pair<int, int>> selfCollisionPairs(const Figure& figure);

/// True when a collision-disabling constraint attaches the body to the world: the engine then lets it pass
/// through all static world geometry (docs/format.md §4.1, §6.2, §8 item 7).
bool attachedToWorld(const Figure& figure, int body);

/// Signed separation of two bodies' polytopes at the load pose, metres, along the best separating axis of the
/// separating-axis test (face normals and edge cross products): > 0 apart (a lower bound of the distance),
/// < 0 overlapping (minus the smallest penetration depth).
double separation(const FigureBody& a, const FigureBody& b);

} // namespace afb::figure
