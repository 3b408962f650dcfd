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
#include "TestSupport.h"
#include "afb/bullet/Method.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/decl/Library.h"
#include "afb/detail/Convert.h"
#include "afb/figure/Load.h"
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

// Kinetic energy of a ragdoll's bodies (J): ½mv² + ½ωᵀIω, the inertia diagonal in the body frame.
double kineticEnergy(const Figure& f, const Ragdoll& r) {
    double e = 0;
    const std::vector<afb::figure::BodyState> states = r.bodyStates();
    for (std::size_t i = 0; i < states.size(); ++i) {
        const Eigen::Vector3d w = states[i].pose.rotation.transpose() * states[i].angularVelocity;
        e += 0.5 * f.bodies[i].massKg * states[i].linearVelocity.squaredNorm() +
             0.5 * w.dot(f.bodies[i].inertiaKgM2.cwiseProduct(w));
    }
    return e;
}

// The twist of a universal joint's body-2 frame relative to its body-1 frame about shaft 1 (their X axes), rad:
// docs/format.md §4.4's joint keeps it at zero (no relative spin about the shafts).
double twistRad(const Ragdoll& r, int c) {
    const auto [f1, f2] = r.constraintFramesWorld(c);
    btQuaternion q;
    (f1.getBasis().transpose() * f2.getBasis()).getRotation(q);
    if (q.w() < 0) q = -q;
    return std::abs(2 * std::atan2(static_cast<double>(q.x()), static_cast<double>(q.w())));
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
    CHECK_THROWS_WITH(plain.ragdollWorld().spawn(asset, options), Catch::Contains("needs a btMultiBodyDynamicsWorld"));
    CHECK(plain.world().getNumCollisionObjects() == 0);
    CHECK(plain.world().getNumConstraints() == 0);
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

TEST_CASE("multibody: a tree spinning fast gains no energy", "[bullet][multibody]") {
    // Three thin 16 kg boxes (inertia 50:1) joined by ball joints, spun at 20 rad/s in zero gravity without
    // damping: Bullet integrates a btMultiBody's velocity-product terms explicitly, and at ω·dt = 1/3 per step
    // that multiplied the energy by 2e5 within a second (the 10 m explosions of the zsec figures); the energy
    // guard holds every step's unconstrained update to gravity's work (0.1 % slack per step).
    std::vector<afb::test::TestJoint> joints;
    std::string af = "articulatedFigure t {\n settings { selfCollision 0 }\n";
    for (int i = 0; i < 3; ++i) {
        const std::string name = i == 0 ? "origin" : "b" + std::to_string(i);
        joints.push_back({name, i == 0 ? -1 : 0, 20.0 * i, 0, 100});
        af += " body \"b" + std::to_string(i) + "\" { joint \"" + name +
              "\" model box( ( 0, -1, -1 ), ( 20, 1, 1 ) ) origin ( " + std::to_string(20 * i) +
              ", 0, 100 ) density 0.2 }\n";
        if (i > 0)
            af += " ballAndSocketJoint \"j" + std::to_string(i) + "\" { body1 \"b" + std::to_string(i) +
                  "\" body2 \"b" + std::to_string(i - 1) + "\" anchor ( " + std::to_string(20 * i) +
                  ", 0, 100 ) friction 0 }\n";
    }
    const auto built = afb::test::buildTestFigure(af + "}\n", joints);
    INFO(built.diagnostics.str());
    REQUIRE(built.figure);
    Figure f = *built.figure;
    for (afb::figure::FigureBody& b : f.bodies) b.linearDamping = b.angularDamping = 0;
    afb::sim::Scene scene(multibody(), {.gravityMps2 = 0, .ground = false});
    Ragdoll& r = scene.spawn(RagdollAsset::create(f), {.comeToRest = false});
    std::vector<afb::figure::BodyState> spin;
    for (std::size_t i = 0; i < f.bodies.size(); ++i) {
        afb::figure::BodyState s;
        s.pose = f.bodies[i].loadPose;
        s.angularVelocity = (i % 2 ? Eigen::Vector3d(0.3, 1, 0.2) : Eigen::Vector3d(1, -0.2, 0.5)).normalized() * 20;
        spin.push_back(s);
    }
    REQUIRE(r.setBodyStates(spin));
    const double e0 = kineticEnergy(f, r);
    REQUIRE(e0 > 100);
    double worst = 0;
    for (int step = 0; step < 60; ++step) {
        scene.step(1.0 / 60.0);
        worst = std::max(worst, kineticEnergy(f, r) / e0);
        for (int c = 0; c < 2; ++c) REQUIRE(r.jointError(c).anchorM < 1e-5);
    }
    INFO("worst energy / initial " << worst);
    CHECK(worst < 1.07); // (1.001)^60 slack; unguarded: 2e5
}

TEST_CASE("multibody: a universal joint keeps its shafts from twisting, through every swing", "[bullet][multibody]") {
    // §4.4: no relative spin about the shafts, two free swings. The arm falls from horizontal through straight down
    // while turning sideways: a Cardan pair of revolute links (the first version) is singular there (the swing
    // 90° from the load pose toward its first axis, where that axis spins the arm about itself), as the zsec
    // shoulders and elbows reached at a 10 m landing before they exploded.
    const Figure f =
        armFigure("universalJoint \"u\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) shafts ( 1, 0, 0 ), "
                  "( -1, 0, 0 ) friction 0 }");
    afb::sim::Scene scene(multibody(), {.gravityMps2 = 9.81, .ground = false});
    Ragdoll& r = scene.spawn(RagdollAsset::create(f), {.comeToRest = false});
    std::vector<afb::figure::BodyState> states = r.bodyStates();
    states[1].angularVelocity = Eigen::Vector3d(0, 0, 1.5); // the arm turns sideways about the vertical
    states[1].linearVelocity = states[1].angularVelocity.cross(states[1].pose.position - Eigen::Vector3d(0, 0, 2.54));
    REQUIRE(r.setBodyStates(states));
    double twist = 0, lowest = 0, speed = 0;
    for (int step = 0; step < 120; ++step) {
        scene.step(1.0 / 60.0);
        twist = std::max(twist, twistRad(r, 1));
        const afb::figure::BodyState arm = r.bodyStates()[1];
        lowest = std::min(lowest, arm.pose.rotation.col(0).z());
        speed = std::max(speed, arm.angularVelocity.norm());
        REQUIRE(r.jointError(1).anchorM < 1e-5);
    }
    INFO("twist " << twist / kDeg << " deg, lowest shaft z " << lowest << ", fastest " << speed << " rad/s");
    CHECK(lowest < -0.95); // it swung through straight down
    CHECK(twist < 1.0 * kDeg);
    CHECK(speed < 15); // a 0.5 m arm falling 0.5 m turns at about 6 rad/s
}

TEST_CASE("multibody: the zsec sets dropped from 10 m and 100 m never explode", "[bullet][multibody][corpus]") {
    // The first version exploded on all three from 10 m (a Cardan pair at its singular pose, then Bullet's explicit
    // velocity-product terms pumping energy: docs/stability.md). 100 m lands at the damped terminal
    // speed, about 14 m/s, 8.5 s into the drop.
    AFB_REQUIRE_CORPUS(corpus);
    afb::text::Diagnostics diags;
    const auto library = afb::decl::Library::open(corpus / "doom3-kroom3" / "base", diags);
    REQUIRE(library);
    const auto loaded = afb::figure::loadEntityFigure(*library, "monster_zsec_machinegun", {}, diags);
    REQUIRE(loaded);
    for (const double height : {10.0, 100.0}) {
        afb::sim::DropOptions o;
        o.heightM = height;
        o.seconds = height > 50 ? 9.5 : 3.0;
        o.count = 2; // yaws 0° and 37°
        o.sleeping = false;
        o.method = multibody();
        const afb::sim::DropResult d = afb::sim::runDrop(loaded->figure, o);
        INFO(height << " m: anchor " << d.maxAnchorErrorM << " m, limit " << d.maxLimitViolationDeg << " deg at "
                    << d.worstLimitJoint << ", fastest " << d.maxSpeedMps << " m/s");
        CHECK_FALSE(d.exploded);
        CHECK(d.maxAnchorErrorM < 1e-5); // the backend's bound: 0.01 mm
    }
}

namespace {

// A hinge pendulum without air friction (settings friction 0, 0, 0.8): `top` fixed to the world, `arm` (a 20-unit
// box along +X from the anchor, 16 kg) swinging about Y from horizontal; the hinge's friction is `friction`. With
// `worldBall`, the arm hangs from the world by a ball-and-socket joint instead (for the multibody backend a loop
// joint: a point-to-point constraint, its reaction its applied impulse); it swings in the same plane.
Figure frictionPendulum(const std::string& friction, bool worldBall = false) {
    const std::vector<afb::test::TestJoint> joints = {{"origin", -1, 0, 0, 0},
                                                      {"top", 0, 0, 0, 104},
                                                      {"arm", 1, 0, 0, 100}};
    const auto built = afb::test::buildTestFigure(
        "articulatedFigure t {\n settings { selfCollision 0 friction 0, 0, 0.8 }\n"
        " body \"top\" { joint \"origin\" model box( ( -4, -4, -4 ), ( 4, 4, 4 ) ) origin ( 0, 0, 104 ) density 0.1 }\n"
        " body \"arm\" { joint \"arm\" model box( ( 0, -1, -1 ), ( 20, 1, 1 ) ) origin ( 0, 0, 100 ) density 0.2 }\n"
        " fixed \"mount\" { body1 \"top\" body2 \"world\" }\n" +
            std::string(
                worldBall
                    ? " ballAndSocketJoint \"b\" { body1 \"arm\" body2 \"world\" anchor ( 0, 0, 100 ) friction "
                    : " hinge \"h\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) axis ( 0, 1, 0 ) friction ") +
            friction + " }\n}\n",
        joints);
    INFO(built.diagnostics.str());
    REQUIRE(built.figure);
    return *built.figure;
}

// The arm's swing energy after `seconds` (kinetic + m·g·height above its hanging centre of mass, J) and at the
// start (m·g·r, r = 10 units from the anchor to its centre of mass).
struct Swing {
    double startJ = 0, endJ = 0;
};
Swing swing(const Figure& f, const Method& method, double seconds) {
    afb::sim::Scene scene(method, {.gravityMps2 = 9.81, .ground = false});
    Ragdoll& r = scene.spawn(RagdollAsset::create(f), {.comeToRest = false});
    const afb::figure::FigureBody& b = f.bodies[1];
    const double hangingZ = r.bodyStates()[1].pose.position.z() - 10 * f.units.metresPerUnit;
    auto energy = [&] {
        const afb::figure::BodyState s = r.bodyStates()[1];
        const Eigen::Vector3d w = s.pose.rotation.transpose() * s.angularVelocity;
        return 0.5 * b.massKg * s.linearVelocity.squaredNorm() + 0.5 * w.dot(b.inertiaKgM2.cwiseProduct(w)) +
               b.massKg * 9.81 * (s.pose.position.z() - hangingZ);
    };
    Swing out;
    out.startJ = energy();
    const int steps = static_cast<int>(std::lround(seconds * 60));
    for (int i = 0; i < steps; ++i) scene.step(1.0 / 60.0);
    out.endJ = energy();
    return out;
}

} // namespace

TEST_CASE("both backends: joint friction takes the same share of a swinging hinge's energy", "[bullet][multibody]") {
    // §4.8: the friction torque is bounded by friction × the joint's reaction force (in SI × metres per unit). The
    // rigid backend's hinge itself dissipates (a third of the swing's 40 J in 2 s without friction), which slows
    // its swing and so its friction's work; the comparison is therefore each backend's energy with friction as a
    // share of its own without. Measured: multibody 0.85 / 0.73 / 0.44 / 0.16, rigid 0.87 / 0.76 / 0.48 / 0.17.
    const Swing mb0 = swing(frictionPendulum("0"), multibody(), 2.0);
    const Swing rb0 = swing(frictionPendulum("0"), rigid(), 2.0);
    INFO("without friction: multibody " << mb0.endJ << " J, rigid " << rb0.endJ << " J of " << mb0.startJ);
    CHECK(mb0.startJ == Approx(16.0 * 9.81 * 0.254).epsilon(0.01)); // m·g·r, the arm 16 kg
    // Reduced coordinates and no friction: the swing keeps its energy (semi-implicit Euler's few per cent).
    CHECK(std::abs(mb0.endJ - mb0.startJ) < 0.03 * mb0.startJ);
    double previousMb = 1, previousRb = 1;
    for (const char* friction : {"0.1", "0.2", "0.5", "1"}) {
        const Figure f = frictionPendulum(friction);
        const double mb = swing(f, multibody(), 2.0).endJ / mb0.endJ;
        const double rb = swing(f, rigid(), 2.0).endJ / rb0.endJ;
        INFO("friction " << friction << ": kept multibody " << mb << ", rigid " << rb);
        CHECK(std::abs(mb - rb) < 0.06);
        CHECK(mb < previousMb); // more friction, less swing
        CHECK(rb < previousRb);
        previousMb = mb;
        previousRb = rb;
    }
}

TEST_CASE("both backends: a spring settles where k·ΔL² = m·g / its length rows hold", "[bullet][multibody]") {
    // §4.7's force is quadratic: F = k·(L − rest)², so the arm (16 kg) hanging from the top by a spring alone
    // (anchors at its centre of mass and 10 units straight above it: no torque) settles at ΔL = √(m·g/k). For
    // the multibody backend the two bodies are two trees (a spring is not a tree edge): the row spans both. One air
    // friction for the figure (the multibody backend damps a figure with one factor, docs/methods.md), 0.1 per step, so
    // the swing has settled in 5 s.
    auto springFigure = [](const std::string& extra) {
        const std::vector<afb::test::TestJoint> joints = {{"origin", -1, 0, 0, 0},
                                                          {"top", 0, 0, 0, 104},
                                                          {"arm", 1, 0, 0, 100}};
        const auto built = afb::test::buildTestFigure(
            "articulatedFigure t {\n settings { selfCollision 0 friction 0.1, 0.1, 0.5 }\n"
            " body \"top\" { joint \"origin\" model box( ( -4, -4, -4 ), ( 4, 4, 4 ) ) origin ( 0, 0, 104 ) density "
            "0.1 "
            "}\n"
            " body \"arm\" { joint \"arm\" model box( ( 0, -1, -1 ), ( 20, 1, 1 ) ) origin ( 0, 0, 100 ) density 0.2 "
            "}\n"
            " fixed \"mount\" { body1 \"top\" body2 \"world\" }\n"
            " spring \"s\" { body1 \"arm\" body2 \"top\" anchor1 ( 10, 0, 100 ) anchor2 ( 10, 0, 110 ) stretch 120 "
            "compress 120 damping 0 restLength 10 " +
                extra + " }\n}\n",
            joints);
        INFO(built.diagnostics.str());
        REQUIRE(built.figure);
        return *built.figure;
    };
    // The spring's length after `seconds`, m, and the longest it was.
    auto hang = [](const Figure& f, const Method& method, double seconds) {
        afb::sim::Scene scene(method, {.gravityMps2 = 9.81, .ground = false});
        Ragdoll& r = scene.spawn(RagdollAsset::create(f), {.comeToRest = false});
        double longest = 0;
        const int steps = static_cast<int>(std::lround(seconds * 60));
        for (int i = 0; i < steps; ++i) {
            scene.step(1.0 / 60.0);
            const auto [a1, a2] = r.constraintFramesWorld(1);
            longest = std::max(longest, static_cast<double>((a2.getOrigin() - a1.getOrigin()).length()));
        }
        const auto [a1, a2] = r.constraintFramesWorld(1);
        return std::make_pair(static_cast<double>((a2.getOrigin() - a1.getOrigin()).length()), longest);
    };
    const double unit = afb::figure::UnitSystem{}.metresPerUnit;
    for (const Method& method : {rigid(), multibody()}) {
        DYNAMIC_SECTION(afb::bullet::toString(method.backend)) {
            SECTION("equilibrium") {
                const Figure f = springFigure("");
                const double mass = f.bodies[1].massKg;
                const double k = 120.0 / unit; // N/m²
                const double expected = 10 * unit + std::sqrt(mass * 9.81 / k);
                const double length = hang(f, method, 5.0).first;
                INFO("length " << length << " m, expected " << expected << " m");
                CHECK(mass == Approx(16.0));
                CHECK(length == Approx(expected).epsilon(0.005));
            }
            SECTION("maxLength row") {
                // Free, the spring would settle at 10 + 7.2 units; the row holds it at 12 (its first stretch, at
                // about 0.7 m/s, overshoots by 11 mm on both backends).
                const auto [length, longest] = hang(springFigure("minLength 0 maxLength 12"), method, 3.0);
                INFO("length " << length << " m, longest " << longest << " m");
                CHECK(length < 12 * unit + 0.002);
                CHECK(length > 11 * unit);
                CHECK(longest < 12 * unit + 0.015);
            }
            SECTION("compressed, and the minLength row") {
                // The top's anchor 10 units below the arm's centre of mass: the arm rests on the spring, which
                // compresses to 10 − 7.2 units; with minLength 6 the row holds it there.
                auto below = [&](const std::string& extra) {
                    Figure f = springFigure(extra);
                    f.constraints[1].frameInBody2.position.z() -= 20 * unit;
                    return f;
                };
                const double mass = 16.0, k = 120.0 / unit;
                const double free = hang(below(""), method, 5.0).first;
                INFO("compressed to " << free << " m");
                CHECK(free == Approx(10 * unit - std::sqrt(mass * 9.81 / k)).epsilon(0.01));
                const double held = hang(below("minLength 6 maxLength 0"), method, 3.0).first;
                INFO("held at " << held << " m");
                CHECK(held > 6 * unit - 0.002);
                CHECK(held < 7 * unit);
            }
        }
    }
}

TEST_CASE("both backends: joint friction on a joint to the world (a multibody loop joint)", "[bullet][multibody]") {
    // As the hinge above, with the arm hanging from the world by a ball-and-socket joint: for the multibody backend
    // the joint is a btMultiBodyPoint2Point (not a tree edge) and the friction's bound comes from its impulse.
    const Swing mb0 = swing(frictionPendulum("0", true), multibody(), 2.0);
    const Swing rb0 = swing(frictionPendulum("0", true), rigid(), 2.0);
    for (const char* friction : {"0.2", "0.5"}) {
        const Figure f = frictionPendulum(friction, true);
        const double mb = swing(f, multibody(), 2.0).endJ / mb0.endJ;
        const double rb = swing(f, rigid(), 2.0).endJ / rb0.endJ;
        INFO("friction " << friction << ": kept multibody " << mb << ", rigid " << rb << " (without: multibody "
                         << mb0.endJ << " J, rigid " << rb0.endJ << " J of " << mb0.startJ << ")");
        CHECK(mb < 0.9);
        CHECK(std::abs(mb - rb) < 0.06);
    }
}
