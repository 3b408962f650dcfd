#pragma once
// Shared by the method tests (test_methods.cpp, test_position_pass.cpp, test_contact_methods.cpp): small figures
// whose outcome is known, a scene holding one of them, and the `legacy` method with one technique switched on.
#include <catch2/catch.hpp>

#include <string>
#include <vector>

#include "FigureFixture.h"
#include "afb/bullet/Method.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/sim/Scene.h"

namespace afb::test::methods {

using afb::bullet::Method;
using afb::bullet::Ragdoll;
using afb::bullet::RagdollAsset;
constexpr double kDeg = 3.14159265358979323846 / 180.0;
constexpr double kUnit = 0.0254;

inline afb::figure::Figure armFigure(const std::string& constraint) {
    const auto built = afb::test::buildArmFigure(constraint);
    INFO(built.diagnostics.str());
    REQUIRE(built.figure);
    return *built.figure;
}

// A figure of one body of density 0.02 on the skeleton's origin joint: its `.af` model and origin as text.
inline afb::figure::Figure oneBodyFigure(const std::string& model, const std::string& origin) {
    const std::vector<afb::test::TestJoint> joints = {{"origin", -1, 0, 0, 0}};
    const auto built = afb::test::buildTestFigure("articulatedFigure one {\n body \"one\" { joint \"origin\" model " +
                                                      model + " origin " + origin + " density 0.02 }\n}\n",
                                                  joints);
    INFO(built.diagnostics.str());
    REQUIRE(built.figure);
    return *built.figure;
}

// One 16 × 16 × 8-unit box (0.406 × 0.406 × 0.203 m) with its lowest face at the entity's origin.
inline afb::figure::Figure boxFigure() { return oneBodyFigure("box( ( -8, -8, -4 ), ( 8, 8, 4 ) )", "( 0, 0, 4 )"); }

// A 16-unit octahedron (vertices ±8 units on each axis) with its lowest vertex at the entity's origin.
inline afb::figure::Figure octahedronFigure() {
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
inline Method legacy() { return *afb::bullet::methodPreset("legacy"); }

inline Method methodWith(const std::string& knob, const std::string& value) {
    Method m = legacy();
    const auto* k = afb::bullet::findKnob(knob);
    REQUIRE(k != nullptr);
    REQUIRE(afb::bullet::setKnob(m, *k, value).empty());
    return m;
}

// The signed distances of every contact point between `a` and `b` in the scene's manifolds now.
inline std::vector<double> contactDistances(afb::sim::Scene& scene, const btCollisionObject* a,
                                            const btCollisionObject* b) {
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

} // namespace afb::test::methods
