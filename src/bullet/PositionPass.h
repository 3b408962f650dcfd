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

/// Decides whether the pass may move a collision object: only ragdoll bodies are moved (a game's own bodies
/// and static geometry are treated as immovable).
struct MovableTest {
    virtual ~MovableTest() = default;
    virtual bool movable(const btCollisionObject* object) const = 0;
};

/// One sweep over `ragdoll`: every joint's anchor, locked axes and limit, then every contact point of
/// `manifolds` (those touching the ragdoll's bodies) deeper than the slop.
void positionSweep(Ragdoll& ragdoll, std::span<btPersistentManifold* const> manifolds, const MovableTest& movable);

} // namespace detail
} // namespace afb::bullet
