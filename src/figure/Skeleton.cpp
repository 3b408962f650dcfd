#include "afb/figure/Skeleton.h"

#include <cmath>
#include <cstddef>
#include <numbers>
#include <utility>

#include <Eigen/Geometry>

#include "afb/detail/Lexer.h"

namespace afb::figure {
namespace {

// A joint as the anim code blends it: a quaternion and a translation. The quaternion is already the standard
// one, the conjugate of the file's (docs/format.md §0, §7.3); slerp commutes with conjugation, so blending here
// equals blending the engine's quaternions and converting afterwards.
struct JointQuat {
    Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
    Eigen::Vector3d position = Eigen::Vector3d::Zero();
};

Eigen::Vector3d toEigen(const decl::Vec3& v) { return {v.x, v.y, v.z}; }

// The standard quaternion for md5 components (x, y, z) as written: w = +sqrt(|1 − x² − y² − z²|)
// (idQuat::CalcW), then conjugated. Normalised, as rotationFromMd5 does, so an out-of-range input still
// yields a rotation.
Eigen::Quaterniond quatFromMd5(double x, double y, double z) {
    const double w = std::sqrt(std::abs(1.0 - x * x - y * y - z * z));
    return Eigen::Quaterniond(w, -x, -y, -z).normalized();
}

// The baseframe with `frame`'s animated components written over it (nullptr: the baseframe alone), root
// translation relative to the baseframe root (idMD5Anim::LoadAnim subtracts the baseframe value from the
// animated root components and zeroes the baseframe root translation; docs/format.md §7.4).
std::vector<JointQuat> frameJoints(const decl::Md5Anim& anim, const std::vector<double>* frame) {
    std::vector<JointQuat> joints(anim.baseframe.size());
    for (std::size_t j = 0; j < anim.baseframe.size(); ++j) {
        const decl::Md5BaseJoint& base = anim.baseframe[j];
        Eigen::Vector3d t = toEigen(base.position);
        Eigen::Vector3d q = toEigen(base.orientation);
        if (frame && j < anim.hierarchy.size()) {
            const decl::Md5HierarchyEntry& h = anim.hierarchy[j];
            auto next = static_cast<std::size_t>(h.startIndex < 0 ? 0 : h.startIndex);
            // Components are read in the order Tx, Ty, Tz, Qx, Qy, Qz (docs/format.md §7.4); a hand-built frame
            // that is too short leaves the rest at their baseframe values rather than reading past its end.
            const auto take = [&](int bit, double& value) {
                if (!(h.flags & bit)) return;
                if (next < frame->size()) value = (*frame)[next];
                ++next;
            };
            take(decl::kMd5Tx, t.x());
            take(decl::kMd5Ty, t.y());
            take(decl::kMd5Tz, t.z());
            take(decl::kMd5Qx, q.x());
            take(decl::kMd5Qy, q.y());
            take(decl::kMd5Qz, q.z());
        }
        if (j == 0) t -= toEigen(base.position);
        joints[j].rotation = quatFromMd5(q.x(), q.y(), q.z());
        joints[j].position = t;
    }
    return joints;
}

const std::vector<double>* framePointer(const decl::Md5Anim& anim, int frame) {
    if (anim.frames.empty()) return nullptr;
    const int last = static_cast<int>(anim.frames.size()) - 1;
    const int k = frame < 0 ? 0 : (frame > last ? last : frame);
    return &anim.frames[static_cast<std::size_t>(k)];
}

std::vector<Transform> toTransforms(const std::vector<JointQuat>& joints) {
    std::vector<Transform> out;
    out.reserve(joints.size());
    for (const JointQuat& j : joints) out.push_back({j.rotation.toRotationMatrix(), j.position});
    return out;
}

// idSIMD BlendJoints: slerp rotations (shorter arc, as idQuat::Slerp and Eigen's slerp both take), lerp
// translations; `weight` is the engine's backlerp, the share of `to`.
std::vector<JointQuat> blend(std::vector<JointQuat> from, const std::vector<JointQuat>& to, double weight) {
    for (std::size_t j = 0; j < from.size() && j < to.size(); ++j) {
        from[j].rotation = from[j].rotation.slerp(weight, to[j].rotation).normalized();
        from[j].position += weight * (to[j].position - from[j].position);
    }
    return from;
}

bool isFinite(const Transform& t) { return t.rotation.allFinite() && t.position.allFinite(); }

// Angle of the rotation a⁻¹·b, radians.
double angleBetween(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
    const double c = ((a.transpose() * b).trace() - 1.0) / 2.0;
    return std::acos(c > 1.0 ? 1.0 : (c < -1.0 ? -1.0 : c));
}

std::string quotedName(const std::string& s) { return "\"" + s + "\""; }

// Hand-built values can break what the parsers guarantee; the poses rely on it, so build() checks it again: the
// mesh's joints, then (after the hierarchies are compared) the anim's own counts.
std::optional<std::string> meshInconsistency(const decl::Md5Mesh& mesh) {
    if (mesh.joints.empty()) return "the mesh has no joints";
    for (std::size_t i = 0; i < mesh.joints.size(); ++i) {
        const int p = mesh.joints[i].parent;
        if (p < -1 || p >= static_cast<int>(i))
            return "mesh joint " + std::to_string(i) + " " + quotedName(mesh.joints[i].name) + " has parent " +
                   std::to_string(p) + ": parents must precede children";
    }
    if (mesh.joints[0].parent != -1) return "mesh joint 0 " + quotedName(mesh.joints[0].name) + " is not a root";
    return std::nullopt;
}

std::optional<std::string> animInconsistency(const decl::Md5Anim& anim) {
    if (anim.frames.empty()) return "af_pose has no frames";
    if (anim.baseframe.size() != anim.hierarchy.size())
        return "af_pose has " + std::to_string(anim.baseframe.size()) + " baseframe joints but " +
               std::to_string(anim.hierarchy.size()) + " hierarchy joints";
    for (std::size_t k = 0; k < anim.frames.size(); ++k)
        if (anim.frames[k].size() != static_cast<std::size_t>(anim.numAnimatedComponents))
            return "af_pose frame " + std::to_string(k) + " has " + std::to_string(anim.frames[k].size()) +
                   " values, not numAnimatedComponents " + std::to_string(anim.numAnimatedComponents);
    for (std::size_t j = 0; j < anim.hierarchy.size(); ++j) {
        const decl::Md5HierarchyEntry& h = anim.hierarchy[j];
        if (h.flags < 0 || h.flags > decl::kMd5AllComponents || h.startIndex < 0 ||
            h.startIndex + decl::animatedComponentCount(h.flags) > anim.numAnimatedComponents)
            return "af_pose joint " + std::to_string(j) + " " + quotedName(h.name) +
                   " reads components outside numAnimatedComponents";
    }
    return std::nullopt;
}

// Reports the first inconsistency of the mesh and its af_pose (at `where`, or at the af_pose's line of the joint
// whose hierarchy differs, when the files were parsed); true when there is none.
bool consistent(const decl::Md5Mesh& mesh, const decl::Md5Anim& anim, const text::SourceLocation& where,
                text::Diagnostics& diagnostics) {
    if (auto problem = meshInconsistency(mesh)) {
        diagnostics.error(where, *problem);
        return false;
    }
    if (auto mismatch =
            decl::hierarchyMismatchDiagnostic(anim, mesh,
                                              "af_pose does not match the mesh hierarchy (docs/format.md §7.4): ")) {
        diagnostics.error(mismatch->where.line > 0 ? mismatch->where : where, mismatch->message);
        return false;
    }
    if (auto problem = animInconsistency(anim)) {
        diagnostics.error(where, *problem);
        return false;
    }
    return true;
}

// Thresholds for the "load pose is not the runtime pose" warning: well below anything visible, well above
// rounding.
constexpr double kPoseMismatchUnits = 1e-3;
constexpr double kPoseMismatchRad = 1e-4;

} // namespace

std::optional<Skeleton> Skeleton::build(const decl::Md5Mesh& mesh, const decl::Md5Anim& afPose,
                                        const Eigen::Vector3d& modelOffset, text::Diagnostics& diagnostics,
                                        const std::string& context, RootTranslation rootTranslation) {
    const text::SourceLocation where{context, 0, 0};
    if (!consistent(mesh, afPose, where, diagnostics)) return std::nullopt;
    if (!modelOffset.allFinite()) {
        diagnostics.error(where, "the model offset is not finite");
        return std::nullopt;
    }

    Skeleton s;
    s.m_modelOffset = modelOffset;
    s.m_rootTranslation = rootTranslation;
    const std::size_t n = mesh.joints.size();
    s.m_names.reserve(n);
    s.m_parents.reserve(n);
    s.m_bindPose.reserve(n);
    for (const decl::Md5Joint& j : mesh.joints) {
        s.m_names.push_back(j.name);
        s.m_parents.push_back(j.parent);
        // Mesh joints are model-space (docs/format.md §7.3).
        s.m_bindPose.push_back(
            {rotationFromMd5(j.orientation.x, j.orientation.y, j.orientation.z), toEigen(j.position)});
    }

    // docs/format.md §2.1: idAF::Load builds the frame at 1 ms, then the root translation is replaced by (actors)
    // or offset by (AF entities) the visual offset before the hierarchy is concatenated.
    std::vector<Transform> loadLocal = animPoseLocal(afPose, 0.001);
    if (rootTranslation == RootTranslation::ReplacedByOffset) loadLocal[0].position = modelOffset;
    else loadLocal[0].position += modelOffset;
    s.m_loadPose = toModelSpace(loadLocal, s.m_parents);

    // docs/format.md §5.1 step 3: FinishAFPose starts from GetSingleFrame(0), the baseframe (root translation
    // zeroed by the loader); CreateFrame adds the offset to joint 0.
    s.m_afPoseLocal = toTransforms(frameJoints(afPose, nullptr));
    s.m_afPoseLocal[0].position += modelOffset;

    for (std::size_t i = 0; i < n; ++i) {
        if (!isFinite(s.m_bindPose[i]) || !isFinite(s.m_loadPose[i]) || !isFinite(s.m_afPoseLocal[i])) {
            diagnostics.error(where, "joint " + std::to_string(i) + " " + quotedName(s.m_names[i]) +
                                         " has a non-finite bind or af_pose transform");
            return std::nullopt;
        }
    }

    // docs/format.md §8 item 19: calibration uses the 1 ms pose, runtime FK the baseframe. Report where they part.
    const std::vector<Transform> runtime = toModelSpace(s.m_afPoseLocal, s.m_parents);
    double worstUnits = 0, worstRad = 0;
    std::size_t worstJoint = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const double du = (s.m_loadPose[i].position - runtime[i].position).norm();
        const double dr = angleBetween(s.m_loadPose[i].rotation, runtime[i].rotation);
        if (du / kPoseMismatchUnits + dr / kPoseMismatchRad >
            worstUnits / kPoseMismatchUnits + worstRad / kPoseMismatchRad) {
            worstUnits = du;
            worstRad = dr;
            worstJoint = i;
        }
    }
    if (worstUnits > kPoseMismatchUnits || worstRad > kPoseMismatchRad)
        diagnostics.warning(where, "the af_pose load pose (frame 0 at 1 ms) differs from the af_pose baseframe that "
                                   "drives the skeleton at run time (docs/format.md §5.1, §8 item 19): joint " +
                                       std::to_string(worstJoint) + " " + quotedName(s.m_names[worstJoint]) + " is " +
                                       std::to_string(worstUnits) + " units and " +
                                       std::to_string(worstRad * 180.0 / std::numbers::pi) +
                                       " degrees apart; keep af_pose single-frame with frame 0 equal to the baseframe");

    // docs/format.md §8 item 22: lookups find the first of two names equal ignoring case.
    for (std::size_t i = 1; i < n; ++i)
        for (std::size_t k = 0; k < i; ++k)
            if (text::equalsIgnoreCase(s.m_names[i], s.m_names[k])) {
                diagnostics.warning(where, "joint " + std::to_string(i) + " " + quotedName(s.m_names[i]) +
                                               " has the same name, ignoring case, as joint " + std::to_string(k) +
                                               " " + quotedName(s.m_names[k]) + ": lookups by name find joint " +
                                               std::to_string(k) + " (docs/format.md §8 item 22)");
                break;
            }
    return s;
}

std::optional<int> Skeleton::findJoint(std::string_view name) const {
    for (std::size_t i = 0; i < m_names.size(); ++i)
        if (text::equalsIgnoreCase(m_names[i], name)) return static_cast<int>(i);
    return std::nullopt;
}

int Skeleton::firstChild(int joint) const {
    // idAnimator::GetFirstChild: the first joint whose parent equals `joint`, else `joint` itself. The root's
    // parent is -1, so an invalid joint (-1) yields the root.
    const int wanted = joint < 0 ? -1 : joint;
    for (std::size_t i = 0; i < m_parents.size(); ++i)
        if (m_parents[i] == wanted) return static_cast<int>(i);
    return joint;
}

std::vector<int> Skeleton::jointAndDescendants(int joint) const {
    std::vector<int> out;
    if (joint < 0 || joint >= jointCount()) return out;
    out.push_back(joint);
    // idDeclModelDef::GetJointList: children follow their parent; the first joint whose parent comes before
    // `joint` ends the subtree (docs/format.md §5.3).
    for (int i = joint + 1; i < jointCount() && parent(i) >= joint; ++i) out.push_back(i);
    return out;
}

std::vector<Transform> animFrameLocal(const decl::Md5Anim& anim, int frame) {
    return toTransforms(frameJoints(anim, framePointer(anim, frame)));
}

std::vector<Transform> animPoseLocal(const decl::Md5Anim& anim, double timeSeconds) {
    const int numFrames = static_cast<int>(anim.frames.size());
    // idMD5Anim::ConvertTimeToFrame with cyclecount 1 (docs/format.md §2.1, §7.4).
    if (numFrames <= 1 || !(timeSeconds > 0)) return animFrameLocal(anim, 0);
    const double frameTime = timeSeconds * anim.frameRate;
    if (!(frameTime < numFrames - 1)) return animFrameLocal(anim, numFrames - 1);
    const double whole = std::floor(frameTime);
    const int frame1 = static_cast<int>(whole);
    const double weight = frameTime - whole;
    if (weight == 0) return animFrameLocal(anim, frame1);
    return toTransforms(blend(frameJoints(anim, framePointer(anim, frame1)),
                              frameJoints(anim, framePointer(anim, frame1 + 1)), weight));
}

std::vector<Transform> toModelSpace(const std::vector<Transform>& local, const std::vector<int>& parents) {
    std::vector<Transform> model;
    model.reserve(local.size());
    for (std::size_t i = 0; i < local.size(); ++i) {
        const int p = i < parents.size() ? parents[i] : -1;
        if (p < 0 || p >= static_cast<int>(i)) model.push_back(local[i]);
        else model.push_back(model[static_cast<std::size_t>(p)] * local[i]);
    }
    return model;
}

} // namespace afb::figure
