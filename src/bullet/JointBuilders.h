#pragma once
// What a figure constraint becomes in the rigid backend: one builder per joint type (JointBuilders.cpp), each
// giving the Bullet constraints of the joint with the role of their rows (docs/format.md §4).
#include <btBulletDynamicsCommon.h>

#include "afb/bullet/Ragdoll.h"
#include "afb/detail/Constraints.h"

namespace afb::bullet {

namespace detail {
class ObjectArena;
}

/// Where a joint is built: its two rigid bodies (b is Bullet's fixed body for a world constraint), the constraint
/// frame in each rigid body's frame (in the world for the world), and the rotations that take directions fixed in
/// body1 and in body2 into those frames (a merged body sits at an offset in its rigid).
struct JointSite {
    btRigidBody& a;
    btRigidBody& b;
    btTransform frameInA;
    btTransform frameInB;
    btMatrix3x3 body1Rotation;
    btMatrix3x3 body2Rotation;
};

/// The method's choices that change how a joint is built.
struct JointPolicy {
    LimitRowPolicy limits;                  ///< Method::limitErp, Method::speculativeLimits
    bool constantVelocityUniversal = false; ///< Method::constantVelocityUniversal
};

/// A joint's Bullet constraints: the main one (rows of role Joint, or Spring for a spring), a limit of its own (role
/// Limit) or none, and the axes of its friction rows (role Friction; the caller builds them when the joint has
/// friction): the first `frictionRows` columns of `frictionAxes`, fixed in b (JointFrictionConstraint).
struct JointParts {
    btTypedConstraint* main = nullptr;
    RowRole mainRole = RowRole::Joint;
    btTypedConstraint* limit = nullptr;
    btMatrix3x3 frictionAxes = btMatrix3x3::getIdentity();
    int frictionRows = 0;
};

/// Builds the constraints of figure constraint `c` at `site` in `arena`; adds nothing to a world.
JointParts buildJoint(detail::ObjectArena& arena, const figure::FigureConstraint& c, const JointSite& site,
                      const JointPolicy& policy);

/// The axes of a universal joint's two friction rows (docs/format.md §4.8): the Y and Z columns of `frameB` (the
/// swing axes, perpendicular to shaft 1), as the first two columns; `frameB` is frame B's rotation in the body that
/// fixes the rows. Both backends' universal builders use it.
btMatrix3x3 swingFrictionAxes(const btMatrix3x3& frameB);

/// The axis of a hinge's friction row (docs/format.md §4.8): the Z column of `frameB` (the hinge axis), as the first
/// column. Both backends' hinge builders use it.
btMatrix3x3 hingeFrictionAxes(const btMatrix3x3& frameB);

} // namespace afb::bullet
