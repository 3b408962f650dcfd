// A minimal afbullet program, using only the installed public headers:
//   1. open a content folder (af/, def/, models/) and build the figure of an entity,
//   2. create a Bullet world with a ground plane, and install a method's world-level knobs into it,
//   3. spawn two ragdolls of that figure (they share collision shapes),
//   4. step 2 seconds at 60 Hz and print the md5 joint positions of the first ragdoll.
// Usage: ragdoll_example [CONTENT_DIR] [ENTITY]   (defaults: . chain)
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>

#include <afb/afb.h>

int main(int argc, char** argv) {
    const std::string base = argc > 1 ? argv[1] : ".";
    const std::string entity = argc > 2 ? argv[2] : "chain";

    // 1. The figure: entityDef -> model decl -> md5mesh + af_pose -> .af figure, built in SI units.
    afb::text::Diagnostics diagnostics;
    std::optional<afb::figure::LoadedFigure> loaded;
    if (auto library = afb::decl::Library::open(base, diagnostics))
        loaded = afb::figure::loadEntityFigure(*library, entity, afb::figure::UnitSystem{}, diagnostics);
    for (const auto& d : diagnostics.items()) std::cerr << d.str() << "\n";
    if (!loaded) return 1;
    const afb::figure::Figure& figure = loaded->figure;

    // 2. Your world, as you already have it.
    btDefaultCollisionConfiguration config;
    btCollisionDispatcher dispatcher(&config);
    btDbvtBroadphase broadphase;
    // Bullet's solver, plus the default's direct joint solve and warm-started joints (any solver works, but with
    // another one RagdollWorld runs the iterative default: RagdollWorld::method() is the method in force)
    afb::bullet::RagdollSolver solver;
    btDiscreteDynamicsWorld world(&dispatcher, &broadphase, &solver, &config);
    world.setGravity(btVector3(0, 0, btScalar(-figure.units.gravityMps2)));
    btStaticPlaneShape groundShape(btVector3(0, 0, 1), 0);
    btRigidBody ground(0, nullptr, &groundShape);
    world.addRigidBody(&ground);
    // The method: its world-level knobs (solver, substeps, position pass, the engine's contact friction) live
    // as long as this guard; create it before the ragdolls, destroy it after them.
    const afb::bullet::Method method = *afb::bullet::methodPreset("default");
    afb::bullet::RagdollWorld ragdollWorld(world, method);

    // 3. Two ragdolls from one shared asset; the second one 1 m to the side. You own them; destroying one removes
    // it from the world (here: at the end of main, before ragdollWorld, which was declared first).
    const auto asset = afb::bullet::RagdollAsset::create(figure);
    afb::bullet::SpawnOptions where;
    where.method = method; // its per-ragdoll knobs
    afb::bullet::SpawnOptions second = where;
    second.entityTransform.setOrigin(btVector3(0, 1, 0));
    const std::unique_ptr<afb::bullet::Ragdoll> first = ragdollWorld.spawn(asset, where);
    const std::unique_ptr<afb::bullet::Ragdoll> other = ragdollWorld.spawn(asset, second);

    // 4. Step (the method's substeps inside), then read the skeleton back.
    for (int i = 0; i < 120; ++i) ragdollWorld.step(1.0 / 60.0);
    const afb::pose::SkeletonPose pose = afb::pose::driveSkeleton(figure, first->bodyTransforms());
    const auto joints = pose.world();
    std::printf("%s: %d bodies, %d joints after 2 s (world, metres)\n", figure.name.c_str(), first->bodyCount(),
                figure.skeleton.jointCount());
    for (int j = 0; j < figure.skeleton.jointCount(); ++j) {
        const Eigen::Vector3d& p = joints[static_cast<std::size_t>(j)].position;
        std::printf("  %-16s %8.4f %8.4f %8.4f\n", figure.skeleton.name(j).c_str(), p.x(), p.y(), p.z());
    }
    world.removeRigidBody(&ground);
    return 0;
}
