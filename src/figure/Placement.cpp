#include "afb/figure/Placement.h"

#include <Eigen/Geometry>

namespace afb::figure {

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

} // namespace afb::figure
