// Drops split over worlds run on any number of threads with the same results (afb drop --worlds W --threads N).
#include <catch2/catch.hpp>

#include "EntityFixture.h"
#include "afb/sim/Drop.h"

using namespace afb;

TEST_CASE("drop: worlds on 1, 2 or 3 threads give the same results, combined in world order", "[sim][threads]") {
    const auto loaded = test::loadEntity("chain");
    sim::DropOptions o;
    o.count = 6;
    o.worlds = 3;
    o.steps = 90;
    o.seed = 7u; // tilted spawns: the worlds differ
    o.threads = 1;
    const sim::DropResult one = sim::runDrop(loaded.figure, o);
    for (const int threads : {2, 3, 8}) {
        o.threads = threads;
        const sim::DropResult r = sim::runDrop(loaded.figure, o);
        INFO(threads << " threads");
        CHECK(r.awakeBodySteps == one.awakeBodySteps);
        CHECK(r.maxAnchorErrorM == one.maxAnchorErrorM);
        CHECK(r.maxLimitViolationDeg == one.maxLimitViolationDeg);
        CHECK(r.maxPenetrationM == one.maxPenetrationM);
        CHECK(r.worstAnchorJoint == one.worstAnchorJoint);
        CHECK(r.worstContact == one.worstContact);
        CHECK(r.maxEnergyGainJ == one.maxEnergyGainJ);
        REQUIRE(r.firstBodies.size() == one.firstBodies.size());
        for (std::size_t i = 0; i < r.firstBodies.size(); ++i) {
            CHECK(r.firstBodies[i].position == one.firstBodies[i].position);
            CHECK(r.firstBodies[i].rotation == one.firstBodies[i].rotation);
        }
    }
}
