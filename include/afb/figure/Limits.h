#pragma once
// How far a constraint's limit is exceeded, engine-neutral: the one definition the figure's load-pose lint
// and the drop metrics share (docs/format.md §4.3 cone and pyramid, §4.5 hinge). A pose is given as the rotations
// of the two bodies' frames (centre of mass, principal axes) to world; for a world constraint (body2 = −1)
// the "body2 rotation" is the model → world rotation, since the figure keeps body2's data in model space
// then.
#include <Eigen/Core>

#include "afb/figure/Figure.h"

namespace afb::figure {

/// Angle between the cone's shaft (fixed in body1) and its axis (fixed in body2), radians in [0, π].
double coneAngleRad(const ConeLimit& cone, const Eigen::Matrix3d& body1Rotation, const Eigen::Matrix3d& body2Rotation);

/// The pyramid's two planar angles of the shaft (body1) in its basis f, l, u = f×l (body2), radians in
/// (−π, π]: x = atan2(s·l, s·f), the angle in span(f, l), limited by halfAngle1Rad; y = atan2(s·u, s·f), the
/// angle in span(f, u), limited by halfAngle2Rad (docs/format.md §4.3; exact, not small-angle).
Eigen::Vector2d pyramidPlanarAnglesRad(const PyramidLimit& pyramid, const Eigen::Matrix3d& body1Rotation,
                                       const Eigen::Matrix3d& body2Rotation);

/// φ of a hinge (docs/format.md §4.5): the right-handed rotation of constraint c's frame in body1 relative to its frame
/// in body2 about their Z axis (the hinge axis), 0 at the load pose, radians in (−π, π].
double hingeAngleRad(const FigureConstraint& c, const Eigen::Matrix3d& body1Rotation,
                     const Eigen::Matrix3d& body2Rotation);

/// How far φ lies outside `range`, radians (0 inside). Angles wrap: the distance is measured around the
/// circle from the range's centre, so a range that crosses ±π is a range, not its complement.
double hingeExcessRad(const HingeRange& range, double phiRad);

/// How far constraint c's limit is exceeded, radians: the cone angle minus its half angle, the larger of the
/// pyramid's two planar-angle excesses, or the hinge excess; 0 inside the limit or for a constraint without
/// one.
double limitExcessRad(const FigureConstraint& c, const Eigen::Matrix3d& body1Rotation,
                      const Eigen::Matrix3d& body2Rotation);

} // namespace afb::figure
