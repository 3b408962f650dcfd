#pragma once
// Blending physics and animation (docs/motors.md, "Blending physics and animation"): a per-joint weighted blend of
// two skeleton poses of one figure, the per-body weights a game thinks in, and a linear fade of a weight over time.
// Both sides are SkeletonPose values in metres: driveSkeleton gives the simulated one, animatedPose (or
// poseFromJoints on any model-space joint pose) the animated one.
#include <optional>
#include <span>
#include <vector>

#include "afb/decl/Md5Anim.h"
#include "afb/figure/Figure.h"
#include "afb/pose/SkeletonDriver.h"
#include "afb/text/Diagnostics.h"

namespace afb::pose {

/// A skeleton pose from model-space joint transforms (one per md5 joint, metres, as figure::jointsFromAnimation and
/// figure::jointsInMetres give them) placed in the world by `entity` (model → world, metres). `model` is the input
/// as given; `local` is each joint relative to its parent (the root's: model space). Throws std::invalid_argument
/// when the joint count is not the skeleton's.
SkeletonPose poseFromJoints(const figure::Figure& figure, const Transform& entity,
                            std::span<const Transform> jointsModelMetres);

/// The animated side of a blend in one call: `anim` at `timeSeconds` (figure::jointsFromAnimation: played once, the
/// root placed as the load pose placed it) as a SkeletonPose under `entity` (model → world, metres). Errors as
/// jointsFromAnimation: nullopt with an error in `diagnostics`.
std::optional<SkeletonPose> animatedPose(const figure::Figure& figure, const decl::Md5Anim& anim, double timeSeconds,
                                         const Transform& entity, text::Diagnostics& diagnostics);

/// Spherical interpolation of unit quaternions along the shorter arc: `a` turned toward `b` by the fraction `t` of
/// the angle between the two rotations (at most π). `b` and `−b` (the same rotation) give the same result.
Eigen::Quaterniond slerpShortest(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b, double t);

/// A rigid transform between `a` (t = 0) and `b` (t = 1): rotation by slerpShortest, position linearly. t = 0 and
/// t = 1 return `a` and `b` bit for bit (no round trip through quaternions).
Transform interpolate(const Transform& a, const Transform& b, double t);

/// The joint a blend is anchored at: the joint body 0 drives (the pelvis of a humanoid; the joint the simulated
/// entity follows, docs/format.md §2.4), or joint 0 for a figure without bodies.
int blendAnchorJoint(const figure::Figure& figure);

/// The per-joint blend of two poses of one skeleton; weight 0 is `animated`, 1 is `simulated`, clamped to [0, 1].
/// Each joint's local transform (relative to its parent) is interpolated with its own weight (rotation: shortest-arc
/// slerp; translation: linear), and the model-space joints follow from the blended locals, parents first. The root
/// rule: the anchor joint (`anchorJoint`) is blended in world space with its own weight and the entity is placed so
/// that the anchor lands there. Blending the entity itself would swing the whole figure about the model origin (at
/// the feet) whenever the two poses lie far apart, e.g. a ragdoll lying on its back against a standing animation;
/// anchored, the pelvis moves on the straight line between its two places and turns in place. All weights 0 returns
/// `animated` and all weights 1 `simulated` bit for bit; a joint of weight 0 or 1 takes that side's local transform
/// bit for bit. `parents` is the skeleton's parent list (parents precede children). Throws std::invalid_argument when
/// a pose or the weights do not have one entry per joint, a weight is not finite, or the anchor is not a joint.
SkeletonPose blendPoses(std::span<const int> parents, int anchorJoint, const SkeletonPose& animated,
                        const SkeletonPose& simulated, std::span<const double> jointWeights);

/// blendPoses for `figure`'s skeleton, anchored at blendAnchorJoint(figure).
SkeletonPose blendPoses(const figure::Figure& figure, const SkeletonPose& animated, const SkeletonPose& simulated,
                        std::span<const double> jointWeights);

/// Joint weights from body weights (one per figure body): every joint a body contains (containedJoints,
/// figure::Figure::jointBody) takes that body's weight. A joint no body contains takes its parent's weight, so it
/// moves with the joints around it; joint 0, when no body contains it, takes body 0's weight (the body the simulated
/// entity follows). Throws std::invalid_argument when the count is not the figure's body count.
std::vector<double> jointWeightsFromBodies(const figure::Figure& figure, std::span<const double> bodyWeights);

/// A weight that goes linearly from one value to another over a time, then holds; e.g. physics faded in over 0.2 s
/// after a hit (0 → 1) and out again (1 → 0). Weights are clamped to [0, 1]; times in seconds of game time.
class BlendFade {
  public:
    /// Holds `weight`.
    explicit BlendFade(double weight = 0);
    /// Goes from `from` to `to` over `seconds` (≤ 0: at once), starting now.
    BlendFade(double from, double to, double seconds);

    /// A new ramp from the current weight to `to` over `seconds` (≤ 0: at once), starting now: a fade reversed
    /// halfway turns back from where it is, without a jump.
    void fadeTo(double to, double seconds);
    /// Moves the fade on by `dtSeconds` (≥ 0) and returns the new weight.
    double advance(double dtSeconds);
    /// The weight now.
    double weight() const { return weightAt(m_elapsed); }
    /// The weight `secondsSinceStart` after the current ramp began: `from` before it, `to` from its end on, the
    /// straight line between.
    double weightAt(double secondsSinceStart) const;
    /// The current ramp has reached its end value.
    bool finished() const { return m_elapsed >= m_seconds; }

  private:
    double m_from = 0;
    double m_to = 0;
    double m_seconds = 0;
    double m_elapsed = 0;
};

} // namespace afb::pose
