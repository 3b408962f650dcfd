// Mass and inertia stabilisation (figure/Stabilize.h): closed-form redistributions on hand-made figures.
#include <catch2/catch.hpp>

#include "afb/figure/Stabilize.h"
#include "afb/sim/Stress.h"

using namespace afb;

namespace {

// A chain of bodies with the given masses (moments 1, 2, 3 times the mass), each joined to the previous one: the
// stress matrix's generated chain, cut to length.
figure::Figure chain(const std::vector<double>& masses) {
    figure::Figure f = *sim::findStressScenario("chain-mass-1")->build({})->figures.begin();
    REQUIRE(f.bodies.size() >= masses.size());
    f.bodies.resize(masses.size());
    f.constraints.resize(masses.size() - 1);
    for (std::size_t i = 0; i < masses.size(); ++i) {
        f.bodies[i].massKg = masses[i];
        f.bodies[i].inertiaKgM2 = Eigen::Vector3d(1, 2, 3) * masses[i];
    }
    for (std::size_t i = 1; i < masses.size(); ++i) {
        REQUIRE(f.constraints[i - 1].body1 == static_cast<int>(i));
        REQUIRE(f.constraints[i - 1].body2 == static_cast<int>(i) - 1);
    }
    return f;
}

} // namespace

TEST_CASE("stabilize: a pair over the ratio keeps its sum and ends exactly at the ratio", "[figure][stabilize]") {
    const figure::Figure f = chain({1, 1000});
    CHECK(figure::needsStabilizing(f));
    figure::StabilizeReport report;
    const figure::Figure s = figure::stabilizeMassProperties(f, {}, &report);
    CHECK(s.bodies[0].massKg == Approx(1001.0 / 11));
    CHECK(s.bodies[1].massKg == Approx(1001.0 * 10 / 11));
    // Same density: the moments scale with the mass.
    CHECK(s.bodies[0].inertiaKgM2.x() == Approx(1001.0 / 11));
    CHECK(s.bodies[0].inertiaKgM2.z() == Approx(3 * 1001.0 / 11));
    CHECK(report.changes.size() == 2);
    CHECK_FALSE(figure::needsStabilizing(s));
}

TEST_CASE("stabilize: a chain converges within the ratio and keeps its total mass", "[figure][stabilize]") {
    const figure::Figure f = chain({1, 1000, 1, 1000, 1, 1000});
    const figure::Figure s = figure::stabilizeMassProperties(f, {.maxMassRatio = 10});
    double before = 0, after = 0;
    for (std::size_t i = 0; i < f.bodies.size(); ++i) {
        before += f.bodies[i].massKg;
        after += s.bodies[i].massKg;
    }
    CHECK(after == Approx(before));
    CHECK_FALSE(figure::needsStabilizing(s, {.maxMassRatio = 10.0 * 1.001}));
}

TEST_CASE("stabilize: thin bodies get an inertia floor / balanced figures are untouched", "[figure][stabilize]") {
    figure::Figure f = chain({2, 3});
    f.bodies[0].inertiaKgM2 = Eigen::Vector3d(1, 1, 0.001);
    CHECK(figure::needsStabilizing(f));
    figure::StabilizeReport report;
    const figure::Figure s = figure::stabilizeMassProperties(f, {.maxInertiaRatio = 20}, &report);
    CHECK(s.bodies[0].inertiaKgM2.z() == Approx(0.05));
    CHECK(s.bodies[0].inertiaKgM2.x() == 1);
    CHECK(s.bodies[0].massKg == 2);
    REQUIRE(report.changes.size() == 1);
    CHECK(report.changes[0].find("principal moments raised") != std::string::npos);

    const figure::Figure balanced = chain({2, 3, 4});
    CHECK_FALSE(figure::needsStabilizing(balanced));
    figure::StabilizeReport none;
    const figure::Figure same = figure::stabilizeMassProperties(balanced, {}, &none);
    CHECK_FALSE(none.changed());
    for (std::size_t i = 0; i < same.bodies.size(); ++i) {
        CHECK(same.bodies[i].massKg == balanced.bodies[i].massKg);
        CHECK(same.bodies[i].inertiaKgM2 == balanced.bodies[i].inertiaKgM2);
    }
}
