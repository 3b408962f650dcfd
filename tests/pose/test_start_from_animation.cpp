// Starting a ragdoll from an animation in one call (docs/format.md §2.1, §2.5, §5.4, §7.4): figure::jointsInMetres,
// figure::jointsFromAnimation, figure::bodyStatesFromAnimation and bullet::spawnOptionsFor, on the bundled
// humanoid (an actor: its root joint is placed as the load pose placed it).
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "EntityFixture.h"
#include "TestSupport.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/detail/Convert.h"
#include "afb/figure/Load.h"
#include "afb/figure/Placement.h"
#include "afb/sim/Scene.h"

namespace {

using afb::figure::BodyState;
using afb::figure::Transform;

using afb::test::loadEntity;

afb::decl::Md5Anim loadAnim(const std::string& name) {
    afb::text::Diagnostics diags;
    auto anim = afb::decl::loadMd5Anim(afb::test::sourceDir() / "models/md5/humanoid" / name, diags);
    INFO(diags.str());
    REQUIRE(anim);
    return std::move(*anim);
}

// Somewhere away from the origin, turned about a tilted axis: nothing may rely on the identity.
Transform entityTransform() {
    return {Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.2, -0.4, 1.0).normalized()).toRotationMatrix(), {1.5, -2.0, 0.25}};
}

std::vector<BodyState> statesAt(const afb::figure::Figure& f, const afb::decl::Md5Anim& anim, double t) {
    afb::text::Diagnostics diags;
    auto states = afb::figure::bodyStatesFromAnimation(f, anim, t, entityTransform(), diags);
    INFO(diags.str());
    REQUIRE(states);
    CHECK(diags.empty());
    REQUIRE(states->size() == f.bodies.size());
    return std::move(*states);
}

double angleRad(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
    return Eigen::AngleAxisd(a.transpose() * b).angle();
}

} // namespace

TEST_CASE("jointsInMetres is the load pose in metres", "[figure][placement]") {
    const auto loaded = loadEntity("humanoid");
    const auto& f = loaded.figure;
    const std::vector<Transform> joints = afb::figure::jointsInMetres(f);
    REQUIRE(static_cast<int>(joints.size()) == f.skeleton.jointCount());
    for (std::size_t j = 0; j < joints.size(); ++j) {
        CHECK(joints[j].rotation == f.skeleton.loadPose()[j].rotation);
        CHECK(joints[j].position == f.skeleton.loadPose()[j].position * f.units.metresPerUnit);
    }
}

TEST_CASE("bodyStatesFromAnimation at the start of af_pose is the load pose, at rest", "[figure][placement]") {
    const auto loaded = loadEntity("humanoid");
    const auto& f = loaded.figure;
    const afb::decl::Md5Anim afPose = loadAnim("af_pose.md5anim");
    const std::vector<BodyState> states = statesAt(f, afPose, 0.0);
    const Transform entity = entityTransform();
    for (std::size_t i = 0; i < states.size(); ++i) {
        INFO("body " << f.bodies[i].name);
        const Transform expected = entity * f.bodies[i].loadPose;
        CHECK((states[i].pose.position - expected.position).norm() <= 1e-9);
        CHECK(angleRad(states[i].pose.rotation, expected.rotation) <= 1e-9);
        CHECK(states[i].linearVelocity.norm() == 0);
        CHECK(states[i].angularVelocity.norm() == 0);
    }
}

TEST_CASE("bodyStatesFromAnimation velocities are the walk's finite differences", "[figure][placement]") {
    const auto loaded = loadEntity("humanoid");
    const auto& f = loaded.figure;
    const afb::decl::Md5Anim walk = loadAnim("walk.md5anim");
    // t = 0.3 s is frame 7.2 at 24 fps: t − h, t and t + h all blend frame 7 toward frame 8, so no frame
    // boundary lies between the samples.
    const double t = 0.3, h = afb::figure::kAnimationVelocityStepSeconds;
    const std::vector<BodyState> now = statesAt(f, walk, t);
    const std::vector<BodyState> next = statesAt(f, walk, t + h);

    double fastest = 0;
    for (std::size_t i = 0; i < now.size(); ++i) {
        INFO("body " << f.bodies[i].name);
        fastest = std::max(fastest, now[i].linearVelocity.norm());
        // The state at t + h carries the velocity from t to t + h: the same difference of two calls, up to
        // rounding of metre-sized positions divided by 1 ms (about 1e-12 m/s).
        const Eigen::Vector3d forward = (next[i].pose.position - now[i].pose.position) / h;
        CHECK((next[i].linearVelocity - forward).norm() <= 1e-9);
        const Eigen::AngleAxisd turn(next[i].pose.rotation * now[i].pose.rotation.transpose());
        CHECK((next[i].angularVelocity - turn.axis() * (turn.angle() / h)).norm() <= 1e-9);
        // And it is the derivative, not just a difference: one step later the velocities have changed only by
        // the walk's acceleration times 1 ms. Within a frame interval joint rotations are slerps (constant
        // local rates) and translations lerps, so what changes is the direction of swinging limbs' velocities:
        // at most about ω²·r·h = (2.4 rad/s)²·0.5 m·1 ms ≈ 3e-3 m/s here (measured: 3.0e-3 m/s, and below
        // 1e-12 rad/s for the angular velocities).
        CHECK((next[i].linearVelocity - now[i].linearVelocity).norm() <= 0.01);
        CHECK((next[i].angularVelocity - now[i].angularVelocity).norm() <= 0.01);
    }
    CHECK(fastest > 0.1); // the walk moves: the test is not comparing zeros
}

TEST_CASE("bodyStatesFromAnimation reports an animation that does not fit, never crashes", "[figure][placement]") {
    const auto loaded = loadEntity("humanoid");
    const auto& f = loaded.figure;
    const afb::decl::Md5Anim walk = loadAnim("walk.md5anim");
    const auto fails = [&](const afb::decl::Md5Anim& anim, double t = 0.1, double step = 0.001) {
        afb::text::Diagnostics diags;
        const auto states = afb::figure::bodyStatesFromAnimation(f, anim, t, entityTransform(), diags, step);
        INFO(diags.str());
        CHECK(diags.hasErrors());
        return !states.has_value();
    };

    afb::decl::Md5Anim fewer = walk; // a different joint count
    fewer.hierarchy.pop_back();
    fewer.baseframe.pop_back();
    CHECK(fails(fewer));

    afb::decl::Md5Anim renamed = walk; // names compare case-sensitively (docs/format.md §7.4)
    renamed.hierarchy[1].name = "Pelvis";
    CHECK(fails(renamed));

    afb::decl::Md5Anim reparented = walk;
    reparented.hierarchy[2].parent = 0;
    CHECK(fails(reparented));

    afb::decl::Md5Anim shortFrame = walk;
    shortFrame.frames[3].pop_back();
    CHECK(fails(shortFrame));

    afb::decl::Md5Anim noFrames = walk;
    noFrames.frames.clear();
    noFrames.bounds.clear();
    CHECK(fails(noFrames));

    afb::decl::Md5Anim notFinite = walk;
    notFinite.baseframe[4].position.x = std::numeric_limits<double>::quiet_NaN();
    CHECK(fails(notFinite));

    CHECK(fails(walk, std::numeric_limits<double>::quiet_NaN()));
    CHECK(fails(walk, std::numeric_limits<double>::infinity()));
    CHECK(fails(walk, 0.1, 0.0));
    CHECK(fails(walk, 0.1, std::numeric_limits<double>::quiet_NaN()));
}

TEST_CASE("bodyStatesFromAnimation spawns: setBodyStates takes it / spawnOptionsFor carries the rest flag",
          "[figure][placement][runtime]") {
    const auto loaded = loadEntity("humanoid");
    const auto& f = loaded.figure;
    const std::vector<BodyState> states = statesAt(f, loadAnim("walk.md5anim"), 0.3);

    afb::bullet::Method method;
    method.substeps = 2;
    const afb::bullet::SpawnOptions options = afb::bullet::spawnOptionsFor(loaded, method);
    CHECK_FALSE(options.startAtRest);
    CHECK(options.method == method);
    CHECK(afb::bullet::spawnOptionsFor(loadEntity("humanoid_sleeping")).startAtRest);

    afb::sim::Scene scene(afb::bullet::Method{}, {.gravityMps2 = 0, .ground = false});
    afb::bullet::Ragdoll ragdoll(afb::bullet::RagdollAsset::create(f), scene.world(), options);
    REQUIRE(ragdoll.setBodyStates(states));
    for (int i = 0; i < ragdoll.bodyCount(); ++i) {
        const auto& s = states[static_cast<std::size_t>(i)];
        // The body's own frame, also where fixed joints were merged into one rigid body: its velocity is then the
        // rigid's at its centre, which differs from the animation's by the little the fixed joint moved in it.
        const BodyState b = ragdoll.bodyState(i);
        CHECK((b.pose.position - s.pose.position).norm() <= 1e-5);
        CHECK((b.linearVelocity - s.linearVelocity).norm() <= 1e-4);
        CHECK((b.angularVelocity - s.angularVelocity).norm() <= 1e-5);
    }
}
