// The soak: one world, ragdolls spawned and removed in a churn (mixed figures, some spawned at rest so that they
// freeze and sink, hits above the wake threshold, non-finite states injected so that the explosion guard trips),
// with the process's resident memory reported along the way. Fails (exit 1) when a ragdoll's state is not finite at
// its removal or at the end, when a NaN written did not trip the guard (or a trip on a NaN came from nowhere), or
// when memory grows past the bound after the warm-up. Ragdolls spawned into one another at random may also trip the
// guard on speed or an open joint: counted and reported, not failures (the guard restored them).
//
//   afb_soak [--lifetimes N] [--live K] [--method PRESET] [--seed S] [--base DIR] [--max-growth-mb M]
//
// Deterministic: fixed 60 Hz steps, a seeded generator, spawns and removals in a fixed order.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <unistd.h>

#include "afb/bullet/Method.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/decl/Library.h"
#include "afb/detail/Convert.h"
#include "afb/figure/Load.h"
#include "afb/sim/Scene.h"

namespace {

using afb::bullet::Ragdoll;

struct Options {
    long lifetimes = 100000;
    int live = 32;
    std::string method = "default";
    unsigned seed = 1;
    std::string base = AFB_SOURCE_DIR;
    double maxGrowthMb = 16;
};

bool parse(int argc, char** argv, Options& o) {
    for (int i = 1; i + 1 < argc; i += 2) {
        const std::string key = argv[i], value = argv[i + 1];
        if (key == "--lifetimes") o.lifetimes = std::atol(value.c_str());
        else if (key == "--live") o.live = std::atoi(value.c_str());
        else if (key == "--method") o.method = value;
        else if (key == "--seed") o.seed = static_cast<unsigned>(std::atol(value.c_str()));
        else if (key == "--base") o.base = value;
        else if (key == "--max-growth-mb") o.maxGrowthMb = std::atof(value.c_str());
        else return false;
    }
    return argc % 2 == 1 && o.lifetimes > 0 && o.live > 0;
}

double residentMb() {
    long pages = 0, resident = 0;
    if (FILE* f = std::fopen("/proc/self/statm", "r")) {
        if (std::fscanf(f, "%ld %ld", &pages, &resident) != 2) resident = 0;
        std::fclose(f);
    }
    return static_cast<double>(resident) * static_cast<double>(::sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

bool finite(const Ragdoll& r) {
    for (const afb::figure::BodyState& s : r.bodyStates())
        if (!(s.pose.position.allFinite() && s.pose.rotation.allFinite() && s.linearVelocity.allFinite() &&
              s.angularVelocity.allFinite()))
            return false;
    return true;
}

// One ragdoll of the churn and what is planned for it.
struct Life {
    std::unique_ptr<Ragdoll> ragdoll;
    int stepsLeft = 0;
    int hitAt = -1;    ///< steps left when it is hit, or −1
    int poisonAt = -1; ///< steps left when a NaN is written into it, or −1
};

struct Counts {
    long spawned = 0, hits = 0, poisoned = 0, frozenSeen = 0, sunkSeen = 0;
    long nonFiniteTrips = 0, otherTrips = 0; ///< guard trips on a NaN, and on speed or an open joint
};

} // namespace

int main(int argc, char** argv) {
    Options o;
    if (!parse(argc, argv, o)) {
        std::fprintf(stderr, "usage: afb_soak [--lifetimes N] [--live K] [--method PRESET] [--seed S] [--base DIR] "
                             "[--max-growth-mb M]\n");
        return 2;
    }
    const std::optional<afb::bullet::Method> method = afb::bullet::methodPreset(o.method);
    if (!method) {
        std::fprintf(stderr, "afb_soak: unknown method %s\n", o.method.c_str());
        return 2;
    }
    afb::text::Diagnostics diags;
    const std::optional<afb::decl::Library> library = afb::decl::Library::open(o.base, diags);
    std::vector<std::shared_ptr<const afb::bullet::RagdollAsset>> assets;
    for (const char* entity : {"humanoid", "chain", "buggy", "lamp", "props"}) {
        std::optional<afb::figure::LoadedFigure> loaded;
        if (library) loaded = afb::figure::loadEntityFigure(*library, entity, {}, diags);
        if (!loaded) {
            std::fprintf(stderr, "%safb_soak: %s does not load from %s\n", diags.str().c_str(), entity, o.base.c_str());
            return 2;
        }
        assets.push_back(afb::bullet::RagdollAsset::create(std::move(loaded->figure)));
    }

    afb::sim::Scene scene(*method, {.gravityMps2 = 9.81, .ground = true});
    std::mt19937 rng(o.seed);
    auto uniform = [&rng](double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); };
    auto chance = [&](double p) { return uniform(0, 1) < p; };
    Counts n;
    std::vector<Life> lives(static_cast<std::size_t>(o.live));
    auto spawn = [&](Life& l) {
        afb::bullet::SpawnOptions so;
        so.method = *method;
        so.startAtRest = chance(0.2); // frozen from the start; sinks when nothing active comes near
        so.entityTransform.setRotation(btQuaternion(btVector3(0, 0, 1), static_cast<btScalar>(uniform(0, 6.28))));
        so.entityTransform.setOrigin(btVector3(static_cast<btScalar>(uniform(-10, 10)),
                                               static_cast<btScalar>(uniform(-10, 10)),
                                               static_cast<btScalar>(uniform(0.3, 3))));
        so.guard.onTrip = [&n](Ragdoll&, const afb::bullet::GuardTrip& trip) {
            ++(trip.cause == afb::bullet::GuardTrip::Cause::NonFinite ? n.nonFiniteTrips : n.otherTrips);
        };
        const auto& asset = assets[static_cast<std::size_t>(rng() % assets.size())];
        l.ragdoll = scene.ragdollWorld().spawn(asset, so);
        l.stepsLeft = 10 + static_cast<int>(rng() % 50);
        l.hitAt = chance(0.1) ? static_cast<int>(rng() % static_cast<unsigned>(l.stepsLeft)) : -1;
        l.poisonAt = chance(0.02) ? static_cast<int>(rng() % static_cast<unsigned>(l.stepsLeft)) : -1;
        ++n.spawned;
    };

    const double startMb = residentMb();
    double warmMb = 0;
    long lastReport = 0;
    std::printf("afb_soak: %ld lifetimes, %d live, method %s, seed %u; RSS %.1f MB at the start\n", o.lifetimes, o.live,
                o.method.c_str(), o.seed, startMb);
    for (Life& l : lives) spawn(l);
    long steps = 0;
    bool ok = true;
    while (n.spawned < o.lifetimes) {
        for (Life& l : lives) {
            Ragdoll& r = *l.ragdoll;
            if (l.stepsLeft == l.hitAt) {
                const int body = static_cast<int>(rng() % static_cast<unsigned>(r.bodyCount()));
                const btVector3 at = afb::bullet::toBt(Eigen::Vector3d(r.bodyState(body).pose.position));
                n.hits += r.applyBodyImpulse(body, btVector3(0, 0, btScalar(3 * r.impulseThresholdNs())), at);
            }
            if (l.stepsLeft == l.poisonAt) {
                std::vector<afb::figure::BodyState> states = r.bodyStates();
                states[0].linearVelocity.x() = std::numeric_limits<double>::quiet_NaN();
                if (r.setBodyStates(states)) ++n.poisoned;
            }
        }
        scene.step(1.0 / 60.0);
        ++steps;
        for (Life& l : lives) {
            n.frozenSeen += l.ragdoll->frozen();
            n.sunkSeen += l.ragdoll->sunk();
            if (--l.stepsLeft > 0) continue;
            if (!finite(*l.ragdoll)) ok = false;
            l.ragdoll.reset(); // removed from the world by its destructor
            spawn(l);
        }
        if (warmMb == 0 && n.spawned >= o.lifetimes / 10) warmMb = residentMb();
        if (n.spawned - lastReport >= o.lifetimes / 10) {
            lastReport = n.spawned;
            std::printf("afb_soak: %7ld lifetimes, %7ld steps, RSS %.1f MB\n", n.spawned, steps, residentMb());
            std::fflush(stdout);
        }
    }
    for (const Life& l : lives) ok = ok && finite(*l.ragdoll);
    const double endMb = residentMb();
    std::printf("afb_soak: %ld lifetimes in %ld steps: %ld hits, %ld NaN written, %ld guard trips on a NaN and %ld on "
                "speed or an open joint; frozen in %ld and sunk in %ld ragdoll-steps; RSS %.1f MB at the start, %.1f "
                "after the warm-up, %.1f at the end\n",
                n.spawned, steps, n.hits, n.poisoned, n.nonFiniteTrips, n.otherTrips, n.frozenSeen, n.sunkSeen, startMb,
                warmMb, endMb);
    if (!ok) std::printf("afb_soak: FAILED: a ragdoll's state is not finite\n");
    if (n.nonFiniteTrips != n.poisoned) {
        std::printf("afb_soak: FAILED: %ld NaN written but %ld guard trips on a NaN\n", n.poisoned, n.nonFiniteTrips);
        ok = false;
    }
#if defined(__SANITIZE_ADDRESS__)
    std::printf("afb_soak: memory not judged under AddressSanitizer (its quarantine holds freed memory)\n");
#else
    if (endMb - warmMb > o.maxGrowthMb) {
        std::printf("afb_soak: FAILED: RSS grew %.1f MB after the warm-up (bound %.1f)\n", endMb - warmMb,
                    o.maxGrowthMb);
        ok = false;
    }
#endif
    return ok ? 0 : 1;
}
