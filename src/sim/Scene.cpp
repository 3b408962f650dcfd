// The one scene (docs/architecture.md: src/sim): Bullet's default collision parts, the sequential-impulse solver,
// the method's world-level knobs through bullet::RagdollWorld.
#include "afb/sim/Scene.h"

namespace afb::sim {

Scene::Scene(const bullet::Method& method, const SceneSettings& settings)
    : m_method(method), m_config(std::make_unique<btDefaultCollisionConfiguration>()),
      m_dispatcher(std::make_unique<btCollisionDispatcher>(m_config.get())),
      m_broadphase(std::make_unique<btDbvtBroadphase>()) {
    bullet::WorldParts parts = bullet::makeWorld(method, *m_dispatcher, *m_broadphase, *m_config);
    m_solver = std::move(parts.solver);
    m_world = std::move(parts.world);
    // Plain Bullet runs Bullet's own scalar row update (Debian's build has no SSE solver on Linux); afbullet's
    // methods run the SSE one, which rounds bit for bit the same (RowKernels.h).
    if (auto* solver = dynamic_cast<bullet::RagdollSolver*>(m_solver.get()); solver && isRaw(method))
        solver->setSimdRows(false);
    m_world->setGravity(btVector3(0, 0, static_cast<btScalar>(-settings.gravityMps2)));
    // Bullet recomputes every object's bounding box every step by default, sleeping and static ones too; nothing
    // here moves a static or sleeping object without waking it, so only active objects are updated (what a resting
    // ragdoll costs, docs/performance.md).
    m_world->setForceUpdateAllAabbs(false);
    if (settings.ground) {
        m_groundShape = std::make_unique<btStaticPlaneShape>(btVector3(0, 0, 1), 0);
        m_ground = std::make_unique<btRigidBody>(0, nullptr, m_groundShape.get());
        m_ground->setFriction(static_cast<btScalar>(settings.groundFriction));
        m_world->addRigidBody(m_ground.get());
    }
    m_ragdollWorld = std::make_unique<bullet::RagdollWorld>(*m_world, m_method);
    m_ragdollWorld->setSinking(true); // the scene's own world: nothing ray-tests resting ragdolls behind our back
}

Scene::~Scene() {
    m_ragdolls.clear();
    m_rawRagdolls.clear();
    m_ragdollWorld.reset();
    if (m_ground) m_world->removeRigidBody(m_ground.get());
}

bullet::Ragdoll& Scene::spawn(std::shared_ptr<const bullet::RagdollAsset> asset, bullet::SpawnOptions options) {
    options.method = m_method;
    m_ragdolls.push_back(m_ragdollWorld->spawn(std::move(asset), options));
    return *m_ragdolls.back();
}

RawRagdoll& Scene::spawnRaw(std::shared_ptr<const bullet::RagdollAsset> asset, bullet::SpawnOptions options) {
    options.method = m_method;
    m_rawRagdolls.push_back(std::make_unique<RawRagdoll>(std::move(asset), *m_world, options));
    return *m_rawRagdolls.back();
}

ContactDepth Scene::deepestContact() const {
    ContactDepth out;
    for (int m = 0; m < m_dispatcher->getNumManifolds(); ++m) {
        const btPersistentManifold* man = m_dispatcher->getManifoldByIndexInternal(m);
        for (int c = 0; c < man->getNumContacts(); ++c) {
            const double depth = -static_cast<double>(man->getContactPoint(c).getDistance());
            if (depth > out.depthM) out = {depth, man->getBody0(), man->getBody1()};
        }
    }
    // A frozen ragdoll has no contacts in the world; it rests as deep as it was when it froze.
    for (const auto& r : m_ragdolls)
        if (r->frozen() && r->frozenContact().depthM > out.depthM)
            out = {r->frozenContact().depthM, r->frozenContact().a, r->frozenContact().b};
    return out;
}

} // namespace afb::sim
