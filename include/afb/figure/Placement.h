#pragma once
// Placing a figure's bodies from an md5 pose (af-format §2.5, §5.4): what "start from an animation" needs.
#include <span>
#include <vector>

#include "afb/figure/Figure.h"

namespace afb::figure {

/// A body's motion state in world space, SI.
struct BodyState {
    Transform pose;                                            ///< body frame (centre of mass, principal axes)
    Eigen::Vector3d linearVelocity = Eigen::Vector3d::Zero();  ///< m/s of the centre of mass
    Eigen::Vector3d angularVelocity = Eigen::Vector3d::Zero(); ///< rad/s
};

/// Model-space joint transforms (Doom units, as Skeleton and animPoseLocal give them) converted to metres.
std::vector<Transform> toMetres(std::span<const Transform> jointsDoom, double metresPerUnit);

/// World transforms of every body for a model-space joint pose (metres) under `entity` (model → world, metres):
/// body = entity ∘ joint ∘ jointInBody⁻¹ (§2.5). A body whose joint is invalid keeps its load pose.
std::vector<Transform> bodiesFromJoints(const Figure& figure, const Transform& entity,
                                        std::span<const Transform> jointsModelMetres);

/// Body states with velocities inherited from two poses `dt` seconds apart: linear velocity of the centre of
/// mass and angular velocity (the rotation from `before` to `after` as a rotation vector / dt). The engine
/// inherits only the linear part (§5.4); both are given here, from `after`'s pose.
std::vector<BodyState> inheritVelocities(std::span<const Transform> before, std::span<const Transform> after,
                                         double dt);

} // namespace afb::figure
