#include "afb/figure/DoomMath.h"

#include <cmath>

#include <Eigen/Geometry>

namespace afb::figure {

Eigen::Matrix3d anglesToRotation(double pitchDeg, double yawDeg, double rollDeg) {
    return (Eigen::AngleAxisd(yawDeg * kRadPerDeg, Eigen::Vector3d::UnitZ()) *
            Eigen::AngleAxisd(pitchDeg * kRadPerDeg, Eigen::Vector3d::UnitY()) *
            Eigen::AngleAxisd(rollDeg * kRadPerDeg, Eigen::Vector3d::UnitX()))
        .toRotationMatrix();
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
