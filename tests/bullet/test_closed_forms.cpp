// Closed forms every preset must meet. A compound pendulum: a rigid bar on a frictionless hinge below a body fixed to
// the world, released 5° from hanging straight down; small-amplitude theory gives its period from the bar's exact
// mass properties, and the engine's air friction (a fraction of velocity removed each 16 ms step: docs/format.md
// §3.4) how fast its swing decays. A position pass, a joint solve or a velocity rule that added or removed energy, or
// changed the inertia the swing sees, shows there. A stack of boxes, each its own ragdoll, resting on the ground: each
// box rests at the height the boxes below it give, unmoved sideways. A chain hanging at rest: each joint carries the
// weight of the links below it. Deterministic: fixed 60 Hz step.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "FigureFixture.h"
#include "MethodFixture.h"
#include "afb/bullet/Method.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/bullet/RagdollSolver.h"
#include "afb/figure/Placement.h"
#include "afb/sim/Scene.h"

namespace {

constexpr double kPi = 3.14159265358979323846;
using afb::test::methods::kUnit;
constexpr double kG = 9.81;
constexpr double kHz = 60.0;
constexpr double kEngineStepS = 0.016;

// buildArmFigure's pendulum (FigureFixture.h) on a frictionless hinge about Y, with air friction `airFriction` (linear
// and angular) on the bar.
afb::figure::Figure pendulumFigure(const std::string& airFriction) {
    const auto built = afb::test::buildArmFigure(
        "hinge \"h\" { body1 \"arm\" body2 \"top\" anchor ( 0, 0, 100 ) axis ( 0, 1, 0 ) friction 0 }",
        "friction " + airFriction + ", " + airFriction + ", 0.8");
    INFO(built.diagnostics.str());
    REQUIRE(built.figure);
    return *built.figure;
}

struct Swing {
    std::vector<double> crossings; // times the bar's centre passes below the anchor going towards +X, s
    std::vector<double> peaks;     // the centre's largest |x| from the anchor before each crossing, m
};

// Releases the bar `startDeg` from hanging straight down and records its swing for `seconds`.
Swing swing(const afb::figure::Figure& f, const afb::bullet::Method& method, double startDeg, double seconds) {
    afb::sim::Scene scene(method, {.gravityMps2 = kG, .ground = false});
    afb::bullet::Ragdoll& r = scene.spawn(afb::bullet::RagdollAsset::create(f), {.comeToRest = false});
    for (int i = 0; i < r.bodyCount(); ++i) r.collisionObject(i).setActivationState(DISABLE_DEACTIVATION);
    // Turn the bar about the hinge axis (Y) through the anchor, from horizontal (+X) to startDeg off straight down.
    const Eigen::Vector3d anchor(0, 0, 100 * kUnit);
    const Eigen::Matrix3d turn(Eigen::AngleAxisd((90 - startDeg) * kPi / 180, Eigen::Vector3d::UnitY()));
    std::vector<afb::figure::BodyState> states = r.bodyStates();
    afb::figure::Transform& bar = states[1].pose;
    bar = {turn * bar.rotation, anchor + turn * (bar.position - anchor)};
    REQUIRE(r.setBodyStates(states));
    Swing out;
    double lastX = r.bodyState(1).pose.position.x() - anchor.x(), peak = 0;
    const int steps = static_cast<int>(seconds * kHz);
    for (int i = 1; i <= steps; ++i) {
        scene.step(1.0 / kHz);
        const double x = r.bodyState(1).pose.position.x() - anchor.x();
        peak = std::max(peak, std::abs(x));
        if (lastX < 0 && x >= 0) {
            out.crossings.push_back((i - 1 + lastX / (lastX - x)) / kHz);
            out.peaks.push_back(peak);
            peak = 0;
        }
        lastX = x;
    }
    return out;
}

} // namespace

TEST_CASE("pendulum: a bar on a hinge swings at its closed-form period and decays at the engine's air friction",
          "[bullet][methods]") {
    // I about the hinge = m·(L² + t²)/12 + m·c² (the box's exact inertia, the hinge through its end face's centre),
    // ω₀² = m·g·c / I. Air friction f multiplies both velocities by (1 − f) each 16 ms, so the swing decays as
    // e^(−γt) with γ = −ln(1 − f) / (2 · 0.016 s) and turns at ω = √(ω₀² − γ²). Released 5° off vertical, the
    // amplitude's own lengthening of the period is θ₀²/16 ≈ 0.05 %; Bullet's 60 Hz integration shortens it by about
    // 0.3 % (0.01 % at 480 Hz), within the 0.5 % asked.
    const double length = 20 * kUnit, thickness = 2 * kUnit, toCentre = length / 2;
    const double omega0Sq = kG * toCentre / ((length * length + thickness * thickness) / 12 + toCentre * toCentre);
    for (const double f : {0.0, 0.01}) {
        const afb::figure::Figure figure = pendulumFigure(f == 0 ? "0" : "0.01");
        const double gamma = -std::log(1 - f) / (2 * kEngineStepS);
        const double period = 2 * kPi / std::sqrt(omega0Sq - gamma * gamma);
        const double decayPerPeriod = std::exp(-gamma * period);
        REQUIRE(period == Approx(f == 0 ? 1.1689 : 1.1709).margin(0.0001));
        for (const std::string name : {"fast", "balanced", "default", "iterative", "accurate", "legacy", "multibody"}) {
            DYNAMIC_SECTION(name << ", air friction " << f) {
                const Swing s = swing(figure, *afb::bullet::methodPreset(name), 5.0, 6.0);
                REQUIRE(s.crossings.size() >= 5);
                // The period over the crossings, and the peaks' decay per period after the first (which saw the
                // release).
                const double measured = (s.crossings.back() - s.crossings.front()) / double(s.crossings.size() - 1);
                const double decay = std::pow(s.peaks.back() / s.peaks[1], 1.0 / double(s.peaks.size() - 2));
                INFO("period " << measured << " s (closed form " << period << "), amplitude per period " << decay
                               << " (closed form " << decayPerPeriod << ")");
                CHECK(measured == Approx(period).epsilon(0.005));
                CHECK(decay == Approx(decayPerPeriod).epsilon(0.005));
            }
        }
    }
}

// Four boxes spawned on each other, each its own ragdoll, after `seconds` on the ground: per box, its centre and
// speed.
std::vector<afb::figure::BodyState> stack(const afb::bullet::Method& method, double seconds) {
    const afb::figure::Figure box = afb::test::methods::boxFigure();
    afb::sim::Scene scene(method, {.gravityMps2 = kG});
    std::vector<afb::bullet::Ragdoll*> boxes;
    for (int k = 0; k < 4; ++k) {
        btTransform t = btTransform::getIdentity();
        t.setOrigin(btVector3(0, 0, btScalar(k * 8 * kUnit)));
        boxes.push_back(
            &scene.spawn(afb::bullet::RagdollAsset::create(box), {.entityTransform = t, .comeToRest = false}));
    }
    for (int i = 0; i < static_cast<int>(seconds * kHz); ++i) scene.step(1.0 / kHz);
    std::vector<afb::figure::BodyState> out;
    for (const afb::bullet::Ragdoll* b : boxes) out.push_back(b->bodyState(0));
    return out;
}

TEST_CASE("stack: four boxes, each its own ragdoll, rest on each other at their stacked heights", "[bullet][methods]") {
    // Four 16 × 16 × 8-unit boxes (0.2032 m tall, 6.6 kg) spawned touching, one on the other, from the ground up. At
    // rest box k's centre is at (k + ½)·0.2032 m, within the contacts' 2 mm slop. Nothing pushes them sideways, but
    // the presets' contact rows start each step from 0.85 of their last impulse (Bullet's warm-starting factor), and
    // what the iterations leave of the other 15 % is uneven over a box's four corners: the top box creeps sideways
    // at 0.5 mm/s (one friction direction: 2.3 mm/s) and has moved 2–4 mm after 3 s. Started from the whole impulse
    // (warm-starting-factor 1) the direct solve's stack holds still (1.4 µm/s).
    const double height = 8 * kUnit;
    for (const std::string name : {"fast", "balanced", "default", "iterative", "accurate"}) {
        for (const bool fullWarmStart : {false, true}) {
            afb::bullet::Method method = *afb::bullet::methodPreset(name);
            if (fullWarmStart) method.warmStartingFactor = 1;
            const bool holds = fullWarmStart && method.directJoints;
            DYNAMIC_SECTION(name << (fullWarmStart ? ", warm start 1" : "")) {
                const std::vector<afb::figure::BodyState> boxes = stack(method, 3.0);
                for (std::size_t k = 0; k < boxes.size(); ++k) {
                    const afb::figure::BodyState& s = boxes[k];
                    const double sideways = std::hypot(s.pose.position.x(), s.pose.position.y());
                    INFO("box " << k << " centre " << s.pose.position.transpose() << " m, speed "
                                << s.linearVelocity.norm() << " m/s");
                    CHECK(s.pose.position.z() == Approx((double(k) + 0.5) * height).margin(0.002));
                    CHECK(sideways < (holds ? 0.001 : 0.006));
                    CHECK(s.linearVelocity.norm() < (holds ? 1e-5 : 0.003));
                }
            }
        }
    }
}

TEST_CASE("chain: each joint of a chain hanging at rest carries the weight of the links below it",
          "[bullet][methods]") {
    // Three 20-unit bars hanging straight down from the world on ball joints at their top ends. At rest every
    // step's joint impulses hold gravity's velocity: joint k pushes the link below it up with the weight of that
    // link and every link under it. The direct solve takes these impulses from the bodies' momentum in joint space
    // and from the rows' reactions on the tree of bodies and joints; both must give the weights.
    const std::vector<afb::test::TestJoint> joints = {{"origin", -1, 0, 0, 0},
                                                      {"j1", 0, 0, 0, 100},
                                                      {"j2", 1, 0, 0, 80},
                                                      {"j3", 2, 0, 0, 60}};
    std::string af = "articulatedFigure chain {\n settings { selfCollision 0 }\n";
    const char* names[] = {"b1", "b2", "b3"};
    for (int k = 0; k < 3; ++k) {
        const int top = 100 - 20 * k;
        af += std::string(" body \"") + names[k] + "\" { joint \"" +
              (k == 0 ? std::string("origin") : "j" + std::to_string(k + 1)) +
              "\" model box( ( -1, -1, -20 ), ( 1, 1, 0 ) ) origin ( 0, 0, " + std::to_string(top) + " ) density " +
              std::to_string(0.2 + 0.1 * k) + " }\n";
        af += std::string(" ballAndSocketJoint \"s") + std::to_string(k + 1) + "\" { body1 \"" + names[k] +
              "\" body2 \"" + (k == 0 ? "world" : names[k - 1]) + "\" anchor ( 0, 0, " + std::to_string(top) +
              " ) friction 0 }\n";
    }
    af += "}\n";
    const auto built = afb::test::buildTestFigure(af, joints);
    INFO(built.diagnostics.str());
    REQUIRE(built.figure);
    for (const std::string name : {"fast", "balanced", "default"})
        for (const bool jointSpace : {true, false}) {
            DYNAMIC_SECTION(name << (jointSpace ? ", joint space" : ", tree of bodies and joints")) {
                afb::sim::Scene scene(*afb::bullet::methodPreset(name), {.gravityMps2 = kG, .ground = false});
                auto* solver = dynamic_cast<afb::bullet::RagdollSolver*>(scene.world().getConstraintSolver());
                REQUIRE(solver != nullptr);
                solver->setJointSpace(jointSpace);
                afb::bullet::Ragdoll& r =
                    scene.spawn(afb::bullet::RagdollAsset::create(*built.figure), {.comeToRest = false});
                REQUIRE(r.bodyCount() == 3);
                // Each joint's feedback, and the body it holds up (its body1, the link below the anchor).
                std::vector<btJointFeedback> feedback(static_cast<std::size_t>(r.bulletConstraintCount()));
                for (int k = 0; k < r.bulletConstraintCount(); ++k)
                    r.bulletConstraint(k).setJointFeedback(&feedback[static_cast<std::size_t>(k)]);
                for (int i = 0; i < 30; ++i) scene.step(1.0 / kHz);
                double below = 0; // the weight of the links from the current one down, N
                std::vector<double> weights(3);
                for (int k = 2; k >= 0; --k)
                    weights[static_cast<std::size_t>(k)] = below += r.rigidBody(k).getMass() * kG;
                int checked = 0;
                for (int k = 0; k < r.bulletConstraintCount(); ++k) {
                    if (r.bulletConstraintRole(k) != afb::bullet::RowRole::Joint) continue;
                    const btTypedConstraint& c = r.bulletConstraint(k);
                    for (int b = 0; b < 3; ++b) {
                        if (&c.getRigidBodyA() != &r.rigidBody(b)) continue;
                        const btVector3 f = feedback[static_cast<std::size_t>(k)].m_appliedForceBodyA;
                        INFO("joint above link " << b << ": " << f.x() << ", " << f.y() << ", " << f.z() << " N");
                        CHECK(f.z() == Approx(weights[static_cast<std::size_t>(b)]).epsilon(1e-3));
                        CHECK(std::hypot(f.x(), f.y()) < 1e-3 * weights[static_cast<std::size_t>(b)]);
                        ++checked;
                    }
                }
                CHECK(checked == 3);
                for (int k = 0; k < r.bulletConstraintCount(); ++k) r.bulletConstraint(k).setJointFeedback(nullptr);
            }
        }
}
