// Methods (bullet::Method): the knob table and presets, the fallback without a RagdollSolver, and the
// techniques of the solve beyond Bullet's defaults (self-contact cap, joint and limit warm starting, direct joints,
// friction through the figure, impact substeps), each on a case whose outcome is known. Deterministic: fixed 60 Hz
// step, fixed insertion order. The position pass and the contact techniques have files of their own.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "EntityFixture.h"
#include "FigureFixture.h"
#include "LyingHumanoid.h"
#include "MethodFixture.h"
#include "afb/bullet/Method.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/bullet/RagdollSolver.h"
#include "afb/bullet/RagdollWorld.h"
#include "afb/detail/Convert.h"
#include "afb/sim/Report.h"
#include "afb/sim/Scene.h"
#include "bullet/PositionPass.h"

using namespace afb::test::methods;

TEST_CASE("methods: presets, knobs and their text form", "[bullet][methods]") {
    for (std::string_view name : afb::bullet::methodPresetNames()) {
        const auto m = afb::bullet::methodPreset(name);
        REQUIRE(m);
        CHECK(m->name == name);
    }
    CHECK_FALSE(afb::bullet::methodPreset("fastest"));
    CHECK(*afb::bullet::methodPreset("default") == Method{});
    // "iterative": the default's knobs with Bullet's iterative joint solve (the previous default), and the bound on
    // self-contacts' warm start that solve needs.
    Method iterative = afb::bullet::iterativeJoints(Method{});
    iterative.name = "iterative";
    iterative.selfContactCap = 10;
    CHECK(*afb::bullet::methodPreset("iterative") == iterative);
    CHECK_FALSE(afb::bullet::methodPreset("iterative")->directJoints);

    Method m;
    const auto* substeps = afb::bullet::findKnob("substeps");
    REQUIRE(substeps);
    CHECK(afb::bullet::setKnob(m, *substeps, "4").empty());
    CHECK(m.substeps == 4);
    CHECK_FALSE(afb::bullet::setKnob(m, *substeps, "0").empty());   // out of range
    CHECK_FALSE(afb::bullet::setKnob(m, *substeps, "4.5").empty()); // not an integer
    CHECK(m.substeps == 4);                                         // unchanged on error
    const auto* erp = afb::bullet::findKnob("joint-erp");
    REQUIRE(erp);
    CHECK_FALSE(afb::bullet::setKnob(m, *erp, "nan").empty());
    CHECK(afb::bullet::setKnob(m, *erp, "0.5").empty());
    CHECK(m.jointErp == 0.5);
    const auto* split = afb::bullet::findKnob("split-impulse");
    REQUIRE(split);
    CHECK(afb::bullet::setKnob(m, *split, "off").empty());
    CHECK_FALSE(m.splitImpulse);
    CHECK_FALSE(afb::bullet::setKnob(m, *split, "maybe").empty());
    CHECK(afb::bullet::findKnob("no-such-knob") == nullptr);

    // Every knob appears in the description, and the JSON form reads back to the same value.
    const std::string text = afb::bullet::describe(m);
    for (const auto& k : afb::bullet::methodKnobs()) CHECK(text.find(std::string(k.name)) != std::string::npos);
    Method back;
    CHECK(afb::sim::methodFromJson(afb::sim::methodJson(m), back).empty());
    CHECK(back == m);
    for (std::string_view name : afb::bullet::methodPresetNames()) {
        const Method preset = *afb::bullet::methodPreset(name);
        CHECK(afb::sim::methodFromJson(afb::sim::methodJson(preset), back).empty());
        CHECK(back == preset);
    }
}

TEST_CASE("methods: without a RagdollSolver the default falls back to the iterative solve", "[bullet][methods]") {
    const Method def = *afb::bullet::methodPreset("default");
    REQUIRE(def.directJoints);
    btDefaultCollisionConfiguration config;
    btCollisionDispatcher dispatcher(&config);
    btDbvtBroadphase broadphase;
    SECTION("Bullet's own solver: the world runs the iterative default's world-level knobs") {
        btSequentialImpulseConstraintSolver solver;
        btDiscreteDynamicsWorld world(&dispatcher, &broadphase, &solver, &config);
        const afb::bullet::RagdollWorld ragdollWorld(world, def);
        CHECK_FALSE(ragdollWorld.method().directJoints);
        CHECK(ragdollWorld.method().positionTree == 0);
        CHECK(ragdollWorld.method().frictionDirections == 1);
        CHECK(ragdollWorld.method().positionIterations == def.positionIterations); // the rest as given
        CHECK(ragdollWorld.method().mergeFixed == def.mergeFixed);
        CHECK((world.getSolverInfo().m_solverMode & SOLVER_USE_2_FRICTION_DIRECTIONS) == 0);
    }
    SECTION("a RagdollSolver: the method as given") {
        afb::bullet::RagdollSolver solver;
        btDiscreteDynamicsWorld world(&dispatcher, &broadphase, &solver, &config);
        const afb::bullet::RagdollWorld ragdollWorld(world, def);
        CHECK(ragdollWorld.method() == def);
        CHECK(solver.directJoints());
    }
    CHECK(afb::bullet::methodInForce(def, true) == def);
    const Method iterative = *afb::bullet::methodPreset("iterative");
    CHECK(afb::bullet::methodInForce(iterative, false) == iterative); // nothing to fall back from
    const Method fast = *afb::bullet::methodPreset("fast");           // block mode of the direct solve: falls back too
    CHECK_FALSE(afb::bullet::methodInForce(fast, false).directJoints);
    CHECK(afb::bullet::methodInForce(fast, false).figureIterations == 0);
}

TEST_CASE("self-contact cap: a contact within one ragdoll starts from at most k times its pair's weight per step",
          "[bullet][methods]") {
    // RagdollWorld gives its RagdollSolver the bound of Method::selfContactCap (10 in the iterative presets, off in
    // those with the direct joint solve): for two bodies of one ragdoll
    // k·(m_a + m_b)·g·dt, for anything else none. The solver then starts a point whose last impulse is above the
    // bound from the bound, its friction scaled by the same factor, and leaves a point below it alone.
    afb::sim::Scene scene(*afb::bullet::methodPreset("iterative"));
    const afb::figure::Figure humanoid =
        armFigure("ballAndSocketJoint \"b\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) friction 0 }");
    auto& a = scene.spawn(RagdollAsset::create(humanoid), {.comeToRest = false});
    auto& b = scene.spawn(RagdollAsset::create(humanoid), {.comeToRest = false});
    auto* solver = dynamic_cast<afb::bullet::RagdollSolver*>(scene.world().getConstraintSolver());
    REQUIRE(solver != nullptr);
    const auto& cap = solver->contactWarmStartCap();
    REQUIRE(cap);
    const btScalar dt = btScalar(1.0 / 60.0);
    const double k = afb::bullet::methodPreset("iterative")->selfContactCap;
    REQUIRE(k > 0);
    btPersistentManifold self(&a.body(0), &a.body(1), 0, btScalar(0.02), btScalar(0.02));
    btPersistentManifold across(&a.body(1), &b.body(1), 0, btScalar(0.02), btScalar(0.02));
    btRigidBody box(1, nullptr, nullptr);
    btPersistentManifold game(&a.body(1), &box, 0, btScalar(0.02), btScalar(0.02));
    const double weight = (a.body(0).getMass() + a.body(1).getMass()) * 9.81 * dt;
    CHECK(cap(self, dt) == Approx(k * weight).epsilon(1e-5));
    CHECK(cap(across, dt) < 0);
    CHECK(cap(game, dt) < 0);

    // The weight is taken at standard gravity at least: weightless, a self-contact still starts warm.
    afb::sim::Scene weightless(*afb::bullet::methodPreset("iterative"), {.gravityMps2 = 0, .ground = false});
    auto& w = weightless.spawn(RagdollAsset::create(humanoid), {.comeToRest = false});
    auto* wsolver = dynamic_cast<afb::bullet::RagdollSolver*>(weightless.world().getConstraintSolver());
    REQUIRE(wsolver != nullptr);
    btPersistentManifold wself(&w.body(0), &w.body(1), 0, btScalar(0.02), btScalar(0.02));
    CHECK(wsolver->contactWarmStartCap()(wself, dt) == Approx(k * weight).epsilon(1e-5));
    // and at the world's own when that is stronger (Doom's 27.1 m/s²).
    afb::sim::Scene heavy(*afb::bullet::methodPreset("iterative"), {.gravityMps2 = 27.1, .ground = false});
    auto& h = heavy.spawn(RagdollAsset::create(humanoid), {.comeToRest = false});
    auto* hsolver = dynamic_cast<afb::bullet::RagdollSolver*>(heavy.world().getConstraintSolver());
    REQUIRE(hsolver != nullptr);
    btPersistentManifold hself(&h.body(0), &h.body(1), 0, btScalar(0.02), btScalar(0.02));
    CHECK(hsolver->contactWarmStartCap()(hself, dt) == Approx(k * weight * 27.1 / 9.81).epsilon(1e-4));

    // The solver applies a bound when it converts the contacts (a subclass reaches the protected step).
    struct Exposed : afb::bullet::RagdollSolver {
        using afb::bullet::RagdollSolver::convertContacts;
    } exposed;
    exposed.setContactWarmStartCap([](const btPersistentManifold&, btScalar) { return btScalar(2); });
    btRigidBody one(1, nullptr, nullptr), two(1, nullptr, nullptr);
    btPersistentManifold m(&one, &two, 0, btScalar(0.02), btScalar(0.02));
    auto addPoint = [&](btScalar impulse, btScalar lateral) {
        btManifoldPoint cp(btVector3(0, 0, 0), btVector3(0, 0, 0), btVector3(0, 0, 1), 0);
        cp.m_appliedImpulse = impulse;
        cp.m_appliedImpulseLateral1 = lateral;
        m.addManifoldPoint(cp);
    };
    addPoint(10, 4);
    addPoint(1, 0.5);
    btContactSolverInfo info;
    info.m_timeStep = dt;
    info.m_solverMode |= SOLVER_USE_WARMSTARTING;
    btPersistentManifold* list = &m;
    exposed.convertContacts(&list, 1, info);
    CHECK(m.getContactPoint(0).m_appliedImpulse == Approx(2));
    CHECK(m.getContactPoint(0).m_appliedImpulseLateral1 == Approx(0.8));
    CHECK(m.getContactPoint(1).m_appliedImpulse == Approx(1));
    CHECK(m.getContactPoint(1).m_appliedImpulseLateral1 == Approx(0.5));
}

TEST_CASE("joint warm starting: a hanging chain carries its weight without sagging", "[bullet][methods]") {
    // Three 10 kg links hang straight down from the world, at rest in their equilibrium: every joint must carry
    // the weight below it, m·g·dt per step. Bullet starts joint rows
    // from zero each step, so two iterations rebuild only part of that impulse along the chain and the joints
    // sag apart; started from their last impulses (factor 1), the rows carry the load and the chain holds.
    const std::vector<afb::test::TestJoint> joints = {{"origin", -1, 0, 0, 100},
                                                      {"b", 0, 0, 0, 80},
                                                      {"c", 1, 0, 0, 60}};
    const auto built = afb::test::buildTestFigure(
        "articulatedFigure chain {\n settings { selfCollision 0 }\n"
        " body \"a\" { joint \"origin\" model box( ( -1, -1, -20 ), ( 1, 1, 0 ) ) origin ( 0, 0, 90 ) density 0.125 "
        "containedJoints \"origin\" }\n"
        " body \"b\" { joint \"b\" model box( ( -1, -1, -20 ), ( 1, 1, 0 ) ) origin ( 0, 0, 70 ) density 0.125 "
        "containedJoints \"b\" }\n"
        " body \"c\" { joint \"c\" model box( ( -1, -1, -20 ), ( 1, 1, 0 ) ) origin ( 0, 0, 50 ) density 0.125 "
        "containedJoints \"c\" }\n"
        " ballAndSocketJoint \"top\" { body1 \"a\" body2 \"world\" anchor ( 0, 0, 100 ) friction 0 }\n"
        " ballAndSocketJoint \"ab\" { body1 \"b\" body2 \"a\" anchor ( 0, 0, 80 ) friction 0 }\n"
        " ballAndSocketJoint \"bc\" { body1 \"c\" body2 \"b\" anchor ( 0, 0, 60 ) friction 0 }\n}\n",
        joints);
    INFO(built.diagnostics.str());
    REQUIRE(built.figure);
    auto worstSag = [&](bool warm) {
        Method m = legacy();
        m.iterations = m.jointIterations = 2;
        m.warmStartingFactor = 1; // the steady state's impulses, in full
        m.jointWarmStarting = warm;
        ArmScene s(*built.figure, m, 9.81);
        double worst = 0;
        for (int i = 0; i < 120; ++i) {
            s.scene.step(1.0 / 60.0);
            if (i >= 60)
                for (int c = 0; c < 3; ++c) worst = std::max(worst, s.anchorError(c));
        }
        return worst;
    };
    const double cold = worstSag(false), warm = worstSag(true);
    INFO("cold " << cold << " m, warm " << warm << " m");
    CHECK(cold > 5e-3); // 16 mm here
    CHECK(warm < 1e-4);
}

TEST_CASE("limit warm starting: limit rows start from their last impulse exactly when the knob says so",
          "[bullet][methods]") {
    // The arm's hinge has its range as a separate limit constraint (speculative limits); joint warm starting tracks
    // the hinge, limit warm starting the limit too. Resting on its stop, the limit row carries the arm's weight, and
    // with the knob on it starts each step from the impulse it ended the last one with (warming factor 1).
    const afb::figure::Figure f = armFigure("hinge \"h\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) "
                                            "axis ( 0, 1, 0 ) friction 0 limit 0, 120, 0 }");
    for (const bool limitWarm : {false, true}) {
        Method m = methodWith("speculative-limits", "on");
        m.warmStartingFactor = 1;
        m.jointWarmStarting = true;
        m.limitWarmStarting = limitWarm;
        ArmScene s(f, m, 9.81);
        auto* solver = dynamic_cast<afb::bullet::RagdollSolver*>(s.scene.world().getConstraintSolver());
        REQUIRE(solver != nullptr);
        int limits = 0, others = 0;
        for (int k = 0; k < s.ragdoll->bulletConstraintCount(); ++k)
            ++(s.ragdoll->bulletConstraintIsLimit(k) ? limits : others);
        REQUIRE(limits == 1);
        CHECK(solver->trackedCount() == static_cast<std::size_t>(others + (limitWarm ? limits : 0)));
    }
}

TEST_CASE("direct joints: a chain of 1:10:100 masses swings with its joints held at one iteration",
          "[bullet][methods]") {
    // Three links of 0.2, 2 and 20 kg start horizontal from a world pivot and swing down. A sequential-impulse
    // solve with one iteration cannot carry the heavy end's load up a light chain: the joints fly apart. The
    // direct solve holds every joint exactly at the velocity level, so what remains is the drift of a rigid
    // turn within one step (ω²·r·dt²/2, about a millimetre here), corrected by the joint ERP.
    const std::vector<afb::test::TestJoint> joints = {{"origin", -1, 0, 0, 100},
                                                      {"b", 0, 20, 0, 100},
                                                      {"c", 1, 40, 0, 100}};
    const auto built = afb::test::buildTestFigure(
        "articulatedFigure chain {\n settings { selfCollision 0 }\n"
        " body \"a\" { joint \"origin\" model box( ( 0, -1, -1 ), ( 20, 1, 1 ) ) origin ( 0, 0, 100 ) density "
        "0.00125 containedJoints \"origin\" }\n"
        " body \"b\" { joint \"b\" model box( ( 0, -1, -1 ), ( 20, 1, 1 ) ) origin ( 20, 0, 100 ) density 0.0125 "
        "containedJoints \"b\" }\n"
        " body \"c\" { joint \"c\" model box( ( 0, -1, -1 ), ( 20, 1, 1 ) ) origin ( 40, 0, 100 ) density 0.125 "
        "containedJoints \"c\" }\n"
        " ballAndSocketJoint \"top\" { body1 \"a\" body2 \"world\" anchor ( 0, 0, 100 ) friction 0 }\n"
        " ballAndSocketJoint \"ab\" { body1 \"b\" body2 \"a\" anchor ( 20, 0, 100 ) friction 0 }\n"
        " ballAndSocketJoint \"bc\" { body1 \"c\" body2 \"b\" anchor ( 40, 0, 100 ) friction 0 }\n}\n",
        joints);
    INFO(built.diagnostics.str());
    REQUIRE(built.figure);
    auto worstGap = [&](bool direct) {
        Method m = legacy();
        m.iterations = m.jointIterations = 1;
        m.directJoints = direct;
        ArmScene s(*built.figure, m, 9.81);
        double worst = 0;
        for (int i = 0; i < 60; ++i) {
            s.scene.step(1.0 / 60.0);
            for (int c = 0; c < 3; ++c) worst = std::max(worst, s.anchorError(c));
        }
        return worst;
    };
    const double sequential = worstGap(false), direct = worstGap(true);
    INFO("sequential impulse " << sequential << " m, direct " << direct << " m");
    CHECK(sequential > 0.05);
    CHECK(direct < 0.01);
    CHECK(direct < sequential / 100);
}

TEST_CASE("direct joints: a body landing on a light foot is stopped through the joint in one step",
          "[bullet][methods]") {
    // A 50 kg block is fixed onto a 0.5 kg plate and the pair falls flat onto the ground at 3 m/s. Contact rows
    // that see the plate's mass alone stop the plate and then, one iteration at a time, the block: the joint
    // opens and the block sinks into the plate's place. Through the direct solve each contact row has the
    // pair's mass at its corner: both stop in the step of impact and the joint stays closed.
    const auto built = afb::test::buildPlateUnderBlockFigure();
    INFO(built.diagnostics.str());
    REQUIRE(built.figure);
    auto worstGap = [&](bool direct) {
        Method m = legacy();
        m.iterations = m.jointIterations = 4;
        m.multipointContacts = true; // the plate lands on its four corners (one corner would just turn it)
        m.ccd = afb::bullet::CcdPolicy::Off;
        m.directJoints = direct;
        afb::sim::Scene scene(m, {.gravityMps2 = 9.81});
        Ragdoll& r = scene.spawn(RagdollAsset::create(*built.figure), {.comeToRest = false});
        for (int i = 0; i < r.bodyCount(); ++i) r.body(i).setLinearVelocity(btVector3(0, 0, -3));
        double worst = 0;
        for (int i = 0; i < 10; ++i) {
            scene.step(1.0 / 60.0);
            worst = std::max(worst, r.jointError(0).anchorM);
        }
        return worst;
    };
    const double sequential = worstGap(false), direct = worstGap(true);
    INFO("sequential impulse " << sequential << " m, direct " << direct << " m");
    CHECK(sequential > 0.01);
    CHECK(direct < 0.002);
}

TEST_CASE("friction through the figure: a humanoid lying still keeps its hinges' axes together", "[bullet][methods]") {
    // Under the direct joint solve each iteration ends with the contact friction rows. Solved with one body's
    // response (the default), they leave the joints they disturbed to the next iteration's joint solve, and the
    // last iteration's disturbance is left for good: a humanoid lying still ends each step with its knees and
    // hips turning apart about their locked axes at up to 0.18 rad/s, which the position pass takes back. With
    // Method::frictionThroughFigure the friction rows move the figure as its joints let it and the solve ends with
    // the joints held. Without the position pass, what the velocities leave shows as hinges whose two axes part
    // while the figure lies still (Bullet's joint ERP alone pulls them back). Rows one at a time (figure-iterations
    // 0): block mode solves the joints after the friction rows in every iteration (test_figure_block.cpp).
    auto worstHingeAxes = [](bool through) {
        Method m = *afb::bullet::methodPreset("default");
        m.figureIterations = 0;
        m.positionIterations = 0;
        m.positionTree = 0;
        m.frictionThroughFigure = through;
        return afb::test::lyingHumanoidHingeAxesApart(m);
    };
    const double oneBody = worstHingeAxes(false), through = worstHingeAxes(true);
    INFO("hinge axes apart: one-body friction " << oneBody / kDeg << " deg, through the figure " << through / kDeg
                                                << " deg");
    CHECK(oneBody > 0.18 * kDeg);
    CHECK(through < 0.12 * kDeg);
    REQUIRE(afb::bullet::findKnob("friction-through-figure") != nullptr);
    CHECK_FALSE(afb::bullet::methodPreset("default")->frictionThroughFigure);
}

TEST_CASE("joint friction: a humanoid dropped upright stands on it under the default, and folds without it",
          "[bullet][methods]") {
    // Landing on its feet from 1 m, the humanoid carries its weight through its joints, and their friction
    // (± friction × each joint's reaction, docs/format.md §4.8) holds the slightly bent figure up for a while:
    // solved to convergence (8 substeps of 40 iterations) its head stays above 1.4 m for 1.8 s (docs/methods.md).
    // The default's 20 iterations per step hold it at least as long; with the joints' friction at 0 it folds at once.
    // Rest rules off, yaw 0, 60 Hz.
    auto headDropAt = [](double seconds, bool withFriction) {
        afb::figure::LoadedFigure loaded = afb::test::loadEntity("humanoid");
        if (!withFriction)
            for (auto& c : loaded.figure.constraints) c.friction = 0;
        afb::sim::Scene scene(*afb::bullet::methodPreset("default"));
        Ragdoll& r =
            scene.spawn(RagdollAsset::create(loaded.figure),
                        {.entityTransform = afb::test::standing(loaded.figure, 0, 0, 1.0), .comeToRest = false});
        auto highest = [&r] {
            double z = -1e9;
            for (int i = 0; i < r.bodyCount(); ++i) z = std::max(z, double(r.body(i).getCenterOfMassPosition().z()));
            return z;
        };
        for (int step = 0; step < 30; ++step) scene.step(1.0 / 60); // landed at 0.45 s
        const double landed = highest();
        for (int step = 30; step < static_cast<int>(seconds * 60); ++step) scene.step(1.0 / 60);
        return landed - highest();
    };
    const double held = headDropAt(1.5, true), free = headDropAt(1.5, false);
    INFO("highest body's drop from 0.5 s to 1.5 s: with joint friction " << held << " m, without " << free << " m");
    CHECK(held < 0.05);
    CHECK(free > 0.3);
}

TEST_CASE("impact substeps: a frame takes more substeps only while two objects' bodies close fast",
          "[bullet][methods]") {
    // A box rests on a box lying on the ground (their manifold holds points); then the upper one is sent down at
    // 8 m/s, 13.3 cm in a 60 Hz frame: that frame takes ceil(13.3 / 5) = 3 substeps (Method::impactSubsteps,
    // kImpactTravelM) and the contact stops the box within it, so the frames after take one again. A box falling
    // onto the other is stopped by its speculative contact in the step that first finds it (it never closes
    // fast at a frame's start), and a single humanoid dropped 10 m (its own bodies, the ground) never takes more.
    const afb::figure::Figure boxFig = boxFigure();
    auto substepsSeen = [&](int impactSubsteps, double drop) {
        Method m = *afb::bullet::methodPreset("default");
        m.impactSubsteps = impactSubsteps;
        afb::sim::Scene scene(m);
        afb::bullet::SpawnOptions lower, upper;
        lower.comeToRest = upper.comeToRest = false;
        upper.entityTransform.setOrigin(btVector3(0.05f, 0, btScalar(8 * kUnit + drop)));
        Ragdoll& low = scene.spawn(RagdollAsset::create(boxFig), lower);
        Ragdoll& high = scene.spawn(RagdollAsset::create(boxFig), upper);
        std::vector<int> seen;
        for (int s = 0; s < 120; ++s) {
            if (s == 60) high.body(0).setLinearVelocity(btVector3(0, 0, -8));
            scene.step(1.0 / 60);
            seen.push_back(scene.ragdollWorld().lastSubsteps());
        }
        // The upper box ends on the lower one, a box's height above it.
        const double above = high.body(0).getCenterOfMassPosition().z() - low.body(0).getCenterOfMassPosition().z();
        CHECK(above == Approx(8 * kUnit).margin(0.005));
        return seen;
    };
    for (const double drop : {0.0, 2.0}) {
        INFO("dropped from " << drop << " m onto the lower box");
        const std::vector<int> on = substepsSeen(4, drop), off = substepsSeen(1, drop);
        CHECK(on[60] == 3);
        CHECK(std::count(on.begin(), on.end(), 1) == static_cast<long>(on.size()) - 1);
        CHECK(*std::max_element(off.begin(), off.end()) == 1);
    }

    const auto loaded = afb::test::loadEntity("humanoid");
    afb::sim::Scene scene(*afb::bullet::methodPreset("default"));
    afb::bullet::SpawnOptions o;
    o.comeToRest = false;
    o.entityTransform.setOrigin(btVector3(0, 0, 10));
    scene.spawn(RagdollAsset::create(loaded.figure), o);
    int most = 0;
    for (int s = 0; s < 180; ++s) {
        scene.step(1.0 / 60);
        most = std::max(most, scene.ragdollWorld().lastSubsteps());
    }
    CHECK(most == 1);
}

TEST_CASE("joint space: the direct solve in joint space and as a tree of bodies and joints moves a tumbling "
          "humanoid alike",
          "[bullet][methods]") {
    // Method::jointSpace changes how the direct joint solve factors its system, not the system: a humanoid thrown
    // tumbling through the air (its joints and limits the only rows) follows the same path either way, to rounding,
    // and its joints stay closed. Powered (6 Hz motors holding the load pose: soft rows about every joint, a spring
    // and damper on its free motions in joint space) the same holds.
    static const auto loaded = afb::test::loadEntity("humanoid");
    const auto asset = RagdollAsset::create(loaded.figure);
    const bool powered = GENERATE(false, true);
    INFO((powered ? "powered" : "limp"));
    auto path = [&](bool jointSpace) {
        Method m = *afb::bullet::methodPreset("default");
        m.jointSpace = jointSpace;
        afb::sim::Scene scene(m);
        auto* solver = dynamic_cast<afb::bullet::RagdollSolver*>(scene.world().getConstraintSolver());
        REQUIRE(solver != nullptr);
        CHECK(solver->jointSpace() == jointSpace);
        afb::bullet::SpawnOptions o;
        o.comeToRest = false;
        o.entityTransform = btTransform(btQuaternion::getIdentity(), btVector3(0, 0, 30));
        Ragdoll& r = scene.spawn(asset, o);
        if (powered) REQUIRE(r.setMotorGains(afb::bullet::MotorGains{6}));
        for (int i = 0; i < r.bodyCount(); ++i) {
            r.body(i).setAngularVelocity(btVector3(3, -2, 5));
            r.body(i).setLinearVelocity(btVector3(1, 0, 4));
        }
        double worstGap = 0;
        for (int s = 0; s < 30; ++s) {
            scene.step(1.0 / 60);
            for (int j = 0; j < static_cast<int>(loaded.figure.constraints.size()); ++j)
                worstGap = std::max(worstGap, r.jointError(j).anchorM);
        }
        return std::pair{r.bodyTransforms(), worstGap};
    };
    const auto [inJointSpace, gapJointSpace] = path(true);
    const auto [asTree, gapTree] = path(false);
    double apart = 0;
    for (std::size_t i = 0; i < inJointSpace.size(); ++i)
        apart = std::max(apart, (inJointSpace[i].position - asTree[i].position).norm());
    INFO("bodies apart after 0.5 s: " << apart << " m; worst joint gap " << gapJointSpace << " / " << gapTree << " m");
    CHECK(apart < 2e-4); // rounding grows as limits catch and let go: 6e-6 m after 10 steps, 6e-5 m after 30
    CHECK(gapJointSpace < 1e-3);
    CHECK(gapTree < 1e-3);
    CHECK(afb::bullet::methodPreset("default")->jointSpace);
}
