// Block mode of the direct joint solve (Method::figureIterations, Method::figureSweeps): each iteration ends with
// the joints solved and the contact and limit rows that move whole ragdolls solved together.
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
        if (name != "default" && name != "exact") CHECK(afb::bullet::methodPreset(name)->figureIterations == 0);
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
