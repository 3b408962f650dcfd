// One builder per joint type for the rigid backend (JointBuilders.h): docs/format.md §4 (constraint mapping), §4.4
// (universal joints), §4.7 (springs), §4.8 (joint friction axes).
#include "JointBuilders.h"

#include "ObjectArena.h"
#include "afb/detail/Convert.h"

namespace afb::bullet {

using figure::FigureConstraint;
using figure::JointType;

namespace {

/// A cone or pyramid limit of ours between the shaft (fixed in a) and the limit's frame (fixed in b), both in the
/// rigid bodies' frames.
btTypedConstraint* directionLimit(detail::ObjectArena& arena, const JointSite& s, const btVector3& shaft,
                                  const btMatrix3x3& frame, LimitShape shape, double half1, double half2,
                                  const LimitRowPolicy& policy) {
    return arena.make<DirectionLimitConstraint>(s.a, s.b, shaft, frame, shape, static_cast<btScalar>(half1),
                                                static_cast<btScalar>(half2), policy);
}

/// The pyramid limit of a ball or universal joint, or none.
btTypedConstraint* pyramidLimit(detail::ObjectArena& arena, const FigureConstraint& c, const JointSite& s,
                                const LimitRowPolicy& policy) {
    const auto* p = std::get_if<figure::PyramidLimit>(&c.limit);
    if (p == nullptr) return nullptr;
    return directionLimit(arena, s, s.body1Rotation * toBt(p->shaftInBody1), s.body2Rotation * toBt(p->basisInBody2),
                          LimitShape::Pyramid, p->halfAngle1Rad, p->halfAngle2Rad, policy);
}

JointParts fixedJoint(detail::ObjectArena& arena, const JointSite& s) {
    JointParts out;
    out.main = arena.make<btFixedConstraint>(s.a, s.b, s.frameInA, s.frameInB);
    return out;
}

JointParts ballJoint(detail::ObjectArena& arena, const FigureConstraint& c, const JointSite& s,
                     const JointPolicy& policy) {
    JointParts out;
    out.frictionAxes = btMatrix3x3::getIdentity() * s.body2Rotation;
    out.frictionRows = 3;
    const auto* cone = std::get_if<figure::ConeLimit>(&c.limit);
    if (cone == nullptr) {
        out.main = arena.make<btPoint2PointConstraint>(s.a, s.b, s.frameInA.getOrigin(), s.frameInB.getOrigin());
        out.limit = pyramidLimit(arena, c, s, policy.limits);
        return out;
    }
    // btConeTwistConstraint: twist about X is free (span < 0), swing keeps the X axes within the half-angle: frame
    // B's X is the cone axis (body2), frame A's X the shaft (body1), and frame A is frame B turned along the
    // shortest arc, so the twist starts at 0.
    const btVector3 axisB = s.body2Rotation * toBt(cone->axisInBody2);
    const btVector3 shaftA = s.body1Rotation * toBt(cone->shaftInBody1);
    const btMatrix3x3 frameBRot = basisWithX(axisB);
    const btScalar h = static_cast<btScalar>(cone->halfAngleRad);
    if (policy.limits.speculative) {
        // Our own cone row (speculative); the anchor alone is a point-to-point.
        out.main = arena.make<btPoint2PointConstraint>(s.a, s.b, s.frameInA.getOrigin(), s.frameInB.getOrigin());
        out.limit = arena.make<DirectionLimitConstraint>(s.a, s.b, shaftA, frameBRot, LimitShape::Cone, h, btScalar(0),
                                                         policy.limits);
        return out;
    }
    const btTransform bWorld = s.b.getCenterOfMassTransform();
    const btTransform aWorld = s.a.getCenterOfMassTransform();
    const btVector3 axisW = bWorld.getBasis() * axisB, shaftW = aWorld.getBasis() * shaftA;
    const btMatrix3x3 frameAWorld = shortestArc(axisW, shaftW) * (bWorld.getBasis() * frameBRot);
    const btTransform frameA(aWorld.getBasis().transpose() * frameAWorld, s.frameInA.getOrigin());
    const btTransform frameB(frameBRot, s.frameInB.getOrigin());
    auto* ct = arena.make<btConeTwistConstraint>(s.a, s.b, frameA, frameB);
    ct->setLimit(h, h, btScalar(-1), btScalar(1), policy.limits.errorReduction, btScalar(1));
    out.main = ct;
    return out;
}

JointParts universalJoint(detail::ObjectArena& arena, const FigureConstraint& c, const JointSite& s,
                          const JointPolicy& policy) {
    // No relative spin about the shafts (homokinetic, §4.4), swing free: our constant-velocity constraint
    // (Method::constantVelocityUniversal), or cone-twist with twist locked; frames' X axes are shaft 1 (body1) and
    // −shaft 2 (body2), aligned at the load pose.
    JointParts out;
    if (policy.constantVelocityUniversal) {
        out.main = arena.make<UniversalConstraint>(s.a, s.b, s.frameInA, s.frameInB);
    } else {
        auto* ct = arena.make<btConeTwistConstraint>(s.a, s.b, s.frameInA, s.frameInB);
        ct->setLimit(SIMD_PI, SIMD_PI, 0);
        out.main = ct;
    }
    // Friction about the frame's Y and Z (the swing axes), fixed in body2.
    out.frictionRows = 2;
    out.frictionAxes = swingFrictionAxes(s.frameInB.getBasis());
    if (const auto* cone = std::get_if<figure::ConeLimit>(&c.limit))
        out.limit = directionLimit(arena, s, s.body1Rotation * toBt(cone->shaftInBody1),
                                   basisWithX(s.body2Rotation * toBt(cone->axisInBody2)), LimitShape::Cone,
                                   cone->halfAngleRad, 0, policy.limits);
    else out.limit = pyramidLimit(arena, c, s, policy.limits);
    return out;
}

JointParts hingeJoint(detail::ObjectArena& arena, const FigureConstraint& c, const JointSite& s,
                      const JointPolicy& policy) {
    JointParts out;
    auto* h = arena.make<btHingeConstraint>(s.a, s.b, s.frameInA, s.frameInB, false);
    if (const auto* range = std::get_if<figure::HingeRange>(&c.limit)) {
        const btScalar lo = static_cast<btScalar>(range->lowerRad), hi = static_cast<btScalar>(range->upperRad);
        if (policy.limits.speculative)
            out.limit = arena.make<HingeRangeConstraint>(s.a, s.b, s.frameInA, s.frameInB, lo, hi, policy.limits);
        else h->setLimit(lo, hi, 1, policy.limits.errorReduction, 1);
    }
    out.main = h;
    // Friction about the hinge axis (the frame's Z), fixed in body2.
    out.frictionRows = 1;
    out.frictionAxes = hingeFrictionAxes(s.frameInB.getBasis());
    return out;
}

JointParts springJoint(detail::ObjectArena& arena, const FigureConstraint& c, const JointSite& s) {
    JointParts out;
    out.main = arena.make<SpringConstraint>(s.a, s.b, s.frameInA.getOrigin(), s.frameInB.getOrigin(),
                                            SpringConstraint::Params::of(c.spring));
    out.mainRole = RowRole::Spring;
    return out;
}

} // namespace

btMatrix3x3 swingFrictionAxes(const btMatrix3x3& f) {
    return btMatrix3x3(f[0][1], f[0][2], 0, f[1][1], f[1][2], 0, f[2][1], f[2][2], 0);
}

btMatrix3x3 hingeFrictionAxes(const btMatrix3x3& f) { return btMatrix3x3(f[0][2], 0, 0, f[1][2], 0, 0, f[2][2], 0, 0); }

JointParts buildJoint(detail::ObjectArena& arena, const FigureConstraint& c, const JointSite& site,
                      const JointPolicy& policy) {
    switch (c.type) {
    case JointType::Fixed: return fixedJoint(arena, site);
    case JointType::BallAndSocket: return ballJoint(arena, c, site, policy);
    case JointType::Universal: return universalJoint(arena, c, site, policy);
    case JointType::Hinge: return hingeJoint(arena, c, site, policy);
    case JointType::Slider: {
        JointParts out;
        out.main = arena.adopt(makeSlider(site.a, site.b, site.frameInA, site.frameInB));
        return out;
    }
    case JointType::Spring: return springJoint(arena, c, site);
    }
    return {};
}

} // namespace afb::bullet
