#pragma once
// Drop tests: figures dropped onto a ground plane, measured for speed, accuracy and stability while they fall.
// Shared by `afb drop`, `afb golden`, tests and benchmarks (the tools library, src/sim).
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "afb/bullet/Method.h"
#include "afb/bullet/Motor.h"
#include "afb/figure/Figure.h"

namespace afb::sim {

/// A drop scenario: where and how long. How the figure is stepped is the method. Times in seconds, lengths in
/// metres.
struct DropOptions {
    double heightM = 1.0; ///< lowest point of each figure above the ground at spawn
    int count = 1;        ///< instances of the figure, on a grid in one world (or split over worlds)
    int worlds = 1;       ///< independent worlds the instances are split over (instance i: world i mod worlds)
    /// Threads that run the worlds (0: one per world); world w runs on thread w mod threads. The results do not
    /// depend on it: each world is stepped alone, and the worlds' results are combined in world order.
    int threads = 0;
    std::optional<std::uint32_t> seed; ///< random initial orientations (yaw and a tilt); none: yaw = 37°·i
    double seconds = 10.0;             ///< simulated time (ignored when steps is set)
    std::optional<int> steps;          ///< exact number of steps; 0 reports the spawn pose
    double hz = 60.0;                  ///< fixed frame rate (each frame is the method's substeps)
    bullet::Method method = {};        ///< how the figures are simulated (RawRagdoll.h: "raw" is plain Bullet)
    bool sleeping = true;              ///< the figure's rest rules put it to sleep
    bool stopAtRest = false;           ///< end the run as soon as every instance is at rest
    bool startAtRest = false;          ///< spawn at rest until touched (the entity's "nodrop"/"sleep" key)
    /// Level of detail: each instance is switched at spawn to figure::automaticLod with this many rigid bodies
    /// (bullet::Ragdoll::setLod; rigid backend only, ignored for the raw method and the multibody backend).
    std::optional<int> lod;
    /// Joint motors: every instance holds its load pose with motors of these gains (bullet::Ragdoll::setMotorGains;
    /// rigid backend only, ignored for the raw method and the multibody backend). None: limp.
    std::optional<bullet::MotorGains> motors;
};

/// How a drop turns instance i at spawn: about +Z by `yawRad`, then by `tiltRad` about the horizontal axis at
/// `tiltHeadingRad` from +X.
struct DropTurn {
    double yawRad = 0, tiltRad = 0, tiltHeadingRad = 0;
};

/// The turns of `count` instances: without a seed, yaw 37°·i and no tilt; with one (DropOptions::seed), per instance
/// a yaw uniform in [0, 2π), a tilt uniform in [0, π/2) and its heading uniform in [0, 2π), drawn in that order
/// from one std::mt19937 seeded with it.
std::vector<DropTurn> dropTurns(std::optional<std::uint32_t> seed, int count);

/// One joint of a settled pose: model space of the instance, metres.
struct JointPose {
    std::string name;
    double position[3];
    double quaternion[4]; ///< w, x, y, z
};

/// What a drop measured (field names are those of the JSON and CSV reports).
struct DropResult {
    std::string figure;
    std::string precision; ///< "float" or "double" (btScalar of the Bullet build)
    bullet::Method method;
    int bodies = 0, constraints = 0, steps = 0;
    /// Rigid bodies per instance at the level of detail (DropOptions::lod), or nullopt at full detail.
    std::optional<int> lodBodies;
    /// The motors' gains (DropOptions::motors) when the instances held their pose with motors, else nullopt.
    std::optional<bullet::MotorGains> motors;
    double wallMs = 0, usPerStep = 0, usPerBodyStep = 0;
    long long awakeBodySteps = 0;
    /// Thread CPU time inside the steps (CLOCK_THREAD_CPUTIME_ID), summed over the worlds, milliseconds.
    double stepCpuMs = 0;
    /// Of stepCpuMs, the steps that began or ended with some body awake (a world of sleeping ragdolls still costs
    /// a little per step; that is not the method's cost).
    double awakeStepCpuMs = 0;
    /// awakeStepCpuMs per awake body-step, microseconds (0 without one): the cost of a method (afb chart).
    double cpuUsPerAwakeBodyStep = 0;
    double maxAnchorErrorM = 0, maxLimitViolationDeg = 0, maxPenetrationM = 0, maxEnergyGainJ = 0;
    double restPenetrationM = 0;  ///< deepest contact over the last simulated second
    std::string worstAnchorJoint; ///< the constraint with the largest anchor error (empty when none)
    std::string worstLimitJoint;  ///< the constraint with the largest limit violation (empty when none)
    std::string worstContact;     ///< the pair of the deepest contact, "body / ground" or "body / body"
    double maxSpeedMps = 0;
    bool exploded = false;
    std::optional<double> explodedAtS;
    /// A body's pose or velocity was NaN or infinite after some step: the runtime failed, whatever the figure
    /// (a figure that builds must simulate to finite state). Implies `exploded`.
    bool nonFinite = false;
    std::optional<double> settleTimeS;
    /// Instances put to rest by their figure's rules before any of their bodies touched anything but themselves:
    /// frozen in the air (in a fall only `maxMoveTime` does that). Instances spawned at rest, and figures hung from
    /// the world (a constraint to the world), are not counted.
    int frozenBeforeContact = 0;
    double entity[7] = {0, 0, 0, 1, 0, 0, 0}; ///< first instance's entity transform: x y z, qw qx qy qz
    std::vector<JointPose> finalPose;         ///< first instance, model space
    /// First instance's body frames (centre of mass, principal axes) at the end of the run, world space, metres.
    std::vector<figure::Transform> firstBodies;
    /// First instance's entity transform at spawn, world space: firstSpawn⁻¹ ∘ firstBodies is the pose relative to
    /// the spawn, equal to the bodies' load pose at step 0.
    figure::Transform firstSpawn;
};

/// Watches the first instance of a drop frame by frame (`afb drop --gltf` records it this way): called with frame 0
/// at spawn, before the first step, then after every step k with frame k, each time with the instance's body frames
/// (centre of mass, principal axes; world space, metres, Z up; in body order). Runs on the first world's thread.
using DropObserver = std::function<void(int frame, std::span<const figure::Transform> bodiesWorld)>;

/// Runs one drop of `figure`. Deterministic for a given build, options and input. `observer`, when set, sees the
/// first instance at every step (an empty one costs nothing and changes nothing).
DropResult runDrop(const figure::Figure& figure, const DropOptions& options, const DropObserver& observer = {});

/// Thresholds of `exploded`: a speed over kExplodeSpeedMps, an anchor error over kExplodeAnchorM, or NaN.
inline constexpr double kExplodeSpeedMps = 100.0;
inline constexpr double kExplodeAnchorM = 0.1;

/// The Bullet version this library was built against, e.g. "3.24", and "float"/"double".
std::string bulletVersion();
const char* bulletPrecision();

} // namespace afb::sim
