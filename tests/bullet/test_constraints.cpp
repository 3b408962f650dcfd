// Each constraint type and limit loaded against its limit in Bullet (docs/format.md §4): limits hold to within 1°,
// free directions move freely. Deterministic: fixed 60 Hz step, fixed insertion order, no randomness.
#include <catch2/catch.hpp>

#include <cmath>
#include <functional>
#include <memory>

#include "FigureFixture.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/detail/Constraints.h"
#include "afb/detail/Convert.h"
#include "afb/figure/Limits.h"
#include "afb/sim/Scene.h"

namespace {

using afb::bullet::Ragdoll;
using afb::bullet::RagdollAsset;
constexpr double kDeg = 3.14159265358979323846 / 180.0;
constexpr double kUnit = 0.0254;

// A world with gravity `g` holding one ragdoll of `figure` at the identity entity transform.
struct Scene {
    afb::sim::Scene scene{afb::bullet::Method{}, {.gravityMps2 = 0, .ground = false}};
    Ragdoll* ragdoll = nullptr;

    Scene(const afb::figure::Figure& figure, const btVector3& g) {
        scene.world().setGravity(g);
        // Rest rules off: these tests load limits, they do not wait for the figure to sleep.
        ragdoll = &scene.spawn(RagdollAsset::create(figure), afb::bullet::SpawnOptions{.comeToRest = false});
        for (int i = 0; i < ragdoll->bodyCount(); ++i) ragdoll->body(i).setActivationState(DISABLE_DEACTIVATION);
    }
    void run(double seconds, const std::function<void()>& beforeStep = {}) {
        for (int i = 0, n = static_cast<int>(std::lround(seconds * 60)); i < n; ++i) {
            if (beforeStep) beforeStep();
            scene.step(1.0 / 60.0);
        }
    }
    btMatrix3x3 rotation(int body) const { return ragdoll->body(body).getCenterOfMassTransform().getBasis(); }
    btVector3 position(int body) const { return ragdoll->body(body).getCenterOfMassPosition(); }
    // Rotation of body 1 (arm) relative to body 0 (top); both start with identity rotations.
    btMatrix3x3 relative() const { return rotation(0).transpose() * rotation(1); }
};

// Skeleton: origin, top, arm (identity orientations). The arm is a 20-unit box along +X from the anchor.
const std::vector<afb::test::TestJoint> kJoints = {{"origin", -1, 0, 0, 0},
                                                   {"top", 0, 0, 0, 104},
                                                   {"arm", 1, 0, 0, 100}};

std::string figureWith(const std::string& constraint,
                       const std::string& topMount = "fixed \"mount\" { body1 \"top\" body2 \"world\" }") {
    return "articulatedFigure t {\n"
           " settings { selfCollision 0 }\n"
           " body \"top\" { joint \"origin\" model box( ( -4, -4, -4 ), ( 4, 4, 4 ) ) origin ( 0, 0, 104 ) density 0.1 "
           "}\n"
           " body \"arm\" { joint \"arm\" model box( ( 0, -1, -1 ), ( 20, 1, 1 ) ) origin ( 0, 0, 100 ) density 0.2 }\n"
           " " +
           topMount + "\n " + constraint + "\n}\n";
}

afb::figure::Figure build(const std::string& text) {
    auto built = afb::test::buildTestFigure(text, kJoints);
    INFO(built.diagnostics.str());
    REQUIRE(built.figure);
    return *built.figure;
}

double angleBetween(const btVector3& a, const btVector3& b) {
    return std::acos(std::clamp(static_cast<double>(a.normalized().dot(b.normalized())), -1.0, 1.0));
}

} // namespace

TEST_CASE("hinge: the limit range is the spec's, centred and off-centre", "[bullet][constraints]") {
    struct Case {
        const char* limit;
        double gravityZ;
        double expectDeg; // φ at rest against the limit
    };
    // docs/format.md §4.5: φ ∈ [a2 − a0 − a1/2, a2 − a0 + a1/2]; rotation about +Y by +φ turns the arm's +X down.
    const Case cases[] = {{"0, 90, 0", -9.81, 45},
                          {"0, 90, 0", 9.81, -45},
                          {"30, 90, 0", -9.81, 15},
                          {"30, 90, 0", 9.81, -75},
                          {"0, 60, 20", -9.81, 50}};
    for (const Case& c : cases) {
        DYNAMIC_SECTION("limit " << c.limit << " gravity z " << c.gravityZ) {
            Scene scene(build(figureWith(std::string("hinge \"h\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) "
                                                     "axis ( 0, 1, 0 ) friction 0 limit ") +
                                         c.limit + " }")),
                        btVector3(0, 0, btScalar(c.gravityZ)));
            scene.run(2.0);
            const btMatrix3x3 r = scene.relative();
            const double phi = std::atan2(r[0][2], r[0][0]) / kDeg;
            CHECK(phi == Approx(c.expectDeg).margin(1.0));
            // The hinge keeps the axis: no rotation out of the XZ plane.
            CHECK(std::abs(r[1][1] - 1.0) < 1e-3);
        }
    }
}

TEST_CASE("hinge: free inside its range", "[bullet][constraints]") {
    Scene scene(build(figureWith("hinge \"h\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) axis ( 0, 1, 0 ) "
                                 "friction 0 limit 0, 160, 0 }")),
                btVector3(0, 0, -9.81f));
    scene.run(0.25);
    const btMatrix3x3 r = scene.relative();
    const double phi = std::atan2(r[0][2], r[0][0]) / kDeg;
    CHECK(phi > 20); // fell freely under gravity, well before the 80° stop
}

TEST_CASE("ballAndSocketJoint cone limit: shaft within half the apex angle, twist free", "[bullet][constraints]") {
    const std::string cone = "ballAndSocketJoint \"b\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) friction 0 "
                             "coneLimit ( 1, 0, 0 ), 60, ( 1, 0, 0 ) }";
    SECTION("gravity loads it") {
        Scene scene(build(figureWith(cone)), btVector3(0, 0, -9.81f));
        scene.run(2.0);
        const double deg = angleBetween(scene.rotation(1).getColumn(0), scene.rotation(0).getColumn(0)) / kDeg;
        CHECK(deg == Approx(30).margin(1.0));
        // The anchor holds: the arm's end at the anchor stays there.
        const btVector3 anchor = scene.ragdoll->body(1).getCenterOfMassTransform() *
                                 afb::bullet::toBt(scene.ragdoll->figure().constraints[1].frameInBody1.position);
        CHECK((anchor - btVector3(0, 0, btScalar(100 * kUnit))).length() < 0.005);
    }
    SECTION("twist about the shaft is free") {
        Scene scene(build(figureWith(cone)), btVector3(0, 0, 0));
        scene.ragdoll->body(1).setAngularVelocity(btVector3(2, 0, 0));
        scene.run(0.5);
        const btMatrix3x3 r = scene.relative();
        const double twist = std::atan2(r[2][1], r[1][1]);
        CHECK(std::abs(twist) > 0.5);
    }
}

TEST_CASE("ballAndSocketJoint pyramid limit: a true pyramid, corners included", "[bullet][constraints]") {
    // f = +X, l = +Y, u = +Z (roll 0): |angle toward Y| ≤ 30°, |angle toward Z| ≤ 20° (docs/format.md §4.3).
    const std::string pyramid = "ballAndSocketJoint \"b\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) "
                                "friction 0 pyramidLimit ( 1, 0, 0 ), 60, 40, 0, ( 1, 0, 0 ) }";
    auto planar = [](const Scene& s) {
        const btVector3 shaft = s.relative().getColumn(0);
        return std::pair{std::atan2(shaft.y(), shaft.x()) / kDeg, std::atan2(shaft.z(), shaft.x()) / kDeg};
    };
    SECTION("one face") {
        Scene scene(build(figureWith(pyramid)), btVector3(0, 0, -9.81f));
        scene.run(2.0);
        const auto [toL, toU] = planar(scene);
        CHECK(toU == Approx(-20).margin(1.0));
        CHECK(std::abs(toL) < 1.0);
    }
    SECTION("the corner: both planar angles at their limits (an elliptical cone would cut it)") {
        Scene scene(build(figureWith(pyramid)), btVector3(0, -6.9f, -6.9f));
        scene.run(3.0);
        const auto [toL, toU] = planar(scene);
        CHECK(toL == Approx(-30).margin(1.0));
        CHECK(toU == Approx(-20).margin(1.0));
        // The corner's direction is 34.1° from the axis; an ellipse through (30°, 20°) reaches only about 24°.
        const double fromAxis = angleBetween(scene.relative().getColumn(0), btVector3(1, 0, 0)) / kDeg;
        CHECK(fromAxis == Approx(std::atan(std::hypot(std::tan(30 * kDeg), std::tan(20 * kDeg))) / kDeg).margin(1.0));
    }
    SECTION("rolled pyramid: roll 90 swaps the two openings") {
        Scene scene(build(figureWith("ballAndSocketJoint \"b\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) "
                                     "friction 0 pyramidLimit ( 1, 0, 0 ), 60, 40, 90, ( 1, 0, 0 ) }")),
                    btVector3(0, 0, -9.81f));
        scene.run(2.0);
        const auto [toL, toU] = planar(scene);
        CHECK(toU == Approx(-30).margin(1.0));
    }
}

TEST_CASE("direction limit rows: their excess is figure::limitExcessRad's, cone and pyramid", "[bullet][constraints]") {
    // The solver's rows compute the excess in btScalar for their Jacobians; the figure's one definition must
    // agree.
    using afb::bullet::DirectionLimitConstraint;
    using Eigen::AngleAxisd;
    using Eigen::Matrix3d;
    using Eigen::Vector3d;
    btSphereShape sphere(1);
    btRigidBody a(btRigidBody::btRigidBodyConstructionInfo(1, nullptr, &sphere, btVector3(1, 1, 1)));
    btRigidBody b(btRigidBody::btRigidBodyConstructionInfo(1, nullptr, &sphere, btVector3(1, 1, 1)));
    const Vector3d shaft = Vector3d(0.2, 1, -0.3).normalized();
    const Matrix3d basis = AngleAxisd(0.7, Vector3d(1, -2, 0.5).normalized()).matrix(); // f, l, u in body b
    afb::figure::FigureConstraint cone, pyramid;
    cone.limit = afb::figure::ConeLimit{basis.col(0), shaft, 25 * kDeg};
    pyramid.limit = afb::figure::PyramidLimit{basis, shaft, 30 * kDeg, 20 * kDeg};
    DirectionLimitConstraint coneRows(a, b, afb::bullet::toBt(shaft), afb::bullet::toBt(basis),
                                      DirectionLimitConstraint::Shape::Cone, btScalar(25 * kDeg), 0);
    DirectionLimitConstraint pyramidRows(a, b, afb::bullet::toBt(shaft), afb::bullet::toBt(basis),
                                         DirectionLimitConstraint::Shape::Pyramid, btScalar(30 * kDeg),
                                         btScalar(20 * kDeg));
    const double tolerance = sizeof(btScalar) == sizeof(double) ? 1e-9 : 1e-4;
    int exceeded = 0;
    for (int i = 0; i < 24; ++i) {
        const Matrix3d ra = AngleAxisd(0.37 * i, Vector3d(std::sin(i), 1, std::cos(2.0 * i)).normalized()).matrix();
        const Matrix3d rb = AngleAxisd(-0.21 * i, Vector3d(1, std::cos(i), 0.5).normalized()).matrix();
        a.setCenterOfMassTransform(btTransform(afb::bullet::toBt(ra)));
        b.setCenterOfMassTransform(btTransform(afb::bullet::toBt(rb)));
        INFO("pose " << i);
        CHECK(double(coneRows.violation()) == Approx(afb::figure::limitExcessRad(cone, ra, rb)).margin(tolerance));
        CHECK(double(pyramidRows.violation()) ==
              Approx(afb::figure::limitExcessRad(pyramid, ra, rb)).margin(tolerance));
        if (afb::figure::limitExcessRad(pyramid, ra, rb) > 0) ++exceeded;
    }
    CHECK(exceeded > 6); // the poses test the excess, not only the inside
}

TEST_CASE("universalJoint: cone limit on shaft 1, no relative spin, spin is transmitted", "[bullet][constraints]") {
    const std::string universal = "universalJoint \"u\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) "
                                  "shafts ( 1, 0, 0 ), ( -1, 0, 0 ) friction 0 coneLimit ( 1, 0, 0 ), 60 }";
    SECTION("gravity loads the cone limit") {
        Scene scene(build(figureWith(universal)), btVector3(0, 0, -9.81f));
        scene.run(2.0);
        const double deg = angleBetween(scene.rotation(1).getColumn(0), scene.rotation(0).getColumn(0)) / kDeg;
        CHECK(deg == Approx(30).margin(1.0));
    }
    SECTION("pyramid limit on shaft 1") {
        Scene scene(build(figureWith(
                        "universalJoint \"u\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) "
                        "shafts ( 1, 0, 0 ), ( -1, 0, 0 ) friction 0 pyramidLimit ( 1, 0, 0 ), 60, 40, 0 }")),
                    btVector3(0, 0, -9.81f));
        scene.run(2.0);
        const btVector3 shaft = scene.relative().getColumn(0);
        CHECK(std::atan2(shaft.z(), shaft.x()) / kDeg == Approx(-20).margin(1.0));
    }
    SECTION("spin about the shafts is transmitted; swing is free") {
        // The top may only spin about X (a hinge to the world); the arm is driven about X.
        const std::string mount =
            "hinge \"mount\" { body1 \"top\" body2 \"world\" anchor ( 0, 0, 104 ) axis ( 1, 0, 0 ) friction 0 }";
        Scene scene(build(figureWith("universalJoint \"u\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) "
                                     "shafts ( 1, 0, 0 ), ( -1, 0, 0 ) friction 0 }",
                                     mount)),
                    btVector3(0, 0, 0));
        // Drive the arm with a torque about the shaft and one about Z (a swing).
        scene.run(1.0, [&] { scene.ragdoll->body(1).applyTorque(btVector3(1, 0, btScalar(0.1))); });
        const btMatrix3x3 top = scene.rotation(0);
        const double topSpin = std::atan2(top[2][1], top[1][1]);
        CHECK(std::abs(topSpin) > 0.5); // the top turned with the arm
        // Relative rotation is a pure swing (no twist about the shaft): swing-twist decomposition.
        const btMatrix3x3 r = scene.relative();
        btQuaternion q;
        r.getRotation(q);
        const btVector3 shaft(1, 0, 0);
        const btScalar twistAngle = btScalar(2) * btAtan2(q.getAxis().dot(shaft) * btSin(q.getAngle() / 2), q.getW());
        CHECK(std::abs(twistAngle) < 1.0 * kDeg);
        CHECK(angleBetween(r.getColumn(0), shaft) > 5 * kDeg); // it swung
    }
}

TEST_CASE("universalJoint: a constant-velocity constraint whose twist row always exists (cone-twist in legacy)",
          "[bullet][constraints]") {
    SECTION("the twist: zero after any swing, the turn about the shafts without one; always four rows") {
        btBoxShape box(btVector3(0.1f, 0.1f, 0.1f));
        btRigidBody a(1, nullptr, &box), b(1, nullptr, &box);
        afb::bullet::UniversalConstraint c(a, b, btTransform::getIdentity(), btTransform::getIdentity());
        for (const btVector3& axis : {btVector3(0, 1, 0), btVector3(0, 0, 1), btVector3(0, 1, 1).normalized()})
            for (const double deg : {0.0, 30.0, 60.0, 100.0}) {
                a.setCenterOfMassTransform(btTransform(btQuaternion(axis, btScalar(deg * kDeg))));
                CHECK(std::abs(double(c.twist())) < 1e-5);
            }
        a.setCenterOfMassTransform(btTransform(btQuaternion(btVector3(1, 0, 0), btScalar(10 * kDeg))));
        CHECK(double(c.twist()) == Approx(10 * kDeg).margin(1e-5));
        // Both bodies turned alike: no twist.
        const btQuaternion common(btVector3(1, 2, 3).normalized(), 1.1f);
        a.setCenterOfMassTransform(btTransform(common * btQuaternion(btVector3(0, 0, 1), btScalar(50 * kDeg))));
        b.setCenterOfMassTransform(btTransform(common));
        CHECK(std::abs(double(c.twist())) < 1e-5);
        // Aligned frames (where btConeTwistConstraint with a zero twist span has no twist row): four rows.
        a.setCenterOfMassTransform(btTransform::getIdentity());
        b.setCenterOfMassTransform(btTransform::getIdentity());
        btTypedConstraint::btConstraintInfo1 info;
        c.getInfo1(&info);
        CHECK(info.m_numConstraintRows == 4);
    }
    SECTION("bent 30° under gravity, a torque about the arm's shaft does not twist it") {
        Scene scene(build(figureWith("universalJoint \"u\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) "
                                     "shafts ( 1, 0, 0 ), ( -1, 0, 0 ) friction 0 coneLimit ( 1, 0, 0 ), 60 }")),
                    btVector3(0, 0, -9.81f));
        // Both bodies start unrotated, so the frames (X: the shafts) are the bodies' own axes.
        const afb::bullet::UniversalConstraint probe(scene.ragdoll->body(1), scene.ragdoll->body(0),
                                                     btTransform::getIdentity(), btTransform::getIdentity());
        double worst = 0;
        scene.run(2.0, [&] {
            const btVector3 shaft = scene.rotation(1).getColumn(0);
            scene.ragdoll->body(1).applyTorque(shaft * btScalar(0.5));
            worst = std::max(worst, std::abs(double(probe.twist())));
        });
        const double bent = angleBetween(scene.rotation(1).getColumn(0), scene.rotation(0).getColumn(0)) / kDeg;
        CHECK(bent == Approx(30).margin(1.0)); // hanging on its cone limit
        CHECK(worst < 0.5 * kDeg);
    }
    SECTION("legacy keeps Bullet's btConeTwistConstraint") {
        const afb::figure::Figure figure = build(figureWith("universalJoint \"u\" { body1 \"arm\" body2 \"top\" "
                                                            "anchor ( 0, 0, 100 ) shafts ( 1, 0, 0 ), ( -1, 0, 0 ) }"));
        auto coneTwists = [&](const afb::bullet::Method& method) {
            afb::sim::Scene scene{method, {.gravityMps2 = 0, .ground = false}};
            const Ragdoll& r = scene.spawn(RagdollAsset::create(figure), afb::bullet::SpawnOptions{});
            int n = 0;
            for (int k = 0; k < r.bulletConstraintCount(); ++k)
                n += r.bulletConstraint(k).getConstraintType() == CONETWIST_CONSTRAINT_TYPE ? 1 : 0;
            return n;
        };
        CHECK(coneTwists(*afb::bullet::methodPreset("default")) == 0);
        CHECK(coneTwists(*afb::bullet::methodPreset("legacy")) == 1);
    }
}

TEST_CASE("slider: translation along the axis only", "[bullet][constraints]") {
    Scene scene(build(figureWith("slider \"s\" { body1 \"arm\" body2 \"top\" axis ( 1, 0, 0 ) }")),
                btVector3(2, 0, -9.81f));
    const btVector3 start = scene.position(1);
    scene.run(1.0);
    const btVector3 moved = scene.position(1) - start;
    CHECK(moved.x() > 0.5);             // slid ~1 m along +X under 2 m/s²
    CHECK(std::abs(moved.z()) < 0.005); // did not drop
    CHECK(std::abs(moved.y()) < 0.005);
    CHECK(angleBetween(scene.rotation(1).getColumn(0), btVector3(1, 0, 0)) < 1 * kDeg);
}

TEST_CASE("fixed: the relative pose holds under load", "[bullet][constraints]") {
    Scene scene(build(figureWith("fixed \"f\" { body1 \"arm\" body2 \"top\" }")), btVector3(0, 0, -9.81f));
    const btVector3 start = scene.position(1);
    scene.run(2.0);
    CHECK((scene.position(1) - start).length() < 0.005);
    CHECK(angleBetween(scene.relative().getColumn(0), btVector3(1, 0, 0)) < 1 * kDeg);
}

TEST_CASE("spring: quadratic force settles where k·ΔL² = m·g / maxLength holds", "[bullet][constraints]") {
    // The arm hangs from the top by a spring at its centre of mass (10, 0, 100) to (10, 0, 110): rest 10 units.
    auto springFigure = [](const std::string& extra) {
        return "articulatedFigure t {\n settings { selfCollision 0 }\n"
               " body \"top\" { joint \"origin\" model box( ( -4, -4, -4 ), ( 4, 4, 4 ) ) origin ( 0, 0, 104 ) density "
               "0.1 }\n"
               " body \"arm\" { joint \"arm\" model box( ( 0, -1, -1 ), ( 20, 1, 1 ) ) origin ( 0, 0, 100 ) density "
               "0.2 "
               "friction 0.1, 0.1, 0.5 }\n"
               " fixed \"mount\" { body1 \"top\" body2 \"world\" }\n"
               " slider \"guide\" { body1 \"arm\" body2 \"world\" axis ( 0, 0, 1 ) }\n"
               " spring \"s\" { body1 \"arm\" body2 \"top\" anchor1 ( 10, 0, 100 ) anchor2 ( 10, 0, 110 ) "
               "stretch 120 compress 120 damping 0 restLength 10 " +
               extra + " }\n}\n";
    };
    SECTION("equilibrium") {
        const afb::figure::Figure f = build(springFigure(""));
        Scene scene(f, btVector3(0, 0, -9.81f));
        scene.run(5.0);
        const double mass = f.bodies[1].massKg; // 80 in³ × 0.2 = 16
        const double k = 120.0 / kUnit;         // N/m² (F = k ΔL², §4.7)
        const double expected = 10 * kUnit + std::sqrt(mass * 9.81 / k);
        const double length = (btVector3(btScalar(10 * kUnit), 0, btScalar(110 * kUnit)) - scene.position(1)).length();
        CHECK(mass == Approx(16.0));
        CHECK(length == Approx(expected).epsilon(0.005));
    }
    SECTION("maxLength row") {
        Scene scene(build(springFigure("minLength 0 maxLength 12")), btVector3(0, 0, -9.81f));
        scene.run(3.0);
        const double length = (btVector3(btScalar(10 * kUnit), 0, btScalar(110 * kUnit)) - scene.position(1)).length();
        CHECK(length < 12 * kUnit + 0.002);
    }
}
