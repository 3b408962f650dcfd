// Drops split over worlds run on any number of threads with the same results (afb drop --worlds W --threads N).
#include <catch2/catch.hpp>

#include <memory>
#include <thread>
#include <vector>

#include "EntityFixture.h"
#include "afb/bullet/Method.h"
#include "afb/bullet/RagdollAsset.h"
#include "afb/sim/Drop.h"
#include "afb/sim/Scene.h"

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

namespace {

// A world's whole life on one thread: made, a ragdoll of each asset dropped into it for `steps` steps, destroyed.
// Returns every body's final position, in spawn order.
std::vector<Eigen::Vector3d> lifetime(const bullet::Method& method,
                                      const std::vector<std::shared_ptr<const bullet::RagdollAsset>>& assets,
                                      int steps) {
    sim::Scene scene(method, {.gravityMps2 = 9.81, .ground = true});
    for (std::size_t k = 0; k < assets.size(); ++k) {
        bullet::SpawnOptions options;
        options.entityTransform.setOrigin(btVector3(btScalar(2.0 * static_cast<double>(k)), 0, btScalar(0.5)));
        scene.spawn(assets[k], options);
    }
    for (int s = 0; s < steps; ++s) scene.step(1.0 / 60.0);
    std::vector<Eigen::Vector3d> out;
    for (const auto& r : scene.ragdolls())
        for (const figure::BodyState& b : r->bodyStates()) out.push_back(b.pose.position);
    return out;
}

} // namespace

TEST_CASE("threads: worlds made and destroyed on some threads while others step give single-thread results",
          "[sim][threads]") {
    const std::vector<std::shared_ptr<const bullet::RagdollAsset>> assets = {
        bullet::RagdollAsset::create(test::loadEntity("humanoid").figure),
        bullet::RagdollAsset::create(test::loadEntity("chain").figure)};
    for (const char* preset : {"default", "multibody"}) {
        DYNAMIC_SECTION(preset) {
            const bullet::Method method = *bullet::methodPreset(preset);
            const std::vector<Eigen::Vector3d> reference = lifetime(method, assets, 40);
            // One thread steps long-lived worlds; the others make and destroy short-lived ones meanwhile.
            constexpr int kChurners = 3, kLifetimes = 4;
            std::vector<std::vector<Eigen::Vector3d>> churned(kChurners * kLifetimes);
            std::vector<Eigen::Vector3d> longLived;
            std::vector<std::thread> threads;
            threads.emplace_back([&] { longLived = lifetime(method, assets, 40); });
            for (int t = 0; t < kChurners; ++t)
                threads.emplace_back([&, t] {
                    for (int k = 0; k < kLifetimes; ++k)
                        churned[static_cast<std::size_t>(t * kLifetimes + k)] = lifetime(method, assets, 40);
                });
            for (std::thread& t : threads) t.join();
            CHECK(longLived == reference);
            for (const std::vector<Eigen::Vector3d>& c : churned) CHECK(c == reference);
        }
    }
}
