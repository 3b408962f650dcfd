// The same-run reference: the bundled humanoid built through afbullet and as plain Bullet
// (sim::RawRagdoll, method `raw`), dropped in the same program, each one's cost per awake body-step and their ratio.
//   BM_Drop/<method>   16 humanoids dropped 1 m, 300 steps at 60 Hz, sleeping off (the chart's scene, every body
//                      awake): CPU µs per awake body-step (counter us_per_awake_body_step)
//   BM_Rest/<method>   160 humanoids dropped 1 m, 10 s, sleeping on: CPU µs per body-step, awake or not
//   BM_RestTumbled/<method>  the same, each humanoid turned and tipped at random (seeded, as `afb drop --seed 1`):
//                      they land on their sides and backs instead of their feet
//   BM_Crowd/<method>/<resting>  10 humanoids dropped 1 m (kept awake: comeToRest off) beside <resting> humanoids
//                      spawned at rest (standing on the ground, never touched), 120 steps: CPU µs per step
//                      (counter us_per_step)
//   BM_Spawn/<method>  spawning one built figure into a world that holds 100 of it already: µs per ragdoll,
//                      and removing it (apart); heap bytes per live instance
//   BM_LodSwitch       one humanoid of a world of 100 (default method), 0.5 s into its fall: µs to switch it to
//                      LOD 6 (Ragdoll::setLod) and back (setFullDetail), timed apart
// Methods: raw (plain Bullet's defaults: 10 iterations), raw:iterations=20 (equal iterations: afbullet's presets
// solve contacts and joints with 20), default, balanced (the default in block mode), iterative (default with
// direct-joints off, position-tree 0, friction-directions 1), fast; BM_Drop also `floor` (floorMethod()). After the
// runs, a table of the ratios to raw is printed. Time is thread CPU time (other processes do not count); instruction
// counts, exact from run to run, come from cmake/callgrind-cost.sh.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <malloc.h>
#include <time.h>

#include "afb/bullet/RagdollAsset.h"
#include "afb/decl/Library.h"
#include "afb/figure/Load.h"
#include "afb/figure/Lod.h"
#include "afb/sim/Drop.h"
#include "afb/sim/RawRagdoll.h"
#include "afb/sim/Scene.h"

namespace {

using afb::bullet::Method;

double threadCpuSeconds() {
    timespec ts{};
    ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

/// The bundled humanoid, loaded once; null when the repository's content is not found.
std::shared_ptr<const afb::bullet::RagdollAsset> humanoid() {
    static const std::shared_ptr<const afb::bullet::RagdollAsset> asset = [] {
        afb::text::Diagnostics diags;
        std::shared_ptr<const afb::bullet::RagdollAsset> out;
        if (auto lib = afb::decl::Library::open(AFB_SOURCE_DIR, diags))
            if (auto loaded = afb::figure::loadEntityFigure(*lib, "humanoid", {}, diags))
                out = afb::bullet::RagdollAsset::create(loaded->figure);
        return out;
    }();
    return asset;
}

/// The methods compared, by label.
struct Labelled {
    const char* label;
    Method method;
};
std::vector<Labelled> methods() {
    Method rawEqual = afb::sim::rawMethod();
    rawEqual.iterations = 20;
    return {{"raw", afb::sim::rawMethod()},
            {"raw:iterations=20", rawEqual},
            {"default", *afb::bullet::methodPreset("default")},
            {"balanced", *afb::bullet::methodPreset("balanced")},
            {"iterative", *afb::bullet::methodPreset("iterative")},
            {"fast", *afb::bullet::methodPreset("fast")}};
}

/// The floor under any method on Bullet's solver (docs/performance.md): `fast` without the position pass, speculative
/// limits and contacts and full manifolds, i.e. Bullet's 20 iterations over the merged figure, on afbullet's
/// solver (warm-started joints, SSE row updates). Dropped only (BM_Drop/floor): a measure of the solver, not a
/// method anyone would choose for accuracy.
Method floorMethod() {
    Method m = *afb::bullet::methodPreset("fast");
    m.name = "floor";
    m.positionIterations = 0;
    m.speculativeLimits = m.multipointContacts = m.speculativeContacts = false;
    return m;
}

/// The figure's lowest point turned by `turn` (model space).
double lowestPoint(const afb::figure::Figure& figure, const btQuaternion& turn) {
    const btMatrix3x3 m(turn);
    Eigen::Matrix3d r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r(i, j) = double(m[i][j]);
    double lowest = 1e9;
    for (const afb::figure::FigureBody& b : figure.bodies)
        for (const Eigen::Vector3d& v : b.shape.vertices) lowest = std::min(lowest, (r * b.loadPose.apply(v)).z());
    return lowest;
}

/// How the dropped humanoids are turned: 37° apart in yaw, upright; or `tumbled`, as `afb drop --seed 1` turns them
/// (sim::dropTurns: a random yaw, tipped by up to 90° about a random horizontal axis).
enum class Turn { Upright, Tumbled };

/// `count` humanoids on a grid, the lowest point `heightM` above the ground.
struct Drop {
    afb::sim::Scene scene;
    Drop(const Method& method, int count, double heightM, bool sleeping, int resting = 0, Turn turn = Turn::Upright)
        : scene(method) {
        const auto asset = humanoid();
        const double spacing = 2.5;
        const int columns = 13;
        const std::vector<afb::sim::DropTurn> tumbles = afb::sim::dropTurns(1u, turn == Turn::Tumbled ? count : 0);
        const double uprightLowest = lowestPoint(asset->figure(), btQuaternion::getIdentity());
        for (int i = 0; i < count; ++i) {
            btQuaternion q(btVector3(0, 0, 1), btScalar(0.6458 * i));
            if (turn == Turn::Tumbled) {
                const afb::sim::DropTurn& t = tumbles[static_cast<std::size_t>(i)];
                q = btQuaternion(btVector3(btScalar(std::cos(t.tiltHeadingRad)), btScalar(std::sin(t.tiltHeadingRad)),
                                           0),
                                 btScalar(t.tiltRad)) *
                    btQuaternion(btVector3(0, 0, 1), btScalar(t.yawRad));
            }
            const double lowest = turn == Turn::Tumbled ? lowestPoint(asset->figure(), q) : uprightLowest;
            afb::bullet::SpawnOptions o;
            o.comeToRest = sleeping;
            o.entityTransform =
                btTransform(q, btVector3(btScalar(spacing * (i % columns)), btScalar(spacing * (i / columns)),
                                         btScalar(heightM - lowest)));
            if (afb::sim::isRaw(method)) scene.spawnRaw(asset, o);
            else scene.spawn(asset, o);
        }
        // The resting crowd: beyond the dropped ones (y from 20 m), standing on the ground, asleep from the start.
        for (int i = 0; i < resting; ++i) {
            afb::bullet::SpawnOptions o;
            o.startAtRest = true;
            o.entityTransform.setOrigin(btVector3(btScalar(spacing * (i % 40)), btScalar(20 + spacing * (i / 40)),
                                                  btScalar(-uprightLowest + 0.001)));
            if (afb::sim::isRaw(method)) scene.spawnRaw(asset, o);
            else scene.spawn(asset, o);
        }
    }
    int awakeBodies() const {
        int n = 0;
        for (const auto& r : scene.ragdolls()) n += r->awakeBodyCount();
        for (const auto& r : scene.rawRagdolls()) n += r->awakeBodyCount();
        return n;
    }
    int bodies() const {
        int n = 0;
        for (const auto& r : scene.ragdolls()) n += r->bodyCount();
        for (const auto& r : scene.rawRagdolls()) n += r->bodyCount();
        return n;
    }
};

/// Results per benchmark family and label, for the ratio table.
std::map<std::string, std::map<std::string, double>>& results() {
    static std::map<std::string, std::map<std::string, double>> r;
    return r;
}

/// Steps `drop` `steps` times at 60 Hz; returns CPU µs per awake body-step (awake: counted after each step) and
/// per body-step.
std::pair<double, double> run(Drop& drop, int steps) {
    long long awake = 0;
    double cpu = 0;
    for (int s = 0; s < steps; ++s) {
        const double c0 = threadCpuSeconds();
        drop.scene.step(1.0 / 60.0);
        cpu += threadCpuSeconds() - c0;
        awake += drop.awakeBodies();
    }
    const double bodySteps = static_cast<double>(drop.bodies()) * steps;
    return {awake > 0 ? cpu * 1e6 / static_cast<double>(awake) : 0.0, cpu * 1e6 / bodySteps};
}

void dropBenchmark(benchmark::State& state, const Method& method, const char* label) {
    if (!humanoid()) {
        state.SkipWithError("bundled humanoid not found");
        return;
    }
    double perAwake = 0;
    int runs = 0;
    for (auto _ : state) {
        state.PauseTiming();
        Drop drop(method, 16, 1.0, false);
        state.ResumeTiming();
        perAwake += run(drop, 300).first;
        ++runs;
    }
    state.counters["us_per_awake_body_step"] = perAwake / runs;
    results()["drop"][label] = perAwake / runs;
}

void restBenchmark(benchmark::State& state, const Method& method, const char* label, Turn turn) {
    if (!humanoid()) {
        state.SkipWithError("bundled humanoid not found");
        return;
    }
    double perBody = 0, perAwake = 0;
    int runs = 0;
    for (auto _ : state) {
        state.PauseTiming();
        Drop drop(method, 160, 1.0, true, 0, turn);
        state.ResumeTiming();
        const auto [awake, body] = run(drop, 600);
        perBody += body;
        perAwake += awake;
        ++runs;
    }
    state.counters["us_per_body_step"] = perBody / runs;
    state.counters["us_per_awake_body_step"] = perAwake / runs;
    results()[turn == Turn::Upright ? "rest" : "rest tumbled"][label] = perBody / runs;
}

void crowdBenchmark(benchmark::State& state, const Method& method, const char* label) {
    if (!humanoid()) {
        state.SkipWithError("bundled humanoid not found");
        return;
    }
    const int resting = static_cast<int>(state.range(0));
    double perStep = 0;
    int runs = 0;
    bool woke = false;
    for (auto _ : state) {
        state.PauseTiming();
        // The 10 dropped ones never come to rest: the target compares a crowd beside 10 *active* ragdolls with
        // the 10 alone, and the default's humanoids rest within about a second, inside the timed window.
        Drop drop(method, 10, 1.0, false, resting);
        // Half a second first, untimed: the resting ones sink (Ragdoll::sunk) after 30 quiet substeps, a cost
        // paid once per ragdoll that comes to rest; the timed steps are the steady state beside them.
        for (int s = 0; s < 40; ++s) drop.scene.step(1.0 / 60.0);
        state.ResumeTiming();
        const int steps = 120;
        double cpu = 0;
        for (int s = 0; s < steps; ++s) {
            const double c0 = threadCpuSeconds();
            drop.scene.step(1.0 / 60.0);
            cpu += threadCpuSeconds() - c0;
        }
        perStep += cpu * 1e6 / steps;
        ++runs;
        const std::size_t n = drop.scene.ragdolls().size() + drop.scene.rawRagdolls().size();
        for (std::size_t k = 10; k < n; ++k) {
            const int awake = afb::sim::isRaw(method) ? drop.scene.rawRagdolls()[k]->awakeBodyCount()
                                                      : drop.scene.ragdolls()[k]->awakeBodyCount();
            woke = woke || awake > 0;
        }
    }
    if (woke) state.SkipWithError("a resting humanoid woke");
    state.counters["us_per_step"] = perStep / runs;
    results()["crowd" + std::to_string(resting)][label] = perStep / runs;
}

void spawnBenchmark(benchmark::State& state, const Method& method, const char* label) {
    if (!humanoid()) {
        state.SkipWithError("bundled humanoid not found");
        return;
    }
    Drop drop(method, 100, 1.0, true);
    const auto asset = humanoid();
    // Spawns are timed one by one; every 16 live ones are removed together, timed apart (removal is Bullet's
    // linear search of the world's object and constraint arrays and its pair cache: it grows with the world).
    std::vector<std::unique_ptr<afb::bullet::Ragdoll>> live;
    std::vector<std::unique_ptr<afb::sim::RawRagdoll>> liveRaw;
    double spawnCpu = 0, removalCpu = 0;
    long long spawned = 0;
    const auto removeAll = [&] {
        const double c0 = threadCpuSeconds();
        live.clear();
        liveRaw.clear();
        removalCpu += threadCpuSeconds() - c0;
    };
    for (auto _ : state) {
        afb::bullet::SpawnOptions o;
        o.entityTransform.setOrigin(btVector3(btScalar(-5 - 3 * (spawned % 16)), -5, 1));
        const double c0 = threadCpuSeconds();
        if (afb::sim::isRaw(method))
            liveRaw.push_back(std::make_unique<afb::sim::RawRagdoll>(asset, drop.scene.world(), o));
        else live.push_back(drop.scene.ragdollWorld().spawn(asset, o));
        spawnCpu += threadCpuSeconds() - c0;
        ++spawned;
        if (live.size() + liveRaw.size() == 16) removeAll();
    }
    removeAll();
    state.counters["us_spawn"] = spawnCpu * 1e6 / static_cast<double>(spawned);
    state.counters["us_removal"] = removalCpu * 1e6 / static_cast<double>(spawned);
    results()["spawn"][label] = spawnCpu * 1e6 / static_cast<double>(spawned);
    results()["removal"][label] = removalCpu * 1e6 / static_cast<double>(spawned);
    // Heap held per live instance (the asset's shapes are shared and not counted): 100 more spawned and kept.
    {
        Drop more(method, 0, 1.0, true, 0);
        const std::size_t heap1 = ::mallinfo2().uordblks;
        for (int i = 0; i < 100; ++i) {
            afb::bullet::SpawnOptions o;
            o.entityTransform.setOrigin(btVector3(btScalar(3 * i), -10, 1));
            if (afb::sim::isRaw(method)) more.scene.spawnRaw(asset, o);
            else more.scene.spawn(asset, o);
        }
        more.scene.step(1.0 / 60.0); // contact manifolds and solver bodies exist
        const double perInstance = static_cast<double>(::mallinfo2().uordblks - heap1) / 100.0;
        state.counters["bytes_per_ragdoll"] = perInstance;
        results()["memory"][label] = perInstance;
    }
}

void lodSwitchBenchmark(benchmark::State& state) {
    if (!humanoid()) {
        state.SkipWithError("bundled humanoid not found");
        return;
    }
    Drop drop(*afb::bullet::methodPreset("default"), 100, 1.0, false);
    for (int s = 0; s < 30; ++s) drop.scene.step(1.0 / 60.0); // landing: bent, moving, touching
    afb::bullet::Ragdoll& r = *drop.scene.ragdolls().front();
    const afb::figure::LodLevel six = afb::figure::automaticLod(r.figure(), 6);
    double toLod = 0, toFull = 0;
    long long switches = 0;
    for (auto _ : state) {
        const double c0 = threadCpuSeconds();
        (void)r.setLod(six);
        const double c1 = threadCpuSeconds();
        r.setFullDetail();
        toFull += threadCpuSeconds() - c1;
        toLod += c1 - c0;
        ++switches;
    }
    state.counters["us_to_lod"] = toLod * 1e6 / static_cast<double>(switches);
    state.counters["us_to_full"] = toFull * 1e6 / static_cast<double>(switches);
}

void registerAll() {
    for (const Labelled& m : methods()) {
        const std::string label = m.label;
        benchmark::RegisterBenchmark(("BM_Drop/" + label).c_str(), dropBenchmark, m.method, m.label)
            ->Unit(benchmark::kMillisecond)
            ->Iterations(1);
    }
    benchmark::RegisterBenchmark("BM_Drop/floor", dropBenchmark, floorMethod(), "floor")
        ->Unit(benchmark::kMillisecond)
        ->Iterations(1);
    for (const Labelled& m : methods())
        benchmark::RegisterBenchmark((std::string("BM_Rest/") + m.label).c_str(), restBenchmark, m.method, m.label,
                                     Turn::Upright)
            ->Unit(benchmark::kMillisecond)
            ->Iterations(1);
    for (const Labelled& m : methods())
        benchmark::RegisterBenchmark((std::string("BM_RestTumbled/") + m.label).c_str(), restBenchmark, m.method,
                                     m.label, Turn::Tumbled)
            ->Unit(benchmark::kMillisecond)
            ->Iterations(1);
    for (const Labelled& m : methods())
        benchmark::RegisterBenchmark((std::string("BM_Crowd/") + m.label).c_str(), crowdBenchmark, m.method, m.label)
            ->Unit(benchmark::kMillisecond)
            ->Iterations(1)
            ->Arg(0)
            ->Arg(1000);
    for (const Labelled& m : methods())
        benchmark::RegisterBenchmark((std::string("BM_Spawn/") + m.label).c_str(), spawnBenchmark, m.method, m.label)
            ->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark("BM_LodSwitch", lodSwitchBenchmark)->Unit(benchmark::kMicrosecond);
}

void printRatios() {
    const auto& r = results();
    if (r.count("crowd0") && r.count("crowd1000")) {
        std::printf("\ncrowd: CPU µs per step, 10 dropped humanoids alone and beside 1000 resting ones\n");
        for (const auto& [label, alone] : r.at("crowd0"))
            if (r.at("crowd1000").count(label) && alone > 0)
                std::printf("  %-20s %9.1f  %9.1f  %5.2fx\n", label.c_str(), alone, r.at("crowd1000").at(label),
                            r.at("crowd1000").at(label) / alone);
    }
    for (const auto& [family, byLabel] : results()) {
        if (family.rfind("crowd", 0) == 0) continue;
        const auto raw = byLabel.find("raw");
        if (raw == byLabel.end() || raw->second <= 0) continue;
        std::printf("\n%s: %s, and the ratio to raw (plain Bullet's defaults)\n", family.c_str(),
                    family == "spawn"     ? "CPU µs to spawn a ragdoll (into a world of 100)"
                    : family == "removal" ? "CPU µs to remove a ragdoll (from a world of 100)"
                    : family == "memory"  ? "heap bytes per live instance, after one step"
                    : family == "rest"    ? "CPU µs per body-step (160 humanoids dropped upright, 10 s, sleeping on)"
                    : family == "rest tumbled"
                        ? "CPU µs per body-step (160 humanoids dropped tumbled, 10 s, sleeping on)"
                        : "CPU µs per awake body-step (16 humanoids, 300 steps, sleeping off)");
        for (const auto& [label, value] : byLabel)
            std::printf("  %-20s %8.3f  %5.2fx raw\n", label.c_str(), value, value / raw->second);
        const auto equal = byLabel.find("raw:iterations=20");
        if (equal != byLabel.end() && equal->second > 0)
            for (const char* label : {"default", "fast", "floor"})
                if (const auto it = byLabel.find(label); it != byLabel.end())
                    std::printf("  %s / raw:iterations=20 (equal iterations): %.2fx\n", label,
                                it->second / equal->second);
    }
}

} // namespace

int main(int argc, char** argv) {
    registerAll();
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    printRatios();
    return 0;
}
