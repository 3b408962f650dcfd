// Contact and limit techniques beyond Bullet's defaults: speculative limits and contacts, multipoint (vertex)
// contacts, two friction directions, each on a case whose outcome is known. Deterministic: fixed 60 Hz step,
// fixed insertion order.
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
