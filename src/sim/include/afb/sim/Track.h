#pragma once
// Tracking runs (`afb track`, docs/cli.md): a powered ragdoll following a looped animation with its joint motors,
// its root body or its legs keyframed on the animation, measured for how closely it follows and what it costs.
// Tools library (src/sim), like the drop runs.
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "afb/bullet/Method.h"
#include "afb/bullet/Motor.h"
#include "afb/decl/Md5Anim.h"
#include "afb/figure/Figure.h"
#include "afb/sim/Drop.h"

namespace afb::sim {

/// What follows the animation exactly (keyframed), the rest being driven by the motors.
enum class TrackRoot {
    Keyframed, ///< body 0 (the root body: the pelvis of a humanoid) is keyframed; every other body is powered
    Free,      ///< body 0 is powered and the legs (trackLegBodies) are keyframed; the figure stands on the ground
};
/// "keyframed" or "free".
const char* toString(TrackRoot root);

/// The motor gains of a tracking run at strength 1: every joint 15 Hz, damping ratio 4, no torque bound. 15 Hz is a
/// quarter of a 60 Hz step, the stiffest a motor acts at there (docs/motors.md). The ratio is high because a
/// motor's frequency and ratio are set on its own two bodies: an inner joint of a chain (a shoulder, a hip) also
/// swings the bodies beyond it, so it acts several times softer and less damped; at ratio 1 the humanoid's arms
/// swing about a walk instead of following it.
bullet::MotorGains defaultTrackGains();

/// The legs of a figure, keyframed under TrackRoot::Free: the bodies of every subtree that hangs from body 0 in the
/// figure's constraint tree (body 0 at its root, one edge per jointed pair) whose top body's centre of mass lies
/// below body 0's at the load pose (model Z). A humanoid's thighs, shins and feet; its spine, with the arms and the
/// head on it, starts above the pelvis and is not a leg. Body indices, ascending.
std::vector<int> trackLegBodies(const figure::Figure& figure);

/// An impulse during a tracking run.
struct TrackHit {
    int body = 0;           ///< the figure body hit
    double impulseNs = 0;   ///< N·s along world +X (the figure's forward: it is spawned with model axes = world axes)
    double atSeconds = 1.0; ///< simulated time of the hit
    /// How the motors take it (Ragdoll::hit): limp at once, full strength again 0.5 s later.
    bullet::HitReaction reaction = {0.0, 0.5};
};

/// A tracking scenario. Times in seconds.
struct TrackOptions {
    double seconds = 5.0;       ///< simulated time
    double hz = 60.0;           ///< fixed frame rate (each frame is the method's substeps)
    bullet::Method method = {}; ///< rigid backend, not the raw method (motors and keyframes need both)
    TrackRoot root = TrackRoot::Keyframed;
    double strength = 1.0;       ///< the gains are bullet::scaledGains(defaultTrackGains(), strength)
    std::optional<TrackHit> hit; ///< one hit, or none
    double warmupSeconds = 0.5;  ///< the tracking errors are taken from this time on
};

/// What a tracking run measured (field names are those of the JSON and CSV reports).
struct TrackResult {
    std::string figure;
    std::string precision; ///< "float" or "double"
    bullet::Method method;
    TrackRoot root = TrackRoot::Keyframed;
    double strength = 1;
    bullet::MotorGains gains;           ///< the gains at that strength
    std::vector<std::string> keyframed; ///< the keyframed bodies' names
    double loopSeconds = 0;             ///< the animation's cycle
    int bodies = 0, constraints = 0, joints = 0, steps = 0;
    /// Over every md5 joint and every step from warmupSeconds on: the distance of the joint's world position from
    /// the animation's (m) and the angle between their world rotations (deg); root mean square and largest.
    double trackingRmsM = 0, trackingMaxM = 0, trackingRmsDeg = 0, trackingMaxDeg = 0;
    std::string worstJoint; ///< the joint of trackingMaxM
    /// The largest excess of the animation's own pose over the figure's joint limits (cone, pyramid, hinge), deg,
    /// and its constraint: a floor under the tracking errors, since the limits hold and no motor pulls past them.
    double animLimitExcessDeg = 0;
    std::string animLimitJoint;
    /// The largest kinetic + potential energy of the figure's bodies above its start, J (gravity along −Z; the
    /// keyframed bodies included). The motors are springs and dampers that start relaxed on the animation's first
    /// frame: holding a still pose (a one-frame animation) with still keyframed bodies, they and the joints can only
    /// take energy out, so a gain there is the solver's. On a moving animation the keyframed bodies and the motors
    /// do work on the figure: there it measures the animation too.
    double maxEnergyGainJ = 0;
    /// The cut between keyframed and simulated bodies: over the simulated bodies joined by a constraint to a
    /// keyframed one (the humanoid's torso and thighs under a keyframed pelvis, its pelvis above keyframed legs) and
    /// the steps from warmupSeconds on, the largest norm of a body's angular velocity minus its target's (the
    /// animation's), rad/s, and that body (empty when no body lies at the cut).
    double cutMaxRelRadS = 0;
    std::string cutBody;
    /// The largest turn of the animation's own pose about an axis a joint's type locks (a universal joint's twist
    /// about its shafts, a hinge's axis tilting, a fixed joint's whole rotation), deg, against the figure's load
    /// pose, and its constraint: another floor, since the joint holds and a motor drives only its free axes.
    double animLockedExcessDeg = 0;
    std::string animLockedJoint;
    bool exploded = false; ///< NaN, a speed over kExplodeSpeedMps or an anchor error over kExplodeAnchorM
    std::optional<double> explodedAtS;
    double maxSpeedMps = 0, maxAnchorErrorM = 0;
    /// After the hit: seconds from the hit to the last step whose largest joint errors (position and rotation)
    /// exceeded 1.1 times the largest ones of the steps between warmupSeconds and the hit (plus 1 mm and 0.5°).
    /// nullopt without a hit, or when the errors were still above those bounds at the end of the run.
    std::optional<double> recoveryS;
    std::optional<double> hitAtS;            ///< when the hit landed (nullopt without one)
    std::string hitBody;                     ///< the body hit (empty without one)
    double preHitMaxM = 0, preHitMaxDeg = 0; ///< the bounds recoveryS is measured against
    double wallMs = 0, usPerStep = 0;
    long long awakeBodySteps = 0;
    double stepCpuMs = 0, awakeStepCpuMs = 0, cpuUsPerAwakeBodyStep = 0; ///< as DropResult's
};

/// The simulated bodies joined by a constraint to a body of `keyframed` (body indices): the bodies at the cut of a
/// partial ragdoll, where a simulated part hangs from a keyframed one. Ascending.
std::vector<int> trackCutBodies(const figure::Figure& figure, const std::vector<int>& keyframed);

/// Runs `figure` following `anim` (looped: its cycle is numFrames − 1 frames, the last frame being the first
/// again, as the engine loops an anim) for options.seconds. Each step the motors are driven toward the pose and
/// velocities of the animation at the end of the step (figure::jointsFromAnimation, bodiesFromJoints,
/// inheritVelocities over the step) and the keyframed bodies get it as their targets. The figure starts on the
/// animation's first frame at rest, entity at the world origin (feet on the ground plane z = 0), rest rules off.
/// `observer` sees every step as runDrop's does. Returns nullopt with an error in `diagnostics` when the animation
/// does not fit the figure. Throws std::invalid_argument for a raw or multibody method.
std::optional<TrackResult> runTrack(const figure::Figure& figure, const decl::Md5Anim& anim,
                                    const TrackOptions& options, text::Diagnostics& diagnostics,
                                    const DropObserver& observer = {});

/// The scenario as JSON (seconds, hz, root, strength, hit, warmup, method).
nlohmann::json trackOptionsJson(const TrackOptions& options, const figure::Figure& figure);
/// One result as JSON: every field of the table below and the method's knobs.
nlohmann::json trackResultJson(const TrackResult& result);
/// The CSV header of trackCsvRow.
std::string trackCsvHeader();
/// One result as a CSV row (no newline).
std::string trackCsvRow(const TrackResult& result);
/// What each report field means, for --help.
std::string trackFieldsHelp();

} // namespace afb::sim
