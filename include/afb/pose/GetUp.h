#pragma once
// Getting up (docs/motors.md, "Getting up"): from a ragdoll at rest to the first frame of a get-up animation without
// a pop. The ragdoll's skeleton pose is snapshotted, the side it lies on decides between a face-up and a face-down
// get-up, the chosen frame is placed where the ragdoll lies, and the pose blends from the snapshot to that frame.
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "afb/figure/Figure.h"
#include "afb/pose/SkeletonDriver.h"

namespace afb::pose {

/// Which way a lying figure faces.
enum class LyingSide : std::uint8_t {
    FaceUp,   ///< on its back: the chest faces the sky
    FaceDown, ///< on its front: the chest faces the ground
};

/// The side `pose` lies on. The rule reads the anchor joint (blendAnchorJoint: the joint body 0 drives, the
/// pelvis): the figure's forward axis (model +X, docs/format.md §0) carried by that joint's rotation from the load
/// pose to `pose`, in world space; face-up when it points up (world +Z, against gravity) or lies level, face-down
/// when it points down.
LyingSide lyingSide(const figure::Figure& figure, const SkeletonPose& pose);

/// How a get-up is placed and timed.
struct GetUpOptions {
    double blendSeconds = 0.5; ///< from the snapshot to the get-up frame, > 0
    /// World height of the floor under the ragdoll, metres. Unset: the frame's anchor joint (pelvis) is put exactly
    /// where the ragdoll's is, height included. Set: only its horizontal position is matched and the animation's
    /// model origin (its floor) is put at this height.
    std::optional<double> groundHeightM = std::nullopt;
};

/// The entity transform (model → world, metres) that places a lying get-up frame where the ragdoll in `snapshot`
/// lies: a turn about world +Z only (the animation stays upright) and a translation. The turn is the heading that
/// best aligns the frame's anchor joint (pelvis) frame with the ragdoll's, over all three axes (least squares; for
/// a lying figure that is its head-to-feet and left-right directions); the translation puts the frame's anchor on
/// the ragdoll's (see GetUpOptions::groundHeightM). `frame` is model-space joints in metres (one per md5 joint, as
/// figure::jointsFromAnimation gives them). Throws std::invalid_argument on a joint count that is not the skeleton's.
Transform alignGetUp(const figure::Figure& figure, const SkeletonPose& snapshot, std::span<const Transform> frame,
                     const GetUpOptions& options = {});

/// A planned get-up: a plain value, everything getUpPose needs.
struct GetUp {
    LyingSide side = LyingSide::FaceUp; ///< which frame was chosen
    /// The entity transform for the get-up animation (model → world, metres): play the animation under it once the
    /// blend is over, and the character gets up where the ragdoll lay.
    Transform alignment;
    SkeletonPose from;        ///< the snapshot of the ragdoll
    SkeletonPose to;          ///< the chosen frame placed by `alignment`
    double blendSeconds = 0;  ///< length of the blend, seconds
    std::vector<int> parents; ///< the skeleton's parent list, for the blend
    int anchorJoint = 0;      ///< blendAnchorJoint of the figure
};

/// Plans the get-up from `snapshot` (a ragdoll at rest, e.g. driveSkeleton of its body transforms) to the first frame
/// of the face-up or face-down get-up animation (model-space joints in metres, one per md5 joint; e.g.
/// figure::jointsFromAnimation at time 0), chosen by lyingSide and placed by alignGetUp. Throws std::invalid_argument
/// on a joint count that is not the skeleton's or a blend time that is not finite and > 0.
GetUp planGetUp(const figure::Figure& figure, const SkeletonPose& snapshot, std::span<const Transform> faceUpFrame,
                std::span<const Transform> faceDownFrame, const GetUpOptions& options = {});

/// The pose `seconds` into the get-up blend: blendPoses of the placed frame and the snapshot, every joint weighted
/// 1 − s with s = x²(3 − 2x), x = seconds / blendSeconds clamped to [0, 1] (smooth at both ends: the pose starts and
/// arrives without a jerk). At or before 0 it is the snapshot bit for bit; at or after blendSeconds, the placed frame.
/// Throws std::invalid_argument when `seconds` is NaN.
SkeletonPose getUpPose(const GetUp& plan, double seconds);

} // namespace afb::pose
