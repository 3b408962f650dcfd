// shoot_and_hit: a ragdoll on the ground, hit by a shot.
//   1. spawn the entity standing on the ground and let it settle for 3 s (a humanoid rests standing, frozen),
//   2. cast a ray from a gun point 2 m away at the height of its first body (the pelvis of a humanoid),
//   3. find the figure body the ray hit and give it a 30 N·s impulse along the ray at the hit point,
//   4. print the body's name, its speed before and after, and its speed and height 1 s later.
// Usage: shoot_and_hit [CONTENT_DIR] [ENTITY]   (defaults: afbullet's bundled content, humanoid)
#include <cstdio>
#include <exception>
#include <memory>
#include <string>

#include <afb/afb.h>
#include <afb/bullet/Convert.h> // toBt: Eigen and afb::figure::Transform to Bullet

namespace {
/// Prints `error: <message>` to stderr; returns main's exit code for it.
int fail(const std::string& message) {
    std::fprintf(stderr, "error: %s\n", message.c_str());
    return 1;
}
} // namespace

int main(int argc, char** argv) try {
    const std::string base = argc > 1 ? argv[1] : AFB_EXAMPLES_CONTENT_DIR;
    const std::string entity = argc > 2 ? argv[2] : "humanoid";

    afb::text::Diagnostics diagnostics;
    const auto library = afb::decl::Library::open(base, diagnostics);
    std::optional<afb::figure::LoadedFigure> loaded;
    if (library) loaded = afb::figure::loadEntityFigure(*library, entity, afb::figure::UnitSystem{}, diagnostics);
    for (const auto& d : diagnostics.items()) std::fprintf(stderr, "%s\n", d.str().c_str());
    if (!library) return fail("cannot open content folder '" + base + "'");
    if (!loaded) return fail("cannot load entity '" + entity + "'");
    const auto asset = afb::bullet::RagdollAsset::create(loaded->figure);
    const afb::figure::Figure& figure = asset->figure();

    btStaticPlaneShape groundShape(btVector3(0, 0, 1), 0);
    btRigidBody ground(0, nullptr, &groundShape); // outlives the world
    btDefaultCollisionConfiguration config;
    btCollisionDispatcher dispatcher(&config);
    btDbvtBroadphase broadphase;
    afb::bullet::RagdollSolver solver;
    btDiscreteDynamicsWorld world(&dispatcher, &broadphase, &solver, &config);
    world.setGravity(btVector3(0, 0, btScalar(-figure.units.gravityMps2)));
    world.addRigidBody(&ground);
    const afb::bullet::Method method;
    afb::bullet::RagdollWorld ragdollWorld(world, method);

    // 1. Spawned where the entity stands (model space: the floor at z = 0), 1 cm up.
    afb::bullet::SpawnOptions options = afb::bullet::spawnOptionsFor(*loaded, method);
    options.entityTransform.setOrigin(btVector3(0, 0, btScalar(0.01)));
    const std::unique_ptr<afb::bullet::Ragdoll> ragdoll = ragdollWorld.spawn(asset, options);
    for (int frame = 0; frame < 180; ++frame) ragdollWorld.step(1.0 / 60.0);

    // 2. The shot: from 2 m off along +X, through the first body's centre of mass, 5 m long.
    const btVector3 target = afb::bullet::toBt(ragdoll->bodyState(0).pose.position);
    const btVector3 gun = target + btVector3(2, 0, 0.3f);
    const btVector3 end = gun + (target - gun).normalized() * 5;
    btCollisionWorld::ClosestRayResultCallback ray(gun, end);
    world.rayTest(gun, end, ray);
    if (!ray.hasHit()) return fail("the shot missed");

    // 3. What did it hit? The ray hit a Bullet object; the ragdoll says which figure body that is (−1: not its).
    const int body = ragdoll->figureBodyOf(*ray.m_collisionObject, ray.m_hitPointWorld);
    if (body < 0) return fail("the shot hit something else");
    const auto speed = [&] { return ragdoll->bodyState(body).linearVelocity.norm(); };
    const double before = speed();
    const btVector3 impulse = (end - gun).normalized() * 30; // N·s: a heavy hit
    // Always: apply it even below the engine's wake threshold (ImpulseRule::EngineThreshold would ignore those).
    if (!ragdoll->applyBodyImpulse(body, impulse, ray.m_hitPointWorld, afb::bullet::ImpulseRule::Always))
        return fail("the impulse was not applied");
    const double after = speed();
    for (int frame = 0; frame < 60; ++frame) ragdollWorld.step(1.0 / 60.0);

    // 4. The report.
    const auto& hit = ray.m_hitPointWorld;
    std::printf("%s: shot hit body '%s' at (%.3f, %.3f, %.3f) m\n", entity.c_str(),
                figure.bodies[static_cast<std::size_t>(body)].name.c_str(), double(hit.x()), double(hit.y()),
                double(hit.z()));
    std::printf("  speed %.3f m/s before, %.3f m/s after the impulse; 1 s later %.3f m/s, %.3f m above the ground\n",
                before, after, speed(), ragdoll->bodyState(body).pose.position.z());
    return 0;
} catch (const std::exception& e) {
    return fail(e.what());
}
