#pragma once
// The position pass (Method::positionIterations), internal to the bullet layer: nonlinear Gauss–Seidel
// projections after Bullet's velocity solve and integration that move a ragdoll's bodies so that its joints,
// limits and contacts hold at the end of the substep. Velocities are left as the velocity solve made them
// (post-stabilisation; Jolt's position steps do the same).
#include <span>

#include <btBulletDynamicsCommon.h>

namespace afb::bullet {

class Ragdoll;

namespace detail {

/// `sweeps` sweeps over `ragdoll`: every joint's limit, locked axes and anchor, then every contact point of
/// `manifolds` (those touching the ragdoll's bodies) deeper than the slop. Only the ragdoll's own bodies move;
/// poses are written back to Bullet once, at the end.
void positionPass(Ragdoll& ragdoll, int sweeps, std::span<btPersistentManifold* const> manifolds);

} // namespace detail
} // namespace afb::bullet
