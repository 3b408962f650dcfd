#include "afb/figure/Placement.h"

#include <cmath>
#include <cstddef>
#include <string>

#include <Eigen/Geometry>

namespace afb::figure {
namespace {

std::string quoted(const std::string& s) { return "\"" + s + "\""; }

// The engine's CheckModelHierarchy against the figure's skeleton (docs/format.md §7.4), then what animPoseLocal
// relies on that the parser guarantees and a hand-built value may not. The first problem, or nullopt.
std::optional<std::string> animMismatch(const Skeleton& skeleton, const decl::Md5Anim& anim) {
    const std::size_t n = static_cast<std::size_t>(skeleton.jointCount());
    if (anim.hierarchy.size() != n)
        return "the animation has " + std::to_string(anim.hierarchy.size()) + " joints, the skeleton " +
               std::to_string(n) + " (docs/format.md §7.4)";
    for (std::size_t j = 0; j < n; ++j) {
        const decl::Md5HierarchyEntry& h = anim.hierarchy[j];
        const int joint = static_cast<int>(j);
        if (h.name != skeleton.name(joint))
            return "animation joint " + std::to_string(j) + " is " + quoted(h.name) + ", the skeleton's " +
                   quoted(skeleton.name(joint)) + " (names compare case-sensitively, docs/format.md §7.4)";
        if (h.parent != skeleton.parent(joint))
            return "animation joint " + std::to_string(j) + " " + quoted(h.name) + " has parent " +
                   std::to_string(h.parent) + ", the skeleton's " + std::to_string(skeleton.parent(joint)) +
                   " (docs/format.md §7.4)";
        if (h.flags < 0 || h.flags > decl::kMd5AllComponents || h.startIndex < 0 ||
            h.startIndex + decl::animatedComponentCount(h.flags) > anim.numAnimatedComponents)
            return "animation joint " + std::to_string(j) + " " + quoted(h.name) +
                   " reads components outside numAnimatedComponents";
    }
    if (anim.baseframe.size() != n)
        return "the animation has " + std::to_string(anim.baseframe.size()) + " baseframe joints, not " +
               std::to_string(n);
    if (anim.frames.empty()) return "the animation has no frames";
    for (std::size_t k = 0; k < anim.frames.size(); ++k)
        if (anim.frames[k].size() != static_cast<std::size_t>(anim.numAnimatedComponents))
            return "animation frame " + std::to_string(k) + " has " + std::to_string(anim.frames[k].size()) +
                   " values, not numAnimatedComponents " + std::to_string(anim.numAnimatedComponents);
    return std::nullopt;
}

} // namespace

std::vector<Transform> toMetres(std::span<const Transform> jointsDoom, double metresPerUnit) {
    std::vector<Transform> out(jointsDoom.begin(), jointsDoom.end());
    for (Transform& t : out) t.position *= metresPerUnit;
    return out;
}

std::vector<Transform> bodiesFromJoints(const Figure& figure, const Transform& entity,
                                        std::span<const Transform> jointsModelMetres) {
    std::vector<Transform> out;
    out.reserve(figure.bodies.size());
    for (const FigureBody& b : figure.bodies) {
        if (b.joint < 0 || static_cast<std::size_t>(b.joint) >= jointsModelMetres.size()) {
            out.push_back(entity * b.loadPose);
            continue;
        }
        out.push_back(entity * jointsModelMetres[static_cast<std::size_t>(b.joint)] * b.jointInBody.inverse());
    }
    return out;
}

std::vector<BodyState> inheritVelocities(std::span<const Transform> before, std::span<const Transform> after,
                                         double dt) {
    std::vector<BodyState> out(after.size());
    for (std::size_t i = 0; i < after.size(); ++i) {
        out[i].pose = after[i];
        if (i >= before.size() || !(dt > 0)) continue;
        out[i].linearVelocity = (after[i].position - before[i].position) / dt;
        const Eigen::AngleAxisd delta(after[i].rotation * before[i].rotation.transpose());
        out[i].angularVelocity = delta.axis() * (delta.angle() / dt);
    }
    return out;
}

std::vector<Transform> jointsInMetres(const Figure& figure) {
    return toMetres(figure.skeleton.loadPose(), figure.units.metresPerUnit);
}

std::optional<std::vector<Transform>> jointsFromAnimation(const Figure& figure, const decl::Md5Anim& anim,
                                                          double timeSeconds, text::Diagnostics& diagnostics) {
    const text::SourceLocation where{"figure " + quoted(figure.name), 0, 0};
    if (!std::isfinite(timeSeconds)) {
        diagnostics.error(where, "the animation time is not finite");
        return std::nullopt;
    }
    const Skeleton& skeleton = figure.skeleton;
    if (auto problem = animMismatch(skeleton, anim)) {
        diagnostics.error(where, "cannot pose the figure from the animation: " + *problem);
        return std::nullopt;
    }
    // docs/format.md §2.1: the animator treats every frame's root as it treated af_pose's when the figure was loaded.
    std::vector<Transform> local = animPoseLocal(anim, timeSeconds);
    if (skeleton.rootTranslation() == RootTranslation::ReplacedByOffset) local[0].position = skeleton.modelOffset();
    else local[0].position += skeleton.modelOffset();
    std::vector<Transform> joints = toMetres(toModelSpace(local, skeleton.parents()), figure.units.metresPerUnit);
    for (std::size_t j = 0; j < joints.size(); ++j)
        if (!joints[j].rotation.allFinite() || !joints[j].position.allFinite()) {
            diagnostics.error(where, "the animation gives joint " + std::to_string(j) + " " +
                                         quoted(skeleton.name(static_cast<int>(j))) + " a non-finite transform");
            return std::nullopt;
        }
    return joints;
}

std::optional<std::vector<BodyState>> bodyStatesFromAnimation(const Figure& figure, const decl::Md5Anim& anim,
                                                              double timeSeconds, const Transform& entity,
                                                              text::Diagnostics& diagnostics,
                                                              double velocityStepSeconds) {
    if (!std::isfinite(velocityStepSeconds) || !(velocityStepSeconds > 0)) {
        diagnostics.error({"figure " + quoted(figure.name), 0, 0}, "the velocity step is not finite and positive");
        return std::nullopt;
    }
    if (!entity.rotation.allFinite() || !entity.position.allFinite()) {
        diagnostics.error({"figure " + quoted(figure.name), 0, 0}, "the entity transform is not finite");
        return std::nullopt;
    }
    const auto now = jointsFromAnimation(figure, anim, timeSeconds, diagnostics);
    if (!now) return std::nullopt;
    const auto earlier = jointsFromAnimation(figure, anim, timeSeconds - velocityStepSeconds, diagnostics);
    if (!earlier) return std::nullopt;
    // docs/format.md §5.4: SetupPose at t − step, ChangePose at t.
    return inheritVelocities(bodiesFromJoints(figure, entity, *earlier), bodiesFromJoints(figure, entity, *now),
                             velocityStepSeconds);
}

} // namespace afb::figure
