// The SSE row update (src/bullet/RowKernels.h) against Bullet's own scalar reference, which Debian's Bullet runs:
// the same impulses, the same body velocities and the same residual, bit for bit, on random rows that reach every
// branch (clamped below, above, inside; static bodies; split impulse with and without penetration to recover), and
// a whole drop stepped with RagdollSolver's SIMD rows on and off ends in the same state to the bit.
#include <catch2/catch.hpp>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include <btBulletDynamicsCommon.h>

#include "EntityFixture.h"
#include "afb/bullet/RagdollAsset.h"
#include "afb/bullet/RagdollSolver.h"
#include "afb/sim/Scene.h"
#include "bullet/RowKernels.h"

using namespace afb;

namespace {

// Bullet's scalar row functions, as its solver installs them without SIMD (setupSolverFunctions(false), which
// its constructor calls).
struct BulletRows : btSequentialImpulseConstraintSolver {
    btSingleConstraintRowSolver generic() const { return m_resolveSingleConstraintRowGeneric; }
    btSingleConstraintRowSolver lowerLimit() const { return m_resolveSingleConstraintRowLowerLimit; }
    btSingleConstraintRowSolver split() const { return m_resolveSplitPenetrationImpulse; }
};

std::uint32_t bits(float v) { return std::bit_cast<std::uint32_t>(v); }

bool sameBits(const btVector3& a, const btVector3& b) {
    for (int i = 0; i < 4; ++i)
        if (bits(a.m_floats[i]) != bits(b.m_floats[i])) return false;
    return true;
}

bool sameBody(const btSolverBody& a, const btSolverBody& b) {
    return sameBits(a.m_deltaLinearVelocity, b.m_deltaLinearVelocity) &&
           sameBits(a.m_deltaAngularVelocity, b.m_deltaAngularVelocity) &&
           sameBits(a.m_pushVelocity, b.m_pushVelocity) && sameBits(a.m_turnVelocity, b.m_turnVelocity);
}

struct Rng {
    std::mt19937 gen{20261125};
    float uniform(float lo, float hi) { return std::uniform_real_distribution<float>(lo, hi)(gen); }
    btVector3 vector(float scale) {
        return btVector3(uniform(-scale, scale), uniform(-scale, scale), uniform(-scale, scale));
    }
};

void randomBody(Rng& rng, btSolverBody& b, btRigidBody* original) {
    // Every member set (btTransform and btVector3 leave theirs uninitialised): the copies compared are whole.
    b.m_worldTransform.setIdentity();
    b.m_linearVelocity = b.m_angularVelocity = btVector3(0, 0, 0);
    b.m_externalForceImpulse = b.m_externalTorqueImpulse = btVector3(0, 0, 0);
    b.m_deltaLinearVelocity = rng.vector(3);
    b.m_deltaAngularVelocity = rng.vector(5);
    b.m_pushVelocity = rng.vector(0.5f);
    b.m_turnVelocity = rng.vector(0.5f);
    const float invMass = rng.uniform(0.01f, 2);
    b.m_invMass = btVector3(invMass, invMass, invMass);
    // Factors other than 1 (a body locked on an axis, or scaled) exercise Bullet's association of the products.
    b.m_linearFactor = btVector3(1, rng.uniform(0, 1) < 0.2f ? 0 : 1, rng.uniform(0.5f, 1));
    b.m_angularFactor = btVector3(rng.uniform(0.5f, 1), 1, rng.uniform(0, 1) < 0.2f ? 0 : 1);
    b.m_originalBody = original;
}

void randomRow(Rng& rng, btSolverConstraint& c) {
    c.m_friction = 0;
    c.m_originalContactPoint = nullptr;
    c.m_overrideNumSolverIterations = c.m_frictionIndex = c.m_solverBodyIdA = c.m_solverBodyIdB = 0;
    c.m_contactNormal1 = rng.vector(1);
    c.m_contactNormal2 = -c.m_contactNormal1 * rng.uniform(0.5f, 1.5f);
    c.m_relpos1CrossNormal = rng.vector(0.5f);
    c.m_relpos2CrossNormal = rng.vector(0.5f);
    c.m_angularComponentA = rng.vector(2);
    c.m_angularComponentB = rng.vector(2);
    c.m_rhs = rng.uniform(-5, 5);
    c.m_rhsPenetration = rng.uniform(0, 1) < 0.3f ? 0 : rng.uniform(-0.5f, 0.5f);
    c.m_cfm = rng.uniform(0, 1) < 0.5f ? 0 : rng.uniform(0, 0.1f);
    c.m_jacDiagABInv = rng.uniform(0.05f, 3);
    c.m_appliedImpulse = rng.uniform(-2, 2);
    c.m_appliedPushImpulse = rng.uniform(-0.5f, 0.5f);
    // Narrow bounds clamp often, on either side; wide ones rarely.
    const float width = rng.uniform(0, 1) < 0.5f ? rng.uniform(0, 0.5f) : rng.uniform(1, 20);
    c.m_lowerLimit = -width * rng.uniform(0, 1);
    c.m_upperLimit = width * rng.uniform(0, 1);
}

} // namespace

TEST_CASE("row kernels: the SSE row update rounds bit for bit as Bullet's scalar reference", "[bullet][rows]") {
    if (!AFB_SIMD_ROWS) SUCCEED("no SSE in this build: the kernels are Bullet's own vector arithmetic");
    const BulletRows bullet;
    btDefaultMotionState motion;
    btBoxShape shape(btVector3(0.1f, 0.1f, 0.1f));
    btRigidBody dynamic(1, &motion, &shape); // only its address is used: a body the impulses apply to
    Rng rng;
    struct Kind {
        const char* name;
        btSingleConstraintRowSolver ours, theirs;
    };
    const Kind kinds[] = {{"generic", bullet::detail::resolveRowGeneric, bullet.generic()},
                          {"lower limit", bullet::detail::resolveRowLowerLimit, bullet.lowerLimit()},
                          {"split impulse", bullet::detail::resolveRowSplitPenetration, bullet.split()}};
    for (const Kind& kind : kinds) {
        int clampedLow = 0, clampedHigh = 0, inside = 0, mismatches = 0;
        for (int i = 0; i < 20000; ++i) {
            btSolverBody a{}, b{};
            btSolverConstraint c{};
            randomBody(rng, a, &dynamic);
            randomBody(rng, b, rng.uniform(0, 1) < 0.25f ? nullptr : &dynamic); // a static or fixed body sometimes
            randomRow(rng, c);
            btSolverBody a2 = a, b2 = b;
            btSolverConstraint c2 = c;
            const btScalar r1 = kind.ours(a, b, c);
            const btScalar r2 = kind.theirs(a2, b2, c2);
            const bool same = bits(r1) == bits(r2) && bits(c.m_appliedImpulse) == bits(c2.m_appliedImpulse) &&
                              bits(c.m_appliedPushImpulse) == bits(c2.m_appliedPushImpulse) && sameBody(a, a2) &&
                              sameBody(b, b2);
            if (!same) ++mismatches;
            const float applied = kind.ours == bullet::detail::resolveRowSplitPenetration
                                      ? float(c.m_appliedPushImpulse)
                                      : float(c.m_appliedImpulse);
            if (applied == c.m_lowerLimit) ++clampedLow;
            else if (applied == c.m_upperLimit) ++clampedHigh;
            else ++inside;
        }
        INFO(kind.name << ": clamped below " << clampedLow << ", above " << clampedHigh << ", inside " << inside);
        CHECK(mismatches == 0);
        CHECK(clampedLow > 100); // every branch was taken
        CHECK(inside > 100);
        if (kind.ours == bullet::detail::resolveRowGeneric) CHECK(clampedHigh > 100);
    }
}

TEST_CASE("row kernels: a drop stepped with SIMD rows ends where Bullet's scalar rows end, to the bit",
          "[bullet][rows]") {
    const auto loaded = test::loadEntity("humanoid");
    const auto asset = bullet::RagdollAsset::create(loaded.figure);
    // `iterative` solves its joints, limits and contacts in Bullet's iterations; `default` and `fast` solve only
    // their free rows there when their direct solve declines an island, so `iterative` is the method that
    // exercises every row kind. The
    // solver modes that change Bullet's loop (contacts interleaved with their friction, two friction directions,
    // the order randomised, which RagdollSolver leaves to Bullet's own loop) each get a run.
    struct Variant {
        const char* method;
        int solverMode; // added to the method's
    };
    const Variant variants[] = {
        {"iterative", 0},
        {"legacy", 0},
        {"iterative", SOLVER_INTERLEAVE_CONTACT_AND_FRICTION_CONSTRAINTS},
        {"iterative", SOLVER_INTERLEAVE_CONTACT_AND_FRICTION_CONSTRAINTS | SOLVER_USE_2_FRICTION_DIRECTIONS},
        {"iterative", SOLVER_RANDMIZE_ORDER},
    };
    std::vector<figure::Transform> plainIterative; // `iterative`'s final pose in its own solver mode
    for (const Variant& variant : variants) {
        const char* name = variant.method;
        std::vector<std::vector<figure::Transform>> finals;
        std::vector<figure::Transform> spawned;
        for (const bool simd : {true, false}) {
            sim::Scene scene(*bullet::methodPreset(name));
            auto* solver = dynamic_cast<bullet::RagdollSolver*>(scene.world().getConstraintSolver());
            REQUIRE(solver != nullptr);
            solver->setSimdRows(simd);
            bullet::SpawnOptions o;
            // Tilted, so that it lands on a side: self-contacts, limits and friction all come into play.
            o.entityTransform =
                btTransform(btQuaternion(btVector3(0, 0, 1), 0.6f) * btQuaternion(btVector3(1, 0, 0), 0.5f),
                            btVector3(0, 0, 1.5f));
            bullet::Ragdoll& r = scene.spawn(asset, o);
            scene.world().getSolverInfo().m_solverMode |= variant.solverMode;
            if (simd) spawned = r.bodyTransforms();
            for (int s = 0; s < 120; ++s) scene.step(1.0 / 60);
            finals.push_back(r.bodyTransforms());
        }
        INFO(name << ", solver mode +" << variant.solverMode);
        REQUIRE(finals[0].size() == finals[1].size());
        bool moved = false;
        for (std::size_t i = 0; i < finals[0].size(); ++i) {
            CHECK(finals[0][i].position == finals[1][i].position);
            CHECK(finals[0][i].rotation == finals[1][i].rotation);
            moved = moved || (finals[0][i].position - spawned[i].position).norm() > 0.5;
        }
        CHECK(moved); // it fell and landed: contacts, limits and friction were solved
        if (std::string(name) == "iterative" && variant.solverMode == 0) plainIterative = finals[0];
        if (variant.solverMode != 0) { // the mode took effect: Bullet's loop ran differently
            bool differs = false;
            for (std::size_t i = 0; i < finals[0].size(); ++i)
                differs = differs || finals[0][i].position != plainIterative[i].position;
            CHECK(differs);
        }
    }
}

TEST_CASE("row kernels: islands solved in turn end as in Bullet's order, to the bit", "[bullet][rows]") {
    // Bullet solves small islands together; RagdollSolver's iterations take a row of each island in turn
    // (RagdollSolver::islandsInTurn). Each island keeps its own rows' order and no island writes another's bodies,
    // so two ragdolls and a game's box stepped together end as with Bullet's order, to the bit.
    const auto loaded = test::loadEntity("humanoid");
    const auto asset = bullet::RagdollAsset::create(loaded.figure);
    struct Run {
        std::vector<std::vector<figure::Transform>> ragdolls;
        btTransform box;
        int mostInTurn = 0;
    };
    const auto run = [&](bool simd) {
        sim::Scene scene(*bullet::methodPreset("iterative"));
        auto* solver = dynamic_cast<bullet::RagdollSolver*>(scene.world().getConstraintSolver());
        REQUIRE(solver != nullptr);
        solver->setSimdRows(simd);
        std::vector<bullet::Ragdoll*> ragdolls;
        for (int k = 0; k < 2; ++k) {
            bullet::SpawnOptions o; // tilted differently, 5 m apart: two islands
            o.entityTransform = btTransform(btQuaternion(btVector3(0, 0, 1), 0.6f + btScalar(k)) *
                                                btQuaternion(btVector3(1, 0, 0), 0.5f),
                                            btVector3(btScalar(5 * k), 0, 1.5f));
            ragdolls.push_back(&scene.spawn(asset, o));
        }
        btBoxShape cube(btVector3(0.2f, 0.2f, 0.2f));
        btVector3 inertia;
        cube.calculateLocalInertia(1, inertia);
        btRigidBody crate(btRigidBody::btRigidBodyConstructionInfo(1, nullptr, &cube, inertia));
        crate.setWorldTransform(btTransform(btQuaternion(btVector3(1, 1, 0).normalized(), 0.4f), btVector3(-5, 0, 2)));
        scene.world().addRigidBody(&crate);
        Run out;
        for (int s = 0; s < 120; ++s) {
            scene.step(1.0 / 60);
            out.mostInTurn = std::max(out.mostInTurn, solver->islandsInTurn());
        }
        for (bullet::Ragdoll* r : ragdolls) out.ragdolls.push_back(r->bodyTransforms());
        out.box = crate.getWorldTransform();
        scene.world().removeRigidBody(&crate);
        return out;
    };
    const Run inTurn = run(true);
    const Run bullets = run(false);
    CHECK(inTurn.mostInTurn >= 2); // the islands were taken in turn
    CHECK(bullets.mostInTurn == 0);
    for (std::size_t k = 0; k < 2; ++k) {
        INFO("ragdoll " << k);
        REQUIRE(inTurn.ragdolls[k].size() == bullets.ragdolls[k].size());
        for (std::size_t i = 0; i < inTurn.ragdolls[k].size(); ++i) {
            CHECK(inTurn.ragdolls[k][i].position == bullets.ragdolls[k][i].position);
            CHECK(inTurn.ragdolls[k][i].rotation == bullets.ragdolls[k][i].rotation);
        }
    }
    CHECK(inTurn.box.getOrigin() == bullets.box.getOrigin());
    CHECK(inTurn.box.getBasis() == bullets.box.getBasis());
    CHECK(inTurn.box.getOrigin().z() < 0.5f); // the box fell and landed
}
