// RagdollSolver sets up the rows of a world's constraints itself (src/bullet/JointRows.cpp); for constraints it
// does not track, every row must be the one Bullet's own setup writes, to the bit: the Jacobians, the angular
// components, the effective mass, the target, the bounds and the bookkeeping, for Bullet's constraint types and
// afbullet's, in motion and in contact.
#include <catch2/catch.hpp>

#include <cstring>
#include <memory>
#include <vector>

#include <btBulletDynamicsCommon.h>

#include "EntityFixture.h"
#include "afb/bullet/RagdollAsset.h"
#include "afb/bullet/RagdollSolver.h"
#include "afb/sim/Scene.h"

using namespace afb;

namespace {

// A solver's row setup alone: its bodies, then its constraints' rows, on the world's current state.
template <class Solver>
struct RowSetup : Solver {
    struct Result {
        std::vector<btSolverConstraint> rows;
        int mostIterations = 0;
    };
    Result rowsOf(btDiscreteDynamicsWorld& world, const btContactSolverInfo& info) {
        btCollisionObjectArray& objects = world.getCollisionObjectArray();
        std::vector<btTypedConstraint*> constraints;
        for (int i = 0; i < world.getNumConstraints(); ++i) constraints.push_back(world.getConstraint(i));
        this->m_fixedBodyId = -1;
        this->m_maxOverrideNumSolverIterations = 0;
        this->convertBodies(&objects[0], objects.size(), info);
        this->convertJoints(constraints.data(), static_cast<int>(constraints.size()), info);
        Result out;
        for (int j = 0; j < this->m_tmpSolverNonContactConstraintPool.size(); ++j)
            out.rows.push_back(this->m_tmpSolverNonContactConstraintPool[j]);
        out.mostIterations = this->m_maxOverrideNumSolverIterations;
        return out;
    }
};

// Two game boxes joined to each other and to the world by the Bullet constraints a ragdoll does not use.
struct GameBodies {
    btBoxShape cube{btVector3(0.2f, 0.2f, 0.2f)};
    std::vector<std::unique_ptr<btRigidBody>> bodies;
    std::vector<std::unique_ptr<btTypedConstraint>> joints;
    btHingeConstraint* hinge = nullptr;

    explicit GameBodies(btDiscreteDynamicsWorld& world) {
        btVector3 inertia;
        cube.calculateLocalInertia(2, inertia);
        for (int k = 0; k < 2; ++k) {
            bodies.push_back(
                std::make_unique<btRigidBody>(btRigidBody::btRigidBodyConstructionInfo(2, nullptr, &cube, inertia)));
            bodies.back()->setWorldTransform(
                btTransform(btQuaternion(btVector3(1, 0, 1).normalized(), 0.3f * btScalar(k + 1)),
                            btVector3(4 + 0.5f * btScalar(k), 0, 2)));
            bodies.back()->setAngularVelocity(btVector3(1, -2, 0.5f));
            world.addRigidBody(bodies.back().get());
        }
        btRigidBody& a = *bodies[0];
        btRigidBody& b = *bodies[1];
        const btTransform frameA(btQuaternion::getIdentity(), btVector3(0.25f, 0, 0));
        const btTransform frameB(btQuaternion(btVector3(0, 0, 1), 0.2f), btVector3(-0.25f, 0, 0));
        joints.push_back(std::make_unique<btPoint2PointConstraint>(a, btVector3(0, 0, 0.3f)));
        joints.push_back(std::make_unique<btSliderConstraint>(a, b, frameA, frameB, true));
        auto* cone = new btConeTwistConstraint(a, b, frameA, frameB);
        cone->setLimit(0.4f, 0.3f, 0.2f);
        joints.emplace_back(cone);
        hinge = new btHingeConstraint(a, b, frameA, frameB);
        hinge->setLimit(-0.1f, 0.1f);
        joints.emplace_back(hinge);
        joints.push_back(std::make_unique<btFixedConstraint>(a, b, frameA, frameB));
        joints.back()->setEnabled(false); // no rows
        joints.back()->setOverrideNumSolverIterations(37);
        auto* spring = new btGeneric6DofSpring2Constraint(a, b, frameA, frameB);
        spring->enableSpring(0, true);
        spring->setStiffness(0, 50);
        joints.emplace_back(spring);
        joints.back()->setOverrideNumSolverIterations(31);
        for (auto& j : joints) world.addConstraint(j.get(), true);
    }
};

} // namespace

TEST_CASE("solver rows: every constraint's rows are set up as Bullet sets them up, to the bit", "[bullet][rows]") {
    const auto loaded = test::loadEntity("humanoid");
    const auto asset = bullet::RagdollAsset::create(loaded.figure);
    // `default` builds afbullet's own constraints (speculative limits, the constant-velocity universal, joint
    // friction); `legacy` Bullet's (cone-twist, hinges with their own limits).
    for (const char* method : {"default", "legacy"}) {
        sim::Scene scene(*bullet::methodPreset(method));
        bullet::SpawnOptions o;
        o.entityTransform = btTransform(btQuaternion(btVector3(1, 0, 0), 0.5f), btVector3(0, 0, 1.2f));
        scene.spawn(asset, o);
        GameBodies game(scene.world());
        for (const int steps : {10, 50}) { // falling; landed, with limits pressed
            for (int s = 0; s < steps; ++s) scene.step(1.0 / 60);
            btContactSolverInfo info = scene.world().getSolverInfo();
            info.m_timeStep = btScalar(1.0 / 60);
            // A breaking threshold clamps a row's bounds (set only now: a step would break the hinge on it).
            game.hinge->setEnabled(true);
            game.hinge->setBreakingImpulseThreshold(0.5f);
            RowSetup<btSequentialImpulseConstraintSolver> bullet;
            RowSetup<bullet::RagdollSolver> ours; // a fresh one: it tracks no constraint, so warm-starts none
            const auto expected = bullet.rowsOf(scene.world(), info);
            const auto got = ours.rowsOf(scene.world(), info);
            INFO(method << ", after " << steps << " more steps");
            REQUIRE(expected.rows.size() > 60);
            REQUIRE(got.rows.size() == expected.rows.size());
            int differing = 0;
            for (std::size_t j = 0; j < got.rows.size(); ++j)
                if (std::memcmp(&got.rows[j], &expected.rows[j], sizeof(btSolverConstraint)) != 0) ++differing;
            CHECK(differing == 0);
            CHECK(got.mostIterations == expected.mostIterations);
            CHECK(got.mostIterations == 31);
            game.hinge->setBreakingImpulseThreshold(SIMD_INFINITY);
        }
    }
}
