// Hit reactions of a powered ragdoll (Ragdoll::hit, Ragdoll::setMotorStrength): the impulse changes the figure's
// momentum by exactly itself, the motors lose strength at once and regain it linearly, and a humanoid knocked hard
// while weightless (so that nothing but its motors brings it back) returns to the pose it held, at any step.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>
#include <vector>

#include "EntityFixture.h"
#include "MotorPoses.h"
#include "afb/bullet/Convert.h"
#include "afb/bullet/RagdollAsset.h"
#include "afb/sim/Scene.h"
#include "afb/sim/Stress.h"

using namespace afb;
using bullet::toBt;

namespace {

sim::SceneSettings weightless() {
    sim::SceneSettings s;
    s.gravityMps2 = 0;
    s.ground = false;
    return s;
}

constexpr double kDegree = 3.14159265358979323846 / 180;

int bodyNamed(const bullet::Ragdoll& r, const std::string& name) {
    const auto& bodies = r.figure().bodies;
    for (std::size_t i = 0; i < bodies.size(); ++i)
        if (bodies[i].name == name) return static_cast<int>(i);
    FAIL("no body " << name);
    return -1;
}

bullet::SpawnOptions floating() {
    bullet::SpawnOptions where;
    where.entityTransform = btTransform(btQuaternion(btVector3(0, 0, 1), btScalar(0.6)), btVector3(0, 0, 2));
    where.comeToRest = false;
    return where;
}

// The figure's linear momentum and its angular momentum about the world origin, over its rigid bodies.
struct Momentum {
    btVector3 linear{0, 0, 0}, angular{0, 0, 0};
};
Momentum momentumOf(const bullet::Ragdoll& r) {
    Momentum m;
    for (int k = 0; k < r.rigidBodyCount(); ++k) {
        const btRigidBody& b = r.rigidBody(k);
        const btVector3 p = b.getLinearVelocity() / b.getInvMass();
        const btMatrix3x3 inertia = b.getInvInertiaTensorWorld().inverse();
        m.linear += p;
        m.angular += b.getCenterOfMassPosition().cross(p) + inertia * b.getAngularVelocity();
    }
    return m;
}

btVector3 centreOfMass(const bullet::Ragdoll& r) {
    const std::vector<figure::BodyState> states = r.bodyStates();
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double mass = 0;
    for (std::size_t i = 0; i < states.size(); ++i) {
        sum += r.figure().bodies[i].massKg * states[i].pose.position;
        mass += r.figure().bodies[i].massKg;
    }
    return toBt(Eigen::Vector3d(sum / mass));
}

// Kinetic energy, J (no gravity here).
double kineticEnergy(const bullet::Ragdoll& r) { return sim::figureEnergyJ(r.figure(), r.bodyStates(), 0); }

} // namespace

TEST_CASE("hit: a strength scales the motors' stiffness, damping and bounds by itself", "[bullet][motors][hit]") {
    const bullet::MotorGains g{8, 0.7, 40, 90};
    for (const double s : {4.0, 1.0, 0.64, 0.25, 0.01}) {
        INFO("strength " << s);
        const bullet::MotorGains h = bullet::scaledGains(g, s);
        // Stiffness goes with the frequency squared and damping with damping ratio times frequency (same inertia).
        CHECK(h.frequencyHz * h.frequencyHz == Approx(s * g.frequencyHz * g.frequencyHz));
        CHECK(h.dampingRatio * h.frequencyHz == Approx(s * g.dampingRatio * g.frequencyHz));
        CHECK(h.maxTorqueNm == Approx(s * g.maxTorqueNm));
        CHECK(h.maxForceN == Approx(s * g.maxForceN));
    }
    CHECK(bullet::scaledGains(g, 0).frequencyHz == 0); // off: the motor leaves the world
}

TEST_CASE("hit: the impulse changes the figure's momentum by itself and its angular momentum by r x J",
          "[bullet][motors][hit]") {
    const auto asset = bullet::RagdollAsset::create(test::loadEntity("humanoid").figure);
    sim::Scene scene(*bullet::methodPreset("default"), weightless());
    bullet::Ragdoll& r = scene.spawn(asset, floating());
    REQUIRE(r.setMotorGains(bullet::MotorGains{4, 1}));
    const Momentum before = momentumOf(r);
    const int hand = bodyNamed(r, "l_hand");
    const btVector3 at = toBt(r.bodyStates()[static_cast<std::size_t>(hand)].pose.position) + btVector3(0, 0.02f, 0);
    const btVector3 impulse(12, -5, 30);
    REQUIRE(r.hit(hand, impulse, at, {0.3, 0.5}));
    const Momentum after = momentumOf(r);
    const btVector3 dp = after.linear - before.linear, dl = after.angular - before.angular;
    const btVector3 expectedDl = at.cross(impulse);
    for (int axis = 0; axis < 3; ++axis) {
        CHECK(double(dp[axis]) == Approx(double(impulse[axis])).margin(1e-3));
        CHECK(double(dl[axis]) == Approx(double(expectedDl[axis])).margin(1e-3));
    }
    CHECK(r.motorStrength() == Approx(0.3));
}

TEST_CASE("hit: the motors' strength comes back linearly over the regain time", "[bullet][motors][hit]") {
    const auto asset = bullet::RagdollAsset::create(test::loadEntity("humanoid").figure);
    sim::Scene scene(*bullet::methodPreset("default"), weightless());
    bullet::Ragdoll& r = scene.spawn(asset, floating());
    CHECK(r.motorStrength() == 1);
    REQUIRE(r.setMotorGains(bullet::MotorGains{4, 1}));
    REQUIRE(r.hit(0, btVector3(0, 0, 5), toBt(r.bodyStates()[0].pose.position), {0.2, 0.5}));
    constexpr double kDt = 1.0 / 60;
    for (int step = 1; step <= 40; ++step) {
        scene.step(kDt);
        INFO("step " << step);
        CHECK(r.motorStrength() == Approx(std::min(1.0, 0.2 + 0.8 * step * kDt / 0.5)).margin(1e-9));
    }
    // Gains as set are what motorGains reports throughout; a strength set by hand stops nothing it should not.
    CHECK(r.motorGains(0).frequencyHz == 4);
    REQUIRE(r.setMotorStrength(0.5));
    scene.step(kDt);
    CHECK(r.motorStrength() == 0.5);
}

TEST_CASE("hit: a weightless humanoid knocked limp returns to the pose it held as its motors regain, at any step",
          "[bullet][motors][hit]") {
    const auto asset = bullet::RagdollAsset::create(test::loadEntity("humanoid").figure);
    const test::HeldPose held = test::restingPose(asset);
    for (const double hz : {15.0, 60.0, 240.0}) {
        INFO(hz << " Hz");
        sim::Scene scene(*bullet::methodPreset("default"), weightless());
        bullet::Ragdoll& r = scene.spawn(asset, floating());
        REQUIRE(r.setMotorGains(bullet::MotorGains{4, 1}));
        REQUIRE(r.driveToPose(held.states));
        const int steps = static_cast<int>(4 * hz);
        for (int s = 0; s < steps; ++s) scene.step(1 / hz);
        REQUIRE(test::worstMotorError(r, held.rotations) < kDegree);
        // 15 N·s at the left hand, away from the figure's centre of mass (so the figure does not spin: a spinning
        // figure's limbs are flung out and held off their pose), limp at once, full strength after 0.5 s.
        const int hand = bodyNamed(r, "l_hand");
        const btVector3 at = toBt(r.bodyStates()[static_cast<std::size_t>(hand)].pose.position);
        const btVector3 away = (at - centreOfMass(r)).normalized();
        REQUIRE(r.hit(hand, 15 * away, at, {0, 0.5}));
        const double hitEnergy = kineticEnergy(r);
        double mostEnergy = hitEnergy, mostError = 0;
        for (int s = 0; s < static_cast<int>(6 * hz); ++s) { // the last limb settles about 5 s after the hit
            scene.step(1 / hz);
            mostEnergy = std::max(mostEnergy, kineticEnergy(r));
            mostError = std::max(mostError, test::worstMotorError(r, held.rotations));
        }
        INFO("most error " << mostError / kDegree << " degrees; kinetic energy at the hit " << hitEnergy
                           << " J, most after it " << mostEnergy << " J");
        CHECK(mostError > 5 * kDegree); // the hit did knock the figure out of its pose
        CHECK(test::worstMotorError(r, held.rotations) < kDegree);
        // The motors only take energy out: none comes back above what the hit gave.
        CHECK(mostEnergy <= hitEnergy * 1.001);
        CHECK(r.guardTrips() == 0);
    }
}

TEST_CASE("hit: with one arm limp by its profile, the arm stays where the hit sends it while the rest comes back",
          "[bullet][motors][hit]") {
    const auto asset = bullet::RagdollAsset::create(test::loadEntity("humanoid").figure);
    const test::HeldPose held = test::restingPose(asset);
    sim::Scene scene(*bullet::methodPreset("default"), weightless());
    bullet::Ragdoll& r = scene.spawn(asset, floating());
    bullet::MotorProfile profile;
    profile.all = {4, 1};
    profile.joints = {{"l_shoulder", {0, 1}}, {"l_elbow", {0, 1}}};
    REQUIRE(r.setMotorGains(profile));
    REQUIRE(r.driveToPose(held.states));
    for (int s = 0; s < 240; ++s) scene.step(1.0 / 60);
    const int hand = bodyNamed(r, "l_hand");
    const btVector3 at = toBt(r.bodyStates()[static_cast<std::size_t>(hand)].pose.position);
    REQUIRE(r.hit(hand, 15 * (at - centreOfMass(r)).normalized(), at, {0, 0.5}));
    for (int s = 0; s < 360; ++s) scene.step(1.0 / 60);
    const std::vector<btQuaternion> now = test::relativeRotations(r);
    double limpArm = 0, rest = 0;
    for (std::size_t i = 0; i < now.size(); ++i) {
        if (!r.hasMotor(static_cast<int>(i))) continue;
        const double error = test::angleBetween(now[i], held.rotations[i]);
        const std::string& name = r.figure().constraints[i].name;
        double& worst = name == "l_shoulder" || name == "l_elbow" ? limpArm : rest;
        worst = std::max(worst, error);
    }
    CHECK(rest < kDegree);
    CHECK(limpArm > 5 * kDegree);
}

TEST_CASE("hit: refused out of range, and where motors cannot run the impulse alone", "[bullet][motors][hit]") {
    const auto asset = bullet::RagdollAsset::create(test::loadEntity("humanoid").figure);
    sim::Scene scene(*bullet::methodPreset("default"), weightless());
    bullet::Ragdoll& r = scene.spawn(asset, floating());
    const btVector3 at = toBt(r.bodyStates()[0].pose.position);
    CHECK_FALSE(r.hit(-1, btVector3(1, 0, 0), at));
    CHECK_FALSE(r.hit(r.bodyCount(), btVector3(1, 0, 0), at));
    CHECK_FALSE(r.hit(0, btVector3(std::nanf(""), 0, 0), at));
    CHECK_FALSE(r.hit(0, btVector3(1, 0, 0), at, {1.5, 0.5}));
    CHECK_FALSE(r.hit(0, btVector3(1, 0, 0), at, {0.5, -1}));
    CHECK_FALSE(r.setMotorStrength(-0.1));
    CHECK_FALSE(r.setMotorStrength(2));
    CHECK(r.motorStrength() == 1);
    // Limp: the impulse, no strength to lose.
    REQUIRE(r.hit(0, btVector3(1, 0, 0), at));
    CHECK(r.motorStrength() == 1);
}
