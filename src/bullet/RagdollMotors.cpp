// Joint motors of the rigid backend (Ragdoll::setMotorGains, Ragdoll::driveToPose; docs/motors.md).
#include <algorithm>
#include <cmath>
#include <optional>

#include "CarriedInertia.h"
#include "JointMotor.h"
#include "ObjectArena.h"
#include "RagdollWorldLink.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/bullet/RagdollSolver.h"
#include "afb/detail/Convert.h"
#include "afb/detail/Lexer.h"

namespace afb::bullet {
namespace {

using Axes = JointMotorConstraint::Axes;

// What a joint type's motor drives: its free axes (none for a fixed joint or a spring).
std::optional<Axes> motorAxes(figure::JointType type) {
    switch (type) {
    case figure::JointType::BallAndSocket: return Axes::Rotation;
    case figure::JointType::Universal: return Axes::Swing;
    case figure::JointType::Hinge: return Axes::RotationAboutZ;
    case figure::JointType::Slider: return Axes::SlideAlongX;
    case figure::JointType::Fixed:
    case figure::JointType::Spring: return std::nullopt;
    }
    return std::nullopt;
}

bool finite(const figure::BodyState& s) {
    return s.pose.rotation.allFinite() && s.pose.position.allFinite() && s.linearVelocity.allFinite() &&
           s.angularVelocity.allFinite();
}

} // namespace

MotorGains scaledGains(const MotorGains& gains, double strength) {
    if (strength == 1) return gains;
    MotorGains out = gains;
    if (!(strength > 0)) {
        out.frequencyHz = 0;
        return out;
    }
    const double root = std::sqrt(strength);
    out.frequencyHz *= root;
    out.dampingRatio *= root;
    out.maxTorqueNm *= strength;
    out.maxForceN *= strength;
    return out;
}

bool Ragdoll::motorsAllowed() const {
    return !m_multibody && m_manager != nullptr &&
           dynamic_cast<const RagdollSolver*>(m_world.getConstraintSolver()) != nullptr;
}

// Whether figure constraint `constraint`'s type has free axes to drive, whatever the layout: its gains and target
// are kept for it even while a level of detail merges its bodies (and it has no motor).
bool Ragdoll::drivable(int constraint) const {
    const auto& constraints = figure().constraints;
    return constraint >= 0 && static_cast<std::size_t>(constraint) < constraints.size() &&
           motorAxes(constraints[static_cast<std::size_t>(constraint)].type).has_value();
}

bool Ragdoll::hasMotor(int constraint) const {
    return drivable(constraint) && !m_layout->internal[static_cast<std::size_t>(constraint)];
}

MotorGains Ragdoll::motorGains(int constraint) const {
    if (m_motorGains.empty() || !drivable(constraint)) return {};
    return m_motorGains[static_cast<std::size_t>(constraint)];
}

bool Ragdoll::setMotorGains(const MotorGains& gains) {
    if (!motorsAllowed()) return false;
    const bool first = m_motorGains.empty();
    const std::size_t n = figure().constraints.size();
    m_motorGains.assign(n, MotorGains{0});
    m_motorTargets.resize(n);
    for (std::size_t ci = 0; ci < n; ++ci)
        if (drivable(static_cast<int>(ci))) m_motorGains[ci] = gains;
    if (first) {
        addMotors();
        // The new constraints are tracked as soft rows by the world (RagdollWorld::trackJoints).
        detail::RagdollWorldLink::restartWarmStarting(*m_manager, *this);
        return true;
    }
    for (std::size_t ci = 0; ci < n; ++ci) applyMotorGains(ci);
    return true;
}

// A motor is in the world only while its gains give it rows: a motor switched off leaves the world's constraints
// (and the order Bullet solves them in) exactly as without it.
void Ragdoll::applyMotorGains(std::size_t ci) {
    JointMotorConstraint* motor = m_motors[ci];
    if (!motor) return;
    const bool was = motor->active();
    motor->setGains(scaledGains(m_motorGains[ci], m_motorStrength));
    if (m_frozen || was == motor->active()) return;
    if (motor->active()) m_world.addConstraint(motor);
    else m_world.removeConstraint(motor);
}

bool Ragdoll::setMotorGains(int constraint, const MotorGains& gains) {
    if (!motorsAllowed() || !drivable(constraint)) return false;
    if (m_motorGains.empty() && !setMotorGains(MotorGains{0})) return false;
    const auto ci = static_cast<std::size_t>(constraint);
    m_motorGains[ci] = gains;
    applyMotorGains(ci);
    return true;
}

bool Ragdoll::setMotorGains(const MotorProfile& profile) {
    if (!motorsAllowed()) return false;
    const auto& constraints = figure().constraints;
    std::vector<std::pair<std::size_t, MotorGains>> named;
    for (const auto& joint : profile.joints) {
        const std::string& name = joint.first; // a named reference: lambdas cannot capture structured bindings in C++20
        const auto it =
            std::find_if(constraints.begin(), constraints.end(),
                         [&name](const figure::FigureConstraint& c) { return text::equalsIgnoreCase(c.name, name); });
        const auto ci = static_cast<std::size_t>(it - constraints.begin());
        if (it == constraints.end() || !drivable(static_cast<int>(ci))) return false;
        named.emplace_back(ci, joint.second);
    }
    if (!setMotorGains(profile.all)) return false;
    for (const auto& [ci, gains] : named) {
        m_motorGains[ci] = gains;
        applyMotorGains(ci);
    }
    return true;
}

bool Ragdoll::setMotorStrength(double strength) {
    if (!motorsAllowed() || !(strength >= 0 && strength <= 1)) return false;
    m_regainPerSecond = 0;
    m_motorStrength = strength;
    for (std::size_t ci = 0; ci < m_motorGains.size(); ++ci) applyMotorGains(ci);
    return true;
}

bool Ragdoll::hit(int body, const btVector3& impulse, const btVector3& worldPoint, const HitReaction& reaction) {
    const bool finiteHit = std::isfinite(double(impulse.length2())) && std::isfinite(double(worldPoint.length2()));
    if (body < 0 || body >= bodyCount() || !finiteHit || !(reaction.strength >= 0 && reaction.strength <= 1) ||
        !(reaction.regainSeconds >= 0 && std::isfinite(reaction.regainSeconds)))
        return false;
    if (!applyBodyImpulse(body, impulse, worldPoint, ImpulseRule::Always)) return false;
    if (m_motorGains.empty() || reaction.regainSeconds == 0 || reaction.strength >= m_motorStrength) return true;
    m_motorStrength = reaction.strength;
    m_regainPerSecond = (1 - reaction.strength) / reaction.regainSeconds;
    for (std::size_t ci = 0; ci < m_motorGains.size(); ++ci) applyMotorGains(ci);
    return true;
}

// After each substep while a hit's strength comes back: linear in simulated time, exactly 1 at the end.
void Ragdoll::regainStrength(double dt) {
    m_motorStrength = std::min(1.0, m_motorStrength + m_regainPerSecond * dt);
    if (m_motorStrength >= 1) m_regainPerSecond = 0;
    for (std::size_t ci = 0; ci < m_motorGains.size(); ++ci) applyMotorGains(ci);
}

bool Ragdoll::driveToPose(std::span<const figure::BodyState> target) {
    if (!motorsAllowed() || target.size() != static_cast<std::size_t>(bodyCount())) return false;
    for (const figure::BodyState& s : target)
        if (!finite(s)) return false;
    if (m_motorGains.empty() && !setMotorGains(MotorGains{0})) return false;
    const auto& constraints = figure().constraints;
    for (std::size_t ci = 0; ci < constraints.size(); ++ci) {
        if (!drivable(static_cast<int>(ci))) continue;
        const figure::FigureConstraint& c = constraints[ci];
        const figure::BodyState& s1 = target[static_cast<std::size_t>(c.body1)];
        const figure::BodyState* s2 = c.body2 >= 0 ? &target[static_cast<std::size_t>(c.body2)] : nullptr;
        // The joint's two frames where the pose puts them (frame B stays in the world for a world constraint).
        const btTransform fa = toBt(s1.pose) * m_frames[ci].first;
        const btTransform fb = s2 ? toBt(s2->pose) * m_frames[ci].second : m_frames[ci].second;
        const btVector3 w1 = toBt(s1.angularVelocity), w2 = s2 ? toBt(s2->angularVelocity) : btVector3(0, 0, 0);
        MotorTarget& t = m_motorTargets[ci];
        (fa.getBasis().transpose() * fb.getBasis()).getRotation(t.rotation);
        t.angularVelocity = fa.getBasis().transpose() * (w2 - w1);
        // Sliders: frame B's origin along its X from frame A's, and the rate of that offset as the slide row
        // measures it (B's frame origin moving with B, against the point of A under it).
        const btVector3 axis = fb.getBasis().getColumn(0), at = fb.getOrigin();
        t.offset = (at - fa.getOrigin()).dot(axis);
        const btVector3 c1 = toBt(s1.pose.position);
        const btVector3 vB =
            s2 ? toBt(s2->linearVelocity) + w2.cross(at - toBt(s2->pose.position)) : btVector3(0, 0, 0);
        const btVector3 vA = toBt(s1.linearVelocity) + w1.cross(at - c1);
        t.speed = (vB - vA).dot(axis);
        if (JointMotorConstraint* motor = m_motors[ci]) {
            motor->setRotationTarget(t.rotation, t.angularVelocity);
            motor->setSlideTarget(t.offset, t.speed);
        }
    }
    return true;
}

// One motor per joint that has one, between the joint's rigid bodies in the joint's frames, after the joints (so a
// ragdoll without motors keeps its constraint order); only those switched on go into the world. A frozen ragdoll's
// constraints are out of the world; thawing adds these with the rest.
void Ragdoll::addMotors() {
    const auto& constraints = figure().constraints;
    m_motors.assign(constraints.size(), nullptr);
    for (std::size_t ci = 0; ci < constraints.size(); ++ci) {
        const figure::FigureConstraint& c = constraints[ci];
        const std::optional<Axes> axes = motorAxes(c.type);
        if (!axes || !m_main[ci]) continue;
        auto* motor = m_arena->make<JointMotorConstraint>(body(c.body1), other(c.body2), m_rigidFrames[ci].first,
                                                          m_rigidFrames[ci].second, *axes);
        const MotorTarget& t = m_motorTargets[ci];
        motor->setGains(scaledGains(m_motorGains[ci], m_motorStrength));
        motor->setRotationTarget(t.rotation, t.angularVelocity);
        motor->setSlideTarget(t.offset, t.speed);
        m_motors[ci] = motor;
        if (!m_frozen && motor->active()) m_world.addConstraint(motor);
        m_constraints.push_back(motor);
        m_roles.push_back(RowRole::Motor);
    }
    // The tree of the rigids, every joint between two of them a connection.
    std::vector<detail::CarriedInertia::Joint> joints(constraints.size());
    for (std::size_t ci = 0; ci < constraints.size(); ++ci) {
        const figure::FigureConstraint& c = constraints[ci];
        if (m_layout->internal[ci] || c.body1 < 0) continue;
        joints[ci].a = m_layout->rigidOf[static_cast<std::size_t>(c.body1)];
        joints[ci].b = c.body2 >= 0 ? m_layout->rigidOf[static_cast<std::size_t>(c.body2)] : -1;
    }
    if (!m_carried) m_carried = std::make_unique<detail::CarriedInertia>();
    m_carried->reset(static_cast<int>(m_bodies.size()), joints);
    beginMotorStep();
}

// Each motor's spring and damper on the inertia its joint carries in the pose the step starts from.
void Ragdoll::beginMotorStep() {
    if (!m_carried || m_frozen ||
        std::none_of(m_motors.begin(), m_motors.end(), [](const JointMotorConstraint* m) { return m && m->active(); }))
        return;
    m_carried->update(m_bodies);
    btMatrix3x3 w;
    for (std::size_t ci = 0; ci < m_motors.size(); ++ci) {
        JointMotorConstraint* motor = m_motors[ci];
        if (!motor || !motor->active()) continue;
        const btVector3 pivot =
            body(figure().constraints[ci].body1).getCenterOfMassTransform() * m_rigidFrames[ci].first.getOrigin();
        const bool carried = m_carried->inverseInertia(static_cast<int>(ci), pivot, w);
        motor->setCarriedInverseInertia(carried ? &w : nullptr);
    }
}

} // namespace afb::bullet
