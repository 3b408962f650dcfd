#include "afb/detail/DoomMath.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

namespace afb::figure {

Eigen::Matrix3d anglesToRotation(double pitchDeg, double yawDeg, double rollDeg) {
    return (Eigen::AngleAxisd(yawDeg * kRadPerDeg, Eigen::Vector3d::UnitZ()) *
            Eigen::AngleAxisd(pitchDeg * kRadPerDeg, Eigen::Vector3d::UnitY()) *
            Eigen::AngleAxisd(rollDeg * kRadPerDeg, Eigen::Vector3d::UnitX()))
        .toRotationMatrix();
}

Eigen::Vector3d rotationToAngles(const Eigen::Matrix3d& r) {
    // Column 0 (forward) = (cp·cy, cp·sy, −sp); the roll from the z components of left and up (docs/format.md §0).
    const double pitch = std::asin(std::clamp(-r(2, 0), -1.0, 1.0));
    double yaw = 0, roll = 0;
    if (std::abs(r(2, 0)) < 1 - 1e-12) {
        yaw = std::atan2(r(1, 0), r(0, 0));
        roll = std::atan2(r(2, 1), r(2, 2));
    } else {
        yaw = std::atan2(-r(0, 1), r(1, 1));
    }
    return Eigen::Vector3d(pitch, yaw, roll) / kRadPerDeg;
}

PitchYaw toAngles(const Eigen::Vector3d& v) {
    if (v.x() == 0.0 && v.y() == 0.0) return {v.z() > 0.0 ? -90.0 : -270.0, 0.0};
    double yaw = std::atan2(v.y(), v.x()) / kRadPerDeg;
    if (yaw < 0.0) yaw += 360.0;
    const double forward = std::sqrt(v.x() * v.x() + v.y() * v.y());
    double pitch = -std::atan2(v.z(), forward) / kRadPerDeg;
    if (pitch < 0.0) pitch += 360.0;
    return {pitch, yaw};
}

Eigen::Vector3d normalVectorsLeft(const Eigen::Vector3d& v) {
    const double d = v.x() * v.x() + v.y() * v.y();
    if (d == 0.0) return Eigen::Vector3d::UnitX();
    const double inv = 1.0 / std::sqrt(d);
    return {-v.y() * inv, v.x() * inv, 0.0};
}

Eigen::Vector3d orthogonalBasisLeft(const Eigen::Vector3d& v) {
    if (std::abs(v.z()) > 0.7) {
        const double l = std::sqrt(v.y() * v.y() + v.z() * v.z());
        return {l, v.x() * v.y() / l, v.x() * v.z() / l};
    }
    const double l = std::sqrt(v.x() * v.x() + v.y() * v.y());
    return {-v.y() / l, v.x() / l, 0.0};
}

double nonUnitAxisAngle(double thetaRad, double axisLength) {
    const double l = axisLength;
    return std::atan2(l * std::sin(thetaRad), 1.0 - l * l * (1.0 - std::cos(thetaRad)));
}

} // namespace afb::figure
