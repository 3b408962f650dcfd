// ObjectArena (src/bullet/ObjectArena.h), where a ragdoll keeps its bodies, constraints and joint feedback: objects
// come out aligned for Bullet's 16-byte classes, keep their addresses while more are made (new blocks, never moved),
// are destroyed last-made-first by clear() and by the destructor, and an adopted heap object is deleted with them.
#include <catch2/catch.hpp>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <btBulletDynamicsCommon.h>

#include "bullet/ObjectArena.h"

using afb::bullet::detail::ObjectArena;

namespace {

// Records its destruction in a shared log.
struct Tracer {
    Tracer(std::vector<int>& into, int name) : log(into), id(name) {}
    ~Tracer() { log.push_back(id); }
    std::vector<int>& log;
    int id;
    char payload[40] = {};
};

bool aligned16(const void* p) { return reinterpret_cast<std::uintptr_t>(p) % 16 == 0; }

} // namespace

TEST_CASE("arena: objects are destroyed last made first, by clear and by the destructor", "[arena]") {
    std::vector<int> log;
    {
        ObjectArena arena(64); // smaller than what follows: several blocks
        for (int i = 0; i < 50; ++i) arena.make<Tracer>(log, i);
        CHECK(arena.objectCount() == 50);
        CHECK(arena.bytesUsed() >= 50 * sizeof(Tracer));
        arena.clear();
        REQUIRE(log.size() == 50);
        for (int i = 0; i < 50; ++i) CHECK(log[static_cast<std::size_t>(i)] == 49 - i);
        CHECK(arena.objectCount() == 0);
        CHECK(arena.bytesUsed() == 0);
        log.clear();
        arena.make<Tracer>(log, 100); // usable again after clear
        arena.make<Tracer>(log, 101);
    }
    CHECK(log == std::vector<int>{101, 100});
}

TEST_CASE("arena: Bullet objects are aligned and keep their addresses as blocks are added", "[arena]") {
    ObjectArena arena(256);
    std::vector<btRigidBody*> bodies;
    std::vector<btVector3> origins;
    btSphereShape shape(btScalar(0.1));
    for (int i = 0; i < 20; ++i) {
        btRigidBody::btRigidBodyConstructionInfo info(1, nullptr, &shape, btVector3(1, 1, 1));
        info.m_startWorldTransform.setOrigin(btVector3(btScalar(i), 0, 0));
        btRigidBody* b = arena.make<btRigidBody>(info);
        CHECK(aligned16(b));
        bodies.push_back(b);
        arena.make<char>('x'); // misaligns the next free byte: the next object must still be aligned
    }
    for (int i = 0; i < 20; ++i)
        CHECK(bodies[static_cast<std::size_t>(i)]->getCenterOfMassPosition().x() == btScalar(i));
    struct alignas(64) Wide {
        double lanes[8];
    };
    for (int i = 0; i < 5; ++i) {
        arena.make<char>('y');
        CHECK(reinterpret_cast<std::uintptr_t>(arena.make<Wide>()) % 64 == 0); // more than the blocks' 16
    }
    btPoint2PointConstraint* c =
        arena.make<btPoint2PointConstraint>(*bodies[0], *bodies[1], btVector3(0, 0, 0), btVector3(1, 0, 0));
    CHECK(aligned16(c));
    CHECK(&c->getRigidBodyB() == bodies[1]);
}

TEST_CASE("arena: an adopted heap object is deleted with the arena's own", "[arena]") {
    std::vector<int> log;
    {
        ObjectArena arena;
        arena.make<Tracer>(log, 1);
        Tracer* adopted = arena.adopt(std::make_unique<Tracer>(log, 2));
        CHECK(adopted->id == 2);
        arena.make<Tracer>(log, 3);
    }
    CHECK(log == std::vector<int>{3, 2, 1});
}
