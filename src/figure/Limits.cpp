// Limit excess, one definition (docs/format.md §4.3, §4.5). Every angle is exact (atan2 and acos of the current
// directions), so the same number comes out whether the limit is checked at the load pose or after a drop.
#include "afb/figure/Limits.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace afb::figure {

double coneAngleRad(const ConeLimit& cone, const Eigen::Matrix3d& body1Rotation, const Eigen::Matrix3d& body2Rotation) {
    const Eigen::Vector3d shaft = body1Rotation * cone.shaftInBody1;
    const Eigen::Vector3d axis = body2Rotation * cone.axisInBody2;
    return std::acos(std::clamp(shaft.dot(axis), -1.0, 1.0));
}

Eigen::Vector2d pyramidPlanarAnglesRad(const PyramidLimit& pyramid, const Eigen::Matrix3d& body1Rotation,
                                       const Eigen::Matrix3d& body2Rotation) {
    const Eigen::Vector3d shaft = body1Rotation * pyramid.shaftInBody1;
    const Eigen::Vector3d inBasis = (body2Rotation * pyramid.basisInBody2).transpose() * shaft; // (s·f, s·l, s·u)
    return {std::atan2(inBasis.y(), inBasis.x()), std::atan2(inBasis.z(), inBasis.x())};
}

double hingeAngleRad(const FigureConstraint& c, const Eigen::Matrix3d& body1Rotation,
                     const Eigen::Matrix3d& body2Rotation) {
    const Eigen::Matrix3d frame1 = body1Rotation * c.frameInBody1.rotation;
    const Eigen::Matrix3d frame2 = body2Rotation * c.frameInBody2.rotation;
    // Frames coincide at the load pose and share Z (the axis), so frame2ᵀ·frame1 is a rotation about Z by φ.
    const Eigen::Matrix3d relative = frame2.transpose() * frame1;
    return std::atan2(relative(1, 0), relative(0, 0));
}

double hingeExcessRad(const HingeRange& range, double phiRad) {
    const double centre = 0.5 * (range.lowerRad + range.upperRad);
    const double half = 0.5 * (range.upperRad - range.lowerRad);
    return std::max(0.0, std::abs(std::remainder(phiRad - centre, 2 * std::numbers::pi)) - half);
}

double limitExcessRad(const FigureConstraint& c, const Eigen::Matrix3d& body1Rotation,
                      const Eigen::Matrix3d& body2Rotation) {
    if (const auto* hinge = std::get_if<HingeRange>(&c.limit))
        return hingeExcessRad(*hinge, hingeAngleRad(c, body1Rotation, body2Rotation));
    if (const auto* cone = std::get_if<ConeLimit>(&c.limit))
        return std::max(0.0, coneAngleRad(*cone, body1Rotation, body2Rotation) - cone->halfAngleRad);
    if (const auto* pyramid = std::get_if<PyramidLimit>(&c.limit)) {
        const Eigen::Vector2d a = pyramidPlanarAnglesRad(*pyramid, body1Rotation, body2Rotation);
        return std::max({0.0, std::abs(a.x()) - pyramid->halfAngle1Rad, std::abs(a.y()) - pyramid->halfAngle2Rad});
    }
    return 0.0;
}

} // namespace afb::figure
