#pragma once
// Placing a figure's bodies from an md5 pose (docs/format.md §2.5, §5.4): what "start from an animation" needs.
// The one call is bodyStatesFromAnimation; the steps it is made of stay public for other pose sources.
#include <optional>
#include <span>
#include <vector>

#include "afb/decl/Md5Anim.h"
#include "afb/figure/Figure.h"
#include "afb/text/Diagnostics.h"

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
/// body = entity ∘ joint ∘ jointInBody⁻¹ (docs/format.md §2.5). A body whose joint is invalid keeps its load pose.
std::vector<Transform> bodiesFromJoints(const Figure& figure, const Transform& entity,
                                        std::span<const Transform> jointsModelMetres);

/// Body states with velocities inherited from two poses `dt` seconds apart: linear velocity of the centre of
/// mass and angular velocity (the rotation from `before` to `after` as a rotation vector / dt). The engine
/// inherits only the linear part (docs/format.md §5.4); both are given here, from `after`'s pose.
std::vector<BodyState> inheritVelocities(std::span<const Transform> before, std::span<const Transform> after,
                                         double dt);

/// The figure's load pose (Skeleton::loadPose, docs/format.md §2.1) in metres: model-space joint transforms, one per
/// md5 joint, converted with the figure's own UnitSystem. Feed it to bodiesFromJoints to place the bodies as
/// they were built.
std::vector<Transform> jointsInMetres(const Figure& figure);

/// Model-space joint transforms (metres, one per md5 joint) of `anim` at `timeSeconds` after its start, as the figure's
/// animator would pose them: animPoseLocal (played once; frames blended, frame 0 before the start, the last frame after
/// the end), the root translation replaced by or offset by the model offset as the load pose was
/// (Skeleton::rootTranslation, docs/format.md §2.1: an actor's root motion on joint 0 is dropped, the entity carries
/// it), hierarchy concatenated, converted with the figure's UnitSystem. `anim` must match the skeleton as the engine's
/// CheckModelHierarchy demands (joint count, names case-sensitively, parents; docs/format.md §7.4) and be
/// self-consistent (baseframe and frame sizes, component indices, at least one frame). On a mismatch, a non-finite time
/// or a non-finite result: nullopt with an error in `diagnostics` located at the figure.
std::optional<std::vector<Transform>> jointsFromAnimation(const Figure& figure, const decl::Md5Anim& anim,
                                                          double timeSeconds, text::Diagnostics& diagnostics);

/// The default velocity step of bodyStatesFromAnimation, seconds: the engine's time resolution (game time and
/// anim blend weights are in whole milliseconds).
inline constexpr double kAnimationVelocityStepSeconds = 0.001;

/// Start from an animation in one call: the world-space state of every body (body order) for `anim` at `timeSeconds`,
/// the figure's entity at `entity` (model → world, metres). Poses: jointsFromAnimation, then bodiesFromJoints.
/// Velocities: inheritVelocities from the pose `velocityStepSeconds` earlier to this one — the backward difference of
/// the engine's StartFromCurrentPose with velocityTime = step (SetupPose at t − step, ChangePose at t; docs/format.md
/// §5.4), angular velocity included. The anim is played once, so before its start the pose is frame 0 (the first
/// `velocityStepSeconds` see only part of the motion) and after its end the bodies are still; an anim with one frame or
/// frameRate 0 gives zero velocities. The entity is taken as not moving: add its own velocity yourself. Errors as
/// jointsFromAnimation, and a step that is not finite and > 0 or an entity transform that is not finite: nullopt. The
/// result goes to bullet::Ragdoll::setBodyStates of a ragdoll spawned at the same entity transform (its world-attached
/// constraints are placed by the spawn transform).
std::optional<std::vector<BodyState>>
bodyStatesFromAnimation(const Figure& figure, const decl::Md5Anim& anim, double timeSeconds, const Transform& entity,
                        text::Diagnostics& diagnostics, double velocityStepSeconds = kAnimationVelocityStepSeconds);

} // namespace afb::figure
