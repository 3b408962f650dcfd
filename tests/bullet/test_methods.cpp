// Methods (bullet::Method) and the techniques beyond Bullet's defaults, each on a case whose outcome is known:
// the knob table and presets, the position pass closing a separated joint, speculative limits stopping a
// pendulum at its stop, speculative contacts stopping a falling box at the ground, and equal iterations keeping
// a light body on the ground under a heavy one. Deterministic: fixed 60 Hz step, fixed insertion order.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>

#include "FigureFixture.h"
#include "afb/bullet/Convert.h"
#include "afb/bullet/Method.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/sim/Report.h"
#include "afb/sim/Scene.h"

namespace {

using afb::bullet::Method;
using afb::bullet::Ragdoll;
using afb::bullet::RagdollAsset;
constexpr double kDeg = 3.14159265358979323846 / 180.0;
constexpr double kUnit = 0.0254;

// Skeleton: origin, top, arm (identity orientations). The arm is a 20-unit box along +X from the anchor.
const std::vector<afb::test::TestJoint> kJoints = {{"origin", -1, 0, 0, 0},
                                                   {"top", 0, 0, 0, 104},
                                                   {"arm", 1, 0, 0, 100}};

afb::figure::Figure armFigure(const std::string& constraint) {
    const std::string text =
        "articulatedFigure t {\n settings { selfCollision 0 }\n"
        " body \"top\" { joint \"origin\" model box( ( -4, -4, -4 ), ( 4, 4, 4 ) ) origin ( 0, 0, "
        "104 ) density 0.1 }\n"
        " body \"arm\" { joint \"arm\" model box( ( 0, -1, -1 ), ( 20, 1, 1 ) ) origin ( 0, 0, 100 ) "
        "density 0.2 }\n"
        " fixed \"mount\" { body1 \"top\" body2 \"world\" }\n " +
        constraint + "\n}\n";
    const auto built = afb::test::buildTestFigure(text, kJoints);
    INFO(built.diagnostics.str());
    REQUIRE(built.figure);
    return *built.figure;
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

} // namespace

TEST_CASE("methods: presets, knobs and their text form", "[bullet][methods]") {
    for (std::string_view name : afb::bullet::methodPresetNames()) {
        const auto m = afb::bullet::methodPreset(name);
        REQUIRE(m);
        CHECK(m->name == name);
    }
    CHECK_FALSE(afb::bullet::methodPreset("fastest"));
    CHECK(*afb::bullet::methodPreset("default") == Method{});

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
    const std::vector<afb::test::TestJoint> joints = {{"origin", -1, 0, 0, 0}};
    const auto built = afb::test::buildTestFigure("articulatedFigure box {\n body \"box\" { joint \"origin\" model "
                                                  "box( ( -8, -8, -4 ), ( 8, 8, 4 ) ) origin ( 0, "
                                                  "0, 4 ) density 0.02 }\n}\n",
                                                  joints);
    REQUIRE(built.figure);
    auto peakDepth = [&](const Method& method) {
        afb::sim::Scene scene(method);
        btTransform t = btTransform::getIdentity();
        t.setOrigin(btVector3(0, 0, btScalar(1.0 + 0.043))); // lowest point ~1 m up, 3 cm off the step grid
        scene.spawn(RagdollAsset::create(*built.figure), {.entityTransform = t, .comeToRest = false});
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
