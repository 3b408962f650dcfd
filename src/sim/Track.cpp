// Tracking runs (src/sim): a ragdoll driven by its motors toward a looped animation, its root or its legs keyframed
// on it; the joints' distance from the animation, a hit and its recovery, and the cost of the steps.
#include "afb/sim/Track.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <span>
#include <stdexcept>

#include <time.h>

#include "afb/bullet/Convert.h"
#include "afb/figure/Limits.h"
#include "afb/figure/Placement.h"
#include "afb/figure/Vocabulary.h"
#include "afb/sim/RawRagdoll.h"
#include "afb/sim/Scene.h"
#include "afb/sim/Stress.h"

namespace afb::sim {
namespace {

using figure::Transform;

// CPU time of this thread, seconds: the cost of the steps, as runDrop measures it.
double trackThreadCpuSeconds() {
    timespec ts{};
    ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

// The animation as the run plays it: looped, the entity at the world origin.
class LoopedAnimation {
  public:
    LoopedAnimation(const figure::Figure& figure, const decl::Md5Anim& anim) : m_figure(figure), m_anim(anim) {
        // The engine loops over numFrames − 1 frames: the last frame is the first one again.
        const auto frames = static_cast<int>(anim.frames.size());
        if (frames > 1 && anim.frameRate > 0) m_loopSeconds = (frames - 1) / static_cast<double>(anim.frameRate);
    }
    double loopSeconds() const { return m_loopSeconds; }

    // Model-space joints (metres) at `seconds` of looped time, or nullopt (diagnostics say why).
    std::optional<std::vector<Transform>> joints(double seconds, text::Diagnostics& diags) const {
        double t = 0;
        if (m_loopSeconds > 0) {
            t = std::fmod(seconds, m_loopSeconds);
            if (t < 0) t += m_loopSeconds;
        }
        return figure::jointsFromAnimation(m_figure, m_anim, t, diags);
    }

    // Body states at `seconds`: poses there, velocities the move over the `dt` before it.
    std::optional<std::vector<figure::BodyState>> states(double seconds, double dt, text::Diagnostics& diags) const {
        auto before = joints(seconds - dt, diags);
        auto now = joints(seconds, diags);
        if (!before || !now) return std::nullopt;
        return figure::inheritVelocities(figure::bodiesFromJoints(m_figure, Transform{}, *before),
                                         figure::bodiesFromJoints(m_figure, Transform{}, *now), dt);
    }

  private:
    const figure::Figure& m_figure;
    const decl::Md5Anim& m_anim;
    double m_loopSeconds = 0;
};

// Every md5 joint in world space for bodies `bodies` (world body frames): a joint a body drives takes its rotation
// (and, with mod position or both, its position) from the body; every other component follows its parent with the
// animation's local transform, so a joint without a body (a finger, the jaw) counts only what its parents' bodies
// do. The entity follows body 0, placed where the animation has body 0 relative to it.
std::vector<Transform> simulatedJoints(const figure::Figure& f, std::span<const Transform> bodies,
                                       std::span<const Transform> animModel) {
    const auto n = animModel.size();
    std::vector<int> driver(n, -1);
    for (std::size_t b = 0; b < f.bodies.size(); ++b)
        if (const int j = f.bodies[b].joint; j >= 0 && static_cast<std::size_t>(j) < n)
            driver[static_cast<std::size_t>(j)] = static_cast<int>(b); // the later body wins, as driveSkeleton
    Transform entity;
    if (!f.bodies.empty()) {
        const figure::FigureBody& b0 = f.bodies[0];
        const Transform body0Model = animModel[static_cast<std::size_t>(b0.joint)] * b0.jointInBody.inverse();
        entity = bodies[0] * body0Model.inverse();
    }
    std::vector<Transform> world(n);
    for (std::size_t j = 0; j < n; ++j) {
        const int p = f.skeleton.parent(static_cast<int>(j));
        const Transform parent = p < 0 ? entity : world[static_cast<std::size_t>(p)];
        const Transform local = p < 0 ? animModel[j] : animModel[static_cast<std::size_t>(p)].inverse() * animModel[j];
        world[j] = parent * local;
        if (driver[j] < 0) continue;
        const figure::FigureBody& body = f.bodies[static_cast<std::size_t>(driver[j])];
        const Transform driven = bodies[static_cast<std::size_t>(driver[j])] * body.jointInBody;
        if (body.mod != figure::JointMod::Position) world[j].rotation = driven.rotation;
        if (body.mod != figure::JointMod::Orientation) world[j].position = driven.position;
    }
    return world;
}

double angleDeg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
    return Eigen::Quaterniond(a).angularDistance(Eigen::Quaterniond(b)) * 180.0 / std::numbers::pi;
}

// The errors of one step, and what they add to the run's.
struct StepErrors {
    double maxM = 0, maxDeg = 0;
    int worstJoint = -1;
};

StepErrors jointErrors(std::span<const Transform> sim, std::span<const Transform> anim, double& sumM2,
                       double& sumDeg2) {
    StepErrors e;
    for (std::size_t j = 0; j < sim.size(); ++j) {
        const double m = (sim[j].position - anim[j].position).norm();
        const double deg = angleDeg(sim[j].rotation, anim[j].rotation);
        sumM2 += m * m;
        sumDeg2 += deg * deg;
        if (m > e.maxM) {
            e.maxM = m;
            e.worstJoint = static_cast<int>(j);
        }
        e.maxDeg = std::max(e.maxDeg, deg);
    }
    return e;
}

// How far the animation's own pose (body states) lies outside the figure's joint limits: what no motor can follow.
void animationLimitExcess(const figure::Figure& f, std::span<const figure::BodyState> target, TrackResult& r) {
    for (const figure::FigureConstraint& c : f.constraints) {
        const Eigen::Matrix3d r1 = target[static_cast<std::size_t>(c.body1)].pose.rotation;
        const Eigen::Matrix3d r2 =
            c.body2 < 0 ? Eigen::Matrix3d::Identity() : target[static_cast<std::size_t>(c.body2)].pose.rotation;
        const double deg = figure::limitExcessRad(c, r1, r2) * 180.0 / std::numbers::pi;
        if (deg > r.animLimitExcessDeg) {
            r.animLimitExcessDeg = deg;
            r.animLimitJoint = c.name;
        }
    }
}

// How far the animation's own pose turns a joint about an axis its type locks, against the load pose (where the
// joint's two frames coincide): a universal joint's twist about its shafts (the part of the relative rotation about
// frame X: its swings turn about axes across it), a hinge's axis tilting (frame Z), a fixed joint's or a slider's
// whole rotation. Those parts no motor can follow either (JointMotorConstraint drives the free axes only).
void animationLockedExcess(const bullet::Ragdoll& doll, std::span<const figure::BodyState> target, TrackResult& r) {
    const auto& constraints = doll.figure().constraints;
    for (std::size_t ci = 0; ci < constraints.size(); ++ci) {
        const figure::FigureConstraint& c = constraints[ci];
        const figure::RotationHold hold = figure::freedomOf(c.type).rotation;
        if (hold == figure::RotationHold::None) continue;
        const auto& [inBody1, inBody2] = doll.constraintFramesLocal(static_cast<int>(ci));
        const btMatrix3x3 fa =
            bullet::toBt(target[static_cast<std::size_t>(c.body1)].pose).getBasis() * inBody1.getBasis();
        const btMatrix3x3 fb =
            c.body2 < 0 ? inBody2.getBasis()
                        : bullet::toBt(target[static_cast<std::size_t>(c.body2)].pose).getBasis() * inBody2.getBasis();
        btQuaternion q;
        (fa.transpose() * fb).getRotation(q);
        const double w = std::abs(double(q.w())), x = std::abs(double(q.x()));
        double rad = 0;
        if (hold == figure::RotationHold::Twist) rad = 2 * std::atan2(x, w);
        else if (hold == figure::RotationHold::AllButAxis)
            rad = std::acos(std::clamp(double(fa.getColumn(2).dot(fb.getColumn(2))), -1.0, 1.0));
        else rad = 2 * std::acos(std::min(1.0, w));
        const double deg = rad * 180.0 / std::numbers::pi;
        if (deg > r.animLockedExcessDeg) {
            r.animLockedExcessDeg = deg;
            r.animLockedJoint = c.name;
        }
    }
}

// The stability checks of runDrop: non-finite state, a body faster than kExplodeSpeedMps, a joint further apart
// than kExplodeAnchorM.
void checkExplosion(const bullet::Ragdoll& doll, double now, TrackResult& r) {
    bool bad = false;
    for (const figure::BodyState& b : doll.bodyStates()) {
        const double speed = b.linearVelocity.norm();
        const bool finite = std::isfinite(speed) && b.pose.position.allFinite() && b.pose.rotation.allFinite() &&
                            b.angularVelocity.allFinite();
        if (std::isfinite(speed)) r.maxSpeedMps = std::max(r.maxSpeedMps, speed);
        bad = bad || !finite || speed > kExplodeSpeedMps;
    }
    for (int c = 0; c < static_cast<int>(doll.figure().constraints.size()); ++c) {
        const double a = doll.jointError(c).anchorM;
        r.maxAnchorErrorM = std::max(r.maxAnchorErrorM, a);
        bad = bad || a > kExplodeAnchorM;
    }
    if (bad && !r.exploded) r.explodedAtS = now;
    r.exploded = r.exploded || bad;
}

// Sets the motors, the keyframed bodies and the starting state: the animation at time 0. Returns the keyframed
// bodies.
std::vector<int> prepare(bullet::Ragdoll& doll, const TrackOptions& o, const std::vector<figure::BodyState>& start,
                         TrackResult& r) {
    (void)doll.setBodyStates(start); // one state per body, finite: the animation's
    std::vector<int> keyframed = {0};
    if (o.root == TrackRoot::Free) keyframed = trackLegBodies(doll.figure());
    for (int b : keyframed) {
        (void)doll.setBodyMode(b, bullet::BodyMode::Keyframed); // rigid, through the scene's world: cannot fail
        r.keyframed.push_back(doll.figure().bodies[static_cast<std::size_t>(b)].name);
    }
    (void)doll.setMotorGains(r.gains);
    (void)doll.driveToPose(start);
    return keyframed;
}

// The largest angular speed of a body at the cut relative to its target, after a step (cutMaxRelRadS).
void measureCut(const bullet::Ragdoll& doll, const std::vector<int>& cut, std::span<const figure::BodyState> target,
                TrackResult& r) {
    for (int b : cut) {
        const auto i = static_cast<std::size_t>(b);
        const double rel = (doll.bodyState(b).angularVelocity - target[i].angularVelocity).norm();
        if (rel > r.cutMaxRelRadS) {
            r.cutMaxRelRadS = rel;
            r.cutBody = doll.figure().bodies[i].name;
        }
    }
}

// The hit, when this step is its step: along world +X at the body's centre of mass.
void applyHit(bullet::Ragdoll& doll, const TrackHit& hit, double now, TrackResult& r) {
    const btVector3 point = bullet::toBt(doll.bodyState(hit.body).pose.position);
    (void)doll.hit(hit.body, btVector3(btScalar(hit.impulseNs), 0, 0), point, hit.reaction); // checked by runTrack
    r.hitAtS = now;
    r.hitBody = doll.figure().bodies[static_cast<std::size_t>(hit.body)].name;
}

// recoveryS and the bounds it is measured against, from every step's largest errors.
void measureRecovery(const std::vector<StepErrors>& steps, double dt, double warmup, TrackResult& r) {
    if (!r.hitAtS) return;
    const auto hitStep = static_cast<std::size_t>(std::lround(*r.hitAtS / dt));
    for (std::size_t k = 0; k < hitStep && k < steps.size(); ++k)
        if ((static_cast<double>(k) + 1) * dt >= warmup) {
            r.preHitMaxM = std::max(r.preHitMaxM, steps[k].maxM);
            r.preHitMaxDeg = std::max(r.preHitMaxDeg, steps[k].maxDeg);
        }
    // A margin over the largest errors before the hit: a walk's errors differ from cycle to cycle by a little.
    const double boundM = 1.1 * r.preHitMaxM + 1e-3, boundDeg = 1.1 * r.preHitMaxDeg + 0.5;
    std::optional<std::size_t> lastOut;
    for (std::size_t k = hitStep; k < steps.size(); ++k)
        if (steps[k].maxM > boundM || steps[k].maxDeg > boundDeg) lastOut = k;
    if (lastOut && *lastOut + 1 == steps.size()) return; // still out at the end: not recovered
    r.recoveryS = lastOut ? (static_cast<double>(*lastOut) + 1) * dt - *r.hitAtS : 0.0;
}

} // namespace

const char* toString(TrackRoot root) { return root == TrackRoot::Free ? "free" : "keyframed"; }

bullet::MotorGains defaultTrackGains() { return bullet::MotorGains{15.0, 4.0}; }

std::vector<int> trackCutBodies(const figure::Figure& f, const std::vector<int>& keyframed) {
    std::vector<char> held(f.bodies.size(), 0), cut(f.bodies.size(), 0);
    for (int b : keyframed)
        if (b >= 0 && static_cast<std::size_t>(b) < held.size()) held[static_cast<std::size_t>(b)] = 1;
    for (const figure::FigureConstraint& c : f.constraints) {
        if (c.body1 < 0 || c.body2 < 0) continue; // a body joined to the world is no cut
        const auto b1 = static_cast<std::size_t>(c.body1), b2 = static_cast<std::size_t>(c.body2);
        if (held[b1] && !held[b2]) cut[b2] = 1;
        if (held[b2] && !held[b1]) cut[b1] = 1;
    }
    std::vector<int> bodies;
    for (std::size_t b = 0; b < cut.size(); ++b)
        if (cut[b]) bodies.push_back(static_cast<int>(b));
    return bodies;
}

std::vector<int> trackLegBodies(const figure::Figure& f) {
    const auto n = f.bodies.size();
    std::vector<std::vector<int>> next(n);
    for (const figure::FigureConstraint& c : f.constraints)
        if (c.body2 >= 0 && c.body1 != c.body2) {
            next[static_cast<std::size_t>(c.body1)].push_back(c.body2);
            next[static_cast<std::size_t>(c.body2)].push_back(c.body1);
        }
    std::vector<int> legs;
    if (n == 0) return legs;
    std::vector<char> seen(n, 0);
    seen[0] = 1;
    const double rootZ = f.bodies[0].loadPose.position.z();
    for (int top : next[0]) {
        if (seen[static_cast<std::size_t>(top)]) continue;
        const bool leg = f.bodies[static_cast<std::size_t>(top)].loadPose.position.z() < rootZ;
        std::vector<int> stack = {top}; // the subtree under `top`, away from body 0
        seen[static_cast<std::size_t>(top)] = 1;
        while (!stack.empty()) {
            const int b = stack.back();
            stack.pop_back();
            if (leg) legs.push_back(b);
            for (int c : next[static_cast<std::size_t>(b)])
                if (!seen[static_cast<std::size_t>(c)]) {
                    seen[static_cast<std::size_t>(c)] = 1;
                    stack.push_back(c);
                }
        }
    }
    std::sort(legs.begin(), legs.end());
    return legs;
}

namespace {

// The run's loop: each step the targets, the hit, the step, the errors and the checks.
struct TrackLoop {
    const TrackOptions& o;
    const LoopedAnimation& anim;
    Scene& scene;
    bullet::Ragdoll& doll;
    const DropObserver& observer;
    const std::vector<int>& cut; ///< the simulated bodies joined to keyframed ones
    TrackResult& r;

    bool run(text::Diagnostics& diags) {
        const double dt = 1.0 / o.hz;
        const int steps = static_cast<int>(std::lround(o.seconds * o.hz));
        // The step the hit lands on, −1 for none (a plain int: GCC at -O1 takes an optional's value for unset).
        const int hitStep = o.hit ? static_cast<int>(std::lround(o.hit->atSeconds * o.hz)) : -1;
        std::vector<StepErrors> perStep;
        double sumM2 = 0, sumDeg2 = 0, cpu = 0, awakeCpu = 0, wall = 0;
        long long samples = 0;
        const double gravity = doll.figure().units.gravityMps2;
        const double energy0 = figureEnergyJ(doll.figure(), doll.bodyStates(), gravity);
        if (observer) observer(0, doll.bodyTransforms());
        for (int k = 0; k < steps; ++k) {
            const double t1 = (k + 1) * dt;
            auto target = anim.states(t1, dt, diags);
            auto joints = anim.joints(t1, diags);
            if (!target || !joints) return false;
            animationLimitExcess(doll.figure(), *target, r);
            animationLockedExcess(doll, *target, r);
            if (k == hitStep) applyHit(doll, *o.hit, k * dt, r);
            (void)doll.setKeyframeTargets(*target); // one finite state per body
            (void)doll.driveToPose(*target);
            const auto wall0 = std::chrono::steady_clock::now();
            const double cpu0 = trackThreadCpuSeconds();
            const int awakeBefore = doll.awakeBodyCount();
            scene.step(dt);
            const double stepCpu = trackThreadCpuSeconds() - cpu0;
            wall += std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
            const int awake = doll.awakeBodyCount();
            cpu += stepCpu;
            if (awakeBefore > 0 || awake > 0) awakeCpu += stepCpu;
            r.awakeBodySteps += awake;
            ++r.steps;
            if (observer) observer(k + 1, doll.bodyTransforms());
            checkExplosion(doll, t1, r);
            r.maxEnergyGainJ =
                std::max(r.maxEnergyGainJ, figureEnergyJ(doll.figure(), doll.bodyStates(), gravity) - energy0);
            const std::vector<Transform> bodies = doll.bodyTransforms();
            const std::vector<Transform> sim = simulatedJoints(doll.figure(), bodies, *joints);
            double m2 = 0, deg2 = 0;
            const StepErrors e = jointErrors(sim, *joints, m2, deg2); // the entity is the identity: model = world
            perStep.push_back(e);
            if (t1 < o.warmupSeconds - 1e-9) continue;
            measureCut(doll, cut, *target, r);
            sumM2 += m2;
            sumDeg2 += deg2;
            samples += static_cast<long long>(sim.size());
            if (e.maxM > r.trackingMaxM && e.worstJoint >= 0) r.worstJoint = doll.figure().skeleton.name(e.worstJoint);
            r.trackingMaxM = std::max(r.trackingMaxM, e.maxM);
            r.trackingMaxDeg = std::max(r.trackingMaxDeg, e.maxDeg);
        }
        if (samples > 0) {
            r.trackingRmsM = std::sqrt(sumM2 / static_cast<double>(samples));
            r.trackingRmsDeg = std::sqrt(sumDeg2 / static_cast<double>(samples));
        }
        r.stepCpuMs = cpu * 1e3;
        r.awakeStepCpuMs = awakeCpu * 1e3;
        r.cpuUsPerAwakeBodyStep = r.awakeBodySteps > 0 ? awakeCpu * 1e6 / static_cast<double>(r.awakeBodySteps) : 0;
        r.usPerStep = r.steps > 0 ? wall * 1e6 / r.steps : 0;
        measureRecovery(perStep, dt, o.warmupSeconds, r);
        return true;
    }
};

} // namespace

std::optional<TrackResult> runTrack(const figure::Figure& figure, const decl::Md5Anim& anim, const TrackOptions& o,
                                    text::Diagnostics& diags, const DropObserver& observer) {
    if (isRaw(o.method) || o.method.backend != bullet::Backend::Rigid)
        throw std::invalid_argument("runTrack: motors and keyframed bodies need the rigid backend, not raw");
    if (o.hit && (o.hit->body < 0 || o.hit->body >= static_cast<int>(figure.bodies.size())))
        throw std::invalid_argument("runTrack: the hit body is not a body of the figure");
    const auto wall0 = std::chrono::steady_clock::now();
    const LoopedAnimation looped(figure, anim);
    const double dt = 1.0 / o.hz;
    auto start = looped.states(0.0, dt, diags);
    if (!start) return std::nullopt;

    TrackResult r;
    r.figure = figure.name;
    r.precision = bulletPrecision();
    r.method = o.method;
    r.root = o.root;
    r.strength = o.strength;
    r.gains = bullet::scaledGains(defaultTrackGains(), o.strength);
    r.loopSeconds = looped.loopSeconds();
    r.bodies = static_cast<int>(figure.bodies.size());
    r.constraints = static_cast<int>(figure.constraints.size());
    r.joints = figure.skeleton.jointCount();

    // Root keyframed, the figure hangs from its root in the air: an animation played in place (an actor's root motion
    // is the entity's, not the pelvis's) would drag its feet over a ground against friction, a treadmill that
    // measures the friction rather than the motors. Root free, it stands on the legs, which a ground must carry.
    Scene scene(o.method, SceneSettings{figure.units.gravityMps2, o.root == TrackRoot::Free, 1.0});
    bullet::SpawnOptions spawn;
    spawn.comeToRest = false; // a powered figure following an animation never rests
    bullet::Ragdoll& doll = scene.spawn(bullet::RagdollAsset::create(figure), spawn);
    const std::vector<int> cut = trackCutBodies(figure, prepare(doll, o, *start, r));
    TrackLoop loop{o, looped, scene, doll, observer, cut, r};
    if (!loop.run(diags)) return std::nullopt;
    r.wallMs = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count() * 1e3;
    return r;
}

} // namespace afb::sim
