// Methods (bullet::Method) and the techniques beyond Bullet's defaults, each on a case whose outcome is known:
// the knob table and presets, the position pass closing a separated joint, speculative limits stopping a
// pendulum at its stop, speculative contacts stopping a falling box at the ground, and equal iterations keeping
// a light body on the ground under a heavy one. Deterministic: fixed 60 Hz step, fixed insertion order.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "EntityFixture.h"
#include "FigureFixture.h"
#include "LyingHumanoid.h"
#include "afb/bullet/Method.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/bullet/RagdollSolver.h"
#include "afb/bullet/RagdollWorld.h"
#include "afb/detail/Convert.h"
#include "afb/sim/Report.h"
#include "afb/sim/Scene.h"
#include "bullet/PositionPass.h"

namespace {

using afb::bullet::Method;
using afb::bullet::Ragdoll;
using afb::bullet::RagdollAsset;
constexpr double kDeg = 3.14159265358979323846 / 180.0;
constexpr double kUnit = 0.0254;

afb::figure::Figure armFigure(const std::string& constraint) {
    const auto built = afb::test::buildArmFigure(constraint);
    INFO(built.diagnostics.str());
    REQUIRE(built.figure);
    return *built.figure;
}

// A figure of one body of density 0.02 on the skeleton's origin joint: its `.af` model and origin as text.
afb::figure::Figure oneBodyFigure(const std::string& model, const std::string& origin) {
    const std::vector<afb::test::TestJoint> joints = {{"origin", -1, 0, 0, 0}};
    const auto built = afb::test::buildTestFigure("articulatedFigure one {\n body \"one\" { joint \"origin\" model " +
                                                      model + " origin " + origin + " density 0.02 }\n}\n",
                                                  joints);
    INFO(built.diagnostics.str());
    REQUIRE(built.figure);
    return *built.figure;
}

// One 16 × 16 × 8-unit box (0.406 × 0.406 × 0.203 m) with its lowest face at the entity's origin.
afb::figure::Figure boxFigure() { return oneBodyFigure("box( ( -8, -8, -4 ), ( 8, 8, 4 ) )", "( 0, 0, 4 )"); }

// A 16-unit octahedron (vertices ±8 units on each axis) with its lowest vertex at the entity's origin.
afb::figure::Figure octahedronFigure() {
    return oneBodyFigure("octahedron( ( -8, -8, -8 ), ( 8, 8, 8 ) )", "( 0, 0, 8 )");
}

// A scene without ground holding one ragdoll of `figure`, rest rules off.
struct ArmScene {
    afb::sim::Scene scene;
    Ragdoll* ragdoll = nullptr;
    ArmScene(const afb::figure::Figure& figure, const Method& method, double gravity)
        : scene(method, {.gravityMps2 = gravity, .ground = false}) {
        ragdoll = &scene.spawn(RagdollAsset::create(figure), {.comeToRest = false});
        for (int i = 0; i < ragdoll->bodyCount(); ++i) ragdoll->body(i).setActivationState(DISABLE_DEACTIVATION);
    }
    double anchorError(int c) const { return ragdoll->jointError(c).anchorM; }
};

// The method before presets: none of the techniques, so each test can switch on one at a time.
Method legacy() { return *afb::bullet::methodPreset("legacy"); }

Method methodWith(const std::string& knob, const std::string& value) {
    Method m = legacy();
    const auto* k = afb::bullet::findKnob(knob);
    REQUIRE(k != nullptr);
    REQUIRE(afb::bullet::setKnob(m, *k, value).empty());
    return m;
}

// The signed distances of every contact point between `a` and `b` in the scene's manifolds now.
std::vector<double> contactDistances(afb::sim::Scene& scene, const btCollisionObject* a, const btCollisionObject* b) {
    std::vector<double> out;
    btDispatcher& d = *scene.world().getDispatcher();
    for (int m = 0; m < d.getNumManifolds(); ++m) {
        const btPersistentManifold& man = *d.getInternalManifoldPointer()[m];
        if ((man.getBody0() == a && man.getBody1() == b) || (man.getBody0() == b && man.getBody1() == a))
            for (int c = 0; c < man.getNumContacts(); ++c)
                out.push_back(static_cast<double>(man.getContactPoint(c).getDistance()));
    }
    return out;
}

} // namespace

TEST_CASE("methods: presets, knobs and their text form", "[bullet][methods]") {
    for (std::string_view name : afb::bullet::methodPresetNames()) {
        const auto m = afb::bullet::methodPreset(name);
        REQUIRE(m);
        CHECK(m->name == name);
    }
    CHECK_FALSE(afb::bullet::methodPreset("fastest"));
    CHECK(*afb::bullet::methodPreset("default") == Method{});
    // "iterative": the default's knobs with Bullet's iterative joint solve (the previous default).
    Method iterative = afb::bullet::iterativeJoints(Method{});
    iterative.name = "iterative";
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

TEST_CASE("position pass: a separated joint is closed within one step", "[bullet][methods]") {
    // A ball joint pulled 5 cm apart (the arm moved away from its anchor), no gravity, no velocities: the
    // velocity solve alone closes a fraction (Baumgarte, 20 % per step); the position pass closes it to within
    // 0.1 mm, whatever the mass split between the two bodies.
    const afb::figure::Figure f =
        armFigure("ballAndSocketJoint \"b\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) friction 0 }");
    auto separatedAfterOneStep = [&](const Method& method) {
        ArmScene s(f, method, 0);
        btTransform t = s.ragdoll->body(1).getCenterOfMassTransform();
        t.getOrigin() += btVector3(0, btScalar(0.05), 0);
        s.ragdoll->body(1).setCenterOfMassTransform(t);
        REQUIRE(s.anchorError(1) == Approx(0.05).margin(1e-6));
        s.scene.step(1.0 / 60.0);
        return std::max(s.anchorError(0), s.anchorError(1));
    };
    const double without = separatedAfterOneStep(legacy());
    CHECK(without > 0.02);
    const double with = separatedAfterOneStep(methodWith("position-iterations", "4"));
    CHECK(with < 1e-4);
}

TEST_CASE("position velocity: a motion the pass takes back is taken out of the velocity", "[bullet][methods]") {
    // The arm hangs from the world by a ball joint at its centre of mass, so the pass closes a gap by moving the
    // arm alone and without turning it. The arm stands 1 cm off the anchor, as if the substep had carried it there
    // at v = 1 cm / dt. With the knob, the pass moves it back and takes v with it (a motion it reverts every
    // substep would otherwise live on in the velocity); a velocity across the move, which the pass did not
    // undo, is kept either way. Without the knob, velocities are left as they were (post-stabilisation).
    const afb::figure::Figure f =
        armFigure("ballAndSocketJoint \"b\" { body1 \"arm\" body2 \"world\" anchor ( 10, 0, 100 ) friction 0 }");
    const btScalar dt = btScalar(1.0 / 60.0), gap = btScalar(0.01);
    auto afterPass = [&](bool takeVelocity, const btVector3& velocity) {
        ArmScene s(f, legacy(), 0);
        btRigidBody& arm = s.ragdoll->body(1);
        REQUIRE(s.anchorError(1) < 1e-6); // the anchor is the arm's centre of mass
        btTransform t = arm.getCenterOfMassTransform();
        t.getOrigin() += btVector3(0, gap, 0);
        arm.setCenterOfMassTransform(t);
        arm.setLinearVelocity(velocity);
        arm.setAngularVelocity(btVector3(0, 0, 0));
        afb::bullet::detail::positionPass(*s.ragdoll, 4, 0, {}, dt, takeVelocity);
        CHECK(s.anchorError(1) < 1e-4);
        return std::pair{arm.getLinearVelocity(), arm.getAngularVelocity()};
    };
    const btVector3 along(0, gap / dt, 0), across(btScalar(0.3), 0, 0);
    const auto [taken, takenSpin] = afterPass(true, along);
    CHECK(taken.length() < 1e-3 * along.length());
    CHECK(takenSpin.length() < 1e-9);
    const auto [kept, keptSpin] = afterPass(false, along);
    CHECK((kept - along).length() < 1e-6);
    const auto [acrossTaken, acrossSpin] = afterPass(true, across);
    CHECK((acrossTaken - across).length() < 1e-6);
    // Half the motion taken back (the velocity carried the arm twice as far as the gap): half the velocity stays.
    const auto [half, halfSpin] = afterPass(true, along * 2);
    CHECK(half.y() == Approx(along.y()).epsilon(1e-3));
}

TEST_CASE("position tree: every joint of a separated chain is closed at once", "[bullet][methods]") {
    // A free chain of four boxes of unequal mass (ball joints, no gravity, no ground, at rest), its two middle
    // bodies pulled off the line by 5 and 4 cm and turned 17° and 11°: all three joints are open, and closing
    // one by moving its two bodies opens its neighbours. One Gauss–Seidel sweep leaves centimetres; the tree
    // steps (Newton on the joint tree with the bodies' masses) close all three within 0.1 mm at once, by
    // internal moves only, so the chain's centre of mass stays where it was.
    const std::vector<afb::test::TestJoint> joints = {{"origin", -1, 0, 0, 0},
                                                      {"b1", 0, 20, 0, 0},
                                                      {"b2", 1, 40, 0, 0},
                                                      {"b3", 2, 60, 0, 0}};
    const std::string af =
        "articulatedFigure chain {\n settings { selfCollision 0 }\n"
        " body \"b0\" { joint \"origin\" model box( ( -8, -2, -2 ), ( 8, 2, 2 ) ) origin ( 0, 0, 0 ) "
        "density 0.2 }\n"
        " body \"b1\" { joint \"b1\" model box( ( -8, -2, -2 ), ( 8, 2, 2 ) ) origin ( 20, 0, 0 ) "
        "density 0.02 }\n"
        " body \"b2\" { joint \"b2\" model box( ( -8, -3, -3 ), ( 8, 3, 3 ) ) origin ( 40, 0, 0 ) "
        "density 0.1 }\n"
        " body \"b3\" { joint \"b3\" model box( ( -8, -2, -2 ), ( 8, 2, 2 ) ) origin ( 60, 0, 0 ) "
        "density 0.05 }\n"
        " ballAndSocketJoint \"j1\" { body1 \"b1\" body2 \"b0\" anchor ( 10, 0, 0 ) friction 0 }\n"
        " ballAndSocketJoint \"j2\" { body1 \"b2\" body2 \"b1\" anchor ( 30, 0, 0 ) friction 0 }\n"
        " ballAndSocketJoint \"j3\" { body1 \"b3\" body2 \"b2\" anchor ( 50, 0, 0 ) friction 0 }\n"
        "}\n";
    const auto built = afb::test::buildTestFigure(af, joints);
    INFO(built.diagnostics.str());
    REQUIRE(built.figure);
    const afb::figure::Figure& f = *built.figure;
    REQUIRE(f.constraints.size() == 3);
    struct Result {
        double worstGapM;
        btVector3 comShift;
    };
    auto afterOneStep = [&](const Method& method) {
        ArmScene s(f, method, 0);
        auto com = [&] {
            btVector3 sum(0, 0, 0);
            btScalar mass = 0;
            for (int i = 0; i < s.ragdoll->bodyCount(); ++i) {
                const btRigidBody& b = s.ragdoll->body(i);
                sum += b.getCenterOfMassPosition() / b.getInvMass();
                mass += 1 / b.getInvMass();
            }
            return sum / mass;
        };
        const btVector3 pull[] = {{0, 0, 0}, {0, btScalar(0.05), 0}, {0, 0, btScalar(-0.04)}, {0, 0, 0}};
        const btQuaternion turn[] = {btQuaternion::getIdentity(), btQuaternion(btVector3(0, 0, 1), btScalar(0.3)),
                                     btQuaternion(btVector3(1, 1, 0), btScalar(-0.2)), btQuaternion::getIdentity()};
        for (int i = 0; i < 4; ++i) {
            btTransform t = s.ragdoll->body(i).getCenterOfMassTransform();
            t.getOrigin() += pull[i];
            t.setRotation(turn[i] * t.getRotation());
            s.ragdoll->body(i).setCenterOfMassTransform(t);
        }
        REQUIRE(s.anchorError(0) > 0.02);
        const btVector3 before = com();
        s.scene.step(1.0 / 60.0);
        double worst = 0;
        for (int c = 0; c < 3; ++c) worst = std::max(worst, s.anchorError(c));
        return Result{worst, com() - before};
    };
    Method sweep = methodWith("position-iterations", "1");
    const Result swept = afterOneStep(sweep);
    Method tree = methodWith("position-iterations", "0");
    REQUIRE(afb::bullet::setKnob(tree, *afb::bullet::findKnob("position-tree"), "1").empty());
    const Result treed = afterOneStep(tree);
    INFO("one sweep " << swept.worstGapM << " m, tree " << treed.worstGapM << " m");
    CHECK(swept.worstGapM > 0.005);
    CHECK(treed.worstGapM < 1e-4);
    CHECK(treed.comShift.length() < 1e-5);
}

TEST_CASE("position tree 2: a hinge pushed past its stop is put back on it", "[bullet][methods]") {
    // The arm turned down about the hinge, 25° past its upper stop (φ ∈ [0°, 30°]), held still with no gravity:
    // the velocity solve starts to turn it back (Baumgarte), the tree step with limits puts it on the stop.
    const afb::figure::Figure f = armFigure("hinge \"h\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) "
                                            "axis ( 0, 1, 0 ) friction 0 limit 0, 30, 0 }");
    auto excessDegAfterOneStep = [&](const std::string& tree) {
        Method m = methodWith("position-iterations", "0");
        REQUIRE(afb::bullet::setKnob(m, *afb::bullet::findKnob("position-tree"), tree).empty());
        ArmScene s(f, m, 0);
        // Turn the arm about the anchor (0, 0, 100 units) about Y (φ > 0 turns it down) until 25° past the stop.
        const btVector3 pivot(0, 0, btScalar(100 * kUnit));
        const double phi0Deg = s.ragdoll->jointError(1).limitExcessRad / kDeg; // 0: within the range
        REQUIRE(phi0Deg == 0);
        const btQuaternion turn(btVector3(0, 1, 0), btScalar(55 * kDeg));
        btTransform t = s.ragdoll->body(1).getCenterOfMassTransform();
        t.setOrigin(pivot + quatRotate(turn, t.getOrigin() - pivot));
        t.setRotation(turn * t.getRotation());
        s.ragdoll->body(1).setCenterOfMassTransform(t);
        const double excessDeg = s.ragdoll->jointError(1).limitExcessRad / kDeg;
        INFO("excess before the step " << excessDeg << " deg");
        REQUIRE(excessDeg > 15);
        s.scene.step(1.0 / 60.0);
        return std::pair{s.ragdoll->jointError(1).limitExcessRad / kDeg, s.anchorError(1)};
    };
    const auto [anchorsOnly, anchorsOnlyGap] = excessDegAfterOneStep("1");
    const auto [withLimits, gap] = excessDegAfterOneStep("2");
    INFO("tree 1: " << anchorsOnly << " deg, tree 2: " << withLimits << " deg");
    CHECK(anchorsOnly > 5);
    CHECK(withLimits < 0.05);
    CHECK(gap < 1e-4);
    CHECK(anchorsOnlyGap < 1e-4);
}

TEST_CASE("position pass: a corner turned into the ground out of the manifold's sight is lifted", "[bullet][methods]") {
    // An octahedron (vertices ±h on each axis) whose manifold with the ground was made where its bottom vertex
    // touched; then turned 90° about X (the substep's whip), so that a vertex the manifold never held points
    // straight down, 3 cm deep, and the held one points sideways, far above the ground. The pass's contact rule
    // (what is deeper than the 2 mm slop, half of it per sweep) applied to that vertex moves the body straight up
    // (the vertex is below the centre of mass): after one sweep 2 + 28/2 mm deep, after four 2 + 28/16 mm. A vertex
    // the manifold does hold is projected once per sweep, not a second time for being the deepest.
    const auto asset = RagdollAsset::create(octahedronFigure());
    const auto* hull = dynamic_cast<const btConvexHullShape*>(asset->shape(0));
    REQUIRE(hull != nullptr);
    afb::sim::Scene scene(methodWith("multipoint-contacts", "on"), {.gravityMps2 = 0});
    auto& r = scene.spawn(asset, {.comeToRest = false});
    btRigidBody& body = r.body(0);
    // How deep the body's lowest surface point is (Bullet's support function, margin included).
    auto depth = [&] {
        const btTransform& t = body.getCenterOfMassTransform();
        return -(t * hull->localGetSupportingVertex(t.getBasis().transpose() * btVector3(0, 0, -1))).z();
    };
    auto placeAtDepth = [&](const btQuaternion& q, double d) {
        body.setCenterOfMassTransform(btTransform(q, btVector3(0, 0, 1)));
        const double now = depth();
        body.setCenterOfMassTransform(btTransform(q, btVector3(0, 0, btScalar(1 + now - d))));
        REQUIRE(depth() == Approx(d).margin(1e-6));
    };
    auto manifolds = [&] {
        btDispatcher* d = scene.world().getDispatcher();
        std::vector<btPersistentManifold*> out;
        for (int i = 0; i < d->getNumManifolds(); ++i) out.push_back(d->getManifoldByIndexInternal(i));
        return out;
    };
    const btScalar dt = btScalar(1.0 / 60.0);
    const double slop = 0.002, deep = 0.03;

    SECTION("a vertex the manifold does not hold") {
        placeAtDepth(btQuaternion::getIdentity(), 0.0005);
        scene.world().performDiscreteCollisionDetection();
        const auto held = manifolds();
        REQUIRE(held.size() == 1);
        REQUIRE(held[0]->getNumContacts() == 1); // the bottom vertex; the others are h up, beyond reach
        const btQuaternion turned(btVector3(1, 0, 0), btScalar(90 * kDeg));
        placeAtDepth(turned, deep);
        afb::bullet::detail::positionPass(r, 1, 0, held, dt, false);
        CHECK(depth() == Approx(slop + (deep - slop) / 2).margin(1e-5));
        CHECK(body.getOrientation().angleShortestPath(turned) < 1e-5); // lifted, not tipped
        afb::bullet::detail::positionPass(r, 3, 0, held, dt, false);
        CHECK(depth() == Approx(slop + (deep - slop) / 16).margin(1e-5));
    }
    SECTION("a vertex the manifold holds") {
        placeAtDepth(btQuaternion::getIdentity(), deep);
        scene.world().performDiscreteCollisionDetection();
        const auto held = manifolds();
        REQUIRE(held.size() == 1);
        REQUIRE(held[0]->getNumContacts() >= 1);
        afb::bullet::detail::positionPass(r, 1, 0, held, dt, false);
        CHECK(depth() == Approx(slop + (deep - slop) / 2).margin(1e-5));
    }
}

TEST_CASE("position pass: contact points held by static friction do not slide while the pass closes a joint",
          "[bullet][methods]") {
    // A box lying on the ground, joined at its centre by a ball joint to a small cube 30 times heavier inside it
    // (not touching the ground; no self-collision, no gravity), the box moved a centimetre to the side. The box's
    // inertia is scaled up 300 times so that a correction at a corner barely turns it: the split is then
    // the masses'. Its four bottom corners are the manifold's points; the velocity solve's result is written into
    // them: pressed (normal impulse 1 N·s) with no friction used (static friction, well inside the cone), or with
    // friction at its Coulomb bound μ·N (sliding). Each sweep's joint projection closes the gap g, moving the box
    // by g·w_box / (w_box + w_cube). Sliding, that is all: the box moves that far and the joint is closed.
    // Sticking, the corners then go back where they were, so the box stays and the gap shrinks only by the cube's
    // share each sweep: g·(w_box / (w_box + w_cube))⁴ after four.
    const std::vector<afb::test::TestJoint> joints = {{"origin", -1, 0, 0, 0}, {"post", 0, 0, 0, 4}};
    const auto built = afb::test::buildTestFigure(
        "articulatedFigure b {\n settings { selfCollision 0 }\n"
        " body \"box\" { joint \"origin\" model box( ( -8, -8, -4 ), ( 8, 8, 4 ) ) origin ( 0, 0, 4 ) density 0.02 "
        "inertiaScale ( 300 0 0 0 300 0 0 0 300 ) }\n"
        " body \"post\" { joint \"post\" model box( ( -2, -2, -2 ), ( 2, 2, 2 ) ) origin ( 0, 0, 4 ) density 20 }\n"
        " ballAndSocketJoint \"b\" { body1 \"box\" body2 \"post\" anchor ( 0, 0, 4 ) friction 0 }\n}\n",
        joints);
    INFO(built.diagnostics.str());
    REQUIRE(built.figure);
    const double gap = 0.01;
    double boxShare = 0;
    auto afterPass = [&](bool sliding) {
        afb::sim::Scene scene(methodWith("multipoint-contacts", "on"), {.gravityMps2 = 0});
        auto& r = scene.spawn(RagdollAsset::create(*built.figure), {.comeToRest = false});
        btRigidBody& box = r.body(0);
        boxShare = box.getInvMass() / (box.getInvMass() + r.body(1).getInvMass());
        btTransform t = box.getCenterOfMassTransform();
        t.getOrigin() += btVector3(btScalar(gap), 0, btScalar(-5e-5)); // and just touching the ground
        box.setCenterOfMassTransform(t);
        REQUIRE(r.jointError(0).anchorM == Approx(gap).margin(1e-4));
        scene.world().performDiscreteCollisionDetection();
        btDispatcher* d = scene.world().getDispatcher();
        btPersistentManifold* m = nullptr; // the box's with the ground
        for (int i = 0; i < d->getNumManifolds(); ++i) {
            btPersistentManifold* candidate = d->getManifoldByIndexInternal(i);
            if ((candidate->getBody0() == &box && candidate->getBody1()->isStaticObject()) ||
                (candidate->getBody1() == &box && candidate->getBody0()->isStaticObject()))
                m = candidate;
        }
        REQUIRE(m != nullptr);
        REQUIRE(m->getNumContacts() == 4);
        for (int k = 0; k < 4; ++k) {
            btManifoldPoint& cp = m->getContactPoint(k);
            REQUIRE(std::abs(cp.getDistance()) < 2e-4);
            cp.m_appliedImpulse = 1;
            cp.m_appliedImpulseLateral1 = sliding ? cp.m_combinedFriction * cp.m_appliedImpulse : 0;
            cp.m_appliedImpulseLateral2 = 0;
        }
        const btVector3 before = box.getCenterOfMassPosition();
        const double gapBefore = r.jointError(0).anchorM;
        afb::bullet::detail::positionPass(r, 4, 0, std::span<btPersistentManifold* const>(&m, 1), btScalar(1.0 / 60.0),
                                          false);
        return std::tuple{(box.getCenterOfMassPosition() - before).length(), gapBefore, r.jointError(0).anchorM};
    };
    const auto [slid, gapSliding0, gapSliding] = afterPass(true);
    INFO("box's share " << boxShare << "; sliding: the box moved " << slid << " m, the joint is " << gapSliding
                        << " m open");
    CHECK(slid == Approx(gapSliding0 * boxShare).epsilon(1e-3));
    CHECK(gapSliding < 1e-5);
    const auto [stuck, gapSticking0, gapSticking] = afterPass(false);
    INFO("sticking: the box moved " << stuck << " m, the joint is " << gapSticking << " m open");
    // (What the turning left: the four corners pull the box back one after the other, each turning it a little.)
    CHECK(stuck < 0.05 * gap);
    CHECK(gapSticking == Approx(gapSticking0 * std::pow(boxShare, 4)).epsilon(0.02));
}

TEST_CASE("self-contact cap: a contact within one ragdoll starts from at most k times its pair's weight per step",
          "[bullet][methods]") {
    // RagdollWorld gives its RagdollSolver the bound of Method::selfContactCap: for two bodies of one ragdoll
    // k·(m_a + m_b)·g·dt, for anything else none. The solver then starts a point whose last impulse is above the
    // bound from the bound, its friction scaled by the same factor, and leaves a point below it alone.
    afb::sim::Scene scene(*afb::bullet::methodPreset("default"));
    const afb::figure::Figure humanoid =
        armFigure("ballAndSocketJoint \"b\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) friction 0 }");
    auto& a = scene.spawn(RagdollAsset::create(humanoid), {.comeToRest = false});
    auto& b = scene.spawn(RagdollAsset::create(humanoid), {.comeToRest = false});
    auto* solver = dynamic_cast<afb::bullet::RagdollSolver*>(scene.world().getConstraintSolver());
    REQUIRE(solver != nullptr);
    const auto& cap = solver->contactWarmStartCap();
    REQUIRE(cap);
    const btScalar dt = btScalar(1.0 / 60.0);
    const double k = afb::bullet::methodPreset("default")->selfContactCap;
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
    afb::sim::Scene weightless(*afb::bullet::methodPreset("default"), {.gravityMps2 = 0, .ground = false});
    auto& w = weightless.spawn(RagdollAsset::create(humanoid), {.comeToRest = false});
    auto* wsolver = dynamic_cast<afb::bullet::RagdollSolver*>(weightless.world().getConstraintSolver());
    REQUIRE(wsolver != nullptr);
    btPersistentManifold wself(&w.body(0), &w.body(1), 0, btScalar(0.02), btScalar(0.02));
    CHECK(wsolver->contactWarmStartCap()(wself, dt) == Approx(k * weight).epsilon(1e-5));
    // and at the world's own when that is stronger (Doom's 27.1 m/s²).
    afb::sim::Scene heavy(*afb::bullet::methodPreset("default"), {.gravityMps2 = 27.1, .ground = false});
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

TEST_CASE("position tree 2: a body on the ground counts 100 times heavier, so the other one turns back",
          "[bullet][methods]") {
    // A flat box on the ground and a small cube hinged to it at both their centres (so the anchor holds whatever
    // either turns, and the limit is the only error), the cube turned past its stop about the hinge axis. The tree
    // step splits a turn about the axis by the bodies' inverse inertias about it, the box's divided by 100 because
    // it has contact points with the ground (shock propagation): the box turns e·(w_box/100)/(w_cube + w_box/100),
    // the cube the rest. Without the factor the box, much the easier to turn here, would take most of it.
    const std::vector<afb::test::TestJoint> joints = {{"origin", -1, 0, 0, 0}, {"cube", 0, 0, 0, 4}};
    const auto built = afb::test::buildTestFigure(
        "articulatedFigure t {\n settings { selfCollision 0 }\n"
        " body \"box\" { joint \"origin\" model box( ( -8, -8, -4 ), ( 8, 8, 4 ) ) origin ( 0, 0, 4 ) density 0.002 }\n"
        " body \"cube\" { joint \"cube\" model box( ( -2, -2, -2 ), ( 2, 2, 2 ) ) origin ( 0, 0, 4 ) density 0.5 }\n"
        " hinge \"h\" { body1 \"cube\" body2 \"box\" anchor ( 0, 0, 4 ) axis ( 0, 1, 0 ) friction 0 limit 0, 30, 0 "
        "}\n}\n",
        joints);
    INFO(built.diagnostics.str());
    REQUIRE(built.figure);
    afb::sim::Scene scene(methodWith("multipoint-contacts", "on"), {.gravityMps2 = 0});
    auto& r = scene.spawn(RagdollAsset::create(*built.figure), {.comeToRest = false});
    btRigidBody& box = r.body(0);
    btRigidBody& cube = r.body(1);
    REQUIRE(r.jointError(0).limitExcessRad == 0);
    btTransform t = cube.getCenterOfMassTransform();
    t.setRotation(btQuaternion(btVector3(0, 1, 0), btScalar(55 * kDeg)) * t.getRotation());
    cube.setCenterOfMassTransform(t);
    const double excess = r.jointError(0).limitExcessRad;
    REQUIRE(excess > 15 * kDeg);
    scene.world().performDiscreteCollisionDetection();
    btDispatcher* d = scene.world().getDispatcher();
    std::vector<btPersistentManifold*> held;
    for (int i = 0; i < d->getNumManifolds(); ++i)
        if (d->getManifoldByIndexInternal(i)->getNumContacts() > 0) held.push_back(d->getManifoldByIndexInternal(i));
    REQUIRE(held.size() == 1); // the box and the ground
    const btQuaternion box0 = box.getOrientation(), cube0 = cube.getOrientation();
    afb::bullet::detail::positionPass(r, 0, 2, held, btScalar(1.0 / 60.0), false);
    CHECK(r.jointError(0).limitExcessRad < 0.05 * kDeg);
    const double wBox = box.getInvInertiaDiagLocal().y(), wCube = cube.getInvInertiaDiagLocal().y();
    const double boxShare = (wBox / 100) / (wCube + wBox / 100);
    REQUIRE(wBox / (wCube + wBox) > 10 * boxShare); // the factor is what decides the split here
    const double boxTurn = box.getOrientation().angleShortestPath(box0);
    const double cubeTurn = cube.getOrientation().angleShortestPath(cube0);
    INFO("box turned " << boxTurn / kDeg << " deg, cube " << cubeTurn / kDeg << " deg of " << excess / kDeg);
    CHECK(boxTurn == Approx(excess * boxShare).epsilon(0.05));
    CHECK(cubeTurn == Approx(excess * (1 - boxShare)).epsilon(0.05));
}

TEST_CASE("speculative limits: a falling pendulum stops at its hinge limit", "[bullet][methods]") {
    // The arm falls from horizontal about the hinge (axis Y, φ > 0 turns it down) and meets the stop at
    // φ = 60° with ω = sqrt(2·m·g·c·sin 60° / I) ≈ 7.1 rad/s (c = 0.254 m to the centre of mass, I = m·L²/3
    // for a thin 0.508 m bar), i.e. about 6.8° per step at 60 Hz. A row created after the crossing lets the arm
    // pass the stop by a good part of one step; a speculative row stops it at the stop.
    const afb::figure::Figure f = armFigure("hinge \"h\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) "
                                            "axis ( 0, 1, 0 ) friction 0 limit 0, 120, 0 }");
    const double omega = std::sqrt(2 * 9.81 * 0.254 * std::sin(60 * kDeg) / (0.508 * 0.508 / 3));
    REQUIRE(omega == Approx(7.1).margin(0.1));
    auto overshootDeg = [&](const Method& method) {
        ArmScene s(f, method, 9.81);
        double worst = 0;
        for (int i = 0; i < 90; ++i) {
            s.scene.step(1.0 / 60.0);
            worst = std::max(worst, s.ragdoll->jointError(1).limitExcessRad / kDeg);
        }
        return worst;
    };
    const double plain = overshootDeg(legacy());
    CHECK(plain > 1.0);
    CHECK(plain < omega / 60 / kDeg * 1.5); // no more than about a step's travel
    const double speculative = overshootDeg(methodWith("speculative-limits", "on"));
    INFO("plain " << plain << " deg, speculative " << speculative << " deg");
    CHECK(speculative < 0.2 * plain);
    CHECK(speculative < 1.0);
}

TEST_CASE("multipoint and speculative contacts: a falling box stops at the ground", "[bullet][methods]") {
    // A 1 m drop reaches the ground at sqrt(2·g·h) = 4.4 m/s, 7.4 cm per step at 60 Hz. Bullet finds a contact
    // only within a few millimetres of the surface, and then one point of the flat face: the box lands on a
    // corner, tips and sinks by most of a step's travel. Multipoint contacts fill the face at first touch;
    // speculative contacts find it from a step away, so the box stops at the surface.
    const afb::figure::Figure boxFig = boxFigure();
    auto peakDepth = [&](const Method& method) {
        afb::sim::Scene scene(method);
        btTransform t = btTransform::getIdentity();
        t.setOrigin(btVector3(0, 0, btScalar(1.0 + 0.043))); // lowest point ~1 m up, 3 cm off the step grid
        scene.spawn(RagdollAsset::create(boxFig), {.entityTransform = t, .comeToRest = false});
        double worst = 0;
        for (int i = 0; i < 60; ++i) {
            scene.step(1.0 / 60.0);
            worst = std::max(worst, scene.deepestContact().depthM);
        }
        return worst;
    };
    Method both = methodWith("speculative-contacts", "on");
    both.multipointContacts = true;
    CHECK(peakDepth(legacy()) > 0.02);
    CHECK(peakDepth(methodWith("multipoint-contacts", "on")) > 0.01); // found too late, inside the ground
    CHECK(peakDepth(both) < 0.005);
}

TEST_CASE("speculative contacts: a box falling onto a box stops at its face", "[bullet][methods]") {
    // Bullet's box–box algorithm reports contacts only while two boxes overlap, so a widened contact breaking
    // threshold alone gave a box falling onto another no speculative point: it sank by up to a step's travel
    // (7.4 cm at 4.4 m/s) before its first contact. BoxBoxCollision adds the closest points while they are apart.
    const afb::figure::Figure boxFig = boxFigure();
    auto peakDepth = [&](const Method& method) {
        afb::sim::Scene scene(method);
        const auto asset = RagdollAsset::create(boxFig);
        Ragdoll& below = scene.spawn(asset, {.comeToRest = false});
        btTransform t = btTransform::getIdentity();
        // Lowest face ~1 m above the lower box's top (0.203 m), 3 cm off the step grid, turned 30° about the
        // vertical so that the faces' edges cross.
        t.setRotation(btQuaternion(btVector3(0, 0, 1), btScalar(30 * kDeg)));
        t.setOrigin(btVector3(0, 0, btScalar(0.203 + 1.0 + 0.043)));
        Ragdoll& above = scene.spawn(asset, {.entityTransform = t, .comeToRest = false});
        double worst = 0;
        for (int i = 0; i < 60; ++i) {
            scene.step(1.0 / 60.0);
            for (const double d : contactDistances(scene, &above.collisionObject(0), &below.collisionObject(0)))
                worst = std::max(worst, -d);
        }
        return worst;
    };
    Method both = methodWith("speculative-contacts", "on");
    both.multipointContacts = true;
    const double plain = peakDepth(legacy()), speculative = peakDepth(both);
    INFO("legacy " << plain * 1000 << " mm, speculative " << speculative * 1000 << " mm");
    CHECK(plain > 0.02);
    CHECK(speculative < 0.005);
}

TEST_CASE("speculative contacts: two boxes lying still 1 cm apart get no point between them", "[bullet][methods]") {
    // The box–box speculative points are made only when the boxes can close their gap within the step: points
    // between still boxes would take places in the manifold and, measured, kept a humanoid's feet from resting.
    const afb::figure::Figure boxFig = boxFigure();
    afb::sim::Scene scene(afb::bullet::Method{});
    const auto asset = RagdollAsset::create(boxFig);
    Ragdoll& a = scene.spawn(asset, {.comeToRest = false});
    btTransform t = btTransform::getIdentity();
    t.setOrigin(btVector3(btScalar(0.406 + 0.01), 0, 0)); // 1 cm beside the first (the boxes are 0.406 m wide)
    Ragdoll& b = scene.spawn(asset, {.entityTransform = t, .comeToRest = false});
    int points = 0;
    for (int i = 0; i < 60; ++i) {
        scene.step(1.0 / 60.0);
        points += static_cast<int>(contactDistances(scene, &a.collisionObject(0), &b.collisionObject(0)).size());
    }
    CHECK(points == 0);
    // Still apart: neither box moved toward the other.
    CHECK(b.body(0).getCenterOfMassPosition().x() - a.body(0).getCenterOfMassPosition().x() ==
          Approx(0.416).margin(0.002));
}

TEST_CASE("friction directions: a box on the ground pulled by a joint below its friction bound stays with two",
          "[bullet][methods]") {
    // Bullet's default friction is one row per contact point, along the point's sliding velocity before the solve,
    // or along an arbitrary tangent when it does not slide. A pull that arises inside the solve (here a joint's
    // motor drawing a resting box sideways with 30 % of what static friction can hold) is then met by friction
    // only in the steps after the box has started to slide along it: the box creeps. With both tangents
    // (Method::frictionDirections 2) static friction holds it where it lies.
    const afb::figure::Figure boxFig = boxFigure();
    auto slid = [&](int directions) {
        Method method = methodWith("multipoint-contacts", "on");
        method.frictionDirections = directions;
        afb::sim::Scene scene(method);
        auto& box = scene.spawn(RagdollAsset::create(boxFig), {.comeToRest = false});
        btRigidBody& body = box.body(0);
        body.setActivationState(DISABLE_DEACTIVATION);
        for (int i = 0; i < 30; ++i) scene.step(1.0 / 60.0); // settle on its four corners
        const btVector3 start = body.getCenterOfMassPosition();
        // Every axis free; a motor along x with a force bound of 0.3 of the friction bound μ·m·g (μ = 0.8).
        btGeneric6DofSpring2Constraint pull(body, btTransform::getIdentity());
        pull.setLinearLowerLimit(btVector3(1, 1, 1));
        pull.setLinearUpperLimit(btVector3(-1, -1, -1));
        pull.setAngularLowerLimit(btVector3(1, 1, 1));
        pull.setAngularUpperLimit(btVector3(-1, -1, -1));
        pull.enableMotor(0, true);
        pull.setTargetVelocity(0, 1);
        pull.setMaxMotorForce(0, btScalar(0.3 * 0.8 * 9.81) / body.getInvMass());
        scene.world().addConstraint(&pull);
        for (int i = 0; i < 60; ++i) scene.step(1.0 / 60.0);
        scene.world().removeConstraint(&pull);
        return double((body.getCenterOfMassPosition() - start).length());
    };
    const double one = slid(1), two = slid(2);
    INFO("one direction: " << one * 1000 << " mm, two: " << two * 1000 << " mm");
    CHECK(one > 0.005);
    CHECK(two < 0.0005);
}

TEST_CASE("vertex contacts: a box's manifold holds the corners it rests and rolls on", "[bullet][methods]") {
    // A 16 × 16 × 8-unit box (0.406 × 0.406 × 0.203 m). Lying flat on the ground, its four bottom corners are
    // the contact points, at distance 0. Tilted by 10° about X onto one bottom edge, the two corners of that edge
    // touch and the two of the far bottom edge are w·sin 10° = 70.5 mm up: with a speculative reach that long,
    // those are the next two points, so the solver can stop the box's roll onto its face.
    const afb::figure::Figure boxFig = boxFigure();
    const double half = 8 * kUnit, halfHeight = 4 * kUnit, tilt = 10 * kDeg;
    auto manifoldAt = [&](const btTransform& pose, btScalar reach) {
        afb::sim::Scene scene(methodWith("multipoint-contacts", "on"), {.gravityMps2 = 0});
        auto& r = scene.spawn(RagdollAsset::create(boxFig), {.comeToRest = false});
        r.body(0).setCenterOfMassTransform(pose);
        scene.world().performDiscreteCollisionDetection(); // creates the pair's manifold
        btDispatcher* d = scene.world().getDispatcher();
        REQUIRE(d->getNumManifolds() == 1);
        d->getManifoldByIndexInternal(0)->setContactBreakingThreshold(reach);
        scene.world().performDiscreteCollisionDetection();
        std::vector<std::pair<btVector3, double>> points; // (world point on the box, distance)
        const btPersistentManifold* m = d->getManifoldByIndexInternal(0);
        for (int i = 0; i < m->getNumContacts(); ++i)
            points.emplace_back(m->getContactPoint(i).getPositionWorldOnA(), m->getContactPoint(i).getDistance());
        return points;
    };
    SECTION("flat") {
        const auto points =
            manifoldAt(btTransform(btQuaternion::getIdentity(), btVector3(0, 0, btScalar(halfHeight))), btScalar(0.02));
        REQUIRE(points.size() == 4);
        for (const auto& [p, distance] : points) {
            CHECK(std::abs(distance) < 1e-5);
            CHECK(std::abs(std::abs(p.x()) - half) < 1e-5);
            CHECK(std::abs(std::abs(p.y()) - half) < 1e-5);
        }
    }
    SECTION("on an edge") {
        // Rotated about X by 10°: the bottom edge at y = −half (rotated) is lowest; place it on the ground.
        const btQuaternion q(btVector3(1, 0, 0), btScalar(tilt));
        const btMatrix3x3 r(q);
        const btVector3 lowest = r * btVector3(0, btScalar(-half), btScalar(-halfHeight));
        const auto points = manifoldAt(btTransform(q, btVector3(0, 0, -lowest.z())), btScalar(0.3));
        REQUIRE(points.size() == 4);
        int touching = 0, far = 0;
        for (const auto& [p, distance] : points) {
            if (std::abs(distance) < 1e-5) ++touching;
            else if (std::abs(distance - 2 * half * std::sin(tilt)) < 1e-5) ++far;
        }
        CHECK(touching == 2);
        CHECK(far == 2);
    }
}

TEST_CASE("vertex contacts: a hull holds each corner once, so an octahedron on an edge touches at both ends",
          "[bullet][methods]") {
    // An octahedron's vertices each join four faces, and a hull built from the face planes finds each vertex once
    // per triple of planes through it: four times. With the copies, the four-point manifold of a body lying on the
    // ground could be four copies of one corner (a bone lying on the ground was held at one point and rocked its far
    // end 2.4 cm into the ground). Turned 45° about X, the octahedron's lowest edge joins two vertices, both on the
    // ground, and the next vertices are h·cos 45° up, beyond a 2 cm reach: the manifold holds exactly those two.
    const auto asset = RagdollAsset::create(octahedronFigure());
    const auto* hull = dynamic_cast<const btConvexHullShape*>(asset->shape(0));
    REQUIRE(hull != nullptr);
    CHECK(hull->getNumPoints() == 6);
    for (int i = 0; i < hull->getNumPoints(); ++i)
        for (int k = i + 1; k < hull->getNumPoints(); ++k)
            CHECK((hull->getUnscaledPoints()[i] - hull->getUnscaledPoints()[k]).length() > 0.01);

    const double h = 8 * kUnit;
    afb::sim::Scene scene(methodWith("multipoint-contacts", "on"), {.gravityMps2 = 0});
    auto& r = scene.spawn(asset, {.comeToRest = false});
    const btQuaternion q(btVector3(1, 0, 0), btScalar(45 * kDeg));
    r.body(0).setCenterOfMassTransform(btTransform(q, btVector3(0, 0, btScalar(h * std::cos(45 * kDeg)))));
    scene.world().performDiscreteCollisionDetection();
    btDispatcher* d = scene.world().getDispatcher();
    REQUIRE(d->getNumManifolds() == 1);
    d->getManifoldByIndexInternal(0)->setContactBreakingThreshold(btScalar(0.02));
    scene.world().performDiscreteCollisionDetection();
    const btPersistentManifold* m = d->getManifoldByIndexInternal(0);
    REQUIRE(m->getNumContacts() == 2);
    const btVector3 a = m->getContactPoint(0).getPositionWorldOnA(), b = m->getContactPoint(1).getPositionWorldOnA();
    // Both ends of the edge, 2·h·sin 45° = 287 mm apart less what the margin rounds off the corners (the hull is
    // the polytope shrunk by the margin, then grown by a ball of it), each as high as the other, just above the
    // ground (the rounding lifts a corner by a few millimetres).
    CHECK((a - b).length() > 2 * h * std::sin(45 * kDeg) - 0.03);
    CHECK(std::abs(m->getContactPoint(0).getDistance() - m->getContactPoint(1).getDistance()) < 1e-5);
    for (int i = 0; i < 2; ++i) CHECK(std::abs(m->getContactPoint(i).getDistance()) < 0.005);
}

TEST_CASE("vertex contacts: a box slapping down onto its face stops at the ground", "[bullet][methods]") {
    // The box balanced on a bottom edge at 30°, turning onto its face at 40 rad/s: its far edge comes down at
    // about ω·w = 16 m/s, 27 cm per step at 60 Hz. At 30° the corners of the side face are nearer the ground
    // than those of the far edge, so only a choice that looks at where the corners go in this step keeps the
    // far edge among the manifold's four points and stops it at the ground.
    const afb::figure::Figure boxFig = boxFigure();
    auto peakDepth = [&](bool vertexContacts) {
        Method m = methodWith("speculative-contacts", "on");
        m.multipointContacts = vertexContacts;
        afb::sim::Scene scene(m);
        auto& r = scene.spawn(RagdollAsset::create(boxFig), {.comeToRest = false});
        const btQuaternion q(btVector3(1, 0, 0), btScalar(30 * kDeg));
        const btVector3 lowest = btMatrix3x3(q) * btVector3(0, btScalar(-8 * kUnit), btScalar(-4 * kUnit));
        r.body(0).setCenterOfMassTransform(btTransform(q, btVector3(0, 0, -lowest.z())));
        r.body(0).setAngularVelocity(btVector3(-40, 0, 0)); // turning the far (+y) edge down
        double worst = 0;
        for (int i = 0; i < 30; ++i) {
            scene.step(1.0 / 60.0);
            worst = std::max(worst, scene.deepestContact().depthM);
        }
        return worst;
    };
    const double bullet = peakDepth(false), vertex = peakDepth(true);
    INFO("Bullet's plane contacts " << bullet << " m, vertex contacts " << vertex << " m");
    CHECK(vertex < 0.005);
    CHECK(vertex < bullet);
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
