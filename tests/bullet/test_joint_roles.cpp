// What each joint type becomes in the rigid backend: its Bullet constraints in the order they enter the world, each
// with the role of its rows (Ragdoll::bulletConstraintRole), and the number of rows that keep the joint together
// against what figure::freedomOf says the joint type forbids. Built on a two-body arm hung from the world by a
// fixed mount, so the mount's constraint comes first.
#include <catch2/catch.hpp>

#include <string>
#include <vector>

#include "FigureFixture.h"
#include "afb/bullet/Method.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/figure/Vocabulary.h"
#include "afb/sim/Scene.h"

namespace {

using afb::bullet::Method;
using afb::bullet::RowRole;
using afb::figure::AnchorHold;
using afb::figure::JointType;
using afb::figure::RotationHold;

// The default method with fixed joints kept as constraints (the mount stays a Bullet constraint) and limits as
// their own constraints or inside Bullet's (`speculativeLimits`).
Method methodFor(bool speculativeLimits) {
    Method m;
    m.mergeFixed = false;
    m.speculativeLimits = speculativeLimits;
    return m;
}

struct Built {
    std::vector<RowRole> roles;
    std::vector<int> types; ///< Bullet's constraint types
    std::vector<int> rows;  ///< rows of each constraint in the spawn pose (getInfo1)
};

Built build(const std::string& constraint, bool speculativeLimits) {
    const auto figure = afb::test::buildArmFigure(constraint);
    INFO(figure.diagnostics.str());
    REQUIRE(figure.figure);
    afb::sim::Scene scene(methodFor(speculativeLimits), {.gravityMps2 = 0, .ground = false});
    afb::bullet::Ragdoll& r = scene.spawn(afb::bullet::RagdollAsset::create(*figure.figure), {.comeToRest = false});
    Built out;
    for (int k = 0; k < r.bulletConstraintCount(); ++k) {
        btTypedConstraint& c = r.bulletConstraint(k);
        out.roles.push_back(r.bulletConstraintRole(k));
        out.types.push_back(c.getConstraintType());
        btTypedConstraint::btConstraintInfo1 info{};
        c.getInfo1(&info);
        out.rows.push_back(info.m_numConstraintRows);
        CHECK(r.bulletConstraintIsLimit(k) == (out.roles.back() == RowRole::Limit));
    }
    return out;
}

// The rows that keep a joint of `type` together: three per shared point, two for a line, one per forbidden rotation.
int heldRows(JointType type) {
    const afb::figure::JointFreedom f = afb::figure::freedomOf(type);
    const int anchor = f.anchor == AnchorHold::Point ? 3 : f.anchor == AnchorHold::Line ? 2 : 0;
    const int rotation = f.rotation == RotationHold::All          ? 3
                         : f.rotation == RotationHold::AllButAxis ? 2
                         : f.rotation == RotationHold::Twist      ? 1
                                                                  : 0;
    return anchor + rotation;
}

const std::string kHinge = "hinge \"h\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) axis ( 0, 1, 0 ) "
                           "friction 0.2 limit 0, 120, 0 }";
const std::string kBallCone = "ballAndSocketJoint \"b\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) "
                              "friction 0.2 coneLimit ( 1, 0, 0 ), 60, ( 1, 0, 0 ) }";
const std::string kUniversalPyramid = "universalJoint \"u\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) "
                                      "shafts ( 1, 0, 0 ), ( -1, 0, 0 ) friction 0.2 "
                                      "pyramidLimit ( 1, 0, 0 ), 60, 40, 0 }";

} // namespace

TEST_CASE("joint builders: a joint's constraints enter the world as main, friction, limit, each with its role",
          "[bullet][joints]") {
    SECTION("hinge with a range and friction, speculative limits") {
        const Built b = build(kHinge, true);
        CHECK(b.roles == std::vector<RowRole>{RowRole::Joint, RowRole::Joint, RowRole::Friction, RowRole::Limit});
        CHECK(b.types[1] == HINGE_CONSTRAINT_TYPE);
        CHECK(b.rows[1] == heldRows(JointType::Hinge)); // the range is not in the hinge
    }
    SECTION("hinge with its range inside Bullet's hinge") {
        const Built b = build(kHinge, false);
        CHECK(b.roles == std::vector<RowRole>{RowRole::Joint, RowRole::Joint, RowRole::Friction});
        CHECK(b.types[1] == HINGE_CONSTRAINT_TYPE);
    }
    SECTION("ball with a cone: a point-to-point and a cone row of its own, or Bullet's cone-twist") {
        const Built speculative = build(kBallCone, true);
        CHECK(speculative.roles ==
              std::vector<RowRole>{RowRole::Joint, RowRole::Joint, RowRole::Friction, RowRole::Limit});
        CHECK(speculative.types[1] == POINT2POINT_CONSTRAINT_TYPE);
        CHECK(speculative.rows[1] == heldRows(JointType::BallAndSocket));
        const Built inside = build(kBallCone, false);
        CHECK(inside.roles == std::vector<RowRole>{RowRole::Joint, RowRole::Joint, RowRole::Friction});
        CHECK(inside.types[1] == CONETWIST_CONSTRAINT_TYPE);
    }
    SECTION("universal with a pyramid: the constant-velocity joint and a limit of its own") {
        const Built b = build(kUniversalPyramid, false); // pyramid limits are always rows of ours
        CHECK(b.roles == std::vector<RowRole>{RowRole::Joint, RowRole::Joint, RowRole::Friction, RowRole::Limit});
        CHECK(b.rows[1] == heldRows(JointType::Universal));
    }
    SECTION("the fixed mount holds every degree of freedom") {
        const Built b = build(kHinge, true);
        CHECK(b.types[0] == D6_SPRING_2_CONSTRAINT_TYPE); // btFixedConstraint
        CHECK(b.rows[0] == heldRows(JointType::Fixed));
    }
    SECTION("a spring's rows are a spring's, and it has no friction or limit") {
        const Built b = build("spring \"s\" { body1 \"arm\" body2 \"top\" anchor1 ( 0, 0, 100 ) anchor2 ( 0, 0, 104 ) "
                              "stretch 20 compress 10 damping 5 restLength 4 }",
                              true);
        CHECK(b.roles == std::vector<RowRole>{RowRole::Joint, RowRole::Spring});
    }
    SECTION("a slider is one constraint of joint rows") {
        const Built b = build("slider \"s\" { body1 \"arm\" body2 \"top\" axis ( 1, 0, -1 ) friction 0 }", true);
        CHECK(b.roles == std::vector<RowRole>{RowRole::Joint, RowRole::Joint});
        CHECK(b.types[1] == SLIDER_CONSTRAINT_TYPE);
    }
}

TEST_CASE("joint freedoms: every joint type forbids what its keyword means", "[bullet][joints]") {
    // Anchors: a point for every joint but the slider's line and the spring's none; rotations from none (ball) to
    // all (fixed, slider), as docs/format.md §4.2–§4.7 describe each type.
    CHECK(heldRows(JointType::Fixed) == 6);
    CHECK(heldRows(JointType::BallAndSocket) == 3);
    CHECK(heldRows(JointType::Universal) == 4);
    CHECK(heldRows(JointType::Hinge) == 5);
    CHECK(heldRows(JointType::Slider) == 5);
    CHECK(heldRows(JointType::Spring) == 0);
}
