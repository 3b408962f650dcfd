// Blending physics and animation (docs/motors.md): shortest-arc slerp, the per-joint blend of two skeleton poses and
// its root rule, joint weights from body weights, and the linear fade of a weight. Expected values come from
// Eigen's angle-axis algebra and the poses' own definitions, not from the blend's output.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "EntityFixture.h"
#include "FigureFixture.h"
#include "PoseEqual.h"
#include "afb/figure/Placement.h"
#include "afb/pose/Blend.h"

namespace {

using afb::figure::Transform;
using afb::pose::SkeletonPose;

constexpr double kPi = 3.14159265358979323846;

double angleBetween(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
    return Eigen::AngleAxisd(a.transpose() * b).angle();
}

Eigen::Matrix3d turn(double angle, const Eigen::Vector3d& axis) {
    return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}

using afb::test::bitEqual;

afb::decl::Md5Anim loadWalk() {
    afb::text::Diagnostics diags;
    auto anim = afb::decl::loadMd5Anim(afb::test::sourceDir() / "models/md5/humanoid/walk.md5anim", diags);
    INFO(diags.str());
    REQUIRE(anim);
    return std::move(*anim);
}

// Two different poses of the humanoid, far apart: the walk 0.5 s in, standing at one place, and the skeleton driven
// by bodies placed from the walk 0.2 s in under an entity lying on its back elsewhere.
struct TwoPoses {
    afb::figure::LoadedFigure loaded = afb::test::loadEntity("humanoid");
    const afb::figure::Figure& f = loaded.figure;
    SkeletonPose animated, simulated;

    TwoPoses() {
        const afb::decl::Md5Anim walk = loadWalk();
        afb::text::Diagnostics diags;
        const auto anim =
            afb::pose::animatedPose(f, walk, 0.5, {turn(0.3, Eigen::Vector3d::UnitZ()), {1, 2, 0}}, diags);
        const auto joints = afb::figure::jointsFromAnimation(f, walk, 0.2, diags);
        INFO(diags.str());
        REQUIRE(anim);
        REQUIRE(joints);
        animated = *anim;
        const Transform lying{turn(-kPi / 2, Eigen::Vector3d::UnitY()) * turn(1.1, Eigen::Vector3d::UnitZ()),
                              {-0.5, 0.7, 0.15}};
        simulated = afb::pose::driveSkeleton(f, afb::figure::bodiesFromJoints(f, lying, *joints));
    }
};

} // namespace

TEST_CASE("slerpShortest: half of a known turn is the half-angle turn, whatever the quaternion's sign",
          "[pose][blend]") {
    const Eigen::Vector3d axis = Eigen::Vector3d(0.3, -0.8, 0.5).normalized();
    const Eigen::Quaterniond a(Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()));
    const Eigen::Quaterniond b = a * Eigen::Quaterniond(Eigen::AngleAxisd(1.8, axis));
    Eigen::Quaterniond minusB = b;
    minusB.coeffs() = -b.coeffs();
    for (const double t : {0.5, 0.25, 0.9}) {
        INFO("t = " << t);
        const Eigen::Matrix3d expected = (a * Eigen::Quaterniond(Eigen::AngleAxisd(t * 1.8, axis))).toRotationMatrix();
        CHECK(angleBetween(afb::pose::slerpShortest(a, b, t).toRotationMatrix(), expected) < 1e-12);
        CHECK(angleBetween(afb::pose::slerpShortest(a, minusB, t).toRotationMatrix(), expected) < 1e-12);
    }
}

TEST_CASE("interpolate takes the shorter arc across ±180° and is exact at its ends", "[pose][blend]") {
    // 170° and −170° about Z are 20° apart the short way, through 180°; the long way passes through 0°.
    const Transform a{turn(170.0 * kPi / 180, Eigen::Vector3d::UnitZ()), {1, 0, 0}};
    const Transform b{turn(-170.0 * kPi / 180, Eigen::Vector3d::UnitZ()), {3, -2, 4}};
    const Transform half = afb::pose::interpolate(a, b, 0.5);
    CHECK(angleBetween(half.rotation, turn(kPi, Eigen::Vector3d::UnitZ())) < 1e-12);
    CHECK((half.position - Eigen::Vector3d(2, -1, 2)).norm() < 1e-15);
    const Transform quarter = afb::pose::interpolate(a, b, 0.25);
    CHECK(angleBetween(quarter.rotation, turn(175.0 * kPi / 180, Eigen::Vector3d::UnitZ())) < 1e-12);
    CHECK(bitEqual(afb::pose::interpolate(a, b, 0.0), a));
    CHECK(bitEqual(afb::pose::interpolate(a, b, 1.0), b));
}

TEST_CASE("blendPoses: weight 0 is the animated pose and weight 1 the simulated pose, bit for bit", "[pose][blend]") {
    const TwoPoses p;
    const std::size_t n = p.animated.model.size();
    CHECK(bitEqual(afb::pose::blendPoses(p.f, p.animated, p.simulated, std::vector<double>(n, 0.0)), p.animated));
    CHECK(bitEqual(afb::pose::blendPoses(p.f, p.animated, p.simulated, std::vector<double>(n, 1.0)), p.simulated));
    // Out-of-range weights clamp to the ends.
    CHECK(bitEqual(afb::pose::blendPoses(p.f, p.animated, p.simulated, std::vector<double>(n, -3.0)), p.animated));
    CHECK(bitEqual(afb::pose::blendPoses(p.f, p.animated, p.simulated, std::vector<double>(n, 7.0)), p.simulated));
    // The poses differ: the test above compares something.
    CHECK(!bitEqual(p.animated, p.simulated));
}

TEST_CASE("blendPoses: weight 0.5 turns every joint halfway locally and moves the pelvis halfway in the world",
          "[pose][blend]") {
    const TwoPoses p;
    const std::size_t n = p.animated.model.size();
    const SkeletonPose half = afb::pose::blendPoses(p.f, p.animated, p.simulated, std::vector<double>(n, 0.5));
    REQUIRE(half.local.size() == n);
    const std::vector<int>& parents = p.f.skeleton.parents();
    for (std::size_t j = 0; j < n; ++j) {
        INFO("joint " << p.f.skeleton.name(static_cast<int>(j)));
        const Transform& a = p.animated.local[j];
        const Transform& s = p.simulated.local[j];
        const Eigen::AngleAxisd between(a.rotation.transpose() * s.rotation); // angle in [0, π]
        const Eigen::Matrix3d expected = a.rotation * turn(between.angle() / 2, between.axis());
        CHECK(angleBetween(half.local[j].rotation, expected) < 1e-9);
        CHECK((half.local[j].position - (a.position + s.position) / 2).norm() < 1e-12);
        // The model-space joints are the blended locals concatenated down the hierarchy.
        const Transform fk =
            parents[j] >= 0 ? half.model[static_cast<std::size_t>(parents[j])] * half.local[j] : half.local[j];
        CHECK((half.model[j].position - fk.position).norm() < 1e-12);
        CHECK(angleBetween(half.model[j].rotation, fk.rotation) < 1e-12);
    }
    // The root rule: the pelvis (body 0's joint) lies on the straight line between its two world places, turned
    // halfway between its two world orientations.
    const std::size_t r = static_cast<std::size_t>(afb::pose::blendAnchorJoint(p.f));
    CHECK(r == static_cast<std::size_t>(*p.f.skeleton.findJoint("pelvis")));
    const Transform pa = p.animated.entity * p.animated.model[r];
    const Transform ps = p.simulated.entity * p.simulated.model[r];
    const Transform ph = half.entity * half.model[r];
    CHECK((ph.position - (pa.position + ps.position) / 2).norm() < 1e-12);
    const Eigen::AngleAxisd worldTurn(pa.rotation.transpose() * ps.rotation);
    CHECK(angleBetween(ph.rotation, pa.rotation * turn(worldTurn.angle() / 2, worldTurn.axis())) < 1e-9);
    CHECK(worldTurn.angle() > 1.0); // the two pelvises are far apart in orientation: a real test of the rule
}

TEST_CASE("jointWeightsFromBodies: each body's weight reaches exactly the joints it contains", "[pose][blend]") {
    const TwoPoses p;
    const std::size_t bodies = p.f.bodies.size();
    std::vector<double> bodyWeights(bodies);
    for (std::size_t b = 0; b < bodies; ++b) bodyWeights[b] = static_cast<double>(b + 1) / static_cast<double>(bodies);
    const std::vector<double> w = afb::pose::jointWeightsFromBodies(p.f, bodyWeights);
    REQUIRE(w.size() == p.animated.model.size());
    std::vector<int> seen(w.size(), 0);
    for (std::size_t b = 0; b < bodies; ++b)
        for (const int j : p.f.bodies[b].containedJoints) {
            INFO("body " << p.f.bodies[b].name << ", joint " << p.f.skeleton.name(j));
            CHECK(w[static_cast<std::size_t>(j)] == bodyWeights[b]);
            ++seen[static_cast<std::size_t>(j)];
        }
    for (std::size_t j = 0; j < w.size(); ++j) CHECK(seen[j] == 1); // the humanoid's bodies contain every joint

    // One body physical, the rest animated: that body's joints take the simulated local transforms, every other
    // joint the animated ones, bit for bit.
    const std::size_t arm = 3;
    REQUIRE(p.f.bodies[arm].name == "l_upperarm");
    std::vector<double> oneArm(bodies, 0.0);
    oneArm[arm] = 1.0;
    const SkeletonPose blend =
        afb::pose::blendPoses(p.f, p.animated, p.simulated, afb::pose::jointWeightsFromBodies(p.f, oneArm));
    const std::vector<int>& mine = p.f.bodies[arm].containedJoints;
    REQUIRE(!mine.empty());
    for (std::size_t j = 0; j < w.size(); ++j) {
        INFO("joint " << p.f.skeleton.name(static_cast<int>(j)));
        const bool inArm = std::find(mine.begin(), mine.end(), static_cast<int>(j)) != mine.end();
        CHECK(bitEqual(blend.local[j], inArm ? p.simulated.local[j] : p.animated.local[j]));
    }
}

TEST_CASE("jointWeightsFromBodies: a joint no body contains moves with its parent, an uncontained root with body 0",
          "[pose][blend]") {
    // origin → top → arm → tip: "top" contains top only, "arm" contains arm only; origin and tip are nobody's.
    const std::vector<afb::test::TestJoint> joints = {{"origin", -1, 0, 0, 0},
                                                      {"top", 0, 0, 0, 104},
                                                      {"arm", 1, 0, 0, 100},
                                                      {"tip", 2, 20, 0, 100}};
    const afb::test::BuiltFigure built = afb::test::buildTestFigure(
        "articulatedFigure t {\n settings { selfCollision 0 }\n"
        " body \"top\" { joint \"origin\" model box( ( -4, -4, -4 ), ( 4, 4, 4 ) ) origin ( 0, 0, 104 ) density 0.1 "
        "containedJoints \"top\" }\n"
        " body \"arm\" { joint \"arm\" model box( ( 0, -1, -1 ), ( 20, 1, 1 ) ) origin ( 0, 0, 100 ) density 0.2 "
        "containedJoints \"arm\" }\n"
        " ballAndSocketJoint \"shoulder\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) }\n}\n",
        joints);
    INFO(built.diagnostics.str());
    REQUIRE(built.figure);
    REQUIRE(built.figure->jointBody == std::vector<int>{-1, 0, 1, -1});
    const std::vector<double> w = afb::pose::jointWeightsFromBodies(*built.figure, std::vector<double>{0.25, 0.75});
    CHECK(w == std::vector<double>{0.25, 0.25, 0.75, 0.75});
    CHECK_THROWS_AS(afb::pose::jointWeightsFromBodies(*built.figure, std::vector<double>{0.5}), std::invalid_argument);
}

TEST_CASE("blendPoses refuses weights and poses of the wrong size and weights that are not numbers", "[pose][blend]") {
    const TwoPoses p;
    const std::size_t n = p.animated.model.size();
    CHECK_THROWS_AS(afb::pose::blendPoses(p.f, p.animated, p.simulated, std::vector<double>(n - 1, 0.5)),
                    std::invalid_argument);
    std::vector<double> nan(n, 0.5);
    nan[4] = std::numeric_limits<double>::quiet_NaN();
    CHECK_THROWS_AS(afb::pose::blendPoses(p.f, p.animated, p.simulated, nan), std::invalid_argument);
    SkeletonPose shorter = p.simulated;
    shorter.local.pop_back();
    CHECK_THROWS_AS(afb::pose::blendPoses(p.f, p.animated, shorter, std::vector<double>(n, 0.5)),
                    std::invalid_argument);
}

TEST_CASE("BlendFade ramps linearly, holds its ends and turns back without a jump", "[pose][blend]") {
    afb::pose::BlendFade in(0.0, 1.0, 0.2); // physics faded in over 0.2 s
    CHECK(in.weight() == 0.0);
    CHECK(in.weightAt(-1.0) == 0.0);
    CHECK(in.weightAt(0.05) == Approx(0.25).margin(1e-15));
    CHECK(in.weightAt(0.15) == Approx(0.75).margin(1e-15));
    CHECK(in.weightAt(0.2) == 1.0);
    CHECK(in.weightAt(5.0) == 1.0);
    // 60 Hz: step k is at k/12 of the way; one step past the end it holds 1 exactly.
    for (int k = 1; k <= 11; ++k) CHECK(in.advance(1.0 / 60) == Approx(k / 12.0).margin(1e-12));
    CHECK(!in.finished());
    (void)in.advance(1.0 / 60);
    CHECK(in.advance(1.0 / 60) == 1.0);
    CHECK(in.finished());

    // Faded out halfway, then reversed: it turns back from where it is.
    in.fadeTo(0.0, 0.4);
    CHECK(in.advance(0.2) == Approx(0.5).margin(1e-15));
    in.fadeTo(1.0, 1.0);
    CHECK(in.weight() == 0.5);
    CHECK(in.advance(0.5) == Approx(0.75).margin(1e-15));

    // Weights clamp to [0, 1]; a zero time jumps; held fades stay put.
    const afb::pose::BlendFade wide(-1.0, 2.0, 1.0);
    CHECK(wide.weightAt(0.0) == 0.0);
    CHECK(wide.weightAt(0.5) == 0.5);
    CHECK(wide.weightAt(1.0) == 1.0);
    afb::pose::BlendFade cut(0.0, 1.0, 0.0);
    CHECK(cut.weight() == 1.0);
    afb::pose::BlendFade held(0.3);
    CHECK(held.advance(10.0) == 0.3);
    CHECK_THROWS_AS(afb::pose::BlendFade(std::numeric_limits<double>::quiet_NaN()), std::invalid_argument);
    CHECK_THROWS_AS(held.advance(-0.1), std::invalid_argument);
}
