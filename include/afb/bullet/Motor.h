#pragma once
// Joint motors: a drive that pulls a joint toward a target relative pose and velocity as an implicit
// (stable) spring and damper, solved with the joint's other rows.
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace afb::bullet {

/// How hard a joint motor drives toward its target. The spring and the damper are given as the natural frequency and
/// damping ratio of the oscillator the motor makes of the inertia the joint carries about the driven axis (each side
/// of the joint as one rigid body about its anchor, a side held by a keyframed body or the world left out;
/// docs/motors.md), so one setting means the same on a hand and on a chest. The drive is implicit: its stiffness and
/// damping enter the solve of the step (stable proportional-derivative control). A frequency above a quarter of the
/// step rate acts as that quarter (15 Hz at a 60 Hz step): the stiffest drive a step holds without gaining energy,
/// which already closes an error within a few steps. So no setting is unstable at any step.
struct MotorGains {
    double frequencyHz = 0;  ///< natural frequency, Hz; 0 or less: the motor is off
    double dampingRatio = 1; ///< 1: critically damped; below 1 it overshoots, above it creeps; ≥ 0
    double maxTorqueNm = std::numeric_limits<double>::infinity(); ///< bound of each angular row, N·m
    double maxForceN = std::numeric_limits<double>::infinity();   ///< bound of a linear row (sliders), N
};

/// A figure's gains: `all` for every joint, then `joints` by constraint name (as the .af names it, case ignored as
/// the engine compares names), so a character can have a strong spine, weak arms and one arm limp (frequency 0).
/// Later entries win over earlier ones for the same joint.
struct MotorProfile {
    MotorGains all;                                         ///< every joint with a motor
    std::vector<std::pair<std::string, MotorGains>> joints; ///< then these, by constraint name
};

/// The gains at a strength ≥ 0 (Ragdoll::setMotorStrength takes [0, 1]; afb track --strength any): stiffness, damping
/// and the bounds times `strength`, i.e. the frequency and the damping ratio times its square root. 0 gives a motor
/// that is off.
MotorGains scaledGains(const MotorGains& gains, double strength);

/// How a powered ragdoll takes a hit (Ragdoll::hit): its motors drop to `strength` at once and regain the gains as
/// set, linearly, over `regainSeconds` (a puppet unpinned on a hit and pinned back).
struct HitReaction {
    double strength = 0;        ///< the motors' strength right after the hit, in [0, 1] (0: limp)
    double regainSeconds = 0.5; ///< time to full strength again, s ≥ 0 (0: no loss of strength)
};

} // namespace afb::bullet
