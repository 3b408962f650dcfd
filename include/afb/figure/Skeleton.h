#pragma once
// The md5 skeleton a figure is built on: joint names and parents, the mesh bind pose, the af_pose load pose
// the
// `.af` decl is evaluated against (docs/format.md §2.1) and the af_pose local transforms runtime FK starts from
// (docs/format.md §5.1). Everything here is in Doom units, model space (X forward, Y left, Z up) and standard column
// rotations: the md5 quaternion sign and Doom's row matrices are converted once, when the transforms are made
// (docs/format.md §0, §7.3).
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "afb/decl/Md5Anim.h"
#include "afb/decl/Md5Mesh.h"
#include "afb/figure/Transform.h"
#include "afb/text/Diagnostics.h"

namespace afb::figure {

/// How the load pose places the root joint (docs/format.md §2.1; the engine's `remove_origin_offset`).
/// The two differ only when af_pose animates the root translation.
enum class RootTranslation {
    ReplacedByOffset, ///< root translation := model offset (actors: idAI, idPlayer remove the origin offset)
    OffsetAdded,      ///< root translation := animated root translation + model offset (AF entities)
};

/// A joint hierarchy with its reference poses. A plain copyable value, built once by `build`.
/// Invariants: every list has one entry per joint, joint 0 is the root, and parents precede their children.
class Skeleton {
  public:
    /// Checks `afPose` against `mesh` and computes the poses. `modelOffset` is the modelDef `offset` (Doom
    /// units, model space). On any error (no joints, hierarchy mismatch, no frames, inconsistent hand-built
    /// values, non-finite results): nullopt with an error in `diagnostics`, located at `context` (e.g. the
    /// modelDef or af_pose path). Warns when the load pose differs from the af_pose baseframe (docs/format.md §8
    /// item 19) and when joint names repeat ignoring case (docs/format.md §8 item 22).
    static std::optional<Skeleton> build(const decl::Md5Mesh& mesh, const decl::Md5Anim& afPose,
                                         const Eigen::Vector3d& modelOffset, text::Diagnostics& diagnostics,
                                         const std::string& context,
                                         RootTranslation rootTranslation = RootTranslation::ReplacedByOffset);

    /// Number of joints (at least 1).
    int jointCount() const { return static_cast<int>(m_names.size()); }
    /// Joint names as written in the md5mesh, in joint order.
    const std::vector<std::string>& names() const { return m_names; }
    /// Name of joint `joint` (0 <= joint < jointCount()).
    const std::string& name(int joint) const { return m_names[static_cast<std::size_t>(joint)]; }
    /// Parent index per joint, lower than the joint's own index; -1 for the root (joint 0).
    const std::vector<int>& parents() const { return m_parents; }
    /// Parent of joint `joint` (0 <= joint < jointCount()); -1 for the root.
    int parent(int joint) const { return m_parents[static_cast<std::size_t>(joint)]; }
    /// The modelDef visual offset given to `build` (Doom units, model space).
    const Eigen::Vector3d& modelOffset() const { return m_modelOffset; }
    /// How `build` placed the root joint in the load pose; any other animation frame is posed the same way
    /// (the engine's animator applies one rule to every frame, docs/format.md §2.1).
    RootTranslation rootTranslation() const { return m_rootTranslation; }

    /// Model-space bind pose from the md5mesh `joints` block, as written (no model offset), Doom units.
    const std::vector<Transform>& bindPose() const { return m_bindPose; }
    /// Model-space af_pose at t = 1 ms (frame 0 blended frameRate/1000 toward frame 1 when there are several
    /// frames), root translation per RootTranslation, model offset included (docs/format.md §2.1). Doom units. The
    /// `.af` decl's vectors, bodies and constraints are all evaluated in this pose.
    const std::vector<Transform>& loadPose() const { return m_loadPose; }
    /// Parent-relative af_pose baseframe transforms with the root translation zeroed and then set to the
    /// model offset: the local pose runtime FK starts from (docs/format.md §5.1 step 3). Doom units; root: model
    /// space.
    const std::vector<Transform>& afPoseLocal() const { return m_afPoseLocal; }

    /// Index of the first joint named `name` ignoring ASCII case, as the engine's joint lookups do (docs/format.md
    /// §7.3, §8 item 22: a duplicate name is shadowed by the earlier joint); nullopt when absent.
    std::optional<int> findJoint(std::string_view name) const;
    /// The first joint in list order whose parent is `joint`; `joint` itself when it has no child. `joint` =
    /// -1 (no such joint) gives 0, the root (idAnimator::GetFirstChild, docs/format.md §2.4). -1 <= joint <
    /// jointCount().
    int firstChild(int joint) const;
    /// `joint` followed by all its descendants, in joint order: the joints after it up to the first one whose
    /// parent index is lower than `joint` — what `*name` selects in containedJoints and channels (docs/format.md
    /// §5.3; relies on md5 depth-first order, as the engine does). 0 <= joint < jointCount().
    std::vector<int> jointAndDescendants(int joint) const;

  private:
    Skeleton() = default;

    std::vector<std::string> m_names;
    std::vector<int> m_parents;
    Eigen::Vector3d m_modelOffset = Eigen::Vector3d::Zero();
    RootTranslation m_rootTranslation = RootTranslation::ReplacedByOffset;
    std::vector<Transform> m_bindPose;
    std::vector<Transform> m_loadPose;
    std::vector<Transform> m_afPoseLocal;
};

/// Parent-relative transforms of frame `frame` of `anim` (Doom units; the root's is model space without any
/// model offset): the baseframe with the frame's animated components written over it, quaternion w
/// recomputed, and the root translation made relative to the baseframe root translation as the engine's anim
/// loader does (animated root components minus the baseframe value, the others 0; docs/format.md §7.4). `frame` is
/// clamped to the frames present; an anim without frames gives its baseframe (with the root translation
/// zeroed). One entry per baseframe joint.
std::vector<Transform> animFrameLocal(const decl::Md5Anim& anim, int frame);

/// Parent-relative transforms of `anim` at `timeSeconds` after its start, played once (Doom units; root as in
/// animFrameLocal). Follows idMD5Anim::ConvertTimeToFrame with a cycle count of 1: with frame time f =
/// t · frameRate, frame ⌊f⌋ is blended toward frame ⌊f⌋ + 1 by f − ⌊f⌋ (translations lerped, rotations
/// slerped along the shorter arc); t <= 0 or a single frame gives frame 0; from f >= numFrames − 1 on it
/// holds the last frame (no looping, no accumulated root motion). The engine works in whole milliseconds with
/// the blend weight in steps of 1/1000; at whole-millisecond times this agrees with it up to rounding (t =
/// 0.001 gives frame 0 blended frameRate/1000 toward frame 1, the af_pose load time).
std::vector<Transform> animPoseLocal(const decl::Md5Anim& anim, double timeSeconds);

/// Model-space transforms from parent-relative ones: joint i = model[parents[i]] ∘ local[i], roots (parent <
/// 0) unchanged. Parents must precede children; a parent index that does not (or a missing entry in
/// `parents`) is treated as a root. One entry per element of `local`.
std::vector<Transform> toModelSpace(const std::vector<Transform>& local, const std::vector<int>& parents);

} // namespace afb::figure
