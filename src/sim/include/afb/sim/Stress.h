#pragma once
// Where methods fail (`afb stress`): scenarios built in code that break ragdolls in known ways (mass and
// inertia ratios, long chains, fast impacts, big steps, bad spawns, piles), run with every method, each run judged
// against documented failure thresholds; the first failure's time and cause are kept.
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "afb/bullet/Method.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/figure/Figure.h"
#include "afb/figure/Placement.h"
#include "afb/sim/Chart.h"

namespace afb::sim {

/// Why a stress run failed (the first failure of a run; None when it passed).
enum class StressCause {
    None,
    NonFinite,   ///< a body's pose or velocity became NaN or infinite
    Speed,       ///< a body faster than StressThresholds::maxSpeedMps
    Anchor,      ///< a constraint's anchors apart by more than maxAnchorErrorM
    Limit,       ///< a limit exceeded by more than maxLimitOvershootDeg
    Penetration, ///< a contact deeper than maxPenetrationM (or a body centre that far under the ground) after
                 ///< penetrationAfterS
    Jitter,      ///< some body turned faster than maxResidualSpinRadps in the run's last second, or in the second
                 ///< half of a rest window (held still while it reports a spin)
    EnergyGain,  ///< total energy above its start (plus external work) by more than maxEnergyGainJ
    NoRest,      ///< never rested within restWithinS, without jitter (creeping, sliding)
    Skipped,     ///< not run: the scenario needs a figure that was not given (the bundled humanoid)
};
/// "nan", "speed", "anchor", "limit", "penetration", "jitter", "energy", "no-rest", "skipped" (or "pass").
std::string_view toString(StressCause cause);

/// The documented failure thresholds (docs/stability.md). Lengths in metres, angles in degrees, times in seconds.
struct StressThresholds {
    double maxSpeedMps = 100.0;         ///< no body faster than this
    double maxAnchorErrorM = 0.1;       ///< no constraint's two anchors further apart
    double maxLimitOvershootDeg = 30.0; ///< no limit exceeded by more
    double maxPenetrationM = 0.05;      ///< no contact deeper (and no body centre deeper under the ground) ...
    double penetrationAfterS = 1.0;     ///< ... once this much time has passed (impacts of a spawn settle first)
    double maxResidualSpinRadps = 1.0;  ///< a run that never rests: no body turning faster in its last second
    double maxEnergyGainJ = 1.0;        ///< kinetic + potential energy never above its start (+ external work)
    double restWithinS = 30.0;          ///< every scenario must come to rest within this (the run's length)
    /// At rest: over restWindowS, no body moved more than restMoveM nor turned more than restTurnDeg (the engine's
    /// no-move test (docs/format.md §6.1) with tight bounds: a position pass can hold a body still while the velocity
    /// solve leaves it a residual speed, and what a game sees is the motion).
    double restMoveM = 0.01, restTurnDeg = 2.0, restWindowS = 1.0;
};

/// One instance of a figure in a scenario.
struct StressSpawn {
    std::size_t figure = 0;                                    ///< index into StressSetup::figures
    figure::Transform entity;                                  ///< model space → world, metres (Z up, ground z = 0)
    Eigen::Vector3d linearVelocity = Eigen::Vector3d::Zero();  ///< of the instance's centre of mass, m/s
    Eigen::Vector3d angularVelocity = Eigen::Vector3d::Zero(); ///< the whole instance spins about its centre of mass
};

/// An impulse from outside (a projectile), external work the energy check allows for.
struct StressImpulse {
    double atS = 1.0;         ///< applied after the step that ends at this time
    std::size_t instance = 0; ///< index into StressSetup::spawns
    int body = 0;             ///< figure body index; applied at its centre of mass
    Eigen::Vector3d impulseNs = Eigen::Vector3d::Zero();
};

/// What a scenario builds: figures, where they spawn, the frame rate, and an optional impulse. A ground plane
/// (z = 0, friction 1) is always there.
struct StressSetup {
    std::vector<figure::Figure> figures;
    std::vector<StressSpawn> spawns;
    double hz = 60.0;
    std::optional<StressImpulse> impulse;
    /// A spawn that violates its constraints (outside the limits, inside the ground) is resolved by the solver,
    /// which adds energy: the energy check's reference is the highest energy of this first stretch of time.
    double spawnGraceS = 0;
};

/// `setup` turned about the world vertical (Z, through the origin) by `yawDeg`: every spawn's entity transform
/// (rotation and position), its linear and angular velocity, and the impulse. Gravity and the ground (z = 0) are
/// unchanged by such a turn, so a run of the turned setup differs only by its orientation in the world. Yaw 0 is the
/// setup unchanged, bit for bit; multiples of 90° use exact sines and cosines.
StressSetup yawedSetup(const StressSetup& setup, double yawDeg);

/// Figures of the content a scenario may use; built from the bundled content (`afb stress --base`).
struct StressContent {
    std::optional<figure::Figure> humanoid; ///< the bundled humanoid (entity "humanoid")
};

/// A scenario of the matrix.
struct StressScenario {
    std::string name;        ///< short, unique: "chain-mass-1000", "humanoid-drop-100m"
    std::string description; ///< one line for tables
    bool needsHumanoid = false;
    /// The setup, or nullopt when `content` lacks a figure it needs.
    std::function<std::optional<StressSetup>(const StressContent&)> build;
};

/// Every scenario of the matrix, in table order: chains with mass ratios 1:1 … 1:1000, long thin rods, a 30-link
/// rope, a heavy weight on a world-attached chain, three bodies overlapping at the load pose against their limits,
/// tiny 1 cm bodies, and the bundled humanoid dropped from 10 m and 100 m, at 30 and 15 Hz, spinning at 20 rad/s,
/// spawned 10 cm into the ground, spawned 20° outside its hinge limits, hit by a 500 kg·m/s projectile, and 12 and
/// 160 of it dropped in layers onto one spot.
const std::vector<StressScenario>& stressScenarios();
/// The scenario called `name`, or nullptr.
const StressScenario* findStressScenario(std::string_view name);
/// The scenarios CI runs as unit tests (small, deterministic, a few seconds in Debug).
std::vector<std::string_view> stressCiScenarios();

/// A method of the matrix: a preset or raw with knob overrides (afb chart's NAME[:KNOB=VALUE]...), and the
/// opt-in mitigations, spelled as suffixes: "+stabilize" (figure::stabilizeMassProperties on every figure),
/// "+clamp" (bullet::VelocityClamp of kStressClampLinearMps and kStressClampAngularRadps), "+rest" (the figures'
/// rest rules on). Raw takes none of them.
struct StressMethod : ChartMethod {
    bool stabilize = false;
    bullet::VelocityClamp clamp;
    /// "+rest": the figures' own rest rules put them to sleep (SpawnOptions::comeToRest), as in a game. Without it
    /// (the matrix's rule) rest is measured, never imposed: a figure that jitters is seen jittering.
    bool restRules = false;
};
inline constexpr double kStressClampLinearMps = 50.0;
inline constexpr double kStressClampAngularRadps = 30.0;
/// Parses a StressMethod spec ("default", "fast:substeps=2+stabilize+clamp+rest"); nullopt with `error` set on a bad
/// one.
std::optional<StressMethod> parseStressMethod(std::string_view spec, std::string& error);

/// One run of the matrix: a scenario, turned by a yaw, run with a method until it fails, comes to rest or reaches
/// restWithinS.
struct StressResult {
    std::string scenario;
    std::string method; ///< the method's label (ChartMethod::label)
    double yawDeg = 0;  ///< the turn of the scenario about the world vertical (yawedSetup), degrees
    StressCause cause = StressCause::None;
    std::optional<double> failedAtS; ///< time of the first failure
    std::string detail;              ///< what failed: the body, joint or pair and the value
    double simulatedS = 0;
    std::optional<double> restAtS; ///< the start of the first rest window that lasted restWindowS
    int bodies = 0;
    // Worst values seen (up to the failure), in the thresholds' units.
    double maxSpeedMps = 0, maxAnchorErrorM = 0, maxLimitOvershootDeg = 0, maxPenetrationM = 0, maxEnergyGainJ = 0;
    double cpuMs = 0; ///< thread CPU time inside the steps
    bool passed() const { return cause == StressCause::None; }
};

/// Runs one setup with one method (a preset or raw, with any knob overrides). Deterministic for a given build.
StressResult runStress(const StressSetup& setup, const StressMethod& method, const StressThresholds& thresholds = {});

/// One run of the matrix, as runStressMatrix runs it: `yawed` (the scenario's setup turned by `yawDeg`, or nullopt
/// when its figures are missing: a Skipped run) with `method`, named by `scenario` and the yaw.
StressResult runStressRun(const std::optional<StressSetup>& yawed, const std::string& scenario,
                          const StressMethod& method, const StressThresholds& thresholds, double yawDeg);
/// The yaw of run k of `yaws` (k·360°/yaws), degrees.
double stressYawDeg(std::size_t k, std::size_t yaws);

/// Runs every scenario with every method at `yaws` orientations (run k turned by k·360°/yaws, yawedSetup; 1: the
/// scenario as built) on `threads` worker threads (each run its own world, so results do not depend on the thread
/// count); scenarios whose figures are missing from `content` are Skipped. Results in scenario-major, then method,
/// then yaw order. `progress(done, total)` (in runs) is called from the calling thread.
std::vector<StressResult> runStressMatrix(const std::vector<const StressScenario*>& scenarios,
                                          const std::vector<StressMethod>& methods, const StressContent& content,
                                          const StressThresholds& thresholds = {}, int threads = 2, int yaws = 1,
                                          const std::function<void(int done, int total)>& progress = {});

/// One cell of the matrix: the runs of a scenario with a method at every yaw, summed up.
struct StressCell {
    std::string scenario;
    std::string method;
    int passed = 0; ///< runs that passed
    int total = 0;  ///< runs (the yaw count); Skipped runs count here and in `causes`
    /// The failures' causes with how many runs failed of each, most frequent first (ties in StressCause order).
    std::vector<std::pair<StressCause, int>> causes;
    std::optional<std::size_t> firstFailure; ///< index (into the results) of the lowest-yaw failing run
    bool skipped() const { return !causes.empty() && causes.front().first == StressCause::Skipped; }
};
/// The cells of `results` (runStressMatrix's order), scenario-major, then method.
std::vector<StressCell> stressCells(const std::vector<StressResult>& results);

/// A cell as the table shows it: a cell of one run "ok" or the cause and the time of the failure ("jitter 30.00s");
/// of N runs "k/N" passed, then the failures' causes with their counts ("5/8 (jitter 2, limit 1)"); skipped "-".
std::string stressCellText(const StressCell& cell, const std::vector<StressResult>& results);

/// The matrix as a fixed-width terminal table: one row per scenario, one column per method, stressCellText.
std::string stressTable(const std::vector<StressResult>& results, const std::vector<StressMethod>& methods);
/// stress.md: the thresholds, the matrix, and every failing run with its yaw and detail.
std::string stressMarkdown(const std::vector<StressResult>& results, const std::vector<StressMethod>& methods,
                           const StressThresholds& thresholds);
/// stress.json: the yaw count, thresholds, methods (every knob), one object per cell (passed/total, causes, the
/// first failing run) and one per run (with its yaw).
std::string stressJson(const std::vector<StressResult>& results, const std::vector<StressMethod>& methods,
                       const StressThresholds& thresholds);

/// Kinetic + potential energy of bodies in `states` (figure body order) of `figure`, J; gravity along −Z.
double figureEnergyJ(const figure::Figure& figure, const std::vector<figure::BodyState>& states, double gravityMps2);

} // namespace afb::sim
