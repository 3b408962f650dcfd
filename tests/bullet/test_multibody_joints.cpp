// What each joint type becomes in the multibody backend (MultibodyJoints.h): the link that carries the arm and the
// roles of the rows the joint adds beside it, in the order they enter the world. Built on the two-body arm hung from
// the world by a fixed mount, so the mount makes the top box a fixed base and the joint under test is its one link
// (a joint that holds no anchor, a spring, makes the arm a tree of its own).
#include <catch2/catch.hpp>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <BulletDynamics/Featherstone/btMultiBody.h>

#include "FigureFixture.h"
#include "afb/bullet/Method.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/sim/Scene.h"
#include "bullet/Multibody.h"

namespace {

using afb::bullet::RowRole;
using afb::bullet::detail::MultibodyRagdoll;

constexpr int kArm = 1; // the figure's bodies: "top" (the origin body), then "arm"

struct Built {
    int parts = 0;
    int links = 0;                ///< links of the first tree (the top box's)
    int linkType = -1;            ///< btMultibodyLink::eFeatherstoneJointType of its link 0
    btVector3 axisWorld{0, 0, 0}; ///< link 0's revolute or prismatic axis, world
    std::vector<RowRole> roles;   ///< MultibodyRagdoll::rowRoles
};

Built build(const std::string& constraints) {
    const auto figure = afb::test::buildArmFigure(constraints);
    INFO(figure.diagnostics.str());
    REQUIRE(figure.figure);
    const afb::bullet::Method method = *afb::bullet::methodPreset("multibody");
    afb::sim::Scene scene(method, {.gravityMps2 = 0, .ground = false});
    afb::bullet::SpawnOptions options;
    options.method = method;
    options.comeToRest = false;
    const MultibodyRagdoll r(afb::bullet::RagdollAsset::create(*figure.figure), scene.world(), options);
    Built out;
    out.parts = r.partCount();
    out.roles = r.rowRoles();
    btMultiBody& tree = const_cast<MultibodyRagdoll&>(r).part(0);
    out.links = tree.getNumLinks();
    if (out.links > 0) {
        const btMultibodyLink& link = tree.getLink(0);
        out.linkType = link.m_jointType;
        const btMatrix3x3 armToWorld = r.collider(kArm).getWorldTransform().getBasis();
        out.axisWorld =
            armToWorld * (link.m_jointType == btMultibodyLink::ePrismatic ? link.getAxisBottom(0) : link.getAxisTop(0));
    }
    return out;
}

// |cos| of the angle between two directions: 1 when parallel either way.
double alignment(const btVector3& a, const btVector3& b) {
    return std::abs(static_cast<double>(a.normalized().dot(b.normalized())));
}

const std::string kHinge = "hinge \"h\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) axis ( 0, 1, 0 ) "
                           "friction 0.2 limit 0, 120, 0 }";

} // namespace

TEST_CASE("multibody joint builders: each joint type's link and the roles of its rows", "[bullet][multibody][joints]") {
    SECTION("hinge: a revolute link about the hinge axis, its friction row and its range") {
        const Built b = build(kHinge);
        CHECK(b.parts == 1);
        CHECK(b.links == 1);
        CHECK(b.linkType == btMultibodyLink::eRevolute);
        CHECK(alignment(b.axisWorld, btVector3(0, 1, 0)) > 0.9999);
        CHECK(b.roles == std::vector<RowRole>{RowRole::Friction, RowRole::Limit});
    }
    SECTION("ball with a cone: a spherical link, three friction rows and the cone") {
        const Built b = build("ballAndSocketJoint \"b\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) "
                              "friction 0.2 coneLimit ( 1, 0, 0 ), 60, ( 1, 0, 0 ) }");
        CHECK(b.linkType == btMultibodyLink::eSpherical);
        CHECK(b.roles == std::vector<RowRole>{RowRole::Friction, RowRole::Limit});
    }
    SECTION("universal: a spherical link whose twist a joint row holds, after every joint's own rows") {
        const Built b = build("universalJoint \"u\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) "
                              "shafts ( 1, 0, 0 ), ( -1, 0, 0 ) friction 0.2 pyramidLimit ( 1, 0, 0 ), 60, 40, 0 }");
        CHECK(b.linkType == btMultibodyLink::eSpherical);
        CHECK(b.roles == std::vector<RowRole>{RowRole::Friction, RowRole::Limit, RowRole::Joint});
    }
    SECTION("slider: a prismatic link along the slider's axis, no rows of its own") {
        const Built b = build("slider \"s\" { body1 \"arm\" body2 \"top\" axis ( 1, 0, -1 ) friction 0 }");
        CHECK(b.linkType == btMultibodyLink::ePrismatic);
        CHECK(alignment(b.axisWorld, btVector3(1, 0, -1)) > 0.9999);
        CHECK(b.roles.empty());
    }
    SECTION("fixed: a fixed link") {
        const Built b = build("fixed \"f\" { body1 \"arm\" body2 \"top\" }");
        CHECK(b.linkType == btMultibodyLink::eFixed);
        CHECK(b.roles.empty());
    }
    SECTION("spring: no link, the arm a tree of its own, and a spring's rows") {
        const Built b = build("spring \"s\" { body1 \"arm\" body2 \"top\" anchor1 ( 0, 0, 100 ) anchor2 ( 0, 0, 104 ) "
                              "stretch 20 compress 10 damping 5 restLength 4 }");
        CHECK(b.parts == 2);
        CHECK(b.links == 0);
        CHECK(b.roles == std::vector<RowRole>{RowRole::Spring});
    }
    SECTION("a second joint between the same bodies is a loop: a joint constraint, with its friction first") {
        const Built b = build(kHinge + "\n ballAndSocketJoint \"b\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) "
                                       "friction 0.2 }");
        CHECK(b.links == 1);
        CHECK(b.linkType == btMultibodyLink::eRevolute);
        CHECK(b.roles == std::vector<RowRole>{RowRole::Friction, RowRole::Limit, RowRole::Friction, RowRole::Joint});
    }
}
