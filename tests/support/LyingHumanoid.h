// The bundled humanoid lying still on its back: how far its hinges' axes part while the velocity solve alone
// holds them (the tests of the direct solve's endings).
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "EntityFixture.h"
#include "afb/bullet/Method.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/sim/Scene.h"

namespace afb::test {

/// The largest angle (rad) between a hinge's axis in its two bodies over the 4 s after 2 s on the ground, the
/// humanoid spawned lying 0.3 m up at 60 Hz with `method` (rest rules off).
inline double lyingHumanoidHingeAxesApart(const afb::bullet::Method& method) {
    static const auto loaded = loadEntity("humanoid");
    const auto asset = afb::bullet::RagdollAsset::create(loaded.figure);
    const afb::figure::Figure& fig = loaded.figure;
    afb::sim::Scene scene(method);
    afb::bullet::SpawnOptions o;
    o.comeToRest = false;
    const double quarterTurn = std::acos(0.0);
    o.entityTransform =
        btTransform(btQuaternion(btVector3(0, 1, 0), btScalar(-quarterTurn)), btVector3(0, 0, btScalar(0.3)));
    afb::bullet::Ragdoll& r = scene.spawn(asset, o);
    double worst = 0;
    for (int s = 0; s < 360; ++s) {
        scene.step(1.0 / 60);
        if (s < 120) continue;
        const std::vector<afb::figure::Transform> t = r.bodyTransforms();
        for (const afb::figure::FigureConstraint& c : fig.constraints) {
            if (c.type != afb::figure::JointType::Hinge || c.body2 < 0) continue;
            const Eigen::Vector3d a1 = (t[static_cast<std::size_t>(c.body1)] * c.frameInBody1).rotation.col(2);
            const Eigen::Vector3d a2 = (t[static_cast<std::size_t>(c.body2)] * c.frameInBody2).rotation.col(2);
            worst = std::max(worst, std::atan2(a1.cross(a2).norm(), a1.dot(a2)));
        }
    }
    return worst;
}

} // namespace afb::test
