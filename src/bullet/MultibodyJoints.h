#pragma once
// What a figure constraint becomes in the multibody backend: one builder per joint type (MultibodyJoints.cpp), the
// multibody side of JointBuilders.h (docs/format.md §4). Which joints are tree edges, fixed bases or loops is not
// here: the tree layout reads it from figure::freedomOf.
#include <optional>

#include <btBulletDynamicsCommon.h>

#include "MultibodyRows.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/figure/Figure.h"

namespace afb::bullet::detail {

/// The kinds of btMultiBody link a figure joint becomes (btMultibodyLink's joint types).
enum class LinkKind { Fixed, Revolute, Prismatic, Spherical };

/// Where a joint is built: its frames in body1's frame and in body2's (in the world for a world joint, the spawn
/// transform applied), and the rotation that takes directions fixed in body2 (in model space for the world) into
/// frame B's parent frame: the identity, or the spawn rotation for the world.
struct MultibodyJointSite {
    btTransform frameInBody1;
    btTransform frameInBody2;
    btMatrix3x3 body2Rotation;
};

/// A joint in the multibody backend. As a tree edge: the link that carries the child (and the rows that hold what
/// the link leaves free). Wherever it sits: its limit (role Limit) and the axes of its friction rows (role Friction:
/// the first `frictionRows` columns of `frictionAxes`, fixed in body2, in the world for a world joint). A spring
/// (role Spring) is a MultibodySpring and never a link.
struct MultibodyJointParts {
    RowRole mainRole = RowRole::Joint;         ///< Joint: a link or a loop constraint; Spring: a MultibodySpring
    LinkKind link = LinkKind::Fixed;           ///< the link, as a tree edge
    btVector3 axisInBody1{0, 0, 0};            ///< a revolute or prismatic link's axis, in body1's frame
    btVector3 axisInBody2{0, 0, 0};            ///< the same axis in body2's frame
    bool twistRow = false;                     ///< a spherical link whose twist a row holds (role Joint, §4.4)
    std::optional<MultibodyLimit::Kind> limit; ///< a cone, pyramid or hinge range, or none
    btMatrix3x3 frictionAxes = btMatrix3x3::getIdentity();
    int frictionRows = 0;
};

/// The multibody parts of figure constraint `c` at `site`; builds no Bullet object.
MultibodyJointParts buildMultibodyJoint(const figure::FigureConstraint& c, const MultibodyJointSite& site);

} // namespace afb::bullet::detail
