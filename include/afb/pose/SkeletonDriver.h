#pragma once
// Physics → pose (docs/format.md §5.1): the full md5 skeleton from the bodies' world transforms, following the `mod`
// rules, and CPU skinning of the md5mesh from it.
#include <span>
#include <vector>

#include "afb/decl/Md5Mesh.h"
#include "afb/figure/Figure.h"

/// The pose layer: md5 joint transforms from a ragdoll's bodies, for skinning the rendered model.
namespace afb::pose {

/// The figure layer's rigid transform; every pose here is in metres.
using figure::Transform;

/// A skeleton pose, metres: a driven one (driveSkeleton), an animated one (Blend.h: animatedPose, poseFromJoints) or
/// a blend of the two (blendPoses).
struct SkeletonPose {
    Transform entity; ///< model space to world; driveSkeleton's follows body 0 rigidly (docs/format.md §5.1 step 1)
    std::vector<Transform> model; ///< every md5 joint in model space
    std::vector<Transform> local; ///< every md5 joint relative to its parent (the root: model space)

    /// Every joint in world space (entity ∘ model).
    std::vector<Transform> world() const;
};

/// The skeleton for body world transforms `bodies` (one per figure body, body frames, metres). Joints with a body take
/// their orientation (`orientation`), position (`position`) or both (`both`) from it, the later body winning when two
/// drive one joint; every other component follows the parent with the af_pose local transform. Joint 0 never moves in
/// model space. The joint target uses the correct formula for a rotated entity (docs/format.md §5.1 note).
SkeletonPose driveSkeleton(const figure::Figure& figure, std::span<const Transform> bodies);

/// Skinned vertex positions per sub-mesh (metres, model space): Σ bias·(joint ∘ offset) over each vertex's
/// weights (docs/format.md §7.3), for the given model-space joint transforms (metres).
std::vector<std::vector<Eigen::Vector3d>> skin(const decl::Md5Mesh& mesh, std::span<const Transform> jointsModel,
                                               double metresPerUnit);

} // namespace afb::pose
