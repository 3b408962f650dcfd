// The position pass (Method::positionIterations, positionTree, positionVelocity): separated joints closed, a
// motion it takes back taken out of the velocity, the tree step over a chain, limits and contacts. Deterministic:
// fixed 60 Hz step, fixed insertion order.
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
