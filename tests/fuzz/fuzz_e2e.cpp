// libFuzzer target, end to end: bytes → parseAf → buildFigure on a bundled skeleton → spawn into a
// world that also holds a user body → 60 steps. Oracle: whatever builds simulates to finite state, and the
// user's own body (filtered so that it never touches the ragdoll) moves exactly as in a world without it.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <string>
#include <string_view>

#include "afb/bullet/RagdollAsset.h"
#include "afb/decl/AfParser.h"
#include "afb/decl/Library.h"
#include "afb/detail/Lexer.h"
#include "afb/figure/Figure.h"
#include "afb/figure/Load.h"
#include "afb/sim/Scene.h"

namespace {

// The bundled entities' skeletons, by figure name (lower case); the humanoid's is the fallback.
std::map<std::string, std::shared_ptr<afb::figure::Skeleton>> g_skeletons;

std::string lower(std::string s) {
    for (char& c : s) c = static_cast<char>((c >= 'A' && c <= 'Z') ? c - 'A' + 'a' : c);
    return s;
}

void loadSkeletons() {
    afb::text::Diagnostics d;
    const auto library = afb::decl::Library::open(AFB_SOURCE_DIR, d);
    if (!library) std::abort();
    for (const char* entity : {"humanoid", "chain", "props", "lamp", "buggy"}) {
        auto loaded = afb::figure::loadEntityFigure(*library, entity, {}, d);
        if (!loaded) std::abort();
        g_skeletons[lower(loaded->decl.name)] =
            std::make_shared<afb::figure::Skeleton>(std::move(loaded->figure.skeleton));
    }
}

// The user's body: a box sliding on the ground 1 km away, in a collision group the ragdoll never sees.
constexpr int kUserGroup = 1 << 6;

struct UserBody {
    btBoxShape shape{btVector3(0.5f, 0.5f, 0.5f)};
    std::unique_ptr<btRigidBody> body;

    explicit UserBody(btDiscreteDynamicsWorld& world) {
        btVector3 inertia(0, 0, 0);
        shape.calculateLocalInertia(2, inertia);
        btTransform start = btTransform::getIdentity();
        start.setOrigin(btVector3(1000, 0, 0.6f));
        body = std::make_unique<btRigidBody>(2, nullptr, &shape, inertia);
        body->setWorldTransform(start);
        body->setLinearVelocity(btVector3(3, 1, 0));
        body->setAngularVelocity(btVector3(0, 0, 2));
        body->setActivationState(DISABLE_DEACTIVATION);
        world.addRigidBody(body.get(), kUserGroup, btBroadphaseProxy::StaticFilter);
    }
};

struct Run {
    btTransform user;
    bool finite = true;
};

constexpr int kSteps = 60;

// One world: the ground, the user's body and (when given) the ragdoll; kSteps frames at 60 Hz.
Run simulate(const std::shared_ptr<const afb::bullet::RagdollAsset>& asset) {
    afb::sim::Scene scene(afb::bullet::Method{});
    UserBody user(scene.world());
    if (asset) {
        afb::bullet::SpawnOptions options;
        options.collisionMask = btBroadphaseProxy::AllFilter & ~kUserGroup;
        scene.spawn(asset, options);
    }
    Run run;
    for (int step = 0; step < kSteps && run.finite; ++step) {
        scene.step(1.0 / 60.0);
        for (const auto& ragdoll : scene.ragdolls())
            for (const afb::figure::BodyState& s : ragdoll->bodyStates())
                if (!s.pose.position.allFinite() || !s.pose.rotation.allFinite() || !s.linearVelocity.allFinite() ||
                    !s.angularVelocity.allFinite())
                    run.finite = false;
    }
    scene.world().removeRigidBody(user.body.get());
    run.user = user.body->getWorldTransform();
    return run;
}

} // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    loadSkeletons();
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static const Run alone = simulate(nullptr);
    const std::string_view src(reinterpret_cast<const char*>(data), size);
    afb::text::Diagnostics diags;
    const auto file = afb::decl::parseAf(src, "fuzz.af", diags);
    if (!file || file->decls.empty()) return 0;
    const afb::decl::AfDecl& decl = file->decls.front();
    const auto known = g_skeletons.find(lower(decl.name));
    const auto& skeleton = known != g_skeletons.end() ? known->second : g_skeletons.at("humanoid");
    auto figure = afb::figure::buildFigure({&decl, skeleton.get(), {}, false}, diags);
    if (!figure) {
        if (!diags.hasErrors()) std::abort(); // a refused figure must say why
        return 0;
    }
    const Run run = simulate(afb::bullet::RagdollAsset::create(std::move(*figure)));
    if (!run.finite) {
        std::fprintf(stderr, "e2e: a figure that built simulated to non-finite state\n%s\n", diags.str().c_str());
        std::abort();
    }
    const btVector3 dp = run.user.getOrigin() - alone.user.getOrigin();
    const btQuaternion q1 = run.user.getRotation(), q0 = alone.user.getRotation();
    if (dp.length() > 0 || !(q1 == q0)) {
        std::fprintf(stderr, "e2e: the user's body moved differently with the ragdoll in the world (by %g m)\n",
                     static_cast<double>(dp.length()));
        std::abort();
    }
    return 0;
}
