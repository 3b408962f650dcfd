// start_from_animation: a ragdoll that takes over from an animation, as when a walking character dies.
//   1. build the entity's figure and read one of its model's anims (an .md5anim) from the content folder,
//   2. pose every body as the anim poses the skeleton 0.5 s in, with the velocities the anim gives them there,
//      plus the entity's own walking velocity (the anim's root motion is the entity's, not the bodies'),
//   3. spawn the ragdoll at the same entity transform, set those states, step 1 s at 60 Hz and print.
// Usage: start_from_animation [CONTENT_DIR] [ENTITY] [ANIM]   (defaults: bundled content, humanoid, walk)
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
    const std::string animName = argc > 3 ? argv[3] : "walk";

    // 1. The figure, and the anim's file from the entity's model decl (resolveEntity: inheritance applied).
    afb::text::Diagnostics diagnostics;
    const auto library = afb::decl::Library::open(base, diagnostics);
    std::optional<afb::figure::LoadedFigure> loaded;
    std::optional<afb::decl::ResolvedEntity> resolved;
    if (library) resolved = library->resolveEntity(entity, diagnostics);
    if (resolved) loaded = afb::figure::loadEntityFigure(*library, entity, afb::figure::UnitSystem{}, diagnostics);
    std::optional<afb::decl::Md5Anim> anim;
    if (loaded)
        for (const afb::decl::ModelAnim& a : resolved->model.anims)
            if (a.name == animName && !a.files.empty())
                anim = afb::decl::loadMd5Anim(library->baseDir() / a.files[0], diagnostics);
    for (const auto& d : diagnostics.items()) std::fprintf(stderr, "%s\n", d.str().c_str());
    if (!library) return fail("cannot open content folder '" + base + "'");
    if (!loaded) return fail("cannot load entity '" + entity + "'");
    if (!anim) return fail("no readable anim '" + animName + "' in the model of '" + entity + "'");
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

    // 2. Body states at 0.5 s into the anim, the entity standing at the origin, 1 cm up, walking 1.4 m/s along +X.
    afb::figure::Transform entityPose;
    entityPose.position = Eigen::Vector3d(0, 0, 0.01);
    afb::text::Diagnostics poseDiagnostics; // an anim that does not fit the skeleton is reported here
    auto states = afb::figure::bodyStatesFromAnimation(figure, *anim, 0.5, entityPose, poseDiagnostics);
    for (const auto& d : poseDiagnostics.items()) std::fprintf(stderr, "%s\n", d.str().c_str());
    if (!states) return fail("cannot pose '" + entity + "' by '" + animName + "'");
    for (afb::figure::BodyState& s : *states) s.linearVelocity += Eigen::Vector3d(1.4, 0, 0);

    // 3. The ragdoll, spawned at the same entity transform (its world-attached joints are placed by it).
    afb::bullet::SpawnOptions options = afb::bullet::spawnOptionsFor(*loaded, method);
    options.entityTransform = afb::bullet::toBt(entityPose);
    const std::unique_ptr<afb::bullet::Ragdoll> ragdoll = ragdollWorld.spawn(asset, options);
    if (!ragdoll->setBodyStates(*states)) return fail("the states do not fit the ragdoll");
    const auto print = [&](const char* when) {
        const afb::figure::BodyState s = ragdoll->bodyState(0);
        std::printf("  %-9s %s at (%6.3f, %6.3f, %6.3f) m, moving %.3f m/s\n", when, figure.bodies[0].name.c_str(),
                    s.pose.position.x(), s.pose.position.y(), s.pose.position.z(), s.linearVelocity.norm());
    };
    std::printf("%s from '%s' at 0.5 s:\n", entity.c_str(), animName.c_str());
    print("start:");
    for (int frame = 0; frame < 60; ++frame) ragdollWorld.step(1.0 / 60.0);
    print("after 1 s:");
    return 0;
} catch (const std::exception& e) {
    return fail(e.what());
}
