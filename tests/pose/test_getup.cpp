// Getting up (docs/motors.md): which side a lying humanoid faces, where a get-up frame is placed, and the blend from
// the ragdoll's snapshot to that frame. The lying poses are the bundled humanoid's load pose turned by hand, or the
// humanoid dropped in a scene and left to rest (fixed 60 Hz step); the get-up frames are its load pose turned onto
// its back or front with the left thigh drawn up.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "EntityFixture.h"
#include "PoseEqual.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/figure/Placement.h"
#include "afb/pose/Blend.h"
#include "afb/pose/GetUp.h"
#include "afb/sim/Scene.h"

namespace {

using afb::figure::Figure;
using afb::figure::Transform;
using afb::pose::LyingSide;
using afb::pose::SkeletonPose;

constexpr double kPi = 3.14159265358979323846;

Eigen::Matrix3d turn(double angle, const Eigen::Vector3d& axis) {
    return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}

// Model Y is the figure's left: a turn of −90° about it lays the figure on its back (forward +X turns to +Z), +90°
// on its front (docs/format.md §0).
const Eigen::Matrix3d kOnBack = turn(-kPi / 2, Eigen::Vector3d::UnitY());
const Eigen::Matrix3d kOnFront = turn(kPi / 2, Eigen::Vector3d::UnitY());

double angleBetween(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
    return Eigen::AngleAxisd(a.transpose() * b).angle();
}

using afb::test::bitEqual;

std::size_t jointOf(const Figure& f, const char* name) {
    const auto j = f.skeleton.findJoint(name);
    REQUIRE(j);
    return static_cast<std::size_t>(*j);
}

// A get-up frame made by hand (model space, metres): the load pose turned by `lie` with the pelvis put at (0, 0,
// pelvisHeight), joint 0 left on the model offset as an actor's animation leaves it, and the left thigh drawn up 40°
// about the hip.
std::vector<Transform> lyingFrame(const Figure& f, const Eigen::Matrix3d& lie, double pelvisHeight) {
    std::vector<Transform> joints = afb::figure::jointsInMetres(f);
    const std::size_t pelvis = jointOf(f, "pelvis");
    const Transform place{lie, Eigen::Vector3d(0, 0, pelvisHeight) - lie * joints[pelvis].position};
    for (std::size_t j = 1; j < joints.size(); ++j) joints[j] = place * joints[j];
    const int thigh = static_cast<int>(jointOf(f, "l_thigh"));
    const Eigen::Vector3d hip = joints[static_cast<std::size_t>(thigh)].position;
    const Transform draw{turn(-0.7, lie * Eigen::Vector3d::UnitY()), Eigen::Vector3d::Zero()};
    const Transform aboutHip =
        Transform{Eigen::Matrix3d::Identity(), hip} * draw * Transform{Eigen::Matrix3d::Identity(), -hip};
    for (const int j : f.skeleton.jointAndDescendants(thigh))
        joints[static_cast<std::size_t>(j)] = aboutHip * joints[static_cast<std::size_t>(j)];
    return joints;
}

// The ragdoll lying rigidly in its load pose under `entity`: the skeleton driven by its bodies placed there.
SkeletonPose lyingSnapshot(const Figure& f, const Transform& entity) {
    return afb::pose::driveSkeleton(f, afb::figure::bodiesFromJoints(f, entity, afb::figure::jointsInMetres(f)));
}

// The humanoid spawned lying (`lie`) 0.3 m above the ground, turned `heading` about Z, stepped at 60 Hz until its
// rest rules put it to rest: its driven skeleton.
SkeletonPose restedSnapshot(const afb::figure::LoadedFigure& loaded, const Eigen::Matrix3d& lie, double heading) {
    const auto asset = afb::bullet::RagdollAsset::create(loaded.figure);
    afb::sim::Scene scene(afb::bullet::Method{});
    afb::bullet::SpawnOptions o;
    const Eigen::Quaterniond q(turn(heading, Eigen::Vector3d::UnitZ()) * lie);
    o.entityTransform = btTransform(btQuaternion(btScalar(q.x()), btScalar(q.y()), btScalar(q.z()), btScalar(q.w())),
                                    btVector3(1, -2, btScalar(0.3)));
    afb::bullet::Ragdoll& r = scene.spawn(asset, o);
    int steps = 0;
    while (!r.atRest() && steps < 60 * 10) {
        scene.step(1.0 / 60);
        ++steps;
    }
    REQUIRE(r.atRest());
    return afb::pose::driveSkeleton(loaded.figure, r.bodyTransforms());
}

} // namespace

TEST_CASE("lyingSide: on its back is face-up and on its front face-down, at any heading", "[pose][getup]") {
    const auto loaded = afb::test::loadEntity("humanoid");
    const Figure& f = loaded.figure;
    for (const double heading : {0.0, 1.0, 2.5, -2.0}) {
        for (const double roll : {0.0, 0.6, -0.6}) { // rolled partly onto a side, about the body's long axis
            INFO("heading " << heading << ", roll " << roll);
            const Eigen::Matrix3d rz = turn(heading, Eigen::Vector3d::UnitZ());
            const Eigen::Matrix3d rolled = turn(roll, Eigen::Vector3d::UnitZ());
            const Eigen::Vector3d at(0.5, -1, 0.12);
            CHECK(afb::pose::lyingSide(f, lyingSnapshot(f, {rz * kOnBack * rolled, at})) == LyingSide::FaceUp);
            CHECK(afb::pose::lyingSide(f, lyingSnapshot(f, {rz * kOnFront * rolled, at})) == LyingSide::FaceDown);
        }
    }
}

TEST_CASE("lyingSide: the humanoid dropped on its back lies face-up, on its front face-down", "[pose][getup]") {
    const auto loaded = afb::test::loadEntity("humanoid");
    const Figure& f = loaded.figure;
    const SkeletonPose back = restedSnapshot(loaded, kOnBack, 0.8);
    const SkeletonPose front = restedSnapshot(loaded, kOnFront, -1.9);
    CHECK(afb::pose::lyingSide(f, back) == LyingSide::FaceUp);
    CHECK(afb::pose::lyingSide(f, front) == LyingSide::FaceDown);

    // planGetUp takes the frame of that side.
    const std::vector<Transform> up = lyingFrame(f, kOnBack, 0.1), down = lyingFrame(f, kOnFront, 0.1);
    const afb::pose::GetUp fromBack = afb::pose::planGetUp(f, back, up, down);
    const afb::pose::GetUp fromFront = afb::pose::planGetUp(f, front, up, down);
    CHECK(fromBack.side == LyingSide::FaceUp);
    CHECK(fromFront.side == LyingSide::FaceDown);
    for (std::size_t j = 0; j < up.size(); ++j) {
        CHECK(bitEqual(fromBack.to.model[j], up[j]));
        CHECK(bitEqual(fromFront.to.model[j], down[j]));
    }
}

TEST_CASE("alignGetUp: the frame's pelvis lands on the ragdoll's, turned about world up by the ragdoll's heading",
          "[pose][getup]") {
    const auto loaded = afb::test::loadEntity("humanoid");
    const Figure& f = loaded.figure;
    const std::size_t pelvis = jointOf(f, "pelvis");
    const double h = 0.1; // the frame's pelvis height, metres
    const Eigen::Vector3d loadPelvis = afb::figure::jointsInMetres(f)[pelvis].position;
    for (const bool onBack : {true, false}) {
        for (const double heading : {0.0, 0.7, -2.9}) {
            INFO((onBack ? "on its back" : "on its front") << ", heading " << heading);
            const Eigen::Matrix3d lie = onBack ? kOnBack : kOnFront;
            const Eigen::Matrix3d rz = turn(heading, Eigen::Vector3d::UnitZ());
            const Transform entity{rz * lie, {2, -1, 0.13}};
            const SkeletonPose snapshot = lyingSnapshot(f, entity);
            const std::vector<Transform> frame = lyingFrame(f, lie, h);

            // The ragdoll lies as the frame does, turned by `heading`: the alignment is that turn, and it carries
            // the frame's pelvis (0, 0, h) onto the ragdoll's, entity ∘ load-pose pelvis.
            const Eigen::Vector3d ragdollPelvis = entity.rotation * loadPelvis + entity.position;
            const Transform a = afb::pose::alignGetUp(f, snapshot, frame);
            CHECK(angleBetween(a.rotation, rz) < 1e-9);
            CHECK((a.position - (ragdollPelvis - rz * Eigen::Vector3d(0, 0, h))).norm() < 1e-9);
            CHECK((a.rotation * Eigen::Vector3d::UnitZ() - Eigen::Vector3d::UnitZ()).norm() < 1e-12);

            // With the floor's height given, the frame's model origin stands on it, still under the pelvis.
            const Transform onFloor = afb::pose::alignGetUp(f, snapshot, frame, {.groundHeightM = -0.25});
            CHECK(onFloor.position.z() == -0.25);
            CHECK((onFloor.position.head<2>() - a.position.head<2>()).norm() < 1e-12);
            CHECK(angleBetween(onFloor.rotation, rz) < 1e-9);
        }
    }
}

TEST_CASE("getUpPose: the snapshot at the start, the placed frame at the end, bit for bit", "[pose][getup]") {
    const auto loaded = afb::test::loadEntity("humanoid");
    const Figure& f = loaded.figure;
    const SkeletonPose snapshot = restedSnapshot(loaded, kOnBack, 0.8);
    const std::vector<Transform> up = lyingFrame(f, kOnBack, 0.1), down = lyingFrame(f, kOnFront, 0.1);
    const afb::pose::GetUp plan = afb::pose::planGetUp(f, snapshot, up, down, {.blendSeconds = 0.75});
    CHECK(bitEqual(afb::pose::getUpPose(plan, 0.0), snapshot));
    CHECK(bitEqual(afb::pose::getUpPose(plan, -1.0), snapshot));
    const SkeletonPose end = afb::pose::getUpPose(plan, 0.75);
    CHECK(bitEqual(end, afb::pose::poseFromJoints(f, plan.alignment, up)));
    CHECK(bitEqual(afb::pose::getUpPose(plan, 3.0), end));

    // The end pose is the frame under the alignment, with its pelvis where the ragdoll's lies.
    const std::vector<Transform> world = end.world();
    for (std::size_t j = 0; j < up.size(); ++j) {
        const Transform expected = plan.alignment * up[j];
        CHECK((world[j].position - expected.position).norm() < 1e-12);
        CHECK(angleBetween(world[j].rotation, expected.rotation) < 1e-12);
    }
    const std::size_t pelvis = jointOf(f, "pelvis");
    CHECK((world[pelvis].position - (snapshot.entity * snapshot.model[pelvis]).position).norm() < 1e-9);
}

TEST_CASE("getUpPose: no joint jumps between 60 Hz frames of the blend", "[pose][getup]") {
    const auto loaded = afb::test::loadEntity("humanoid");
    const Figure& f = loaded.figure;
    const SkeletonPose snapshot = restedSnapshot(loaded, kOnBack, 0.8);
    const std::vector<Transform> up = lyingFrame(f, kOnBack, 0.1), down = lyingFrame(f, kOnFront, 0.1);
    const double seconds = 1.0;
    const afb::pose::GetUp plan = afb::pose::planGetUp(f, snapshot, up, down, {.blendSeconds = seconds});

    // A cut from the snapshot to the frame would pop: some joint turns by more than 30°.
    const std::vector<Transform> from = snapshot.world(), to = plan.to.world();
    double cut = 0;
    for (std::size_t j = 0; j < from.size(); ++j) cut = std::max(cut, angleBetween(from[j].rotation, to[j].rotation));
    CHECK(cut > 30 * kPi / 180);

    // The bound, from the blend's definition: the weight s = x²(3 − 2x) moves at most 1.5/T per second, so by at
    // most 1.5/60 per 60 Hz frame at T = 1 s; every factor of a joint's world rotation (the pelvis's world rotation
    // and the local rotations between the pelvis and the joint) turns at a constant rate in s, through its angle
    // between the two poses, so a frame turns the joint by at most 1.5/60 times the sum of those angles.
    const std::size_t r = static_cast<std::size_t>(plan.anchorJoint);
    const double anchorAngle = angleBetween(from[r].rotation, to[r].rotation);
    const std::vector<int>& parents = f.skeleton.parents();
    std::vector<double> bound(from.size());
    for (std::size_t j = 0; j < from.size(); ++j) {
        double sum = anchorAngle;
        // Walk from the deeper of j and the anchor up to the other one (the humanoid's joints are the pelvis's
        // descendants but for joint 0, its parent).
        std::size_t k = j > r ? j : r;
        const std::size_t stop = j > r ? r : j;
        while (k != stop) {
            sum += angleBetween(snapshot.local[k].rotation, plan.to.local[k].rotation);
            REQUIRE(parents[k] >= 0);
            k = static_cast<std::size_t>(parents[k]);
        }
        bound[j] = 1.5 / 60 / seconds * sum + 1e-9;
    }
    double worstTurn = 0, worstMove = 0;
    std::vector<Transform> before = from;
    for (int frame = 1; frame <= 60; ++frame) {
        const std::vector<Transform> now = afb::pose::getUpPose(plan, frame / 60.0).world();
        for (std::size_t j = 0; j < now.size(); ++j) {
            const double turned = angleBetween(before[j].rotation, now[j].rotation);
            CHECK(turned <= bound[j]);
            worstTurn = std::max(worstTurn, turned);
            worstMove = std::max(worstMove, (before[j].position - now[j].position).norm());
        }
        before = now;
    }
    // The stated limits: no joint turns more than 6° or moves more than 4 cm from one 60 Hz frame to the next. The
    // farthest mover is joint 0, the model origin about a metre from the pelvis, swung through the quarter turn
    // between the lying ragdoll's entity and the upright frame's: at most 1.5/60 · π/2 · 1 m ≈ 3.9 cm a frame.
    CAPTURE(worstTurn * 180 / kPi, worstMove);
    CHECK(worstTurn < 6 * kPi / 180);
    CHECK(worstMove < 0.04);
}

TEST_CASE("planGetUp refuses frames of the wrong size and a blend time that is not positive", "[pose][getup]") {
    const auto loaded = afb::test::loadEntity("humanoid");
    const Figure& f = loaded.figure;
    const SkeletonPose snapshot = lyingSnapshot(f, {kOnBack, {0, 0, 0.12}});
    const std::vector<Transform> up = lyingFrame(f, kOnBack, 0.1);
    std::vector<Transform> shorter = up;
    shorter.pop_back();
    CHECK_THROWS_AS(afb::pose::planGetUp(f, snapshot, shorter, up), std::invalid_argument);
    CHECK_THROWS_AS(afb::pose::planGetUp(f, snapshot, up, up, {.blendSeconds = 0}), std::invalid_argument);
    CHECK_THROWS_AS(afb::pose::planGetUp(f, snapshot, up, up, {.blendSeconds = -1}), std::invalid_argument);
}
