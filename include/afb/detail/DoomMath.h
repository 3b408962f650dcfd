#pragma once
// The engine's angle and basis helpers (docs/format.md §0), expressed in standard column math. Results are what the
// engine computes; only the representation differs (columns here, rows in Doom's idMat3).
#include <Eigen/Core>

namespace afb::figure {

/// Degrees to radians.
inline constexpr double kRadPerDeg = 0.017453292519943295769;

/// idAngles(pitch, yaw, roll).ToMat3() as a standard rotation R = Rz(yaw)·Ry(pitch)·Rx(roll): its columns are
/// forward, left and up. Degrees; positive pitch points the nose down (docs/format.md §0).
Eigen::Matrix3d anglesToRotation(double pitchDeg, double yawDeg, double rollDeg);

/// The inverse of anglesToRotation: (pitch, yaw, roll) in degrees of a proper rotation, pitch in [−90, 90]; at
/// pitch ±90 the roll is folded into the yaw. For writing `angles` of an `.af` body (afb gen).
Eigen::Vector3d rotationToAngles(const Eigen::Matrix3d& rotation);

/// idVec3::ToAngles: yaw = atan2(y, x) in [0, 360), pitch = −atan2(z, √(x²+y²)); roll 0. The vertical case uses
/// the engine's exact test (x == 0 and y == 0: yaw 0, pitch −90 for z > 0, else −270). Degrees.
struct PitchYaw {
    double pitchDeg = 0;
    double yawDeg = 0;
};
PitchYaw toAngles(const Eigen::Vector3d& v);

/// idVec3::NormalVectors' `left`: (−y, x, 0)/√(x²+y²), or (1, 0, 0) when x² + y² is exactly 0.
Eigen::Vector3d normalVectorsLeft(const Eigen::Vector3d& v);

/// idVec3::OrthogonalBasis' `left` for a possibly non-unit v (the engine does not normalize first).
Eigen::Vector3d orthogonalBasisLeft(const Eigen::Vector3d& v);

/// The engine's rotation of θ about a non-unit axis of length L, seen as an angle about the unit axis
/// (docs/format.md §4.5): g(θ) = atan2(L·sin θ, 1 − L²(1 − cos θ)). Radians in, radians out; g = θ (wrapped) for L = 1.
double nonUnitAxisAngle(double thetaRad, double axisLength);

} // namespace afb::figure
