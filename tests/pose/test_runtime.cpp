// The ragdoll runtime (docs/format.md §2.5, §5, §6.1): spawn pose, skeleton driving, impulses, rest, velocity
// inheritance, drops. Deterministic: fixed 60 Hz step, fixed insertion order.
#include <catch2/catch.hpp>

#include <cmath>
#include <memory>

#include "EntityFixture.h"
#include "TestSupport.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/detail/Convert.h"
#include "afb/figure/Load.h"
#include "afb/pose/SkeletonDriver.h"
#include "afb/sim/Scene.h"

namespace {

using afb::bullet::Ragdoll;
using afb::bullet::RagdollAsset;
using afb::figure::Transform;

// The tools' one scene (default method), with or without a ground plane.
struct World {
    afb::sim::Scene scene;
    btDiscreteDynamicsWorld& world = scene.world();
    btRigidBody* ground = scene.ground();

    explicit World(double gravity = 9.81, bool withGround = false)
        : scene(afb::bullet::Method{}, {.gravityMps2 = gravity, .ground = withGround}) {}
    void step(int steps) {
        for (int i = 0; i < steps; ++i) scene.step(1.0 / 60.0);
    }
};

afb::figure::LoadedFigure load(const std::filesystem::path& base, const std::string& entity) {
    return afb::test::loadEntity(entity, base);
}

// The sets a runtime test runs on: the bundled chain, plus the corpus' complete zsec sets when present.
std::vector<std::pair<std::filesystem::path, std::string>> entities() {
    std::vector<std::pair<std::filesystem::path, std::string>> out;
    for (const char* e : {"chain", "humanoid", "props", "lamp", "buggy"}) out.emplace_back(afb::test::sourceDir(), e);
    if (const auto corpus = afb::test::corpusDir())
        for (const char* e : {"monster_zsec_pistol", "monster_zsec_shotgun", "monster_zsec_machinegun"})
            out.emplace_back(*corpus / "doom3-kroom3/base", e);
    return out;
}

double angleDeg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
    return Eigen::AngleAxisd(a.transpose() * b).angle() * 180.0 / 3.14159265358979323846;
}

btTransform spawnTransform() {
    btTransform t;
    t.setRotation(btQuaternion(btVector3(0.3f, -0.2f, 1).normalized(), btScalar(1.1)));
    t.setOrigin(btVector3(3, -2, 1.5f));
    return t;
}

} // namespace

TEST_CASE("spawn pose: the driven skeleton is the af_pose skeleton", "[runtime]") {
    for (const auto& [base, entity] : entities()) {
        const afb::figure::LoadedFigure loaded = load(base, entity);
        const afb::figure::Figure& f = loaded.figure;
        for (const btTransform& spawn : {btTransform::getIdentity(), spawnTransform()}) {
            World w;
            Ragdoll ragdoll(RagdollAsset::create(f), w.world, {.entityTransform = spawn});
            const afb::pose::SkeletonPose pose = afb::pose::driveSkeleton(f, ragdoll.bodyTransforms());
            const Transform entityT = afb::bullet::toEigen(spawn);
            // The entity follows body 0: it is the spawn transform.
            CHECK((pose.entity.position - entityT.position).norm() < 1e-4);
            CHECK(angleDeg(pose.entity.rotation, entityT.rotation) < 0.01);
            double worstM = 0, worstDeg = 0;
            const std::vector<Transform> world = pose.world();
            for (int j = 0; j < f.skeleton.jointCount(); ++j) {
                const Transform& load = f.skeleton.loadPose()[static_cast<std::size_t>(j)];
                const Transform expected = entityT * Transform{load.rotation, load.position * f.units.metresPerUnit};
                worstM = std::max(worstM, (world[static_cast<std::size_t>(j)].position - expected.position).norm());
                worstDeg = std::max(worstDeg, angleDeg(world[static_cast<std::size_t>(j)].rotation, expected.rotation));
            }
            INFO(entity << ": worst joint error " << worstM << " m, " << worstDeg << " deg");
            CHECK(worstM < 1e-4);
            CHECK(worstDeg < 0.01);
        }
    }
}

TEST_CASE("impulses reach the body containing the joint", "[runtime]") {
    const afb::figure::LoadedFigure loaded = load(afb::test::sourceDir(), "chain");
    const afb::figure::Figure& f = loaded.figure;
    World w;
    Ragdoll ragdoll(RagdollAsset::create(f), w.world, {.startAtRest = true});
    CHECK(ragdoll.atRest());
    const int joint = *f.skeleton.findJoint("link7");
    const int body = f.jointBody[static_cast<std::size_t>(joint)];
    REQUIRE(body == 6); // af/chain.af: body "link7" contains "*link7 -*link8"
    const btVector3 at = ragdoll.body(body).getCenterOfMassPosition();
    const double threshold = ragdoll.impulseThresholdNs();
    CHECK_FALSE(ragdoll.applyImpulse(joint, btVector3(btScalar(threshold * 0.5), 0, 0), at)); // below: ignored
    CHECK(ragdoll.atRest());
    CHECK(ragdoll.applyImpulse(joint, btVector3(btScalar(threshold * 2), 0, 0), at));
    CHECK_FALSE(ragdoll.atRest());
    CHECK(ragdoll.body(body).getLinearVelocity().x() > 0);
    for (int i = 0; i < ragdoll.bodyCount(); ++i)
        if (i != body) CHECK(ragdoll.body(i).getLinearVelocity().length() == 0);
    CHECK_FALSE(ragdoll.applyImpulse(-1, btVector3(100, 0, 0), at));
}

TEST_CASE("rest: a hanging chain comes to rest by its rules, sleeps, and an impulse wakes it", "[runtime]") {
    const afb::figure::LoadedFigure loaded = load(afb::test::sourceDir(), "chain");
    World w;
    Ragdoll ragdoll(RagdollAsset::create(loaded.figure), w.world);
    // Swing it first so there is something to settle.
    const int tip = *loaded.figure.skeleton.findJoint("link10");
    REQUIRE(ragdoll.applyImpulse(tip, btVector3(btScalar(ragdoll.impulseThresholdNs() * 2), 0, 0),
                                 ragdoll.body(9).getCenterOfMassPosition()));
    int steps = 0;
    while (!ragdoll.atRest() && steps < 60 * 12) {
        w.step(1);
        ++steps;
    }
    INFO("steps to rest: " << steps);
    CHECK(ragdoll.atRest());
    CHECK(steps <= 60 * 10 + 1); // maxMoveTime 10 s in af/chain.af
    for (int i = 0; i < ragdoll.bodyCount(); ++i) CHECK_FALSE(ragdoll.body(i).isActive());
    const btTransform before = ragdoll.body(5).getCenterOfMassTransform();
    w.step(30);
    CHECK((ragdoll.body(5).getCenterOfMassPosition() - before.getOrigin()).length() == 0); // asleep: no cost, no drift
    CHECK(ragdoll.applyImpulse(tip, btVector3(0, btScalar(ragdoll.impulseThresholdNs() * 2), 0),
                               ragdoll.body(9).getCenterOfMassPosition()));
    CHECK_FALSE(ragdoll.atRest());
    w.step(1);
    for (int i = 0; i < ragdoll.bodyCount(); ++i) CHECK(ragdoll.body(i).isActive());
}

TEST_CASE("velocity inheritance reproduces the motion's velocities", "[runtime]") {
    const afb::figure::LoadedFigure loaded = load(afb::test::sourceDir(), "chain");
    const afb::figure::Figure& f = loaded.figure;
    // The af_pose carried by an entity that moves at v and turns at ω about Z: every body's velocity is
    // v + ω × (p − centre), its angular velocity ω.
    const Eigen::Vector3d v(1.0, 0.5, 0.0), omega(0, 0, 1.2);
    const double dt = 1.0 / 60.0;
    auto entityAt = [&](double t) {
        return Transform{Eigen::AngleAxisd(omega.z() * t, Eigen::Vector3d::UnitZ()).toRotationMatrix(), v * t};
    };
    const std::vector<Transform> joints = afb::figure::toMetres(f.skeleton.loadPose(), f.units.metresPerUnit);
    const auto before = afb::figure::bodiesFromJoints(f, entityAt(-dt), joints);
    const auto after = afb::figure::bodiesFromJoints(f, entityAt(0), joints);
    const auto states = afb::figure::inheritVelocities(before, after, dt);
    World w(0);
    Ragdoll ragdoll(RagdollAsset::create(f), w.world);
    REQUIRE(ragdoll.setBodyStates(states));
    for (int i = 0; i < ragdoll.bodyCount(); ++i) {
        const Eigen::Vector3d p = afb::bullet::toEigen(ragdoll.body(i).getCenterOfMassPosition());
        const Eigen::Vector3d expected = v + omega.cross(p);
        const Eigen::Vector3d got = afb::bullet::toEigen(ragdoll.body(i).getLinearVelocity());
        CHECK((got - expected).norm() <= 0.05 * expected.norm());
        const Eigen::Vector3d w2 = afb::bullet::toEigen(ragdoll.body(i).getAngularVelocity());
        CHECK((w2 - omega).norm() <= 0.05 * omega.norm());
    }
}

TEST_CASE("drop: zsec figures settle on the ground by their rules, stay connected, stay above it",
          "[runtime][corpus]") {
    AFB_REQUIRE_CORPUS(corpus);
    for (const char* entity : {"monster_zsec_pistol", "monster_zsec_shotgun", "monster_zsec_machinegun"}) {
        const afb::figure::LoadedFigure loaded = load(corpus / "doom3-kroom3/base", entity);
        const afb::figure::Figure& f = loaded.figure;
        World w(9.81, true);
        btTransform spawn = btTransform::getIdentity();
        spawn.setOrigin(btVector3(0, 0, 1.0f)); // a 1 m drop
        Ragdoll ragdoll(RagdollAsset::create(f), w.world, {.entityTransform = spawn});
        const double limit = f.rest.maxMoveTimeS > 0 ? f.rest.maxMoveTimeS : 10.0;
        int steps = 0;
        double lowest = 1e9;
        while (!ragdoll.atRest() && steps < static_cast<int>(limit * 60) + 2) {
            w.step(1);
            ++steps;
        }
        INFO(entity << ": rest after " << steps << " steps");
        CHECK(ragdoll.atRest());
        const afb::pose::SkeletonPose pose = afb::pose::driveSkeleton(f, ragdoll.bodyTransforms());
        const std::vector<Transform> world = pose.world();
        const auto skinned = afb::pose::skin(loaded.mesh, world, f.units.metresPerUnit);
        std::string lowestShader;
        for (std::size_t m = 0; m < skinned.size(); ++m)
            for (const Eigen::Vector3d& p : skinned[m])
                if (p.z() < lowest) {
                    lowest = p.z();
                    const auto& sub = loaded.mesh.meshes[m];
                    const auto vi = static_cast<std::size_t>(&p - skinned[m].data());
                    lowestShader =
                        sub.shader + " joint " +
                        f.skeleton.name(sub.weights[static_cast<std::size_t>(sub.verts[vi].firstWeight)].joint);
                }
        INFO("lowest vertex is on " << lowestShader);
        // Tolerances: the bodies' hulls stay out of the ground within 1 cm (Bullet's contact slop, checked below).
        // The skinned surface is not the collision shape: id's zsec bodies are smaller than the mesh (the pelvis
        // flesh reaches ~6 in. past the waist box), so their mesh may sink up to 0.2 m; measured 0.149 m.
        INFO("lowest skinned vertex z = " << lowest);
        CHECK(lowest > -0.2);
        for (int i = 0; i < ragdoll.bodyCount(); ++i) {
            btVector3 mn, mx;
            ragdoll.body(i).getAabb(mn, mx);
            CHECK(mx.z() > -0.01);
        }
        // Connected: each driven joint within 2 cm of where its body puts it.
        double worst = 0;
        const auto bodies = ragdoll.bodyTransforms();
        for (std::size_t i = 0; i < f.bodies.size(); ++i) {
            const int j = f.bodies[i].joint;
            if (j <= 0) continue;
            const Eigen::Vector3d bodyImplied = (bodies[i] * f.bodies[i].jointInBody).position;
            worst = std::max(worst, (world[static_cast<std::size_t>(j)].position - bodyImplied).norm());
        }
        INFO("worst joint-to-body distance " << worst << " m");
        CHECK(worst < 0.02);
    }
}

TEST_CASE("spawn and remove cycles leave the world as it was", "[runtime]") {
    const afb::figure::LoadedFigure loaded = load(afb::test::sourceDir(), "chain");
    const auto asset = RagdollAsset::create(loaded.figure);
    World w;
    for (int cycle = 0; cycle < 10; ++cycle) {
        {
            Ragdoll a(asset, w.world), b(asset, w.world, {.entityTransform = spawnTransform()});
            CHECK(a.body(0).getCollisionShape() == b.body(0).getCollisionShape());
            w.step(5);
        }
        CHECK(w.world.getNumCollisionObjects() == 0);
        CHECK(w.world.getNumConstraints() == 0);
    }
    CHECK(asset.use_count() == 1);
}

#include "FigureFixture.h"

TEST_CASE("contact friction combines as the engine's: min between ragdoll bodies, own value against the world",
          "[runtime]") {
    // Two loose boxes of one figure, the upper one resting on the lower one, the lower one on the ground.
    const std::vector<afb::test::TestJoint> joints = {{"origin", -1, 0, 0, 0},
                                                      {"low", 0, 0, 0, 2},
                                                      {"high", 1, 0, 0, 6}};
    const auto built = afb::test::buildTestFigure(
        "articulatedFigure f {\n"
        " body \"low\" { joint \"origin\" model box( ( -8, -8, -2 ), ( 8, 8, 2 ) ) origin ( 0, 0, 2 ) density 0.02 "
        "friction 0.01, 0.01, 0.5 }\n"
        " body \"high\" { joint \"high\" model box( ( -4, -4, -2 ), ( 4, 4, 2 ) ) origin ( 0, 0, 6 ) density 0.02 "
        "friction 0.01, 0.01, 0.3 }\n}\n",
        joints);
    INFO(built.diagnostics.str());
    REQUIRE(built.figure);
    World w(9.81, true);
    w.ground->setFriction(btScalar(0.7));
    Ragdoll ragdoll(RagdollAsset::create(*built.figure), w.world, {.comeToRest = false});
    REQUIRE(ragdoll.engineContactFriction()); // the scene's RagdollWorld holds the guard
    w.step(30);
    int checked = 0;
    btDispatcher& dispatcher = *w.world.getDispatcher();
    for (int m = 0; m < dispatcher.getNumManifolds(); ++m) {
        const btPersistentManifold* man = dispatcher.getManifoldByIndexInternal(m);
        const bool withGround = man->getBody0() == w.ground || man->getBody1() == w.ground;
        for (int c = 0; c < man->getNumContacts(); ++c) {
            const double f = man->getContactPoint(c).m_combinedFriction;
            // Ground: low's own 0.5 (Bullet's product would be 0.35); boxes: min(0.5, 0.3) (product 0.15).
            CHECK(f == Approx(withGround ? 0.5 : 0.3));
            ++checked;
        }
    }
    CHECK(checked >= 8);
}

TEST_CASE("drop: every bundled figure settles by its own rules, without exploding", "[runtime]") {
    for (const char* entity : {"humanoid", "props", "buggy", "lamp", "chain"}) {
        const afb::figure::LoadedFigure loaded = load(afb::test::sourceDir(), entity);
        const afb::figure::Figure& f = loaded.figure;
        World w(9.81, true);
        btTransform spawn = btTransform::getIdentity();
        spawn.setOrigin(btVector3(0, 0, 0.5f));
        Ragdoll ragdoll(RagdollAsset::create(f), w.world, {.entityTransform = spawn});
        const int limitSteps = static_cast<int>((f.rest.maxMoveTimeS > 0 ? f.rest.maxMoveTimeS : 10.0) * 60) + 2;
        int steps = 0;
        while (!ragdoll.atRest() && steps < limitSteps) {
            w.step(1);
            ++steps;
        }
        INFO(entity << ": " << steps << " steps");
        CHECK(ragdoll.atRest());
        for (const Transform& t : ragdoll.bodyTransforms()) CHECK(t.position.allFinite());
    }
}

TEST_CASE("an entity with \"sleep\" or \"nodrop\" spawns at rest", "[runtime]") {
    CHECK(load(afb::test::sourceDir(), "humanoid_sleeping").startAtRest);
    CHECK_FALSE(load(afb::test::sourceDir(), "humanoid").startAtRest);
}
