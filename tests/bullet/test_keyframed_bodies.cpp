// Keyframed bodies and partial ragdolls (Ragdoll::setBodyMode, Ragdoll::setKeyframeTargets; docs/motors.md): a
// keyframed body lands on its target after every step whatever acts on it, pushes a free box without being pushed
// back, holds up a limp figure hanging from it, keeps its velocity when it goes back to simulated, follows an
// animation exactly, keeps a moving figure awake; merged rigid bodies follow their first keyframed body; bad input
// and backends that cannot keyframe are refused.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "EntityFixture.h"
#include "MotorPoses.h"
#include "TestSupport.h"
#include "afb/bullet/Convert.h"
#include "afb/bullet/RagdollAsset.h"
#include "afb/decl/Md5Anim.h"
#include "afb/figure/Placement.h"
#include "afb/sim/Scene.h"

using namespace afb;

namespace {

constexpr double kDt = 1.0 / 60;
constexpr double kPi = 3.14159265358979323846;
// A keyframed body lands on its target to Bullet's float precision: the target rounded to float, about 1e-7 of a
// metre-sized coordinate and of a rotation.
constexpr double kLandM = 1e-5;
constexpr double kLandRad = 1e-5;

int bodyNamed(const figure::Figure& f, const std::string& name) {
    for (std::size_t i = 0; i < f.bodies.size(); ++i)
        if (f.bodies[i].name == name) return static_cast<int>(i);
    FAIL("no body " << name);
    return -1;
}

double metresApart(const figure::Transform& a, const figure::Transform& b) { return (a.position - b.position).norm(); }
double radiansApart(const figure::Transform& a, const figure::Transform& b) {
    return Eigen::AngleAxisd(a.rotation.transpose() * b.rotation).angle();
}

// `pose` moved by `offset` (world) and turned by `yaw` (rad) about the vertical through its own origin.
figure::Transform moved(const figure::Transform& pose, const Eigen::Vector3d& offset, double yaw) {
    return {Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() * pose.rotation,
            pose.position + offset};
}

// The largest anchor gap of the figure's joints now, metres.
double worstAnchorM(const bullet::Ragdoll& r) {
    double worst = 0;
    for (std::size_t i = 0; i < r.figure().constraints.size(); ++i)
        worst = std::max(worst, r.jointError(static_cast<int>(i)).anchorM);
    return worst;
}

// How far joint `name`'s relative rotation is from the one `pose` gives it, rad.
double jointOffRad(const bullet::Ragdoll& r, const std::vector<figure::BodyState>& pose, const std::string& name) {
    const auto& constraints = r.figure().constraints;
    const auto it = std::find_if(constraints.begin(), constraints.end(),
                                 [&name](const figure::FigureConstraint& c) { return c.name == name; });
    REQUIRE(it != constraints.end());
    const int ci = static_cast<int>(it - constraints.begin());
    const btTransform a =
        bullet::toBt(pose[static_cast<std::size_t>(it->body1)].pose) * r.constraintFramesLocal(ci).first;
    const btTransform b =
        bullet::toBt(pose[static_cast<std::size_t>(it->body2)].pose) * r.constraintFramesLocal(ci).second;
    btQuaternion q;
    (a.getBasis().transpose() * b.getBasis()).getRotation(q);
    return test::angleBetween(test::relativeRotations(r)[static_cast<std::size_t>(ci)], q);
}

bullet::SpawnOptions at(double heightM, bool comeToRest = false) {
    bullet::SpawnOptions o;
    o.entityTransform = btTransform(btQuaternion::getIdentity(), btVector3(0, 0, btScalar(heightM)));
    o.comeToRest = comeToRest;
    return o;
}

// The state list with body `body`'s pose replaced.
std::vector<figure::BodyState> withPose(std::vector<figure::BodyState> states, int body, const figure::Transform& p) {
    states[static_cast<std::size_t>(body)].pose = p;
    return states;
}

} // namespace

TEST_CASE("keyframed: the pelvis lands on its target after every step while the standing figure's legs push back",
          "[bullet][keyframed]") {
    const auto loaded = test::loadEntity("humanoid");
    const figure::Figure& f = loaded.figure;
    const auto asset = bullet::RagdollAsset::create(f);
    const int substeps = GENERATE(1, 3);
    bullet::Method method = *bullet::methodPreset("default");
    method.substeps = substeps;
    sim::Scene scene(method);
    bullet::Ragdoll& r = scene.spawn(asset, at(0.02));
    const int pelvis = bodyNamed(f, "pelvis");
    REQUIRE(r.setBodyMode(pelvis, bullet::BodyMode::Keyframed));
    CHECK(r.bodyMode(pelvis) == bullet::BodyMode::Keyframed);
    CHECK(r.body(pelvis).isKinematicObject());
    const figure::Transform start = r.bodyState(pelvis).pose;
    // Sways 0.3 m sideways and crouches 0.2 m, turning ±0.5 rad, at 0.5 Hz: the legs on the ground resist.
    const auto path = [&](double t) {
        const double phase = 2 * kPi * 0.5 * t;
        return moved(start, {0, 0.3 * std::sin(phase), -0.1 * (1 - std::cos(phase))}, 0.5 * std::sin(phase));
    };
    double worstM = 0, worstRad = 0, worstSpeedError = 0, worstAnchor = 0;
    for (int s = 1; s <= 240; ++s) {
        const std::vector<figure::BodyState> targets = withPose(r.bodyStates(), pelvis, path(s * kDt));
        REQUIRE(r.setKeyframeTargets(targets));
        scene.step(kDt);
        const figure::BodyState now = r.bodyState(pelvis);
        worstM = std::max(worstM, metresApart(now.pose, path(s * kDt)));
        worstRad = std::max(worstRad, radiansApart(now.pose, path(s * kDt)));
        // Its velocity is the step's move over the step (the path's secant, computed here in double).
        const Eigen::Vector3d secant = (path(s * kDt).position - path((s - 1) * kDt).position) / kDt;
        worstSpeedError = std::max(worstSpeedError, (now.linearVelocity - secant).norm());
        worstAnchor = std::max(worstAnchor, worstAnchorM(r));
    }
    INFO(substeps << " substeps: off the target by " << worstM << " m, " << worstRad
                  << " rad; velocity off the secant by " << worstSpeedError << " m/s; worst anchor gap " << worstAnchor
                  << " m");
    CHECK(worstM < kLandM);
    CHECK(worstRad < kLandRad);
    CHECK(worstSpeedError < 1e-3);
    CHECK(worstAnchor < 0.02); // the hips and the waist follow it
    CHECK(r.guardTrips() == 0);
}

TEST_CASE("keyframed: a figure keyframed through a box pushes it away and stays on its path", "[bullet][keyframed]") {
    const auto loaded = test::loadEntity("humanoid");
    const figure::Figure& f = loaded.figure;
    const auto asset = bullet::RagdollAsset::create(f);
    sim::Scene scene(*bullet::methodPreset("default"));
    bullet::Ragdoll& r = scene.spawn(asset, at(0.02));
    for (int i = 0; i < r.bodyCount(); ++i) REQUIRE(r.setBodyMode(i, bullet::BodyMode::Keyframed));
    const std::vector<figure::BodyState> start = r.bodyStates();
    double frontM = -1e9; // the figure's foremost body centre along +X
    for (const figure::BodyState& s : start) frontM = std::max(frontM, s.pose.position.x());

    // A 20 kg box of 0.4 m on the ground, 0.3 m ahead of the foremost body.
    const auto half = btScalar(0.2);
    btBoxShape shape(btVector3(half, half, half));
    btVector3 inertia;
    shape.calculateLocalInertia(20, inertia);
    btRigidBody box(20, nullptr, &shape, inertia);
    box.setWorldTransform(btTransform(btQuaternion::getIdentity(), btVector3(btScalar(frontM + 0.5), 0, half)));
    scene.world().addRigidBody(&box);
    const btScalar boxStartX = box.getCenterOfMassPosition().x();

    // The whole figure walks through it along +X at 1 m/s for 1.5 s.
    double worstM = 0;
    btScalar fastestBox = 0;
    for (int s = 1; s <= 90; ++s) {
        std::vector<figure::BodyState> targets = start;
        for (figure::BodyState& t : targets) t.pose.position.x() += 1.0 * s * kDt;
        REQUIRE(r.setKeyframeTargets(targets));
        scene.step(kDt);
        const std::vector<figure::BodyState> now = r.bodyStates();
        for (std::size_t i = 0; i < now.size(); ++i)
            worstM = std::max(worstM, metresApart(now[i].pose, targets[i].pose));
        fastestBox = std::max(fastestBox, box.getLinearVelocity().x());
    }
    const btScalar pushedM = box.getCenterOfMassPosition().x() - boxStartX;
    INFO("bodies off their targets by " << worstM << " m; the box went " << pushedM << " m, at most at " << fastestBox
                                        << " m/s");
    CHECK(worstM < kLandM); // the box never pushed a body back
    CHECK(fastestBox > 0.5);
    CHECK(pushedM > 0.5); // the figure went 1.5 m and the box started 0.3 m ahead of it
    scene.world().removeRigidBody(&box);
}

TEST_CASE("keyframed: a limp figure hangs from its keyframed pelvis swung round in the air, its joints holding",
          "[bullet][keyframed]") {
    const auto loaded = test::loadEntity("humanoid");
    const figure::Figure& f = loaded.figure;
    const auto asset = bullet::RagdollAsset::create(f);
    sim::Scene scene(*bullet::methodPreset("default"));
    bullet::Ragdoll& r = scene.spawn(asset, at(1.5));
    const int pelvis = bodyNamed(f, "pelvis");
    REQUIRE(r.setBodyMode(pelvis, bullet::BodyMode::Keyframed));
    const figure::Transform start = r.bodyState(pelvis).pose;
    // A horizontal circle of 0.3 m at 0.5 Hz (about 0.94 m/s), entered from where it hangs.
    const auto path = [&](double t) {
        const double phase = 2 * kPi * 0.5 * t;
        return moved(start, {0.3 * (std::cos(phase) - 1), 0.3 * std::sin(phase), 0}, 0);
    };
    double worstM = 0, worstAnchor = 0, fastest = 0;
    for (int s = 1; s <= 240; ++s) {
        REQUIRE(r.setKeyframeTargets(withPose(r.bodyStates(), pelvis, path(s * kDt))));
        scene.step(kDt);
        worstM = std::max(worstM, metresApart(r.bodyState(pelvis).pose, path(s * kDt)));
        if (s > 30) worstAnchor = std::max(worstAnchor, worstAnchorM(r)); // after the first half second's drop
        for (const figure::BodyState& b : r.bodyStates()) fastest = std::max(fastest, b.linearVelocity.norm());
    }
    const double pelvisZ = r.bodyState(pelvis).pose.position.z();
    INFO("pelvis off its path by " << worstM << " m; worst anchor gap " << worstAnchor << " m; fastest body " << fastest
                                   << " m/s");
    CHECK(worstM < kLandM);
    CHECK(worstAnchor < 0.02);
    CHECK(fastest < 10); // swinging, never thrown
    CHECK(r.guardTrips() == 0);
    for (const char* foot : {"l_foot", "r_foot"}) // the legs hang below it
        CHECK(r.bodyState(bodyNamed(f, foot)).pose.position.z() < pelvisZ - 0.5);
}

TEST_CASE("keyframed: back to simulated, a body keeps its pose and its last keyframed velocity",
          "[bullet][keyframed]") {
    const auto loaded = test::loadEntity("humanoid");
    const figure::Figure& f = loaded.figure;
    const auto asset = bullet::RagdollAsset::create(f);
    sim::Scene scene(*bullet::methodPreset("default"));
    bullet::Ragdoll& r = scene.spawn(asset, at(1.5));
    const int pelvis = bodyNamed(f, "pelvis");
    REQUIRE(r.setBodyMode(pelvis, bullet::BodyMode::Keyframed));
    const figure::Transform start = r.bodyState(pelvis).pose;
    // 0.5 m/s along X, 0.2 m/s along Y, turning at 1 rad/s about the vertical: velocities known beforehand.
    const Eigen::Vector3d velocity(0.5, 0.2, 0);
    const auto path = [&](double t) { return moved(start, velocity * t, 1.0 * t); };
    for (int s = 1; s <= 30; ++s) {
        REQUIRE(r.setKeyframeTargets(withPose(r.bodyStates(), pelvis, path(s * kDt))));
        scene.step(kDt);
    }
    const figure::BodyState keyframed = r.bodyState(pelvis);
    REQUIRE(r.setBodyMode(pelvis, bullet::BodyMode::Simulated));
    CHECK(r.bodyMode(pelvis) == bullet::BodyMode::Simulated);
    CHECK_FALSE(r.body(pelvis).isKinematicObject());
    CHECK(r.body(pelvis).getInvMass() > 0);
    const figure::BodyState simulated = r.bodyState(pelvis);
    CHECK(simulated.pose.position == keyframed.pose.position);
    CHECK(simulated.pose.rotation == keyframed.pose.rotation);
    CHECK((simulated.linearVelocity - velocity).norm() < 1e-4);
    CHECK((simulated.angularVelocity - Eigen::Vector3d(0, 0, 1)).norm() < 1e-4);
    // The next step carries it on at that velocity (gravity adds g·dt²/2 = 1.4 mm; stopping dead would leave 9 mm).
    scene.step(kDt);
    const Eigen::Vector3d went = r.bodyState(pelvis).pose.position - simulated.pose.position;
    INFO("moved " << went.transpose() << " m in the step after the switch, against " << (velocity * kDt).transpose());
    CHECK((went - velocity * kDt).norm() < 0.004);
}

TEST_CASE("keyframed: bad input is refused and changes nothing, and backends that cannot keyframe refuse",
          "[bullet][keyframed]") {
    const auto loaded = test::loadEntity("humanoid");
    const figure::Figure& f = loaded.figure;
    const auto asset = bullet::RagdollAsset::create(f);
    sim::Scene scene(*bullet::methodPreset("default"));
    bullet::Ragdoll& r = scene.spawn(asset, at(1.5));
    const int head = bodyNamed(f, "head");
    CHECK_FALSE(r.setBodyMode(-1, bullet::BodyMode::Keyframed));
    CHECK_FALSE(r.setBodyMode(r.bodyCount(), bullet::BodyMode::Keyframed));
    CHECK_FALSE(r.setBodyMode(head, static_cast<bullet::BodyMode>(7)));
    CHECK(r.bodyMode(head) == bullet::BodyMode::Simulated);
    CHECK(r.bodyMode(-1) == bullet::BodyMode::Simulated);
    for (int k = 0; k < r.rigidBodyCount(); ++k) CHECK_FALSE(r.rigidKeyframed(k));

    REQUIRE(r.setBodyMode(head, bullet::BodyMode::Keyframed));
    const figure::Transform target = moved(r.bodyState(head).pose, {0, 0, 0.1}, 0.2);
    const std::vector<figure::BodyState> good = withPose(r.bodyStates(), head, target);
    REQUIRE(r.setKeyframeTargets(good));
    std::vector<figure::BodyState> notFinite = withPose(good, head, moved(target, {0, 0, 0.5}, 0));
    notFinite[3].linearVelocity.y() = std::numeric_limits<double>::quiet_NaN();
    std::vector<figure::BodyState> notRotation = withPose(good, head, moved(target, {0, 0, 0.5}, 0));
    notRotation[static_cast<std::size_t>(head)].pose.rotation *= 2;
    CHECK_FALSE(r.setKeyframeTargets(notFinite));
    CHECK_FALSE(r.setKeyframeTargets(notRotation));
    CHECK_FALSE(r.setKeyframeTargets(std::span(good).first(good.size() - 1)));
    for (int s = 0; s < 3; ++s) scene.step(kDt);
    CHECK(metresApart(r.bodyState(head).pose, target) < kLandM); // the refused targets never took hold
    CHECK(radiansApart(r.bodyState(head).pose, target) < kLandRad);

    sim::Scene multibody(*bullet::methodPreset("multibody"));
    bullet::Ragdoll& m = multibody.spawn(asset, at(1.5));
    CHECK_FALSE(m.setBodyMode(head, bullet::BodyMode::Keyframed));
    CHECK_FALSE(m.setKeyframeTargets(m.bodyStates()));
    CHECK(m.bodyMode(head) == bullet::BodyMode::Simulated);
    // A ragdoll in a world no RagdollWorld steps: nothing would move its keyframed bodies.
    btDefaultCollisionConfiguration configuration;
    btCollisionDispatcher dispatcher(&configuration);
    btDbvtBroadphase broadphase;
    btSequentialImpulseConstraintSolver solver;
    btDiscreteDynamicsWorld world(&dispatcher, &broadphase, &solver, &configuration);
    bullet::Ragdoll plain(asset, world);
    CHECK_FALSE(plain.setBodyMode(head, bullet::BodyMode::Keyframed));
    CHECK_FALSE(plain.setKeyframeTargets(plain.bodyStates()));
}

TEST_CASE("keyframed: a figure with every body keyframed follows a walk exactly", "[bullet][keyframed]") {
    const auto loaded = test::loadEntity("humanoid");
    const figure::Figure& f = loaded.figure;
    const auto asset = bullet::RagdollAsset::create(f);
    text::Diagnostics diags;
    const auto walk = decl::loadMd5Anim(test::sourceDir() / "models/md5/humanoid/walk.md5anim", diags);
    INFO(diags.str());
    REQUIRE(walk);
    const figure::Transform entity{Eigen::AngleAxisd(0.6, Eigen::Vector3d::UnitZ()).toRotationMatrix(), {1, -2, 0}};
    const auto frame = [&](double t) {
        auto states = figure::bodyStatesFromAnimation(f, *walk, t, entity, diags);
        REQUIRE(states);
        return std::move(*states);
    };
    // Every body its own rigid (a merged hand follows its forearm: see the merged-body test).
    bullet::Method method = *bullet::methodPreset("default");
    method.mergeFixed = false;
    sim::Scene scene(method);
    bullet::SpawnOptions o;
    o.entityTransform = bullet::toBt(entity);
    o.comeToRest = false;
    bullet::Ragdoll& r = scene.spawn(asset, o);
    REQUIRE(r.setBodyStates(frame(0)));
    for (int i = 0; i < r.bodyCount(); ++i) REQUIRE(r.setBodyMode(i, bullet::BodyMode::Keyframed));
    double worstM = 0, worstRad = 0, worstSpeedError = 0, fastest = 0;
    std::vector<figure::BodyState> before = frame(0);
    for (int s = 1; s <= 60; ++s) {
        const std::vector<figure::BodyState> targets = frame(s * kDt);
        REQUIRE(r.setKeyframeTargets(targets));
        scene.step(kDt);
        const std::vector<figure::BodyState> now = r.bodyStates();
        for (std::size_t i = 0; i < now.size(); ++i) {
            worstM = std::max(worstM, metresApart(now[i].pose, targets[i].pose));
            worstRad = std::max(worstRad, radiansApart(now[i].pose, targets[i].pose));
            const Eigen::Vector3d secant = (targets[i].pose.position - before[i].pose.position) / kDt;
            worstSpeedError = std::max(worstSpeedError, (now[i].linearVelocity - secant).norm());
            fastest = std::max(fastest, secant.norm());
        }
        before = targets;
    }
    INFO("off the walk by " << worstM << " m, " << worstRad << " rad; velocities off the frames' secants by "
                            << worstSpeedError << " m/s; fastest body " << fastest << " m/s");
    CHECK(worstM < kLandM);
    CHECK(worstRad < kLandRad);
    CHECK(worstSpeedError < 1e-3);
    CHECK(fastest > 0.1); // the walk moves
}

TEST_CASE("keyframed: a merged rigid body follows its first keyframed body, and modes outlive levels of detail",
          "[bullet][keyframed]") {
    const auto loaded = test::loadEntity("humanoid");
    const figure::Figure& f = loaded.figure;
    const auto asset = bullet::RagdollAsset::create(f);
    sim::SceneSettings weightless;
    weightless.gravityMps2 = 0;
    weightless.ground = false;
    sim::Scene scene(*bullet::methodPreset("default"), weightless); // merges each hand into its forearm
    bullet::Ragdoll& r = scene.spawn(asset, at(1.5));
    const int fore = bodyNamed(f, "l_forearm"), hand = bodyNamed(f, "l_hand");
    REQUIRE(fore < hand);
    REQUIRE(r.rigidIndexOf(fore) == r.rigidIndexOf(hand));
    const std::vector<figure::BodyState> start = r.bodyStates();
    const figure::Transform handInFore =
        start[static_cast<std::size_t>(fore)].pose.inverse() * start[static_cast<std::size_t>(hand)].pose;
    std::vector<figure::BodyState> targets = start;
    const figure::Transform handTarget = moved(start[static_cast<std::size_t>(hand)].pose, {0, 0, 0.2}, 0.3);
    const figure::Transform foreTarget = moved(start[static_cast<std::size_t>(fore)].pose, {0.3, 0, 0}, 0);
    targets[static_cast<std::size_t>(hand)].pose = handTarget;
    targets[static_cast<std::size_t>(fore)].pose = foreTarget;

    // The hand alone keyframed: the rigid follows the hand, the forearm rides along at its merged offset.
    REQUIRE(r.setBodyMode(hand, bullet::BodyMode::Keyframed));
    CHECK(r.bodyMode(fore) == bullet::BodyMode::Simulated);
    CHECK(r.rigidKeyframed(r.rigidIndexOf(fore)));
    REQUIRE(r.setKeyframeTargets(targets));
    scene.step(kDt);
    CHECK(metresApart(r.bodyState(hand).pose, handTarget) < kLandM);
    CHECK(metresApart(r.bodyState(fore).pose, handTarget * handInFore.inverse()) < kLandM);
    // The forearm keyframed too: the first in body order leads, and goes to its own target.
    REQUIRE(r.setBodyMode(fore, bullet::BodyMode::Keyframed));
    scene.step(kDt);
    CHECK(metresApart(r.bodyState(hand).pose, handTarget) < kLandM); // held where it was until new targets
    REQUIRE(r.setKeyframeTargets(targets));
    scene.step(kDt);
    CHECK(metresApart(r.bodyState(fore).pose, foreTarget) < kLandM);
    CHECK(metresApart(r.bodyState(hand).pose, foreTarget * handInFore) < kLandM);
    // Both simulated again: a dynamic rigid with the two bodies' mass.
    REQUIRE(r.setBodyMode(fore, bullet::BodyMode::Simulated));
    CHECK(r.body(hand).isKinematicObject());
    REQUIRE(r.setBodyMode(hand, bullet::BodyMode::Simulated));
    CHECK_FALSE(r.body(hand).isKinematicObject());
    CHECK(1 / r.body(hand).getInvMass() ==
          Approx(f.bodies[static_cast<std::size_t>(fore)].massKg + f.bodies[static_cast<std::size_t>(hand)].massKg));

    // A level of detail that merges the left leg: its rigid is keyframed while the shin is, and back at full detail
    // only the shin's rigid is.
    const int thigh = bodyNamed(f, "l_thigh"), shin = bodyNamed(f, "l_shin"), foot = bodyNamed(f, "l_foot");
    REQUIRE(r.setBodyMode(shin, bullet::BodyMode::Keyframed));
    figure::LodLevel level;
    level.groups.push_back({thigh, shin, foot});
    for (int i = 0; i < r.bodyCount(); ++i)
        if (i != thigh && i != shin && i != foot) level.groups.push_back({i});
    REQUIRE(r.setLod(level).empty());
    CHECK(r.body(thigh).isKinematicObject());
    CHECK(r.body(foot).isKinematicObject());
    const figure::Transform shinTarget = moved(r.bodyState(shin).pose, {0, 0.2, 0}, 0.2);
    REQUIRE(r.setKeyframeTargets(withPose(r.bodyStates(), shin, shinTarget)));
    scene.step(kDt);
    CHECK(metresApart(r.bodyState(shin).pose, shinTarget) < kLandM);
    r.setFullDetail();
    CHECK(r.bodyMode(shin) == bullet::BodyMode::Keyframed);
    CHECK(r.body(shin).isKinematicObject());
    CHECK_FALSE(r.body(thigh).isKinematicObject());
    CHECK_FALSE(r.body(foot).isKinematicObject());
    scene.step(kDt);
    CHECK(metresApart(r.bodyState(shin).pose, shinTarget) < kLandM);
    CHECK(r.guardTrips() == 0);
}

TEST_CASE("keyframed: a figure is not put to rest while a keyframed body moves, however slowly",
          "[bullet][keyframed]") {
    const auto loaded = test::loadEntity("humanoid");
    const figure::Figure& f = loaded.figure;
    const auto asset = bullet::RagdollAsset::create(f);
    const int head = bodyNamed(f, "head");
    // On its back on the ground, rest rules on; with its head keyframed or not.
    const auto lying = [&](sim::Scene& scene) -> bullet::Ragdoll& {
        bullet::SpawnOptions o = at(0.3, true);
        o.entityTransform.setRotation(btQuaternion(btVector3(0, 1, 0), btScalar(-kPi / 2)));
        return scene.spawn(asset, o);
    };
    using Targets = std::function<std::vector<figure::BodyState>(int)>;
    // The steps from `from` until the figure rests (−1: not within `steps`), targets from `targetAt` if any.
    const auto stepsToRest = [](sim::Scene& scene, bullet::Ragdoll& r, const Targets& targetAt, int from, int steps) {
        for (int s = from; s < from + steps; ++s) {
            if (targetAt) REQUIRE(r.setKeyframeTargets(targetAt(s)));
            scene.step(kDt);
            if (r.atRest()) return s - from;
        }
        return -1;
    };
    {
        sim::Scene scene(*bullet::methodPreset("default"));
        bullet::Ragdoll& r = lying(scene);
        CHECK(stepsToRest(scene, r, Targets{}, 0, 360) >= 0); // the rules rest this figure within 6 s
    }
    sim::Scene scene(*bullet::methodPreset("default"));
    bullet::Ragdoll& r = lying(scene);
    REQUIRE(stepsToRest(scene, r, Targets{}, 0, 360) >= 0);
    r.wake(); // awake on the ground
    REQUIRE_FALSE(r.atRest());
    REQUIRE(r.setBodyMode(head, bullet::BodyMode::Keyframed));
    const figure::Transform start = r.bodyState(head).pose;
    // A circle of 5 cm at 0.3 Hz: 0.09 m/s, and never 0.1 m from where it was a second before, both well inside the
    // figure's rest rules (0.5 m/s, 0.25 m in 1 s).
    const auto circling = [&](int s) {
        const double phase = 2 * kPi * 0.3 * s * kDt;
        return withPose(r.bodyStates(), head,
                        moved(start, {0.05 * (std::cos(phase) - 1), 0.05 * std::sin(phase), 0}, 0));
    };
    CHECK(stepsToRest(scene, r, Targets(circling), 1, 600) == -1);
    CHECK(metresApart(r.bodyState(head).pose, circling(600)[static_cast<std::size_t>(head)].pose) < kLandM);
    // Held still, the figure rests; a target away from it wakes it again.
    const figure::Transform held = r.bodyState(head).pose;
    const Targets still = [&](int) { return withPose(r.bodyStates(), head, held); };
    CHECK(stepsToRest(scene, r, still, 0, 360) >= 0);
    CHECK(r.frozen());
    const figure::Transform away = moved(held, {0, 0, 0.05}, 0);
    REQUIRE(r.setKeyframeTargets(withPose(r.bodyStates(), head, away)));
    scene.step(kDt);
    CHECK_FALSE(r.atRest());
    CHECK(metresApart(r.bodyState(head).pose, away) < kLandM);
}

TEST_CASE("keyframed: legs keyframed on a walk, the upper body powered at 30 % and its left arm limp",
          "[bullet][keyframed][motors]") {
    const auto loaded = test::loadEntity("humanoid");
    const figure::Figure& f = loaded.figure;
    const auto asset = bullet::RagdollAsset::create(f);
    text::Diagnostics diags;
    const auto walk = decl::loadMd5Anim(test::sourceDir() / "models/md5/humanoid/walk.md5anim", diags);
    INFO(diags.str());
    REQUIRE(walk);
    const auto frame = [&](double t) {
        auto states = figure::bodyStatesFromAnimation(f, *walk, t, figure::Transform{}, diags);
        REQUIRE(states);
        return std::move(*states);
    };
    const std::vector<std::string> legs{"pelvis", "l_thigh", "l_shin", "l_foot", "r_thigh", "r_shin", "r_foot"};
    const std::vector<std::string> watched{"waist", "l_shoulder", "l_elbow", "r_shoulder", "r_elbow"};
    struct Run {
        double legsOffM = 0, worstAnchorM = 0;
        std::vector<double> meanErrorRad; // per watched joint, over the second second: off the walk's rotation
    };
    // Two seconds of the walk on the ground: legs keyframed, the rest driven toward the walk at `strength`.
    const auto run = [&](double strength, bool limpLeftArm) {
        sim::Scene scene(*bullet::methodPreset("default"));
        bullet::Ragdoll& r = scene.spawn(asset, at(0));
        REQUIRE(r.setBodyStates(frame(0)));
        for (const std::string& leg : legs) REQUIRE(r.setBodyMode(bodyNamed(f, leg), bullet::BodyMode::Keyframed));
        bullet::MotorProfile profile;
        profile.all = {6, 1};
        if (limpLeftArm) profile.joints = {{"l_shoulder", {0, 1}}, {"l_elbow", {0, 1}}};
        REQUIRE(r.setMotorGains(profile));
        REQUIRE(r.setMotorStrength(strength));
        Run out;
        out.meanErrorRad.assign(watched.size(), 0);
        for (int s = 1; s <= 120; ++s) {
            const std::vector<figure::BodyState> targets = frame(s * kDt);
            REQUIRE(r.setKeyframeTargets(targets));
            REQUIRE(r.driveToPose(targets));
            scene.step(kDt);
            for (const std::string& leg : legs) {
                const auto i = static_cast<std::size_t>(bodyNamed(f, leg));
                out.legsOffM =
                    std::max(out.legsOffM, metresApart(r.bodyState(static_cast<int>(i)).pose, targets[i].pose));
            }
            if (s > 30) out.worstAnchorM = std::max(out.worstAnchorM, worstAnchorM(r));
            if (s <= 60) continue;
            for (std::size_t w = 0; w < watched.size(); ++w)
                out.meanErrorRad[w] += jointOffRad(r, targets, watched[w]) / 60;
        }
        CHECK(r.guardTrips() == 0);
        return out;
    };
    // Measured (rad, mean over the second second): waist 0.006 powered against 0.37 limp; left elbow 0.40 limp
    // against 0.25 powered; right elbow 0.22 either way.
    const Run partial = run(0.3, true), limp = run(0, false), armed = run(0.3, false);
    enum { Waist, LeftShoulder, LeftElbow, RightShoulder, RightElbow };
    std::ostringstream errors;
    for (std::size_t w = 0; w < watched.size(); ++w)
        errors << watched[w] << " off the walk: " << partial.meanErrorRad[w] << " rad with the left arm limp, "
               << limp.meanErrorRad[w] << " all limp, " << armed.meanErrorRad[w] << " all powered\n";
    INFO(errors.str());
    for (const Run* each : {&partial, &limp, &armed}) {
        CHECK(each->legsOffM < kLandM);
        CHECK(each->worstAnchorM < 0.02);
    }
    // At 30 % the motors hold the spine on the walk; the limp arm's elbow hangs further off it than a powered
    // one's, and the right arm does not notice.
    CHECK(partial.meanErrorRad[Waist] < 0.1 * limp.meanErrorRad[Waist]);
    CHECK(partial.meanErrorRad[LeftElbow] > 1.3 * armed.meanErrorRad[LeftElbow]);
    CHECK(std::abs(partial.meanErrorRad[RightElbow] - armed.meanErrorRad[RightElbow]) < 0.02);
    CHECK(partial.meanErrorRad[RightElbow] < limp.meanErrorRad[RightElbow]);
}
