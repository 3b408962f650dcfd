// Joint motors against the damped oscillator they make of a joint: a bar jointed to the world at its centre of mass
// (no gravity torque) by a hinge about Z (or a ball joint), driven toward a target rotation. With inertia I about
// the axis, the motor is the spring I·ω² and the damper 2·I·ζ·ω, so the angle follows θ(t) = θ*·(1 − e^(−ζωt)·(cos
// ω_d t + ζ/√(1−ζ²)·sin ω_d t)) (ζ < 1) or θ*·(1 − (1 + ωt)·e^(−ωt)) (ζ = 1). The motor is implicit: the solve
// evaluates the spring and damper at the end of the step, so it stays stable and overdamped at any frequency.
#include <catch2/catch.hpp>

#include <cmath>
#include <memory>
#include <vector>

#include "afb/bullet/RagdollSolver.h"
#include "bullet/JointMotor.h"

namespace {

using afb::bullet::JointMotorConstraint;
using afb::bullet::MotorGains;
using afb::bullet::RagdollSolver;

// A world without gravity holding the bar, its hinge and its motor (hinge axis: the world's Z).
struct JointedBar {
    btDefaultCollisionConfiguration configuration;
    btCollisionDispatcher dispatcher{&configuration};
    btDbvtBroadphase broadphase;
    RagdollSolver solver;
    btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &configuration};
    btBoxShape shape{btVector3(0.4f, 0.1f, 0.1f)};
    std::unique_ptr<btRigidBody> bar;
    std::unique_ptr<btTypedConstraint> hinge;
    std::unique_ptr<JointMotorConstraint> motor;
    btScalar inertiaZ = 0;

    // `ball`: a point-to-point joint and a three-axis motor toward the rotation `axis`·targetRad; otherwise the
    // hinge about Z and its one-axis motor.
    explicit JointedBar(const MotorGains& gains, double targetRad, bool ball = false,
                        const btVector3& axis = btVector3(0, 0, 1)) {
        world.setGravity(btVector3(0, 0, 0));
        const btScalar mass = 2;
        btVector3 inertia;
        shape.calculateLocalInertia(mass, inertia);
        inertiaZ = inertia.z();
        btRigidBody::btRigidBodyConstructionInfo info(mass, nullptr, &shape, inertia);
        bar = std::make_unique<btRigidBody>(info);
        bar->setDamping(0, 0);
        bar->setActivationState(DISABLE_DEACTIVATION);
        world.addRigidBody(bar.get());
        if (ball) hinge = std::make_unique<btPoint2PointConstraint>(*bar, btVector3(0, 0, 0));
        else hinge = std::make_unique<btHingeConstraint>(*bar, btVector3(0, 0, 0), btVector3(0, 0, 1));
        world.addConstraint(hinge.get(), true);
        motor = std::make_unique<JointMotorConstraint>(btTypedConstraint::getFixedBody(), *bar,
                                                       btTransform::getIdentity(), btTransform::getIdentity(),
                                                       ball ? JointMotorConstraint::Axes::Rotation
                                                            : JointMotorConstraint::Axes::RotationAboutZ);
        motor->setGains(gains);
        motor->setRotationTarget(btQuaternion(axis.normalized(), btScalar(targetRad)), btVector3(0, 0, 0));
        world.addConstraint(motor.get(), true);
        solver.track(*motor, false, false, true);
    }
    ~JointedBar() {
        world.removeConstraint(motor.get());
        world.removeConstraint(hinge.get());
        world.removeRigidBody(bar.get());
    }
    JointedBar(const JointedBar&) = delete;
    JointedBar& operator=(const JointedBar&) = delete;

    double angle() const {
        const btQuaternion q = bar->getWorldTransform().getRotation();
        return 2 * std::atan2(double(q.z()), double(q.w()));
    }
    // The angle after each of `steps` steps of 1/hz.
    std::vector<double> run(double hz, int steps) {
        std::vector<double> out;
        for (int i = 0; i < steps; ++i) {
            world.stepSimulation(btScalar(1 / hz), 0, btScalar(1 / hz));
            out.push_back(angle());
        }
        return out;
    }
};

double oscillator(double target, double omega, double zeta, double t) {
    if (zeta >= 1) return target * (1 - (1 + omega * t) * std::exp(-omega * t));
    const double wd = omega * std::sqrt(1 - zeta * zeta);
    return target * (1 - std::exp(-zeta * omega * t) *
                             (std::cos(wd * t) + zeta / std::sqrt(1 - zeta * zeta) * std::sin(wd * t)));
}

// When the response enters 2 % of the target for good: the last sample outside the band and the next one,
// interpolated linearly (sample i is at time (i + 1)·dt).
double settlingTime(const std::vector<double>& angles, double dt, double target) {
    const double band = 0.02 * std::abs(target);
    std::size_t last = angles.size();
    for (std::size_t i = 0; i < angles.size(); ++i)
        if (std::abs(angles[i] - target) > band) last = i;
    if (last == angles.size()) return 0;
    if (last + 1 == angles.size()) return double(angles.size()) * dt;
    const double e0 = std::abs(angles[last] - target), e1 = std::abs(angles[last + 1] - target);
    return (double(last + 1) + (e0 - band) / (e0 - e1)) * dt;
}

} // namespace

// The drive is implicit Euler on the oscillator: first-order accurate, lagging and damping by about ω·h/2.
TEST_CASE("a critically damped hinge motor settles as the analytic oscillator", "[motors]") {
    const double hz = GENERATE(60.0, 120.0, 240.0);
    const double target = 1.0, frequency = 1.0;
    JointedBar rig(MotorGains{frequency, 1.0}, target);
    const std::vector<double> angles = rig.run(hz, int(4 * hz));
    std::vector<double> analytic;
    for (std::size_t i = 0; i < angles.size(); ++i)
        analytic.push_back(oscillator(target, 2 * M_PI * frequency, 1.0, double(i + 1) / hz));
    const double expected = settlingTime(analytic, 1 / hz, target);
    const double settled = settlingTime(angles, 1 / hz, target);
    INFO(hz << " Hz: settling " << settled << " s, analytic " << expected << " s");
    CHECK(expected == Approx(0.9285).epsilon(0.01));  // ωt = 5.834 solves (1 + ωt)·e^(−ωt) = 0.02
    CHECK(settled == Approx(expected).epsilon(0.05)); // 4.3 % late at 60 Hz (ω·h = 0.10), 2.1 % at 120 Hz
    CHECK(settled >= expected);                       // implicit: never ahead
    CHECK(angles.back() == Approx(target).margin(1e-3));
}

TEST_CASE("an underdamped hinge motor overshoots as the analytic oscillator", "[motors]") {
    const double hz = 240.0, target = 0.5, frequency = 1.0, zeta = 0.3;
    JointedBar rig(MotorGains{frequency, zeta}, target);
    const std::vector<double> angles = rig.run(hz, int(3 * hz));
    double peak = 0, peakAt = 0;
    for (std::size_t i = 0; i < angles.size(); ++i)
        if (angles[i] > peak) {
            peak = angles[i];
            peakAt = double(i + 1) / hz;
        }
    const double omega = 2 * M_PI * frequency;
    const double overshoot = std::exp(-M_PI * zeta / std::sqrt(1 - zeta * zeta)); // 0.372
    const double peakTime = M_PI / (omega * std::sqrt(1 - zeta * zeta));
    CHECK((peak - target) / target == Approx(overshoot).margin(0.03));
    CHECK(peakAt == Approx(peakTime).epsilon(0.05));
}

// Above a quarter of the step rate a motor is held to that quarter (JointMotor.h): ω·h = 10 moves as ω·h = π/2.
TEST_CASE("a hinge motor far stiffer than the step moves as one at a quarter of the step rate", "[motors]") {
    const double hz = GENERATE(15.0, 60.0, 240.0);
    const double target = 1.0;
    JointedBar stiff(MotorGains{10 * hz / (2 * M_PI), 1.0}, target); // ω·h = 10
    JointedBar quarter(MotorGains{hz / 4, 1.0}, target);
    const std::vector<double> angles = stiff.run(hz, int(2 * hz)), held = quarter.run(hz, int(2 * hz));
    std::vector<double> analytic;
    for (std::size_t i = 0; i < angles.size(); ++i)
        analytic.push_back(oscillator(target, M_PI / 2 * hz, 1.0, double(i + 1) / hz));
    INFO(hz << " Hz");
    for (std::size_t i = 0; i < angles.size(); ++i) CHECK(angles[i] == Approx(held[i]).margin(1e-5));
    for (double a : angles) CHECK(a <= target * 1.001);
    // Implicit Euler at ω·h = π/2 lags the oscillator: settled within twice its time, and at rest at the end.
    const double settled = settlingTime(angles, 1 / hz, target), expected = settlingTime(analytic, 1 / hz, target);
    INFO("settling " << settled << " s, analytic " << expected << " s");
    CHECK(settled >= expected);
    CHECK(settled < 2 * expected);
    CHECK(std::abs(double(stiff.bar->getAngularVelocity().length())) < 1e-3);
}

TEST_CASE("a hinge motor's torque bound caps the drive", "[motors]") {
    const double hz = 60.0, maxTorque = 0.5;
    JointedBar rig(MotorGains{50.0, 1.0, maxTorque}, 3.0); // far off: the bound holds throughout
    rig.run(hz, 30);
    // Constant torque from rest: ω(t) = τ/I·t.
    CHECK(double(rig.bar->getAngularVelocity().z()) == Approx(maxTorque / double(rig.inertiaZ) * 0.5).epsilon(0.01));
}

TEST_CASE("a three-axis motor turns a ball-jointed bar onto its target rotation", "[motors]") {
    const btVector3 axis = btVector3(1, 2, 3).normalized();
    const double target = 1.2;
    JointedBar rig(MotorGains{2.0, 1.0}, target, true, axis);
    rig.run(60.0, 120);
    const btQuaternion reached = rig.bar->getWorldTransform().getRotation();
    const btQuaternion wanted(axis, btScalar(target));
    CHECK(double(reached.angleShortestPath(wanted)) < 1e-3);
    CHECK(double(rig.bar->getAngularVelocity().length()) < 1e-2);
}
