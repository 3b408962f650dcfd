// The ragdoll interface that serves both backends (bodyState, setBodyVelocities, applyBodyImpulse with
// ImpulseRule::Always, collisionObject), the rigid backend's own accessors refusing a multibody ragdoll with
// std::logic_error instead of crashing, and the engine's contact friction callback written once per process.
// Deterministic: fixed 60 Hz steps, fixed insertion order; no timing is asserted.
#include <catch2/catch.hpp>

#include <stdexcept>
#include <vector>

#include <Eigen/Geometry>

#include "EntityFixture.h"
#include "afb/bullet/Method.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/bullet/RagdollWorld.h"
#include "afb/detail/Convert.h"
#include "afb/sim/Scene.h"

namespace {

using afb::bullet::Backend;
using afb::bullet::BodyVelocity;
using afb::bullet::ImpulseRule;
using afb::bullet::Method;
using afb::bullet::Ragdoll;
using afb::bullet::RagdollAsset;

Method presetNamed(const char* name) { return *afb::bullet::methodPreset(name); }

// Total linear momentum of a ragdoll's bodies, kg·m/s.
Eigen::Vector3d momentum(const Ragdoll& r) {
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    const std::vector<afb::figure::BodyState> states = r.bodyStates();
    for (std::size_t i = 0; i < states.size(); ++i) p += r.figure().bodies[i].massKg * states[i].linearVelocity;
    return p;
}

} // namespace

TEST_CASE("multibody: the rigid backend's accessors throw std::logic_error, the shared ones answer",
          "[bullet][multibody]") {
    const auto asset = RagdollAsset::create(afb::test::loadEntity("humanoid").figure);
    afb::sim::Scene scene(presetNamed("multibody"), {.gravityMps2 = 0, .ground = false});
    Ragdoll& r = scene.spawn(asset);
    const Ragdoll& c = r;
    CHECK_THROWS_AS(r.body(0), std::logic_error);
    CHECK_THROWS_AS(c.body(0), std::logic_error);
    CHECK_THROWS_AS(r.rigidBody(0), std::logic_error);
    CHECK_THROWS_AS(r.constraint(0), std::logic_error);
    CHECK_THROWS_AS(c.constraint(0), std::logic_error);
    CHECK_THROWS_AS(r.bulletConstraint(0), std::logic_error);
    CHECK_THROWS_AS(r.bulletConstraintIsLimit(0), std::logic_error);
    CHECK(r.rigidBodyCount() == 0);
    CHECK(r.bulletConstraintCount() == 0);
    CHECK_THROWS_WITH(r.body(0), Catch::Contains("multibody"));
    for (int i = 0; i < r.bodyCount(); ++i) CHECK(r.figureBodyOf(r.collisionObject(i), {0, 0, 0}) == i);
}

TEST_CASE("rigid: the rigid backend's accessors answer without throwing", "[bullet]") {
    const auto asset = RagdollAsset::create(afb::test::loadEntity("humanoid").figure);
    afb::sim::Scene scene(presetNamed("default"), {.gravityMps2 = 0, .ground = false});
    Ragdoll& r = scene.spawn(asset);
    REQUIRE(r.rigidBodyCount() > 0);
    CHECK(r.rigidBodyCount() <= r.bodyCount()); // fixed joints merged
    for (int i = 0; i < r.bodyCount(); ++i) {
        CHECK(&r.body(i) == &r.rigidBody(r.rigidIndexOf(i)));
        CHECK(&r.collisionObject(i) == &r.body(i));
    }
    CHECK(r.bulletConstraintCount() > 0);
    CHECK_NOTHROW(r.bulletConstraint(0));
}

TEST_CASE("both backends: bodyState, setBodyVelocities and applyBodyImpulse through one interface",
          "[bullet][multibody]") {
    const auto asset = RagdollAsset::create(afb::test::loadEntity("humanoid").figure);
    for (const char* preset : {"default", "multibody", "fast"}) {
        DYNAMIC_SECTION(preset) {
            Method method = presetNamed(preset);
            SECTION("bodyState(i) is bodyStates()[i]") {
                afb::sim::Scene scene(method, {.gravityMps2 = 9.81, .ground = true});
                Ragdoll& r = scene.spawn(asset, {.comeToRest = false});
                for (int s = 0; s < 20; ++s) scene.step(1.0 / 60.0);
                const std::vector<afb::figure::BodyState> all = r.bodyStates();
                for (int i = 0; i < r.bodyCount(); ++i) {
                    const afb::figure::BodyState one = r.bodyState(i);
                    INFO("body " << i);
                    CHECK((one.pose.position - all[static_cast<std::size_t>(i)].pose.position).norm() < 1e-9);
                    CHECK((one.linearVelocity - all[static_cast<std::size_t>(i)].linearVelocity).norm() < 1e-9);
                    CHECK((one.angularVelocity - all[static_cast<std::size_t>(i)].angularVelocity).norm() < 1e-9);
                }
            }
            SECTION("a rigid motion set through setBodyVelocities reads back; the poses stay") {
                afb::sim::Scene scene(method, {.gravityMps2 = 0, .ground = false});
                Ragdoll& r = scene.spawn(asset, {.comeToRest = false});
                const std::vector<afb::figure::BodyState> before = r.bodyStates();
                const Eigen::Vector3d centre = before[0].pose.position, v(1, -2, 0.5), w(0, 0.5, 1);
                std::vector<BodyVelocity> in;
                for (const afb::figure::BodyState& s : before)
                    in.push_back({afb::bullet::toBt(Eigen::Vector3d(v + w.cross(s.pose.position - centre))),
                                  afb::bullet::toBt(w)});
                REQUIRE(r.setBodyVelocities(in));
                const std::vector<afb::figure::BodyState> after = r.bodyStates();
                for (std::size_t i = 0; i < after.size(); ++i) {
                    INFO("body " << r.figure().bodies[i].name);
                    CHECK((after[i].pose.position - before[i].pose.position).norm() < 1e-5);
                    CHECK((after[i].linearVelocity - afb::bullet::toEigen(in[i].linearMps)).norm() < 1e-4);
                    CHECK((after[i].angularVelocity - w).norm() < 1e-4);
                }
                CHECK_FALSE(r.setBodyVelocities(std::span(in).first(2)));
            }
            SECTION("an impulse below the wake threshold: ignored by the engine's rule, applied with Always") {
                afb::sim::Scene scene(method, {.gravityMps2 = 0, .ground = false});
                Ragdoll& r = scene.spawn(asset, {.comeToRest = false});
                const btVector3 small(0, btScalar(0.5 * r.impulseThresholdNs()), 0);
                const btVector3 at = afb::bullet::toBt(r.bodyState(2).pose.position);
                CHECK_FALSE(r.applyBodyImpulse(2, small, at));
                CHECK(momentum(r).norm() < 1e-9);
                REQUIRE(r.applyBodyImpulse(2, small, at, ImpulseRule::Always));
                // Joints are internal forces: the figure's momentum is the impulse.
                CHECK((momentum(r) - afb::bullet::toEigen(small)).norm() < 1e-3 * small.length());
                CHECK_FALSE(r.applyBodyImpulse(r.bodyCount(), small, at, ImpulseRule::Always));
            }
        }
    }
}

TEST_CASE("the engine's contact friction callback: written once, in force after its worlds are gone", "[bullet]") {
    {
        afb::sim::Scene scene(presetNamed("default"), {.gravityMps2 = 9.81, .ground = true});
        CHECK(scene.ragdollWorld().engineContactFriction());
    }
    CHECK(afb::bullet::EngineContactFriction::installed());
    CHECK(afb::bullet::EngineContactFriction::install());
    afb::sim::Scene again(presetNamed("default"), {.gravityMps2 = 9.81, .ground = true});
    Ragdoll& r = again.spawn(RagdollAsset::create(afb::test::loadEntity("humanoid").figure));
    CHECK(r.engineContactFriction());
}
