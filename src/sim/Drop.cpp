// Drop runs (src/sim): the scene, the per-step measurements and their aggregation over worlds and threads.
#include "afb/sim/Drop.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <numbers>
#include <optional>
#include <random>
#include <thread>

#include <LinearMath/btScalar.h>
#include <time.h>

#include "afb/detail/Convert.h"
#include "afb/figure/Lod.h"
#include "afb/pose/SkeletonDriver.h"
#include "afb/sim/RawRagdoll.h"
#include "afb/sim/Scene.h"
#include "afb/sim/Stress.h"

namespace afb::sim {
namespace {

using bullet::Ragdoll;
using bullet::RagdollAsset;

// Model-space bounds of a figure's bodies at the load pose, for spacing and spawn height.
void figureBounds(const figure::Figure& f, const btMatrix3x3& rotation, btVector3& lo, btVector3& hi) {
    lo = btVector3(BT_LARGE_FLOAT, BT_LARGE_FLOAT, BT_LARGE_FLOAT);
    hi = -lo;
    for (const figure::FigureBody& b : f.bodies)
        for (const Eigen::Vector3d& v : b.shape.vertices) {
            const btVector3 p = rotation * bullet::toBt(b.loadPose.apply(v));
            lo.setMin(p);
            hi.setMax(p);
        }
}

struct Partial {
    DropResult r;
    double stepSeconds = 0;
    double cpuSeconds = 0;                    // thread CPU time inside the steps
    double awakeCpuSeconds = 0;               // of it, in steps that began or ended with a body awake
    double worstAnchor = -1, worstLimit = -1; // for the names of the worst joints
    std::vector<double> restTimes;            // per instance, −1 if never
    std::vector<char> touched;                // per instance: a body of it has touched something not its own
    std::vector<figure::Transform> firstBodies;
};

// Kinetic + potential energy of a ragdoll, J, from its body states and the figure's mass properties.
template <class Doll>
double energy(const Doll& d, double g) {
    return figureEnergyJ(d.figure(), d.bodyStates(), g);
}

// The body's name if `o` is one of `dolls`' bodies.
template <class Doll>
std::optional<std::string> bodyName(const std::vector<std::unique_ptr<Doll>>& dolls, const btCollisionObject* o) {
    for (const auto& d : dolls)
        for (int i = 0; i < d->bodyCount(); ++i)
            if (&d->collisionObject(i) == o) return d->figure().bodies[static_cast<std::size_t>(i)].name;
    return std::nullopt;
}

// "figure/body" of a collision object in the scene, "ground", or "other".
std::string objectName(Scene& scene, const btCollisionObject* o) {
    if (o == scene.ground()) return "ground";
    if (auto name = bodyName(scene.ragdolls(), o)) return *name;
    if (auto name = bodyName(scene.rawRagdolls(), o)) return *name;
    return "other";
}

std::string contactName(Scene& scene, const ContactDepth& c) {
    return objectName(scene, c.a) + " / " + objectName(scene, c.b);
}

// A contact point this close (metres) is a touch: Bullet keeps points up to its breaking threshold apart.
constexpr double kTouchM = 1e-3;

// Marks the instances with a body touching something other than the instance itself (the ground, another
// instance). Run after each step while some instance has neither touched anything nor come to rest.
template <class Doll>
void markTouches(Scene& scene, const std::vector<std::unique_ptr<Doll>>& dolls, std::vector<char>& touched) {
    std::map<const btCollisionObject*, std::size_t> owner;
    for (std::size_t k = 0; k < dolls.size(); ++k)
        for (int i = 0; i < dolls[k]->bodyCount(); ++i) owner[&dolls[k]->collisionObject(i)] = k;
    btDispatcher& dispatcher = *scene.world().getDispatcher();
    for (int m = 0; m < dispatcher.getNumManifolds(); ++m) {
        const btPersistentManifold& manifold = *dispatcher.getManifoldByIndexInternal(m);
        bool touching = false;
        for (int p = 0; p < manifold.getNumContacts() && !touching; ++p)
            touching = manifold.getContactPoint(p).getDistance() < kTouchM;
        if (!touching) continue;
        const auto a = owner.find(manifold.getBody0()), b = owner.find(manifold.getBody1());
        const bool aIsDoll = a != owner.end(), bIsDoll = b != owner.end();
        if (aIsDoll && bIsDoll && a->second == b->second) continue; // the instance touching itself
        if (aIsDoll) touched[a->second] = 1;
        if (bIsDoll) touched[b->second] = 1;
    }
}

// CPU time this thread has used, seconds (what the cost of a method is measured in: not wall time, so other
// threads and processes on the machine do not count).
double threadCpuSeconds() {
    timespec ts{};
    ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

// The measurements of one world, the same for every kind of ragdoll (bullet::Ragdoll or the plain-Bullet
// RawRagdoll): everything is read through the ragdolls' probes and the scene's contacts.
// `observer` (first world only, may be null) sees the first instance at spawn and after every step.
template <class Doll>
Partial measure(Scene& scene, const std::vector<std::unique_ptr<Doll>>& dolls, const DropOptions& o, double g,
                bool holdsFirst, int steps, const DropObserver* observer) {
    Partial out;
    out.restTimes.assign(dolls.size(), -1);
    // A figure hung from the world (a constraint with no body2) rests in the air by design: it counts as touching.
    const bool hung =
        !dolls.empty() && std::any_of(dolls[0]->figure().constraints.begin(), dolls[0]->figure().constraints.end(),
                                      [](const figure::FigureConstraint& c) { return c.body2 < 0; });
    out.touched.assign(dolls.size(), hung ? 1 : 0);
    if (dolls.empty()) observer = nullptr;
    if (observer) (*observer)(0, dolls[0]->bodyTransforms());

    auto totalEnergy = [&] {
        double e = 0;
        for (const auto& d : dolls) e += energy(*d, g);
        return e;
    };
    const double e0 = totalEnergy();
    const int lastSecondFrom = steps - static_cast<int>(std::lround(o.hz));
    auto awakeNow = [&] {
        int n = 0;
        for (const auto& d : dolls) n += d->awakeBodyCount();
        return n;
    };
    int awakeBefore = awakeNow();
    for (int step = 0; step < steps; ++step) {
        const auto t0 = std::chrono::steady_clock::now();
        const double cpu0 = threadCpuSeconds();
        scene.step(1.0 / o.hz);
        const double cpu = threadCpuSeconds() - cpu0;
        out.stepSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        const double now = (step + 1) / o.hz;
        ++out.r.steps;
        if (observer) (*observer)(step + 1, dolls[0]->bodyTransforms());
        // The cost of a method is the CPU of steps that simulated something: a world whose ragdolls all sleep
        // still costs a little per step, which is not the method's.
        const int awake = awakeNow();
        out.cpuSeconds += cpu;
        if (awakeBefore > 0 || awake > 0) out.awakeCpuSeconds += cpu;
        awakeBefore = awake;
        out.r.awakeBodySteps += awake;

        bool pending = false; // an instance that has neither touched anything nor come to rest
        for (std::size_t k = 0; k < dolls.size(); ++k) pending = pending || (!out.touched[k] && out.restTimes[k] < 0);
        if (pending) markTouches(scene, dolls, out.touched);
        bool allRest = true;
        for (std::size_t k = 0; k < dolls.size(); ++k) {
            const Doll& d = *dolls[k];
            for (const figure::BodyState& b : d.bodyStates()) {
                const double speed = b.linearVelocity.norm();
                const bool finite = std::isfinite(speed) && b.pose.position.allFinite() &&
                                    b.pose.rotation.allFinite() && b.angularVelocity.allFinite();
                out.r.nonFinite = out.r.nonFinite || !finite;
                if (!finite || speed > kExplodeSpeedMps) {
                    if (!out.r.exploded) out.r.explodedAtS = now;
                    out.r.exploded = true;
                }
                if (std::isfinite(speed)) out.r.maxSpeedMps = std::max(out.r.maxSpeedMps, speed);
            }
            for (int c = 0; c < static_cast<int>(d.figure().constraints.size()); ++c) {
                const bullet::JointError e = d.jointError(c);
                const std::string& name = d.figure().constraints[static_cast<std::size_t>(c)].name;
                if (e.anchorM > out.worstAnchor) {
                    out.worstAnchor = e.anchorM;
                    if (e.anchorM > 0) out.r.worstAnchorJoint = name;
                }
                if (e.limitExcessRad > out.worstLimit) {
                    out.worstLimit = e.limitExcessRad;
                    if (e.limitExcessRad > 0) out.r.worstLimitJoint = name;
                }
                out.r.maxAnchorErrorM = std::max(out.r.maxAnchorErrorM, e.anchorM);
                out.r.maxLimitViolationDeg =
                    std::max(out.r.maxLimitViolationDeg, e.limitExcessRad * 180.0 / std::numbers::pi);
                if (e.anchorM > kExplodeAnchorM && !out.r.exploded) {
                    out.r.exploded = true;
                    out.r.explodedAtS = now;
                }
            }
            if (d.atRest() && out.restTimes[k] < 0) {
                out.restTimes[k] = now;
                // At rest before touching anything: its rules froze it in the air (a spawn at rest is meant so).
                if (!out.touched[k] && !o.startAtRest) ++out.r.frozenBeforeContact;
            }
            allRest = allRest && d.atRest();
        }
        const ContactDepth deepest = scene.deepestContact();
        const double depth = deepest.depthM;
        if (depth > out.r.maxPenetrationM) out.r.worstContact = contactName(scene, deepest);
        out.r.maxPenetrationM = std::max(out.r.maxPenetrationM, depth);
        if (step >= lastSecondFrom) out.r.restPenetrationM = std::max(out.r.restPenetrationM, depth);
        out.r.maxEnergyGainJ = std::max(out.r.maxEnergyGainJ, totalEnergy() - e0);
        if (o.stopAtRest && allRest) break;
    }
    if (holdsFirst && !dolls.empty()) out.firstBodies = dolls[0]->bodyTransforms();
    return out;
}

// One world: a scene with the method, the instances spawned (plain Bullet's for the raw method), measured.
Partial runWorld(const std::shared_ptr<const RagdollAsset>& asset, const DropOptions& o,
                 const std::vector<btTransform>& spawns, bool holdsFirst, int steps, const DropObserver* observer) {
    const double g = asset->figure().units.gravityMps2;
    Scene scene(o.method, SceneSettings{g, true, 1.0});
    const std::optional<figure::LodLevel> lod =
        o.lod ? std::optional(figure::automaticLod(asset->figure(), *o.lod)) : std::nullopt;
    for (const btTransform& t : spawns) {
        bullet::SpawnOptions so;
        so.entityTransform = t;
        so.comeToRest = o.sleeping;
        so.startAtRest = o.startAtRest;
        if (isRaw(o.method)) scene.spawnRaw(asset, so);
        else if (Ragdoll& r = scene.spawn(asset, so); r.backend() == bullet::Backend::Rigid) {
            if (lod) (void)r.setLod(*lod);                  // a partition of the figure by construction: cannot fail
            if (o.motors) (void)r.setMotorGains(*o.motors); // rigid, through the scene's RagdollWorld: cannot fail
        }
    }
    if (isRaw(o.method)) return measure(scene, scene.rawRagdolls(), o, g, holdsFirst, steps, observer);
    return measure(scene, scene.ragdolls(), o, g, holdsFirst, steps, observer);
}

} // namespace

std::string bulletVersion() {
    const int v = btGetVersion();
    return std::to_string(v / 100) + "." + std::to_string(v % 100);
}

const char* bulletPrecision() { return sizeof(btScalar) == sizeof(double) ? "double" : "float"; }

std::vector<DropTurn> dropTurns(std::optional<std::uint32_t> seed, int count) {
    std::mt19937 rng(seed.value_or(0));
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::vector<DropTurn> out(static_cast<std::size_t>(std::max(count, 0)));
    for (int i = 0; i < count; ++i) {
        DropTurn& t = out[static_cast<std::size_t>(i)];
        if (!seed) {
            t.yawRad = 37.0 * i * std::numbers::pi / 180.0;
            continue;
        }
        t.yawRad = unit(rng) * 2 * std::numbers::pi;
        t.tiltRad = unit(rng) * std::numbers::pi / 2;
        t.tiltHeadingRad = unit(rng) * 2 * std::numbers::pi;
    }
    return out;
}

namespace {

// Spawn transforms, per world: a grid, each figure turned (fixed set or seeded), its lowest point at the height;
// instance i goes to world i mod worlds.
std::vector<std::vector<btTransform>> spawnGrid(const figure::Figure& figure, const DropOptions& o, int count,
                                                int worlds) {
    const std::vector<DropTurn> turns = dropTurns(o.seed, count);
    btVector3 lo, hi;
    figureBounds(figure, btMatrix3x3::getIdentity(), lo, hi);
    const double spacing = (hi - lo).length() + 0.5;
    const int columns = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(count))));
    std::vector<std::vector<btTransform>> perWorld(static_cast<std::size_t>(worlds));
    for (int i = 0; i < count; ++i) {
        const DropTurn& turn = turns[static_cast<std::size_t>(i)];
        btQuaternion q(btVector3(0, 0, 1), btScalar(turn.yawRad));
        if (turn.tiltRad > 0)
            q = btQuaternion(btVector3(btScalar(std::cos(turn.tiltHeadingRad)), btScalar(std::sin(turn.tiltHeadingRad)),
                                       0),
                             btScalar(turn.tiltRad)) *
                q;
        const btMatrix3x3 rot(q);
        figureBounds(figure, rot, lo, hi);
        const double x = (i % columns) * spacing, y = (i / columns) * spacing;
        btTransform t(rot, btVector3(btScalar(x), btScalar(y), btScalar(o.heightM - lo.z())));
        perWorld[static_cast<std::size_t>(i % worlds)].push_back(t);
    }
    return perWorld;
}

// Into r (world 0's result): the other worlds' counts and worst errors, the settle time over every instance.
void combineWorlds(const std::vector<Partial>& parts, DropResult& r) {
    double lastRest = 0;
    double worstAnchor = parts[0].worstAnchor, worstLimit = parts[0].worstLimit;
    bool allRested = true;
    for (std::size_t w = 0; w < parts.size(); ++w) {
        const DropResult& p = parts[w].r;
        if (w > 0) {
            r.awakeBodySteps += p.awakeBodySteps;
            r.maxAnchorErrorM = std::max(r.maxAnchorErrorM, p.maxAnchorErrorM);
            r.maxLimitViolationDeg = std::max(r.maxLimitViolationDeg, p.maxLimitViolationDeg);
            if (p.maxPenetrationM > r.maxPenetrationM) r.worstContact = p.worstContact;
            r.maxPenetrationM = std::max(r.maxPenetrationM, p.maxPenetrationM);
            r.restPenetrationM = std::max(r.restPenetrationM, p.restPenetrationM);
            if (parts[w].worstAnchor > worstAnchor) {
                worstAnchor = parts[w].worstAnchor;
                r.worstAnchorJoint = p.worstAnchorJoint;
            }
            if (parts[w].worstLimit > worstLimit) {
                worstLimit = parts[w].worstLimit;
                r.worstLimitJoint = p.worstLimitJoint;
            }
            r.maxEnergyGainJ = std::max(r.maxEnergyGainJ, p.maxEnergyGainJ);
            r.maxSpeedMps = std::max(r.maxSpeedMps, p.maxSpeedMps);
            if (p.exploded && (!r.exploded || *p.explodedAtS < *r.explodedAtS)) r.explodedAtS = p.explodedAtS;
            r.exploded = r.exploded || p.exploded;
            r.nonFinite = r.nonFinite || p.nonFinite;
            r.frozenBeforeContact += p.frozenBeforeContact;
        }
        for (double t : parts[w].restTimes) {
            allRested = allRested && t >= 0;
            lastRest = std::max(lastRest, t);
        }
    }
    if (allRested && r.steps > 0) r.settleTimeS = lastRest;
}

// Into r: wall, step and CPU times. Step time: the worlds of one thread one after the other, the threads side by
// side; CPU time adds up over the worlds' threads.
void combineTimes(const std::vector<Partial>& parts, int threadCount, double wallSeconds, DropResult& r) {
    std::vector<double> threadStepSeconds(static_cast<std::size_t>(threadCount), 0.0);
    double cpuSeconds = 0, awakeCpuSeconds = 0;
    for (std::size_t w = 0; w < parts.size(); ++w) {
        threadStepSeconds[w % static_cast<std::size_t>(threadCount)] += parts[w].stepSeconds;
        cpuSeconds += parts[w].cpuSeconds;
        awakeCpuSeconds += parts[w].awakeCpuSeconds;
    }
    const double stepSeconds = *std::max_element(threadStepSeconds.begin(), threadStepSeconds.end());
    r.wallMs = wallSeconds * 1000.0;
    r.usPerStep = r.steps > 0 ? stepSeconds * 1e6 / r.steps : 0;
    r.usPerBodyStep = r.bodies > 0 ? r.usPerStep * threadCount / r.bodies : 0;
    r.stepCpuMs = cpuSeconds * 1000.0;
    r.awakeStepCpuMs = awakeCpuSeconds * 1000.0;
    r.cpuUsPerAwakeBodyStep = r.awakeBodySteps > 0 ? awakeCpuSeconds * 1e6 / static_cast<double>(r.awakeBodySteps) : 0;
}

// Into r: the first instance's settled pose, in its own model space (metres).
void recordFirstPose(const figure::Figure& figure, const Partial& first, const btTransform& spawn, DropResult& r) {
    r.firstBodies = first.firstBodies;
    r.firstSpawn = bullet::toEigen(spawn);
    const pose::SkeletonPose pose = pose::driveSkeleton(figure, r.firstBodies);
    const Eigen::Quaterniond qe(pose.entity.rotation);
    const double entity[7] = {
        pose.entity.position.x(), pose.entity.position.y(), pose.entity.position.z(), qe.w(), qe.x(), qe.y(), qe.z()};
    std::copy(entity, entity + 7, r.entity);
    for (int j = 0; j < figure.skeleton.jointCount(); ++j) {
        const figure::Transform& t = pose.model[static_cast<std::size_t>(j)];
        const Eigen::Quaterniond q(t.rotation);
        r.finalPose.push_back(
            {figure.skeleton.name(j), {t.position.x(), t.position.y(), t.position.z()}, {q.w(), q.x(), q.y(), q.z()}});
    }
}

} // namespace

DropResult runDrop(const figure::Figure& figure, const DropOptions& o, const DropObserver& observer) {
    const auto asset = RagdollAsset::create(figure);
    const int count = std::max(1, o.count);
    const int worlds = std::clamp(o.worlds, 1, count);
    const int steps = o.steps ? std::max(0, *o.steps) : static_cast<int>(std::lround(o.seconds * o.hz));
    const std::vector<std::vector<btTransform>> perWorld = spawnGrid(figure, o, count, worlds);

    std::vector<Partial> parts(static_cast<std::size_t>(worlds));
    const int threadCount = std::clamp(o.threads > 0 ? o.threads : worlds, 1, worlds);
    // Thread t runs worlds t, t + threadCount, …, one after the other; this thread is thread 0 (world 0, the
    // observed one). Each world is stepped alone, so the split over threads changes nothing in the results.
    const auto runThread = [&](int t) {
        for (int w = t; w < worlds; w += threadCount)
            parts[static_cast<std::size_t>(w)] = runWorld(asset, o, perWorld[static_cast<std::size_t>(w)], w == 0,
                                                          steps, w == 0 && observer ? &observer : nullptr);
    };
    const auto wall0 = std::chrono::steady_clock::now();
    {
        std::vector<std::thread> threads;
        for (int t = 1; t < threadCount; ++t) threads.emplace_back(runThread, t);
        runThread(0);
        for (std::thread& t : threads) t.join();
    }
    const double wallSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();

    DropResult r = parts[0].r;
    r.figure = figure.name;
    r.precision = bulletPrecision();
    r.method = o.method;
    r.bodies = static_cast<int>(figure.bodies.size()) * count;
    r.constraints = static_cast<int>(figure.constraints.size()) * count;
    const bool rigid = !isRaw(o.method) && o.method.backend == bullet::Backend::Rigid;
    if (o.lod && rigid) r.lodBodies = static_cast<int>(figure::automaticLod(figure, *o.lod).groups.size());
    if (o.motors && rigid) r.motors = o.motors;
    combineWorlds(parts, r);
    combineTimes(parts, threadCount, wallSeconds, r);
    recordFirstPose(figure, parts[0], perWorld[0][0], r);
    return r;
}

} // namespace afb::sim
