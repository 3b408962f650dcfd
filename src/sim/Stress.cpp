// Stress runs (Stress.h): one scenario with one method, judged step by step against the failure thresholds; the
// matrix over worker threads (its cells, table, Markdown and JSON: StressReport.cpp).
#include "afb/sim/Stress.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <numbers>
#include <thread>

#include <nlohmann/json.hpp>
#include <time.h>

#include "RestWindow.h"
#include "StressText.h"
#include "afb/detail/Convert.h"
#include "afb/figure/Stabilize.h"
#include "afb/sim/Drop.h"
#include "afb/sim/RawRagdoll.h"
#include "afb/sim/Scene.h"

namespace afb::sim {
using detail::fixed;
namespace {

double yawDegOf(std::size_t k, std::size_t n) { return stressYawDeg(k, n); }

// The run's state while it steps: the worst values, the first failure, the rest window.
struct Judge {
    const StressThresholds& th;
    StressResult& r;
    double now = 0;
    bool failed() const { return r.cause != StressCause::None; }
    void fail(StressCause cause, std::string detail) {
        if (failed()) return;
        r.cause = cause;
        r.failedAtS = now;
        r.detail = std::move(detail);
    }
};

// "instance 3 / l2" or "l2" for a single instance: which body of which instance.
template <class Doll>
std::string bodyLabel(const std::vector<std::unique_ptr<Doll>>& dolls, std::size_t k, int body) {
    const std::string& name = dolls[k]->figure().bodies[static_cast<std::size_t>(body)].name;
    return dolls.size() > 1 ? "#" + std::to_string(k) + " " + name : name;
}

template <class Doll>
std::string objectLabel(Scene& scene, const std::vector<std::unique_ptr<Doll>>& dolls, const btCollisionObject* o) {
    if (o == scene.ground()) return "ground";
    for (std::size_t k = 0; k < dolls.size(); ++k)
        for (int i = 0; i < dolls[k]->bodyCount(); ++i)
            if (&dolls[k]->collisionObject(i) == o) return bodyLabel(dolls, k, i);
    return "other";
}

template <class Doll>
double totalEnergy(const std::vector<std::unique_ptr<Doll>>& dolls, double g) {
    double e = 0;
    for (const auto& d : dolls) e += figureEnergyJ(d->figure(), d->bodyStates(), g);
    return e;
}

// Sets every body of an instance to one rigid motion: `v` at the instance's centre of mass and spin `w` about it.
template <class Doll>
void setRigidMotion(Doll& d, const Eigen::Vector3d& v, const Eigen::Vector3d& w) {
    const std::vector<figure::BodyState> states = d.bodyStates();
    double mass = 0;
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < states.size(); ++i) {
        const double m = d.figure().bodies[i].massKg;
        mass += m;
        centre += m * states[i].pose.position;
    }
    centre /= mass;
    std::vector<bullet::BodyVelocity> velocities;
    for (const figure::BodyState& s : states)
        velocities.push_back({bullet::toBt(Eigen::Vector3d(v + w.cross(s.pose.position - centre))), bullet::toBt(w)});
    [[maybe_unused]] const bool set = d.setBodyVelocities(velocities);
}

// Potential energy the ground adds when it lifts an instance that spawned inside it out as a whole (work of the
// world, not a gain): the instance's mass times g times its deepest point's depth.
template <class Doll>
double groundAllowanceJ(const std::vector<std::unique_ptr<Doll>>& dolls, double g) {
    double allowance = 0;
    for (const auto& d : dolls) {
        double lowest = 0, mass = 0;
        const std::vector<figure::Transform> frames = d->bodyTransforms(); // body frames (merged bodies too)
        for (int i = 0; i < d->bodyCount(); ++i) {
            const figure::FigureBody& body = d->figure().bodies[static_cast<std::size_t>(i)];
            const btTransform t = bullet::toBt(frames[static_cast<std::size_t>(i)]);
            mass += body.massKg;
            for (const Eigen::Vector3d& v : body.shape.vertices)
                lowest = std::min(lowest, static_cast<double>((t * bullet::toBt(v)).z()));
        }
        allowance += mass * g * -lowest;
    }
    return allowance;
}

// The rest window: every body's frame at its start.
template <class Doll>
std::vector<btTransform> framesOf(const std::vector<std::unique_ptr<Doll>>& dolls) {
    std::vector<btTransform> out;
    for (const auto& d : dolls)
        for (const figure::Transform& t : d->bodyTransforms()) out.push_back(bullet::toBt(t));
    return out;
}

// True when no body moved more than the rest bounds since `window`.
template <class Doll>
bool stillSince(const std::vector<std::unique_ptr<Doll>>& dolls, const std::vector<btTransform>& window,
                const StressThresholds& th) {
    std::size_t n = 0;
    const double turn = th.restTurnDeg * std::numbers::pi / 180;
    for (const auto& d : dolls)
        for (const figure::Transform& t : d->bodyTransforms()) {
            const btTransform now = bullet::toBt(t);
            const btTransform& then = window[n++];
            if ((now.getOrigin() - then.getOrigin()).length() > th.restMoveM) return false;
            const btQuaternion dq = then.getRotation().inverse() * now.getRotation();
            if (static_cast<double>(dq.getAngle()) > turn &&
                2 * std::numbers::pi - static_cast<double>(dq.getAngle()) > turn)
                return false;
        }
    return true;
}

// A trip of a ragdoll's explosion guard (bullet::ExplosionGuard), as the run's failure: the guard restores and
// freezes the ragdoll, so the state after the step would otherwise look healthy.
struct GuardReport {
    std::optional<StressCause> cause;
    std::string detail;
};

// One run's steps and their judgement (runSteps): the worst values and the first failure into the result.
template <class Doll>
class Stepper {
  public:
    Stepper(Scene& scene, const std::vector<std::unique_ptr<Doll>>& dolls, const StressSetup& setup,
            const StressThresholds& th, StressResult& r)
        : m_scene(scene), m_dolls(dolls), m_setup(setup), m_th(th), m_r(r), m_judge{th, r}, m_rest(th),
          m_g(setup.figures.front().units.gravityMps2), m_dt(1.0 / setup.hz) {
        for (std::size_t k = 0; k < dolls.size(); ++k)
            setRigidMotion(*dolls[k], setup.spawns[k].linearVelocity, setup.spawns[k].angularVelocity);
        m_e0 = totalEnergy(dolls, m_g) + groundAllowanceJ(dolls, m_g);
        m_impulseDone = !setup.impulse;
        m_window = framesOf(dolls);
    }

    // The run: steps until it fails, rests or reaches the end of its time.
    void run(const GuardReport& guard) {
        const int steps = static_cast<int>(std::ceil(m_th.restWithinS * m_setup.hz - 1e-9));
        m_lastSecondFrom = steps - static_cast<int>(std::lround(m_setup.hz));
        for (int step = 0; step < steps && !m_judge.failed(); ++step) {
            this->step(step);
            if (guard.cause) {
                m_judge.fail(*guard.cause, guard.detail);
                break;
            }
            const bool checkPenetration = m_judge.now > m_th.penetrationAfterS + 1e-9;
            for (std::size_t k = 0; k < m_dolls.size() && !m_judge.failed(); ++k) {
                checkBodies(k, step, checkPenetration);
                checkJoints(k);
            }
            if (m_judge.failed()) break;
            if (checkPenetration) checkContacts();
            checkEnergy();
            if (m_judge.failed() || rested()) return;
        }
        if (m_judge.failed()) return;
        if (m_lastSecondSpin > m_th.maxResidualSpinRadps)
            m_judge.fail(StressCause::Jitter, m_lastSecondSpinBody + " turning at " + fixed(m_lastSecondSpin, 1) +
                                                  " rad/s in the last second");
        else m_judge.fail(StressCause::NoRest, "still moving after " + fixed(m_th.restWithinS, 0) + " s");
    }

  private:
    // One step of the world (its thread CPU time counted), then the scenario's impulse when it is due.
    void step(int step) {
        timespec t0{}, t1{};
        ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t0);
        m_scene.step(m_dt);
        ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t1);
        m_r.cpuMs +=
            (static_cast<double>(t1.tv_sec - t0.tv_sec) + static_cast<double>(t1.tv_nsec - t0.tv_nsec) * 1e-9) * 1000.0;
        m_judge.now = m_r.simulatedS = (step + 1) * m_dt;
        if (m_impulseDone || m_judge.now < m_setup.impulse->atS - 1e-9) return;
        const double eBefore = totalEnergy(m_dolls, m_g);
        auto& doll = *m_dolls[m_setup.impulse->instance];
        const Eigen::Vector3d centre = doll.bodyStates()[static_cast<std::size_t>(m_setup.impulse->body)].pose.position;
        doll.applyBodyImpulse(m_setup.impulse->body, bullet::toBt(m_setup.impulse->impulseNs), bullet::toBt(centre),
                              bullet::ImpulseRule::Always);
        m_externalWork += totalEnergy(m_dolls, m_g) - eBefore;
        m_impulseDone = true;
    }

    // Instance k's bodies: finite, not too fast, centres above the ground; their spin for the rest window.
    void checkBodies(std::size_t k, int step, bool checkPenetration) {
        const std::vector<figure::BodyState> states = m_dolls[k]->bodyStates();
        for (std::size_t i = 0; i < states.size(); ++i) {
            const figure::BodyState& s = states[i];
            const int body = static_cast<int>(i);
            if (!(s.pose.position.allFinite() && s.pose.rotation.allFinite() && s.linearVelocity.allFinite() &&
                  s.angularVelocity.allFinite())) {
                m_judge.fail(StressCause::NonFinite, bodyLabel(m_dolls, k, body) + " not finite");
                return;
            }
            const double speed = s.linearVelocity.norm(), spin = s.angularVelocity.norm();
            m_r.maxSpeedMps = std::max(m_r.maxSpeedMps, speed);
            if (speed > m_th.maxSpeedMps)
                m_judge.fail(StressCause::Speed, bodyLabel(m_dolls, k, body) + " at " + fixed(speed, 1) + " m/s");
            const double under = -s.pose.position.z();
            if (checkPenetration && under > m_th.maxPenetrationM) {
                m_r.maxPenetrationM = std::max(m_r.maxPenetrationM, under);
                m_judge.fail(StressCause::Penetration,
                             bodyLabel(m_dolls, k, body) + " centre " + fixed(under * 100, 1) + " cm under the ground");
            }
            if (step >= m_lastSecondFrom && spin > m_lastSecondSpin) {
                m_lastSecondSpin = spin;
                m_lastSecondSpinBody = bodyLabel(m_dolls, k, body);
            }
            if (m_rest.counts(m_judge.now) && spin > m_rest.worstSpin())
                m_rest.spin(m_judge.now, spin, bodyLabel(m_dolls, k, body));
        }
    }

    // Instance k's joints: anchors together, limits within the thresholds.
    void checkJoints(std::size_t k) {
        const Doll& d = *m_dolls[k];
        for (int c = 0; c < static_cast<int>(d.figure().constraints.size()) && !m_judge.failed(); ++c) {
            const bullet::JointError e = d.jointError(c);
            const std::string& name = d.figure().constraints[static_cast<std::size_t>(c)].name;
            const std::string label = m_dolls.size() > 1 ? "#" + std::to_string(k) + " " + name : name;
            const double limitDeg = e.limitExcessRad * 180.0 / std::numbers::pi;
            m_r.maxAnchorErrorM = std::max(m_r.maxAnchorErrorM, e.anchorM);
            m_r.maxLimitOvershootDeg = std::max(m_r.maxLimitOvershootDeg, limitDeg);
            if (e.anchorM > m_th.maxAnchorErrorM)
                m_judge.fail(StressCause::Anchor, label + " anchors " + fixed(e.anchorM * 1000, 0) + " mm apart");
            else if (limitDeg > m_th.maxLimitOvershootDeg)
                m_judge.fail(StressCause::Limit, label + " " + fixed(limitDeg, 0) + "° past its limit");
        }
    }

    // The deepest contact of the scene.
    void checkContacts() {
        const ContactDepth deepest = m_scene.deepestContact();
        m_r.maxPenetrationM = std::max(m_r.maxPenetrationM, deepest.depthM);
        if (deepest.depthM > m_th.maxPenetrationM)
            m_judge.fail(StressCause::Penetration, objectLabel(m_scene, m_dolls, deepest.a) + " / " +
                                                       objectLabel(m_scene, m_dolls, deepest.b) + " " +
                                                       fixed(deepest.depthM * 100, 1) + " cm deep");
    }

    // Energy above the start (the highest of the spawn grace), less the impulse's work.
    void checkEnergy() {
        const double energy = totalEnergy(m_dolls, m_g);
        if (m_judge.now <= m_setup.spawnGraceS + 1e-9) m_e0 = std::max(m_e0, energy);
        const double gain = energy - m_e0 - m_externalWork;
        m_r.maxEnergyGainJ = std::max(m_r.maxEnergyGainJ, gain);
        if (gain > m_th.maxEnergyGainJ) m_judge.fail(StressCause::EnergyGain, "+" + fixed(gain, 1) + " J");
    }

    // Rest: a window of restWindowS over which nothing moved; a body that moved starts a new one now. True when
    // the run is decided (rested, or still with a body that spins: jitter).
    bool rested() {
        const bool still = m_impulseDone && stillSince(m_dolls, m_window, m_th);
        if (!still) m_window = framesOf(m_dolls);
        const detail::RestWindow::Verdict verdict = m_rest.update(m_judge.now, still);
        if (verdict == detail::RestWindow::Verdict::Jitter) {
            // Still, but a body held in place reports a spin.
            m_judge.fail(StressCause::Jitter,
                         m_rest.worstBody() + " turning at " + fixed(m_rest.worstSpin(), 1) + " rad/s while at rest");
            return true;
        }
        if (verdict == detail::RestWindow::Verdict::Rested) {
            m_r.restAtS = m_rest.start();
            return true;
        }
        return false;
    }

    Scene& m_scene;
    const std::vector<std::unique_ptr<Doll>>& m_dolls;
    const StressSetup& m_setup;
    const StressThresholds& m_th;
    StressResult& m_r;
    Judge m_judge;
    detail::RestWindow m_rest;
    const double m_g, m_dt;
    double m_e0 = 0, m_externalWork = 0, m_lastSecondSpin = 0;
    bool m_impulseDone = false;
    int m_lastSecondFrom = 0;
    std::vector<btTransform> m_window;
    std::string m_lastSecondSpinBody;
};

template <class Doll>
void runSteps(Scene& scene, const std::vector<std::unique_ptr<Doll>>& dolls, const StressSetup& setup,
              const StressThresholds& th, StressResult& r, const GuardReport& guard) {
    Stepper<Doll>(scene, dolls, setup, th, r).run(guard);
}

} // namespace

std::string_view toString(StressCause cause) {
    switch (cause) {
    case StressCause::None: return "pass";
    case StressCause::NonFinite: return "nan";
    case StressCause::Speed: return "speed";
    case StressCause::Anchor: return "anchor";
    case StressCause::Limit: return "limit";
    case StressCause::Penetration: return "penetration";
    case StressCause::Jitter: return "jitter";
    case StressCause::EnergyGain: return "energy";
    case StressCause::NoRest: return "no-rest";
    case StressCause::Skipped: return "skipped";
    }
    return "?";
}

double figureEnergyJ(const figure::Figure& figure, const std::vector<figure::BodyState>& states, double g) {
    double e = 0;
    for (std::size_t i = 0; i < states.size() && i < figure.bodies.size(); ++i) {
        const figure::FigureBody& body = figure.bodies[i];
        const figure::BodyState& s = states[i];
        const Eigen::Vector3d wBody = s.pose.rotation.transpose() * s.angularVelocity;
        e += 0.5 * body.massKg * s.linearVelocity.squaredNorm() +
             0.5 * wBody.dot(body.inertiaKgM2.cwiseProduct(wBody)) + body.massKg * g * s.pose.position.z();
    }
    return e;
}

std::optional<StressMethod> parseStressMethod(std::string_view spec, std::string& error) {
    const std::size_t plus = spec.find('+');
    auto base = parseChartMethod(spec.substr(0, plus), error);
    if (!base) return std::nullopt;
    StressMethod m;
    static_cast<ChartMethod&>(m) = std::move(*base);
    m.label = std::string(spec);
    std::string_view rest = plus == std::string_view::npos ? std::string_view() : spec.substr(plus + 1);
    while (plus != std::string_view::npos) {
        const std::size_t next = rest.find('+');
        const std::string_view item = rest.substr(0, next);
        if (item == "stabilize") m.stabilize = true;
        else if (item == "clamp") m.clamp = {kStressClampLinearMps, kStressClampAngularRadps};
        else if (item == "rest") m.restRules = true;
        else {
            error = "method " + std::string(spec) + ": unknown mitigation '+" + std::string(item) +
                    "' (+stabilize, +clamp, +rest)";
            return std::nullopt;
        }
        if (next == std::string_view::npos) break;
        rest = rest.substr(next + 1);
    }
    if (isRaw(m.method) && (m.stabilize || m.clamp.maxLinearMps > 0 || m.restRules)) {
        error = "method " + std::string(spec) + ": raw (plain Bullet) takes no mitigations";
        return std::nullopt;
    }
    return m;
}

StressResult runStress(const StressSetup& setup, const StressMethod& method, const StressThresholds& thresholds) {
    StressResult r;
    r.method = method.label;
    if (setup.figures.empty() || setup.spawns.empty()) return r;
    std::vector<std::shared_ptr<const bullet::RagdollAsset>> assets;
    for (const figure::Figure& f : setup.figures)
        assets.push_back(
            bullet::RagdollAsset::create(method.stabilize ? figure::stabilizeMassProperties(f) : figure::Figure(f)));
    Scene scene(method.method, SceneSettings{setup.figures.front().units.gravityMps2, true, 1.0});
    GuardReport guard;
    for (const StressSpawn& s : setup.spawns) {
        bullet::SpawnOptions so;
        so.guard.onTrip = [&guard](bullet::Ragdoll& doll, const bullet::GuardTrip& t) {
            if (guard.cause) return;
            using Cause = bullet::GuardTrip::Cause;
            guard.cause = t.cause == Cause::NonFinite ? StressCause::NonFinite
                          : t.cause == Cause::Speed   ? StressCause::Speed
                                                      : StressCause::Anchor;
            const figure::Figure& f = doll.figure();
            const std::string what = t.body >= 0 ? f.bodies[static_cast<std::size_t>(t.body)].name
                                                 : f.constraints[static_cast<std::size_t>(t.constraint)].name;
            guard.detail = "explosion guard froze " + f.name + " (" + std::string(bullet::toString(t.cause)) + " at " +
                           what + (t.value > 0 ? ", " + fixed(t.value, 2) : std::string()) + ")";
        };
        so.entityTransform = bullet::toBt(s.entity);
        // The rest rules would put a jittering figure to sleep (or stop it after maxMoveTime): the stress judges
        // the method's own physics, so rest is measured (StressThresholds), never imposed, unless "+rest" asks
        // for the figures as a game runs them.
        so.comeToRest = method.restRules;
        so.velocityClamp = method.clamp;
        const auto& asset = assets[s.figure];
        r.bodies += static_cast<int>(asset->figure().bodies.size());
        if (isRaw(method.method)) scene.spawnRaw(asset, so);
        else scene.spawn(asset, so);
    }
    if (isRaw(method.method)) runSteps(scene, scene.rawRagdolls(), setup, thresholds, r, guard);
    else runSteps(scene, scene.ragdolls(), setup, thresholds, r, guard);
    return r;
}

StressSetup yawedSetup(const StressSetup& setup, double yawDeg) {
    StressSetup out = setup;
    if (yawDeg == 0) return out;
    // Quarter turns exactly (cos 90° in double is 6e-17, not 0), so 4 × 90° composes to the identity.
    double c = 0, s = 0;
    const double quarters = yawDeg / 90;
    if (quarters == std::round(quarters)) {
        static constexpr double kCos[] = {1, 0, -1, 0}, kSin[] = {0, 1, 0, -1};
        const auto q = static_cast<std::size_t>(((std::llround(quarters) % 4) + 4) % 4);
        c = kCos[q];
        s = kSin[q];
    } else {
        c = std::cos(yawDeg * std::numbers::pi / 180);
        s = std::sin(yawDeg * std::numbers::pi / 180);
    }
    Eigen::Matrix3d rz;
    rz << c, -s, 0, s, c, 0, 0, 0, 1;
    for (StressSpawn& spawn : out.spawns) {
        spawn.entity.rotation = rz * spawn.entity.rotation;
        spawn.entity.position = rz * spawn.entity.position;
        spawn.linearVelocity = rz * spawn.linearVelocity;
        spawn.angularVelocity = rz * spawn.angularVelocity;
    }
    if (out.impulse) out.impulse->impulseNs = rz * out.impulse->impulseNs;
    return out;
}

std::vector<StressResult> runStressMatrix(const std::vector<const StressScenario*>& scenarios,
                                          const std::vector<StressMethod>& methods, const StressContent& content,
                                          const StressThresholds& thresholds, int threads, int yaws,
                                          const std::function<void(int done, int total)>& progress) {
    const auto yawCount = static_cast<std::size_t>(std::max(1, yaws));
    // Every (scenario, yaw) setup is built once, before the workers start; each run is one job.
    std::vector<std::optional<StressSetup>> setups;
    for (const StressScenario* s : scenarios) {
        const std::optional<StressSetup> built = s->build(content);
        for (std::size_t k = 0; k < yawCount; ++k)
            setups.push_back(built ? std::optional(yawedSetup(*built, yawDegOf(k, yawCount))) : std::nullopt);
    }
    const std::size_t total = scenarios.size() * methods.size() * yawCount;
    std::vector<StressResult> results(total);
    std::atomic<std::size_t> next{0};
    std::atomic<int> done{0};
    auto work = [&] {
        for (std::size_t i = next++; i < total; i = next++) {
            const std::size_t k = i % yawCount, m = i / yawCount % methods.size(), s = i / yawCount / methods.size();
            results[i] = runStressRun(setups[s * yawCount + k], scenarios[s]->name, methods[m], thresholds,
                                      yawDegOf(k, yawCount));
            ++done;
        }
    };
    std::vector<std::thread> pool;
    for (int t = 1; t < std::max(1, threads); ++t) pool.emplace_back(work);
    if (progress) {
        std::thread self(work);
        int last = -1;
        while (done < static_cast<int>(total)) {
            if (done != last) progress(last = done, static_cast<int>(total));
            std::this_thread::sleep_for(std::chrono::milliseconds(200));
        }
        self.join();
        progress(static_cast<int>(total), static_cast<int>(total));
    } else {
        work();
    }
    for (std::thread& t : pool) t.join();
    return results;
}

} // namespace afb::sim
