#include "afb/pose/GetUp.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "afb/pose/Blend.h"

namespace afb::pose {

namespace {

void requireFrameJoints(std::size_t count, const figure::Figure& figure, const char* what) {
    const std::size_t joints = static_cast<std::size_t>(figure.skeleton.jointCount());
    if (count != joints)
        throw std::invalid_argument(std::string(what) + ": " + std::to_string(count) + " joints for a skeleton of " +
                                    std::to_string(joints));
}

// The anchor joint's world transform in `pose`.
Transform anchorInWorld(const SkeletonPose& pose, int anchor) {
    return pose.entity * pose.model[static_cast<std::size_t>(anchor)];
}

} // namespace

LyingSide lyingSide(const figure::Figure& figure, const SkeletonPose& pose) {
    requireFrameJoints(pose.model.size(), figure, "lyingSide");
    const int r = blendAnchorJoint(figure);
    // The joint's turn from its load pose (model space) to `pose` (world), applied to the model's forward axis.
    const Eigen::Matrix3d& load = figure.skeleton.loadPose()[static_cast<std::size_t>(r)].rotation;
    const Eigen::Vector3d forward = anchorInWorld(pose, r).rotation * load.transpose() * Eigen::Vector3d::UnitX();
    return forward.z() >= 0 ? LyingSide::FaceUp : LyingSide::FaceDown;
}

Transform alignGetUp(const figure::Figure& figure, const SkeletonPose& snapshot, std::span<const Transform> frame,
                     const GetUpOptions& options) {
    requireFrameJoints(snapshot.model.size(), figure, "alignGetUp: snapshot");
    requireFrameJoints(frame.size(), figure, "alignGetUp: frame");
    const int r = blendAnchorJoint(figure);
    const Transform& inFrame = frame[static_cast<std::size_t>(r)]; // model space = world under an identity entity
    const Transform lying = anchorInWorld(snapshot, r);
    // The turn θ about +Z minimising ‖Rz(θ)·A − B‖ (Frobenius) for the frame's anchor rotation A and the ragdoll's B:
    // it maximises trace(Rz(θ)·M), M = A·Bᵀ, which is cos θ·(M00 + M11) + sin θ·(M01 − M10) + M22.
    const Eigen::Matrix3d m = inFrame.rotation * lying.rotation.transpose();
    const double sinPart = m(0, 1) - m(1, 0), cosPart = m(0, 0) + m(1, 1);
    const double heading = sinPart == 0 && cosPart == 0 ? 0.0 : std::atan2(sinPart, cosPart);
    Transform out;
    out.rotation = Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    out.position = lying.position - out.rotation * inFrame.position;
    if (options.groundHeightM) out.position.z() = *options.groundHeightM;
    return out;
}

GetUp planGetUp(const figure::Figure& figure, const SkeletonPose& snapshot, std::span<const Transform> faceUpFrame,
                std::span<const Transform> faceDownFrame, const GetUpOptions& options) {
    requireFrameJoints(faceUpFrame.size(), figure, "planGetUp: face-up frame");
    requireFrameJoints(faceDownFrame.size(), figure, "planGetUp: face-down frame");
    requireFrameJoints(snapshot.local.size(), figure, "planGetUp: snapshot");
    if (!std::isfinite(options.blendSeconds) || !(options.blendSeconds > 0))
        throw std::invalid_argument("planGetUp: the blend time must be finite and > 0");
    GetUp plan;
    plan.side = lyingSide(figure, snapshot);
    const std::span<const Transform> frame = plan.side == LyingSide::FaceUp ? faceUpFrame : faceDownFrame;
    plan.alignment = alignGetUp(figure, snapshot, frame, options);
    plan.from = snapshot;
    plan.to = poseFromJoints(figure, plan.alignment, frame);
    plan.blendSeconds = options.blendSeconds;
    plan.parents = figure.skeleton.parents();
    plan.anchorJoint = blendAnchorJoint(figure);
    return plan;
}

SkeletonPose getUpPose(const GetUp& plan, double seconds) {
    const double x = std::clamp(seconds / plan.blendSeconds, 0.0, 1.0);
    const double s = x * x * (3 - 2 * x);
    const std::vector<double> weights(plan.parents.size(), 1 - s);
    return blendPoses(plan.parents, plan.anchorJoint, plan.to, plan.from, weights);
}

} // namespace afb::pose
