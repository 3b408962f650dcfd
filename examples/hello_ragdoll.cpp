// hello_ragdoll: an entity's ragdoll dropped onto the ground of your own Bullet world.
//   1. open a content folder (af/, def/, models/) and build the entity's figure (SI units),
//   2. make a btDiscreteDynamicsWorld with afbullet's solver and a ground plane, and a RagdollWorld over it,
//   3. spawn one ragdoll, tilted, half a metre above the ground, step 2 s at 60 Hz,
//   4. drive the md5 skeleton from the bodies and print a few joints, and whether the ragdoll came to rest.
// Usage: hello_ragdoll [CONTENT_DIR] [ENTITY]   (defaults: afbullet's bundled content, humanoid)
#include <algorithm>
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

    // 1. Every problem (missing folder, unknown entity, a bad file) is a diagnostic: print them all.
    afb::text::Diagnostics diagnostics;
    const auto library = afb::decl::Library::open(base, diagnostics);
    std::optional<afb::figure::LoadedFigure> loaded;
    if (library) loaded = afb::figure::loadEntityFigure(*library, entity, afb::figure::UnitSystem{}, diagnostics);
    for (const auto& d : diagnostics.items()) std::fprintf(stderr, "%s\n", d.str().c_str());
    if (!library) return fail("cannot open content folder '" + base + "'");
    if (!loaded) return fail("cannot load entity '" + entity + "'");
    const auto asset = afb::bullet::RagdollAsset::create(loaded->figure);
    const afb::figure::Figure& figure = asset->figure();

    // 2. The world. The ground is declared first: it must outlive the world, whose destructor still reads it.
    btStaticPlaneShape groundShape(btVector3(0, 0, 1), 0);
    btRigidBody ground(0, nullptr, &groundShape);
    btDefaultCollisionConfiguration config;
    btCollisionDispatcher dispatcher(&config);
    btDbvtBroadphase broadphase;
    afb::bullet::RagdollSolver solver; // the default method's direct joint solve needs it
    btDiscreteDynamicsWorld world(&dispatcher, &broadphase, &solver, &config);
    world.setGravity(btVector3(0, 0, btScalar(-figure.units.gravityMps2)));
    world.addRigidBody(&ground);
    const afb::bullet::Method method;                      // the "default" preset
    afb::bullet::RagdollWorld ragdollWorld(world, method); // outlives the ragdolls: declared before them

    // 3. Spawn tilted 30° about X, the lowest point of its bodies 0.5 m above the ground (shape bounds).
    afb::bullet::SpawnOptions options = afb::bullet::spawnOptionsFor(*loaded, method);
    options.entityTransform.setRotation(btQuaternion(btVector3(1, 0, 0), btScalar(0.52)));
    btScalar lowest = BT_LARGE_FLOAT;
    for (std::size_t i = 0; i < figure.bodies.size(); ++i) {
        btVector3 lo, hi;
        const btTransform pose = options.entityTransform * afb::bullet::toBt(figure.bodies[i].loadPose);
        asset->shape(static_cast<int>(i))->getAabb(pose, lo, hi);
        lowest = std::min(lowest, lo.z());
    }
    options.entityTransform.setOrigin(btVector3(0, 0, btScalar(0.5) - lowest));
    // Yours to own: destroying it (here, at the end of main, before ragdollWorld) takes it out of the world.
    const std::unique_ptr<afb::bullet::Ragdoll> ragdoll = ragdollWorld.spawn(asset, options);
    for (int frame = 0; frame < 120; ++frame) ragdollWorld.step(1.0 / 60.0);

    // 4. The skeleton a renderer would skin, in world space (metres).
    const afb::pose::SkeletonPose skeleton = afb::pose::driveSkeleton(figure, ragdoll->bodyTransforms());
    const std::vector<afb::figure::Transform> joints = skeleton.world();
    std::printf("%s: %d bodies, %d md5 joints, after 2 s:\n", entity.c_str(), ragdoll->bodyCount(),
                figure.skeleton.jointCount());
    for (std::size_t i = 0; i < std::min<std::size_t>(figure.bodies.size(), 6); ++i) {
        const int j = figure.bodies[i].joint; // the md5 joint body i drives
        if (j < 0) continue;
        const Eigen::Vector3d& p = joints[static_cast<std::size_t>(j)].position;
        std::printf("  %-12s (%7.3f, %7.3f, %7.3f) m\n", figure.skeleton.name(j).c_str(), p.x(), p.y(), p.z());
    }
    std::printf("at rest: %s (%d of %d bodies awake)\n", ragdoll->atRest() ? "yes" : "no", ragdoll->awakeBodyCount(),
                ragdoll->bodyCount());
    return 0;
} catch (const std::exception& e) {
    return fail(e.what());
}
