#include "afb/pose/Blend.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "afb/figure/Placement.h"

namespace afb::pose {

namespace {

void requireJointCount(std::size_t count, std::size_t joints, const char* what) {
    if (count != joints)
        throw std::invalid_argument(std::string(what) + ": " + std::to_string(count) + " entries for " +
                                    std::to_string(joints) + " joints");
}

double clampedWeight(double w, const char* what) {
    if (!std::isfinite(w)) throw std::invalid_argument(std::string(what) + ": a weight is not finite");
    return std::clamp(w, 0.0, 1.0);
}

} // namespace

SkeletonPose poseFromJoints(const figure::Figure& figure, const Transform& entity,
                            std::span<const Transform> jointsModelMetres) {
    const std::vector<int>& parents = figure.skeleton.parents();
    requireJointCount(jointsModelMetres.size(), parents.size(), "poseFromJoints");
    SkeletonPose out;
    out.entity = entity;
    out.model.assign(jointsModelMetres.begin(), jointsModelMetres.end());
    out.local.resize(out.model.size());
    for (std::size_t j = 0; j < out.model.size(); ++j) {
        const int parent = parents[j];
        out.local[j] =
            parent >= 0 ? out.model[static_cast<std::size_t>(parent)].inverse() * out.model[j] : out.model[j];
    }
    return out;
}

std::optional<SkeletonPose> animatedPose(const figure::Figure& figure, const decl::Md5Anim& anim, double timeSeconds,
                                         const Transform& entity, text::Diagnostics& diagnostics) {
    const auto joints = figure::jointsFromAnimation(figure, anim, timeSeconds, diagnostics);
    if (!joints) return std::nullopt;
    return poseFromJoints(figure, entity, *joints);
}

Eigen::Quaterniond slerpShortest(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b, double t) {
    // q and −q are one rotation: take the b on a's side of the 4D sphere, so the arc is the shorter one.
    Eigen::Quaterniond near = b;
    if (a.dot(b) < 0) near.coeffs() = -b.coeffs();
    // The rotation from a to b in a's frame; its w = a·near ≥ 0, so its angle 2·atan2(|v|, w) is at most π.
    const Eigen::Quaterniond relative = a.conjugate() * near;
    const double sinHalf = relative.vec().norm();
    if (sinHalf == 0) return a;
    const double angle = 2 * std::atan2(sinHalf, relative.w());
    const Eigen::Quaterniond step(Eigen::AngleAxisd(t * angle, relative.vec() / sinHalf));
    return (a * step).normalized();
}

Transform interpolate(const Transform& a, const Transform& b, double t) {
    if (t == 0) return a;
    if (t == 1) return b;
    const Eigen::Quaterniond qa(a.rotation), qb(b.rotation);
    return {slerpShortest(qa.normalized(), qb.normalized(), t).toRotationMatrix(),
            a.position + t * (b.position - a.position)};
}

int blendAnchorJoint(const figure::Figure& figure) {
    if (figure.bodies.empty()) return 0;
    const int joint = figure.bodies[0].joint;
    return joint >= 0 && joint < figure.skeleton.jointCount() ? joint : 0;
}

SkeletonPose blendPoses(std::span<const int> parents, int anchorJoint, const SkeletonPose& animated,
                        const SkeletonPose& simulated, std::span<const double> jointWeights) {
    const std::size_t n = parents.size();
    requireJointCount(animated.model.size(), n, "blendPoses: animated model");
    requireJointCount(animated.local.size(), n, "blendPoses: animated local");
    requireJointCount(simulated.model.size(), n, "blendPoses: simulated model");
    requireJointCount(simulated.local.size(), n, "blendPoses: simulated local");
    requireJointCount(jointWeights.size(), n, "blendPoses: weights");
    if (anchorJoint < 0 || static_cast<std::size_t>(anchorJoint) >= n)
        throw std::invalid_argument("blendPoses: anchor joint " + std::to_string(anchorJoint) + " of " +
                                    std::to_string(n) + " joints");
    std::vector<double> w(n);
    for (std::size_t j = 0; j < n; ++j) w[j] = clampedWeight(jointWeights[j], "blendPoses");
    if (std::all_of(w.begin(), w.end(), [](double x) { return x == 0; })) return animated;
    if (std::all_of(w.begin(), w.end(), [](double x) { return x == 1; })) return simulated;

    SkeletonPose out;
    out.local.resize(n);
    out.model.resize(n);
    for (std::size_t j = 0; j < n; ++j) {
        out.local[j] = interpolate(animated.local[j], simulated.local[j], w[j]);
        const int parent = parents[j];
        out.model[j] = parent >= 0 && static_cast<std::size_t>(parent) < j
                           ? out.model[static_cast<std::size_t>(parent)] * out.local[j]
                           : out.local[j];
    }
    // The root rule: the anchor's world transform is blended, and the entity is whatever puts it there.
    const std::size_t r = static_cast<std::size_t>(anchorJoint);
    const Transform anchorWorld =
        interpolate(animated.entity * animated.model[r], simulated.entity * simulated.model[r], w[r]);
    out.entity = anchorWorld * out.model[r].inverse();
    return out;
}

SkeletonPose blendPoses(const figure::Figure& figure, const SkeletonPose& animated, const SkeletonPose& simulated,
                        std::span<const double> jointWeights) {
    return blendPoses(figure.skeleton.parents(), blendAnchorJoint(figure), animated, simulated, jointWeights);
}

std::vector<double> jointWeightsFromBodies(const figure::Figure& figure, std::span<const double> bodyWeights) {
    if (bodyWeights.size() != figure.bodies.size())
        throw std::invalid_argument("jointWeightsFromBodies: " + std::to_string(bodyWeights.size()) + " weights for " +
                                    std::to_string(figure.bodies.size()) + " bodies");
    const std::vector<int>& parents = figure.skeleton.parents();
    std::vector<double> out(parents.size(), bodyWeights.empty() ? 0.0 : bodyWeights[0]);
    for (std::size_t j = 0; j < out.size(); ++j) {
        const int body = j < figure.jointBody.size() ? figure.jointBody[j] : -1;
        if (body >= 0 && static_cast<std::size_t>(body) < bodyWeights.size())
            out[j] = bodyWeights[static_cast<std::size_t>(body)];
        else if (parents[j] >= 0) out[j] = out[static_cast<std::size_t>(parents[j])];
    }
    return out;
}

BlendFade::BlendFade(double weight) : BlendFade(weight, weight, 0) {}

BlendFade::BlendFade(double from, double to, double seconds)
    : m_from(clampedWeight(from, "BlendFade")), m_to(clampedWeight(to, "BlendFade")),
      m_seconds(std::isfinite(seconds) ? std::max(seconds, 0.0) : throw std::invalid_argument("BlendFade: time")) {}

void BlendFade::fadeTo(double to, double seconds) { *this = BlendFade(weight(), to, seconds); }

double BlendFade::advance(double dtSeconds) {
    if (!(dtSeconds >= 0) || !std::isfinite(dtSeconds))
        throw std::invalid_argument("BlendFade::advance: the step must be finite and >= 0");
    m_elapsed = std::min(m_elapsed + dtSeconds, m_seconds);
    return weight();
}

double BlendFade::weightAt(double secondsSinceStart) const {
    if (secondsSinceStart >= m_seconds) return m_to;
    if (secondsSinceStart <= 0) return m_from;
    return m_from + (m_to - m_from) * (secondsSinceStart / m_seconds);
}

} // namespace afb::pose
