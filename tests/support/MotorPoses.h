// Poses for the motor tests: the joints' relative rotations, how far a ragdoll's motor joints are from a set of
// them, and a pose the humanoid can take (every joint holds and every limit is met: the figure after it came to
// rest on the ground), which its load pose is not.
#pragma once

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "afb/bullet/Method.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/bullet/RagdollAsset.h"
#include "afb/sim/Scene.h"

namespace afb::test {

/// Frame B's rotation in frame A of every constraint, now.
inline std::vector<btQuaternion> relativeRotations(const bullet::Ragdoll& r) {
    std::vector<btQuaternion> out;
    for (std::size_t i = 0; i < r.figure().constraints.size(); ++i) {
        const auto [a, b] = r.constraintFramesWorld(static_cast<int>(i));
        btQuaternion q;
        (a.getBasis().transpose() * b.getBasis()).getRotation(q);
        out.push_back(q);
    }
    return out;
}

/// The angle (rad) between two rotations.
inline double angleBetween(const btQuaternion& a, const btQuaternion& b) {
    const double d = std::abs(double(a.dot(b)));
    return 2 * std::acos(std::min(1.0, d));
}

/// The largest angle (rad) between a motor joint's relative rotation now and in `target`.
inline double worstMotorError(const bullet::Ragdoll& r, const std::vector<btQuaternion>& target) {
    const std::vector<btQuaternion> now = relativeRotations(r);
    double worst = 0;
    for (std::size_t i = 0; i < now.size(); ++i)
        if (r.hasMotor(static_cast<int>(i))) worst = std::max(worst, angleBetween(now[i], target[i]));
    return worst;
}

/// The entity `heightM` up, turned 0.6 rad about the vertical, rest rules off.
inline bullet::SpawnOptions turnedAt(double heightM) {
    bullet::SpawnOptions where;
    where.entityTransform =
        btTransform(btQuaternion(btVector3(0, 0, 1), btScalar(0.6)), btVector3(0, 0, btScalar(heightM)));
    where.comeToRest = false;
    return where;
}

/// A pose and its joints' relative rotations.
struct HeldPose {
    std::vector<figure::BodyState> states;
    std::vector<btQuaternion> rotations;
};

/// The figure dropped from 1 m (`default`, 60 Hz) after 3 s on the ground.
inline HeldPose restingPose(const std::shared_ptr<const bullet::RagdollAsset>& asset) {
    sim::Scene scene(*bullet::methodPreset("default"));
    bullet::Ragdoll& r = scene.spawn(asset, turnedAt(1.0));
    for (int s = 0; s < 180; ++s) scene.step(1.0 / 60);
    return {r.bodyStates(), relativeRotations(r)};
}

} // namespace afb::test
