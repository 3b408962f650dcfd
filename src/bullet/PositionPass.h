#pragma once
// The position pass (Method::positionIterations), internal to the bullet layer: nonlinear Gauss–Seidel
// projections after Bullet's velocity solve and integration that move a ragdoll's bodies so that its joints,
// limits and contacts hold at the end of the substep. Velocities are left as the velocity solve made them
// (post-stabilisation; Jolt's position steps do the same), except, with Method::positionVelocity, the part whose
// motion the pass took back.
#include <span>

#include <btBulletDynamicsCommon.h>

namespace afb::bullet {

class Ragdoll;

namespace detail {

/// `sweeps` sweeps over `ragdoll`: every joint's limit, locked axes and anchor, then every contact point of
/// `manifolds` (those touching the ragdoll's bodies) deeper than the slop, and for each body with a manifold
/// against a static plane its deepest point below the plane when no manifold point is within a millimetre of it
/// (a body whipped round in the substep). Then, with `tree` 1 or 2 (Method::positionTree), up to three Newton
/// steps over the ragdoll's joint tree that close every anchor at once (1), and with 2 also the locked axes and
/// the limit rows past their limit, with bodies that have contact points against anything outside the ragdoll
/// counted 100 times heavier (shock propagation: the step moves what is above the ground, not a foot into it);
/// contacts are not part of the tree step. Only the ragdoll's own bodies move; poses are written back to Bullet once,
/// at the end. With `takeVelocity` (Method::positionVelocity), each moved body loses the part of its velocity whose
/// motion over the substep `dt` the pass took back.
void positionPass(Ragdoll& ragdoll, int sweeps, int tree, std::span<btPersistentManifold* const> manifolds, btScalar dt,
                  bool takeVelocity);

} // namespace detail
} // namespace afb::bullet
