// Convex pairs plainly apart skip Bullet's narrow phase (Method::separatedPairs, src/bullet/SeparatedPairs.h): the skip
// may only leave out work whose result is no contact, so every body ends where Bullet's own algorithm puts it, bit for
// bit.
#include <catch2/catch.hpp>

#include <vector>

#include "BitEqual.h"
#include "EntityFixture.h"
#include "afb/bullet/RagdollAsset.h"
#include "afb/sim/RawRagdoll.h"
#include "afb/sim/Scene.h"

using namespace afb;

namespace {

constexpr double kDt = 1.0 / 60;

struct Outcome {
    std::vector<btTransform> transforms; // every ragdoll body after the run
    int touchingBodyPairs = 0;           // manifolds between two dynamic bodies with points, summed over the steps
};

// Three humanoids dropped from 1 m on top of one another's reach (overlapping bounding boxes between figures as
// well as within them), each turned differently; with the skip on or with Bullet's algorithm alone.
Outcome dropThree(const std::string& method, bool skip) {
    const auto asset = bullet::RagdollAsset::create(test::loadEntity("humanoid").figure);
    bullet::Method chosen = *bullet::methodPreset(method);
    chosen.separatedPairs = skip;
    sim::Scene scene(chosen);
    btDispatcher* dispatcher = scene.world().getDispatcher();
    std::vector<bullet::Ragdoll*> ragdolls;
    for (int i = 0; i < 3; ++i) {
        bullet::SpawnOptions where;
        where.entityTransform = btTransform(btQuaternion(btVector3(0, 0, 1), btScalar(0.9 * i)),
                                            btVector3(btScalar(0.25 * i), btScalar(0.1 * i), btScalar(1 + 0.4 * i)));
        where.comeToRest = false;
        ragdolls.push_back(&scene.spawn(asset, where));
    }
    Outcome out;
    for (int s = 0; s < 240; ++s) {
        scene.step(kDt);
        for (int m = 0; m < dispatcher->getNumManifolds(); ++m) {
            const btPersistentManifold* manifold = dispatcher->getManifoldByIndexInternal(m);
            if (manifold->getNumContacts() > 0 && !manifold->getBody0()->isStaticObject() &&
                !manifold->getBody1()->isStaticObject())
                ++out.touchingBodyPairs;
        }
    }
    for (const bullet::Ragdoll* r : ragdolls)
        for (int b = 0; b < r->bodyCount(); ++b) out.transforms.push_back(r->collisionObject(b).getWorldTransform());
    return out;
}

} // namespace

TEST_CASE("separated pairs: skipping GJK for pairs apart along their centre line leaves every body where Bullet's "
          "algorithm puts it",
          "[bullet][collision]") {
    CHECK(bullet::methodPreset("default")->separatedPairs);
    CHECK_FALSE(bullet::methodPreset("legacy")->separatedPairs);
    CHECK_FALSE(sim::rawMethod().separatedPairs); // plain Bullet runs GJK on every pair
    for (const char* method : {"fast", "default"}) {
        INFO(method);
        const Outcome skipped = dropThree(method, true);
        const Outcome bullet = dropThree(method, false);
        // The run has bodies touching bodies (the skip's other path, Bullet's algorithm, runs for them).
        CHECK(bullet.touchingBodyPairs > 100);
        CHECK(skipped.touchingBodyPairs == bullet.touchingBodyPairs);
        REQUIRE(skipped.transforms.size() == bullet.transforms.size());
        for (std::size_t i = 0; i < bullet.transforms.size(); ++i) {
            INFO("body " << i);
            CHECK(test::bitEqual(skipped.transforms[i], bullet.transforms[i]));
        }
    }
}
