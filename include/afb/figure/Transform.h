#pragma once
// Rigid transforms in standard column-vector convention (Bullet's): world = rotation * local + position.
// Doom's row-matrix "axis" is converted to this once, where a file's values enter the figure layer (docs/format.md §0).
#include <Eigen/Geometry>

namespace afb::figure {

/// A rotation and a translation; maps local points to the parent frame as `rotation * p + position`.
struct Transform {
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity(); ///< proper rotation, columns = local axes in parent
    Eigen::Vector3d position = Eigen::Vector3d::Zero();     ///< origin of the local frame in the parent frame

    /// The point `local` expressed in the parent frame.
    Eigen::Vector3d apply(const Eigen::Vector3d& local) const { return rotation * local + position; }
    /// This transform followed by nothing else: (this ∘ child) maps child-local points to this transform's parent.
    Transform operator*(const Transform& child) const {
        return {rotation * child.rotation, rotation * child.position + position};
    }
    /// The inverse transform.
    Transform inverse() const { return {rotation.transpose(), -(rotation.transpose() * position)}; }
};

/// Standard rotation from md5 quaternion components as written (x, y, z; w = +sqrt(|1 − x² − y² − z²|)).
/// The engine uses R(q) as a row "axis", so the rotation applied to vectors is R(q)ᵀ = R(conj q) (docs/format.md §0,
/// §7.3, §8 item 21).
inline Eigen::Matrix3d rotationFromMd5(double x, double y, double z) {
    const double w = std::sqrt(std::abs(1.0 - x * x - y * y - z * z));
    return Eigen::Quaterniond(w, -x, -y, -z).normalized().toRotationMatrix();
}

} // namespace afb::figure
