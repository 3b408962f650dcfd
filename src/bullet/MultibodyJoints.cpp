// One builder per joint type for the multibody backend (MultibodyJoints.h): docs/format.md §4.2–§4.7 as links, the
// §4.3/§4.5 limits, §4.4 the universal joint's twist row and §4.8 the friction axes (shared with JointBuilders).
#include "MultibodyJoints.h"

#include "JointBuilders.h"
#include "afb/detail/Convert.h"

namespace afb::bullet::detail {

using figure::FigureConstraint;
using figure::JointType;

namespace {

/// A ball or universal joint's cone or pyramid limit (the rigid backend's DirectionLimitConstraint), or none.
std::optional<MultibodyLimit::Kind> directionLimit(const FigureConstraint& c, const MultibodyJointSite& s) {
    if (const auto* cone = std::get_if<figure::ConeLimit>(&c.limit))
        return MultibodyLimit::Direction{LimitShape::Cone, toBt(cone->shaftInBody1),
                                         basisWithX(s.body2Rotation * toBt(cone->axisInBody2)),
                                         static_cast<btScalar>(cone->halfAngleRad), 0};
    if (const auto* pyramid = std::get_if<figure::PyramidLimit>(&c.limit))
        return MultibodyLimit::Direction{LimitShape::Pyramid, toBt(pyramid->shaftInBody1),
                                         s.body2Rotation * toBt(pyramid->basisInBody2),
                                         static_cast<btScalar>(pyramid->halfAngle1Rad),
                                         static_cast<btScalar>(pyramid->halfAngle2Rad)};
    return std::nullopt;
}

MultibodyJointParts fixedJoint() {
    MultibodyJointParts out;
    out.link = LinkKind::Fixed;
    return out;
}

MultibodyJointParts ballJoint(const FigureConstraint& c, const MultibodyJointSite& s) {
    MultibodyJointParts out;
    out.link = LinkKind::Spherical;
    out.limit = directionLimit(c, s);
    out.frictionRows = 3; // about body2's own axes (the world's for a world joint)
    return out;
}

MultibodyJointParts universalJoint(const FigureConstraint& c, const MultibodyJointSite& s) {
    // §4.4: two free swings and no spin about the shafts: a spherical link whose twist a row holds. A Cardan pair
    // of revolute links (a massless link turning about one axis, the child about a second) has a singular pose at
    // 90° from the load pose, reached at impact, where the first coordinate spins the child about its own long axis
    // and explodes (docs/stability.md).
    MultibodyJointParts out;
    out.link = LinkKind::Spherical;
    out.twistRow = true;
    out.limit = directionLimit(c, s);
    out.frictionAxes = swingFrictionAxes(s.frameInBody2.getBasis());
    out.frictionRows = 2;
    return out;
}

MultibodyJointParts hingeJoint(const FigureConstraint& c, const MultibodyJointSite& s) {
    MultibodyJointParts out;
    out.link = LinkKind::Revolute;
    out.axisInBody1 = s.frameInBody1.getBasis().getColumn(2); // §4.5: the frame's Z is the hinge axis
    out.axisInBody2 = s.frameInBody2.getBasis().getColumn(2);
    if (const auto* range = std::get_if<figure::HingeRange>(&c.limit))
        out.limit =
            MultibodyLimit::Hinge{s.frameInBody1.getBasis(), s.frameInBody2.getBasis(),
                                  static_cast<btScalar>(range->lowerRad), static_cast<btScalar>(range->upperRad)};
    out.frictionAxes = hingeFrictionAxes(s.frameInBody2.getBasis());
    out.frictionRows = 1;
    return out;
}

MultibodyJointParts sliderJoint(const MultibodyJointSite& s) {
    MultibodyJointParts out;
    out.link = LinkKind::Prismatic;
    out.axisInBody1 = s.frameInBody1.getBasis().getColumn(0); // §4.6: the frame's X is the axis
    out.axisInBody2 = s.frameInBody2.getBasis().getColumn(0);
    return out;
}

MultibodyJointParts springJoint() {
    MultibodyJointParts out;
    out.mainRole = RowRole::Spring;
    return out;
}

} // namespace

MultibodyJointParts buildMultibodyJoint(const FigureConstraint& c, const MultibodyJointSite& site) {
    switch (c.type) {
    case JointType::Fixed: return fixedJoint();
    case JointType::BallAndSocket: return ballJoint(c, site);
    case JointType::Universal: return universalJoint(c, site);
    case JointType::Hinge: return hingeJoint(c, site);
    case JointType::Slider: return sliderJoint(site);
    case JointType::Spring: return springJoint();
    }
    return {};
}

} // namespace afb::bullet::detail
