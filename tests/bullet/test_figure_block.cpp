// Block mode of the direct joint solve (Method::figureIterations, Method::figureSweeps): each iteration ends with
// the joints solved and the contact and limit rows that move whole ragdolls solved together.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "BitEqual.h"
#include "EntityFixture.h"
#include "FigureFixture.h"
#include "LyingHumanoid.h"
#include "MotorPoses.h"
#include "afb/bullet/Method.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/bullet/RagdollSolver.h"
#include "afb/sim/Scene.h"

namespace {

using afb::bullet::Method;
using afb::bullet::Ragdoll;
using afb::bullet::RagdollAsset;
constexpr double kDeg = 3.14159265358979323846 / 180.0;

// The plate under the block, its fixed joint kept as a joint (the test does not merge it).
afb::figure::Figure plateAndBlock() {
    const auto built = afb::test::buildPlateUnderBlockFigure();
    INFO(built.diagnostics.str());
    REQUIRE(built.figure);
    return *built.figure;
}

} // namespace

TEST_CASE("figure block: the knobs have their names, ranges and preset values", "[bullet][methods]") {
    const auto* iterations = afb::bullet::findKnob("figure-iterations");
    const auto* sweeps = afb::bullet::findKnob("figure-sweeps");
    REQUIRE(iterations != nullptr);
    REQUIRE(sweeps != nullptr);
    Method m = *afb::bullet::methodPreset("default");
    CHECK(afb::bullet::setKnob(m, *iterations, "4").empty());
    CHECK(m.figureIterations == 4);
    CHECK_FALSE(afb::bullet::setKnob(m, *sweeps, "0").empty()); // at least one sweep
    CHECK(afb::bullet::iterativeJoints(m).figureIterations == 0);
    for (const std::string_view name : afb::bullet::methodPresetNames())
        CHECK(afb::bullet::methodPreset(name)->figureIterations == (name == "balanced" ? 3 : name == "fast" ? 2 : 0));
}

TEST_CASE("figure block: a plate landing on four corners under a heavy block stops in one iteration",
          "[bullet][methods]") {
    // The four corner contacts of the plate all carry the pair's 50 kg, dropped at 6 m/s: solved one after the
    // other in a single pass, each sees the later ones' impulses only on the next iteration, and the pair keeps
    // sinking at millimetres per second. In block mode one iteration sweeps the four together until they share
    // the load: the pair stops at the ground in the step it lands, as a rigid body of the pair's mass would.
    const afb::figure::Figure figure = plateAndBlock();
    auto sinkAfterLanding = [&](int figureIterations) {
        Method m = *afb::bullet::methodPreset("default");
        m.iterations = m.jointIterations = 1;
        m.figureIterations = figureIterations;
        m.figureSweeps = 20;
        m.mergeFixed = false;
        m.positionIterations = 0;
        m.positionTree = 0;
        m.ccd = afb::bullet::CcdPolicy::Off;
        afb::sim::Scene scene(m, {.gravityMps2 = 9.81});
        Ragdoll& r = scene.spawn(RagdollAsset::create(figure), {.comeToRest = false});
        for (int i = 0; i < r.bodyCount(); ++i) r.body(i).setLinearVelocity(btVector3(0, 0, -6));
        double fastest = 0; // the largest downward speed of the block after the plate first touched
        bool touched = false;
        for (int i = 0; i < 20; ++i) {
            scene.step(1.0 / 60.0);
            touched = touched || r.bodyState(0).linearVelocity.z() > -5.5;
            if (touched && i > 0) fastest = std::max(fastest, -r.bodyState(1).linearVelocity.z());
        }
        return fastest;
    };
    const double inTurn = sinkAfterLanding(0), block = sinkAfterLanding(1);
    INFO("block's downward speed after landing: rows in turn " << inTurn << " m/s, block " << block << " m/s");
    CHECK(block < 0.0005);
    CHECK(inTurn > 0.002);
}

TEST_CASE("figure block: each iteration ends with the joints held, so a humanoid lying still keeps its hinges",
          "[bullet][methods]") {
    // Without the position pass, what the velocity solve leaves at the joints shows as hinges whose axes part
    // while the figure lies still. Rows in turn end each iteration with the contact friction rows, which disturb
    // the joints (0.18° and more: the friction-through-the-figure test). Block mode solves the friction rows
    // first, then the joints, then the block, whose responses move the figure as its joints let it.
    Method m = *afb::bullet::methodPreset("default");
    m.positionIterations = 0;
    m.positionTree = 0;
    m.figureIterations = 4;
    const double worst = afb::test::lyingHumanoidHingeAxesApart(m);
    INFO("hinge axes apart: " << worst / kDeg << " deg");
    CHECK(worst < 0.12 * kDeg);
}

namespace {

// A game's stack of four crates (1.2 × 1.2 × 0.3 m, 10 kg: its own bodies, in the ragdoll's island once touched)
// with a humanoid dropped onto it from 1 m above its top: the deepest crate-on-crate contact over the last two of
// four seconds and how far the top crate sank below where the stack stands.
struct StackOutcome {
    double deepestM = 0, sunkM = 0;
};
StackOutcome humanoidOnCrates(int figureIterations) {
    Method method = *afb::bullet::methodPreset("default");
    method.figureIterations = figureIterations;
    afb::sim::Scene scene(method);
    btBoxShape crate(btVector3(0.6f, 0.6f, 0.15f));
    btVector3 inertia;
    crate.calculateLocalInertia(10, inertia);
    std::vector<std::unique_ptr<btRigidBody>> crates;
    for (int i = 0; i < 4; ++i) {
        btRigidBody::btRigidBodyConstructionInfo info(10, nullptr, &crate, inertia);
        info.m_startWorldTransform.setOrigin(btVector3(0, 0, btScalar(0.15 + 0.3 * i)));
        info.m_friction = 0.8f;
        crates.push_back(std::make_unique<btRigidBody>(info));
        crates.back()->setActivationState(DISABLE_DEACTIVATION);
        scene.world().addRigidBody(crates.back().get());
    }
    const auto asset = RagdollAsset::create(afb::test::loadEntity("humanoid").figure);
    afb::bullet::SpawnOptions where;
    where.entityTransform = btTransform(btQuaternion::getIdentity(), btVector3(0, 0, 2.2f));
    where.comeToRest = false;
    scene.spawn(asset, where);
    StackOutcome out;
    btDispatcher& dispatcher = *scene.world().getDispatcher();
    for (int s = 0; s < 240; ++s) {
        scene.step(1.0 / 60);
        if (s < 120) continue;
        for (int m = 0; m < dispatcher.getNumManifolds(); ++m) {
            const btPersistentManifold* manifold = dispatcher.getManifoldByIndexInternal(m);
            const auto isCrate = [&](const btCollisionObject* o) {
                return std::any_of(crates.begin(), crates.end(), [o](const auto& c) { return c.get() == o; });
            };
            if (!isCrate(manifold->getBody0()) || !isCrate(manifold->getBody1())) continue;
            for (int p = 0; p < manifold->getNumContacts(); ++p)
                out.deepestM = std::max(out.deepestM, -double(manifold->getContactPoint(p).getDistance()));
        }
        out.sunkM = std::max(out.sunkM, 1.05 - double(crates.back()->getCenterOfMassPosition().z()));
    }
    for (auto& c : crates) scene.world().removeRigidBody(c.get());
    return out;
}

} // namespace

TEST_CASE("figure block: a game's crates under a humanoid keep the world's iterations", "[bullet][methods]") {
    // With two block iterations and nothing more, the crates ended 19 cm inside each other and the top one 23 cm
    // down; with the rows between the crates taking the world's 20 iterations, 1.2 mm and 1.6 mm.
    for (const int iterations : {2, 4}) {
        INFO("figure-iterations " << iterations);
        const StackOutcome o = humanoidOnCrates(iterations);
        INFO("deepest crate contact " << o.deepestM << " m, top crate sunk " << o.sunkM << " m");
        CHECK(o.deepestM < 0.005);
        CHECK(o.sunkM < 0.005);
    }
}

namespace {

// A weightless humanoid hit off its first body's centre, after `steps` steps: every body's transform, and with 4 Hz
// motors holding the load pose the worst angle of a motor joint from its target (rad; 0 when limp).
struct Hit {
    std::vector<btTransform> transforms;
    double worstMotorErrorRad = 0;
};

Hit hitHumanoid(int figureIterations, bool motors, int steps = 90) {
    Method method = *afb::bullet::methodPreset("default");
    method.figureIterations = figureIterations;
    afb::sim::SceneSettings weightless;
    weightless.gravityMps2 = 0;
    weightless.ground = false;
    afb::sim::Scene scene(method, weightless);
    afb::bullet::SpawnOptions where;
    where.entityTransform = btTransform(btQuaternion::getIdentity(), btVector3(0, 0, 2));
    where.comeToRest = false;
    Ragdoll& r = scene.spawn(RagdollAsset::create(afb::test::loadEntity("humanoid").figure), where);
    const std::vector<btQuaternion> target = afb::test::relativeRotations(r);
    if (motors) {
        REQUIRE(r.setMotorGains(afb::bullet::MotorGains{4, 1}));
        REQUIRE(r.driveToPose(r.bodyStates()));
    }
    const btVector3 at = r.rigidBody(0).getCenterOfMassPosition() + btVector3(0.3f, 0, 0.2f);
    REQUIRE(r.hit(0, btVector3(10, 4, 20), at, {1, 0.5}));
    for (int s = 0; s < steps; ++s) scene.step(1.0 / 60);
    Hit out;
    for (int b = 0; b < r.bodyCount(); ++b) out.transforms.push_back(r.collisionObject(b).getWorldTransform());
    if (motors) out.worstMotorErrorRad = afb::test::worstMotorError(r, target);
    return out;
}

bool sameTransforms(const std::vector<btTransform>& a, const std::vector<btTransform>& b) {
    return std::ranges::equal(a, b, afb::test::bitEqual);
}

} // namespace

TEST_CASE("figure block: a ragdoll with motors is solved in block mode and returns to its pose after a hit",
          "[bullet][motors]") {
    // The motors are soft rows: an unbounded one in the joint solve, a bounded one in the block. In block mode
    // (2 iterations) the 4 Hz motors hold the hit humanoid as row by row (20 iterations) does: measured 0.04° from
    // the target after 1.5 s in block mode and 0.00° row by row, 0.00° and 0.04° after 4 s.
    const Hit block = hitHumanoid(2, true), rows = hitHumanoid(0, true);
    CHECK_FALSE(sameTransforms(block.transforms, rows.transforms)); // block mode ran
    const Hit blockLater = hitHumanoid(2, true, 240), rowsLater = hitHumanoid(0, true, 240);
    INFO("after 1.5 s: block " << block.worstMotorErrorRad / kDeg << "°, row by row " << rows.worstMotorErrorRad / kDeg
                               << "°; after 4 s: " << blockLater.worstMotorErrorRad / kDeg << "°, "
                               << rowsLater.worstMotorErrorRad / kDeg << "°");
    for (const Hit* h : {&block, &rows, &blockLater, &rowsLater}) CHECK(h->worstMotorErrorRad < 0.5 * kDeg);
    // Limp, the same hit is solved in block mode too, which moves the bodies otherwise.
    CHECK_FALSE(sameTransforms(hitHumanoid(2, false).transforms, hitHumanoid(0, false).transforms));
}
