#pragma once
// The one scene the tools and tests build: a Bullet world set up the one documented way from a Method (through
// bullet::RagdollWorld), an optional ground plane, and the ragdolls spawned into it. A game brings its own world
// instead (see tests/consumer); this type is for afbullet's own drop runs, goldens, charts and tests.
#include <memory>
#include <vector>

#include <btBulletDynamicsCommon.h>

#include "afb/bullet/Method.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/bullet/RagdollSolver.h"
#include "afb/bullet/RagdollWorld.h"
#include "afb/sim/RawRagdoll.h"

namespace afb::sim {

/// What the scene holds besides the ragdolls.
struct SceneSettings {
    double gravityMps2 = 9.81;   ///< along −Z (0: weightless)
    bool ground = true;          ///< a static plane z = 0
    double groundFriction = 1.0; ///< Coulomb coefficient of the ground
};

/// The deepest contact in the scene now.
struct ContactDepth {
    double depthM = 0; ///< penetration, metres (0 when nothing overlaps)
    const btCollisionObject* a = nullptr;
    const btCollisionObject* b = nullptr;
};

/// A world with the method's settings, a ground and ragdolls. Not copyable; one thread. The world is a
/// btMultiBodyDynamicsWorld with Bullet's btMultiBodyConstraintSolver for a multibody method, a
/// btDiscreteDynamicsWorld with a bullet::RagdollSolver otherwise (bullet::makeWorld decides).
class Scene {
  public:
    explicit Scene(const bullet::Method& method, const SceneSettings& settings = {});
    ~Scene();
    Scene(const Scene&) = delete;
    Scene& operator=(const Scene&) = delete;

    /// Spawns a ragdoll of `asset`; `options.method` is replaced by the scene's method.
    bullet::Ragdoll& spawn(std::shared_ptr<const bullet::RagdollAsset> asset, bullet::SpawnOptions options = {});
    /// Spawns plain Bullet's version of `asset` (the reference; see RawRagdoll); `options.method` is replaced by
    /// the scene's method. A scene made with rawMethod() is a world with Bullet's defaults: its RagdollWorld sets
    /// the knobs to them and its position pass and contact friction touch no raw body.
    RawRagdoll& spawnRaw(std::shared_ptr<const bullet::RagdollAsset> asset, bullet::SpawnOptions options = {});

    /// Steps one frame of `dtSeconds` (the method's substeps inside).
    void step(double dtSeconds) { m_ragdollWorld->step(dtSeconds); }

    const bullet::Method& method() const { return m_method; }
    btDiscreteDynamicsWorld& world() { return *m_world; }
    bullet::RagdollWorld& ragdollWorld() { return *m_ragdollWorld; }
    /// The ground body, or nullptr without a ground.
    btRigidBody* ground() { return m_ground.get(); }
    /// The ragdolls in spawn order.
    const std::vector<std::unique_ptr<bullet::Ragdoll>>& ragdolls() const { return m_ragdolls; }
    /// The plain-Bullet ragdolls in spawn order.
    const std::vector<std::unique_ptr<RawRagdoll>>& rawRagdolls() const { return m_rawRagdolls; }

    /// The deepest contact between any two objects now (ragdoll bodies and the ground).
    ContactDepth deepestContact() const;

  private:
    bullet::Method m_method;
    std::unique_ptr<btDefaultCollisionConfiguration> m_config;
    std::unique_ptr<btCollisionDispatcher> m_dispatcher;
    std::unique_ptr<btBroadphaseInterface> m_broadphase;
    std::unique_ptr<btConstraintSolver> m_solver;
    std::unique_ptr<btDiscreteDynamicsWorld> m_world;
    std::unique_ptr<btCollisionShape> m_groundShape;
    std::unique_ptr<btRigidBody> m_ground;
    std::unique_ptr<bullet::RagdollWorld> m_ragdollWorld;
    std::vector<std::unique_ptr<bullet::Ragdoll>> m_ragdolls; // destroyed first
    std::vector<std::unique_ptr<RawRagdoll>> m_rawRagdolls;
};

} // namespace afb::sim
