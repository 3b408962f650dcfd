// The reduced-coordinate backend (Method::backend = multibody): spawn exactness, the wrong world, single-joint
// limit probes against the rigid backend, and the ragdoll interface (rest, impulses, body states, skeleton
// driving) answering the same way for both backends from one parameterised test. Deterministic: fixed 60 Hz
// steps, fixed insertion order; no timing is asserted.
#include <catch2/catch.hpp>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <BulletDynamics/Featherstone/btMultiBodyDynamicsWorld.h>
#include <Eigen/Geometry>

#include "EntityFixture.h"
#include "FigureFixture.h"
#include "afb/bullet/Convert.h"
#include "afb/bullet/Method.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/pose/SkeletonDriver.h"
#include "afb/sim/Drop.h"
#include "afb/sim/Scene.h"

namespace {

using afb::bullet::Backend;
using afb::bullet::Method;
using afb::bullet::Ragdoll;
using afb::bullet::RagdollAsset;
using afb::figure::Figure;
constexpr double kDeg = 3.14159265358979323846 / 180.0;

Method multibody() { return *afb::bullet::methodPreset("multibody"); }
Method rigid() { return *afb::bullet::methodPreset("default"); }

double rotationAngle(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
    return Eigen::AngleAxisd(Eigen::Quaterniond(a * b.transpose()).normalized()).angle();
}

btTransform spawnTransform() {
    const btQuaternion q(btVector3(1, 2, 3).normalized(), btScalar(0.7));
    return btTransform(q, btVector3(btScalar(1.5), btScalar(-2.0), btScalar(0.75)));
}

Figure armFigure(const std::string& constraint) {
    const auto built = afb::test::buildArmFigure(constraint);
    INFO(built.diagnostics.str());
    REQUIRE(built.figure);
    return *built.figure;
}

// The worst limit excess of constraint `c` over `steps` steps of a pendulum released from the load pose, degrees,
// and the worst anchor error of any joint, metres.
struct Probe {
    double overshootDeg = 0;
    double anchorM = 0;
};
Probe pendulum(const Figure& f, const Method& method, int c, int steps = 90) {
    afb::sim::Scene scene(method, {.gravityMps2 = 9.81, .ground = false});
    Ragdoll& r = scene.spawn(RagdollAsset::create(f), {.comeToRest = false});
    Probe p;
    for (int i = 0; i < steps; ++i) {
        scene.step(1.0 / 60.0);
        p.overshootDeg = std::max(p.overshootDeg, r.jointError(c).limitExcessRad / kDeg);
        p.anchorM = std::max(p.anchorM, r.jointError(c).anchorM);
    }
    return p;
}

} // namespace

TEST_CASE("multibody: every body spawns at spawn × loadPose, every joint holds, nothing moves without gravity",
          "[bullet][multibody]") {
    for (const char* entity : {"humanoid", "chain", "lamp", "buggy", "props"}) {
        const Figure f = afb::test::loadEntity(entity).figure;
        afb::sim::Scene scene(multibody(), {.gravityMps2 = 0, .ground = false});
        afb::bullet::SpawnOptions options;
        options.entityTransform = spawnTransform();
        options.comeToRest = false;
        Ragdoll& r = scene.spawn(RagdollAsset::create(f), options);
        REQUIRE(r.backend() == Backend::Multibody);
        REQUIRE(r.bodyCount() == static_cast<int>(f.bodies.size()));
        CHECK(r.bulletConstraintCount() == 0);
        const afb::figure::Transform spawn = afb::bullet::toEigen(options.entityTransform);
        auto check = [&](const char* when, double positionM, double angleRad) {
            const std::vector<afb::figure::Transform> now = r.bodyTransforms();
            for (std::size_t i = 0; i < f.bodies.size(); ++i) {
                INFO(entity << " " << when << " body " << f.bodies[i].name);
                const afb::figure::Transform expected = spawn * f.bodies[i].loadPose;
                CHECK((now[i].position - expected.position).norm() <= positionM);
                CHECK(rotationAngle(now[i].rotation, expected.rotation) <= angleRad);
            }
            for (int c = 0; c < static_cast<int>(f.constraints.size()); ++c) {
                INFO(entity << " " << when << " constraint " << f.constraints[static_cast<std::size_t>(c)].name);
                CHECK(r.jointError(c).anchorM <= positionM);
            }
        };
        check("at spawn", 1e-5, 1e-5);
        for (int step = 0; step < 60; ++step) scene.step(1.0 / 60.0);
        check("after 1 s", 1e-4, 0.01 * kDeg); // the spawn bound: 1e-4 m and 0.01°
    }
}

TEST_CASE("multibody: spawning into a plain btDiscreteDynamicsWorld is the documented error", "[bullet][multibody]") {
    afb::sim::Scene plain(rigid(), {.gravityMps2 = 9.81, .ground = false});
    const auto asset = RagdollAsset::create(afb::test::loadEntity("chain").figure);
    afb::bullet::SpawnOptions options;
    options.method = multibody();
    CHECK_THROWS_WITH(Ragdoll(asset, plain.world(), options), Catch::Contains("needs a btMultiBodyDynamicsWorld"));
    CHECK(plain.world().getNumCollisionObjects() == 0); // nothing half-added
    // And a rigid ragdoll works in a multibody world.
    afb::sim::Scene mbWorld(multibody(), {.gravityMps2 = 9.81, .ground = false});
    REQUIRE(dynamic_cast<btMultiBodyDynamicsWorld*>(&mbWorld.world()));
    options.method = rigid();
    Ragdoll rigidInMb(asset, mbWorld.world(), options);
    for (int i = 0; i < 30; ++i) mbWorld.world().stepSimulation(btScalar(1.0 / 60), 1, btScalar(1.0 / 60));
    for (int c = 0; c < rigidInMb.bodyCount() - 1; ++c) CHECK(rigidInMb.jointError(c).anchorM < 0.01);
}

TEST_CASE("multibody: single joints driven into their limits stop there", "[bullet][multibody]") {
    // Each arm falls from horizontal (about 7 rad/s at the stop, some 7° per step at 60 Hz) into its limit. The
    // bound: 1° (the rigid backend's speculative rows stop the hinge within 1°, test_methods.cpp), and never
    // worse than the rigid backend with the same substeps by more than 0.5°.
    struct Case {
        const char* name;
        std::string constraint;
        int index;
    };
    const Case cases[] = {
        {"hinge 0..60",
         "hinge \"h\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) axis ( 0, 1, 0 ) friction 0 limit 0, 120, 0 }",
         1},
        {"cone 45 deg (apex 90)",
         "ballAndSocketJoint \"b\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) friction 0 coneLimit ( 1, 0, 0 "
         "), "
         "90, ( 1, 0, 0 ) }",
         1},
        {"cone 90 deg (apex 180) about a tilted axis",
         "ballAndSocketJoint \"b\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) friction 0 coneLimit ( 1, 0, 1 "
         "), "
         "180, ( 1, 0, 0 ) }",
         1},
        {"pyramid 30 x 20 deg",
         "ballAndSocketJoint \"b\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) friction 0 pyramidLimit ( 1, 0, "
         "0 "
         "), 60, 40, 0, ( 1, 0, 0 ) }",
         1},
        {"universal, cone 30 deg on shaft 1",
         "universalJoint \"u\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) shafts ( 1, 0, 0 ), ( -1, 0, 0 ) "
         "friction 0 coneLimit ( 1, 0, 0 ), 60 }",
         1},
    };
    for (const Case& k : cases) {
        const Figure f = armFigure(k.constraint);
        const Probe mb = pendulum(f, multibody(), k.index);
        const Probe rb = pendulum(f, rigid(), k.index);
        INFO(k.name << ": multibody " << mb.overshootDeg << " deg (anchor " << mb.anchorM << " m), rigid "
                    << rb.overshootDeg << " deg (anchor " << rb.anchorM << " m)");
        CHECK(mb.overshootDeg < 1.0);
        CHECK(mb.overshootDeg <= rb.overshootDeg + 0.5);
        CHECK(mb.anchorM < 1e-5); // a tree joint: separation is round-off
    }
    // The slider has no range in the .af format (§4.6): it must hold its axis while the body slides along it.
    const Figure slider = armFigure("slider \"s\" { body1 \"arm\" body2 \"top\" axis ( 1, 0, -1 ) friction 0 }");
    const Probe s = pendulum(slider, multibody(), 1, 30);
    CHECK(s.anchorM < 1e-5);
}

TEST_CASE("both backends: rest, impulses, body states and skeleton driving answer alike", "[bullet][multibody]") {
    const afb::figure::LoadedFigure loaded = afb::test::loadEntity("humanoid");
    const Figure& f = loaded.figure;
    const auto asset = RagdollAsset::create(f);
    for (const Method& method : {rigid(), multibody()}) {
        DYNAMIC_SECTION(afb::bullet::toString(method.backend)) {
            SECTION("skeleton driving: the load pose drives the skeleton to its af_pose") {
                afb::sim::Scene scene(method, {.gravityMps2 = 0, .ground = false});
                Ragdoll& r = scene.spawn(asset);
                const afb::pose::SkeletonPose pose = afb::pose::driveSkeleton(f, r.bodyTransforms());
                const std::vector<afb::figure::Transform> expected = afb::figure::jointsInMetres(f);
                REQUIRE(pose.model.size() == expected.size());
                for (std::size_t j = 0; j < expected.size(); ++j) {
                    INFO("joint " << j);
                    CHECK((pose.model[j].position - expected[j].position).norm() < 1e-4);
                }
            }
            SECTION("body states: what goes in comes out (a consistent pose and a rigid spin)") {
                afb::sim::Scene scene(method, {.gravityMps2 = 0, .ground = false});
                Ragdoll& r = scene.spawn(asset, {.comeToRest = false});
                // The whole figure turned by 30° about Z, moved, and spinning at 1 rad/s about Z while moving at
                // 2 m/s along X: every body's velocity follows from the rigid motion.
                const Eigen::Matrix3d turn = Eigen::AngleAxisd(30 * kDeg, Eigen::Vector3d::UnitZ()).toRotationMatrix();
                const Eigen::Vector3d move(1, 2, 3), w(0, 0, 1), v(2, 0, 0);
                std::vector<afb::figure::BodyState> in;
                for (const afb::figure::FigureBody& b : f.bodies) {
                    afb::figure::BodyState s;
                    s.pose = {turn * b.loadPose.rotation, turn * b.loadPose.position + move};
                    s.angularVelocity = w;
                    s.linearVelocity = v + w.cross(s.pose.position - move);
                    in.push_back(s);
                }
                REQUIRE(r.setBodyStates(in));
                const std::vector<afb::figure::BodyState> out = r.bodyStates();
                for (std::size_t i = 0; i < in.size(); ++i) {
                    INFO("body " << f.bodies[i].name);
                    CHECK((out[i].pose.position - in[i].pose.position).norm() < 1e-5);
                    CHECK(rotationAngle(out[i].pose.rotation, in[i].pose.rotation) < 1e-5);
                    CHECK((out[i].linearVelocity - in[i].linearVelocity).norm() < 1e-4);
                    CHECK((out[i].angularVelocity - in[i].angularVelocity).norm() < 1e-4);
                }
                CHECK_FALSE(r.setBodyStates(std::span(in).first(3)));
            }
            SECTION("impulses: below the threshold ignored; above, the momentum the impulse gives") {
                afb::sim::Scene scene(method, {.gravityMps2 = 0, .ground = false});
                Ragdoll& r = scene.spawn(asset, {.comeToRest = false});
                const int pelvisJoint = f.bodies[0].joint;
                const btVector3 centre = afb::bullet::toBt(r.bodyStates()[0].pose.position);
                CHECK_FALSE(r.applyImpulse(pelvisJoint, btVector3(0.1f, 0, 0), centre));
                const btVector3 p(30, 0, 0); // N·s at the pelvis centre of mass
                REQUIRE(r.applyImpulse(pelvisJoint, p, centre));
                double momentum = 0;
                for (std::size_t i = 0; i < f.bodies.size(); ++i)
                    momentum += f.bodies[i].massKg * r.bodyStates()[i].linearVelocity.x();
                CHECK(momentum == Approx(30).epsilon(1e-3));
            }
            SECTION("rest: a dropped figure comes to rest by its own rules and sleeps; an impulse wakes it") {
                afb::sim::Scene scene(method, {.gravityMps2 = 9.81, .ground = true});
                afb::bullet::SpawnOptions options;
                options.entityTransform.setOrigin(btVector3(0, 0, btScalar(0.1)));
                Ragdoll& r = scene.spawn(asset, options);
                int steps = 0;
                while (!r.atRest() && steps < 600) {
                    scene.step(1.0 / 60.0);
                    ++steps;
                }
                INFO("steps " << steps);
                CHECK(r.atRest());
                CHECK(r.awakeBodyCount() == 0);
                scene.step(1.0 / 60.0);
                CHECK(r.atRest());
                const btVector3 centre = afb::bullet::toBt(r.bodyStates()[0].pose.position);
                REQUIRE(r.applyImpulse(f.bodies[0].joint, btVector3(0, 0, 50), centre));
                CHECK_FALSE(r.atRest());
                scene.step(1.0 / 60.0);
                CHECK(r.awakeBodyCount() == r.bodyCount());
                CHECK(r.bodyStates()[0].linearVelocity.z() > 0.1);
            }
        }
    }
}

TEST_CASE("multibody: the humanoid's 1 m drop keeps every joint together", "[bullet][multibody][presets]") {
    afb::sim::DropOptions o;
    o.heightM = 1.0;
    o.seconds = 3.0;
    o.sleeping = false;
    o.method = multibody();
    const afb::sim::DropResult r = afb::sim::runDrop(afb::test::loadEntity("humanoid").figure, o);
    INFO("anchor " << r.maxAnchorErrorM << " m, limit " << r.maxLimitViolationDeg << " deg at " << r.worstLimitJoint
                   << ", peak penetration " << r.maxPenetrationM << " m, rest " << r.restPenetrationM << " m");
    CHECK_FALSE(r.exploded);
    CHECK(r.maxAnchorErrorM < 1e-5); // rigid default: about 20 mm
    CHECK(r.maxLimitViolationDeg < 8);
    CHECK(r.restPenetrationM < 0.01);
}
