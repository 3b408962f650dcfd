// Ragdoll's per-step action (joint friction bounds, the explosion guard, the rest rules): internal to Ragdoll's
// source files.
#pragma once

#include <optional>
#include <vector>

#include <btBulletDynamicsCommon.h>

#include "RagdollWorldLink.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/detail/Constraints.h"

namespace afb::bullet {

// Per-step work of a ragdoll: the joint friction bounds follow each joint's reaction force of the step just
// solved (docs/format.md §4.8), and the rest rules (§6.1) decide when the figure sleeps.
class Ragdoll::Action : public btActionInterface {
  public:
    struct Friction {
        JointFrictionConstraint* constraint;
        const btJointFeedback* feedback;
        btScalar coefficientTimesLever; // friction × metres per unit (§4.8 in SI)
    };
    Action(Ragdoll& owner, bool comeToRest, ExplosionGuard settings, VelocityClamp clampSettings)
        : guard(std::move(settings)), clamp(clampSettings), m_owner(owner), m_comeToRest(comeToRest) {}
    ExplosionGuard guard;
    VelocityClamp clamp;
    std::vector<Friction> frictions;
    bool atRest = false;
    double activeTime = 0;
    std::vector<btTransform> good; ///< every body after the last substep the guard passed
    int trips = 0;
    std::optional<GuardTrip> lastTrip;

    void updateAction(btCollisionWorld* world, btScalar dt) override {
        if (m_owner.m_regainPerSecond > 0) m_owner.regainStrength(double(dt));
        if (!atRest && guard.enabled) {
            if (auto trip = check()) {
                restore(*world);
                report(*trip);
                return;
            }
            remember();
        }
        if (!atRest && (clamp.maxLinearMps > 0 || clamp.maxAngularRadps > 0)) clampVelocities();
        if (atRest) {
            // Frozen (a RagdollWorld's): the world wakes it on contact. Asleep in a plain world: Bullet wakes
            // sleeping bodies touched by active ones, and then the figure wakes as a whole.
            if (m_owner.m_frozen) return;
            for (const auto& b : m_owner.m_bodies)
                if (b->isActive()) {
                    wake();
                    break;
                }
            return;
        }
        for (const Friction& f : frictions)
            f.constraint->setMaxImpulse(f.coefficientTimesLever * f.feedback->m_appliedForceBodyA.length() * dt);
        activeTime += dt;
        // Never at rest while a keyframed body moves, however slowly (its target is the game's, not the rules').
        if (m_comeToRest && restNow(dt) && !m_owner.m_keyframes.moving) m_owner.putToRest();
    }
    void debugDraw(btIDebugDraw*) override {}

    // The rest rules over the figure's bodies (a merged rigid's bodies each at its own place and velocity).
    bool restNow(btScalar dt) {
        if (!m_owner.merged()) return m_rest.update(m_owner.m_bodies, dt, activeTime);
        m_owner.figureBodySamples(m_samples);
        return m_rest.update(m_samples, dt, activeTime);
    }

    void wake() {
        atRest = false;
        activeTime = 0;
        m_rest.reset();
        m_owner.thawBodies();
        for (const auto& b : m_owner.m_bodies) b->activate(true);
    }

    void clampVelocities() {
        for (const auto& b : m_owner.m_bodies) {
            if (b->isKinematicObject()) continue; // a keyframed body's velocity is its target's, not the solver's
            const btVector3 v = b->getLinearVelocity(), w = b->getAngularVelocity();
            const btScalar speed = v.length(), spin = w.length();
            if (clamp.maxLinearMps > 0 && speed > clamp.maxLinearMps)
                b->setLinearVelocity(v * (static_cast<btScalar>(clamp.maxLinearMps) / speed));
            if (clamp.maxAngularRadps > 0 && spin > clamp.maxAngularRadps)
                b->setAngularVelocity(w * (static_cast<btScalar>(clamp.maxAngularRadps) / spin));
        }
    }

    // The guard's test: the first body (in body order) that is non-finite or too fast, then the first constraint
    // whose anchors are too far apart.
    std::optional<GuardTrip> check() const {
        const auto& bodies = m_owner.m_bodies;
        for (std::size_t i = 0; i < bodies.size(); ++i) {
            const btRigidBody& b = *bodies[i];
            const btTransform& t = b.getCenterOfMassTransform();
            const btVector3& v = b.getLinearVelocity();
            const btVector3& w = b.getAngularVelocity();
            bool finite = true;
            for (int k = 0; k < 3; ++k)
                finite = finite && std::isfinite(t.getOrigin()[k]) && std::isfinite(v[k]) && std::isfinite(w[k]) &&
                         std::isfinite(t.getBasis()[k][0]) && std::isfinite(t.getBasis()[k][1]) &&
                         std::isfinite(t.getBasis()[k][2]);
            const int body = m_owner.m_layout->rigids[i].representative;
            if (!finite) return trip(GuardTrip::Cause::NonFinite, body, -1, 0);
            const double speed = v.length();
            if (guard.maxSpeedMps > 0 && speed > guard.maxSpeedMps)
                return trip(GuardTrip::Cause::Speed, body, -1, speed);
        }
        if (guard.maxAnchorErrorM > 0)
            for (int c = 0; c < static_cast<int>(m_owner.figure().constraints.size()); ++c) {
                // The anchor copies' distance from the frames alone (jointError also measures limits, in double);
                // a slider's anchors move apart along its axis by design, jointError measures it off the axis.
                const figure::FigureConstraint& fc = m_owner.figure().constraints[static_cast<std::size_t>(c)];
                double gap = 0;
                const figure::AnchorHold held = figure::freedomOf(fc.type).anchor;
                if (held == figure::AnchorHold::None || m_owner.m_layout->internal[static_cast<std::size_t>(c)])
                    continue;
                if (held == figure::AnchorHold::Line) gap = m_owner.jointError(c).anchorM;
                else {
                    const auto [anchor1, anchor2] = m_owner.anchorsWorld(c);
                    gap = (anchor1 - anchor2).length();
                }
                if (gap > guard.maxAnchorErrorM) return trip(GuardTrip::Cause::AnchorError, -1, c, gap);
            }
        return std::nullopt;
    }
    GuardTrip trip(GuardTrip::Cause cause, int body, int constraint, double value) const {
        return GuardTrip{cause, body, constraint, value, activeTime};
    }
    void remember() {
        const auto& bodies = m_owner.m_bodies;
        good.resize(bodies.size());
        for (std::size_t i = 0; i < bodies.size(); ++i) good[i] = bodies[i]->getCenterOfMassTransform();
    }
    // Back to the last good substep, frozen; nothing of the bad state stays where the solver would read it again:
    // not the contacts' or joints' last impulses (warm starting), not the joint friction's feedback.
    void restore(btCollisionWorld& world) {
        auto& bodies = m_owner.m_bodies;
        for (std::size_t i = 0; i < bodies.size() && i < good.size(); ++i) {
            btRigidBody& b = *bodies[i];
            b.setCenterOfMassTransform(good[i]);
            b.setInterpolationWorldTransform(good[i]);
            b.setInterpolationLinearVelocity(btVector3(0, 0, 0));
            b.setInterpolationAngularVelocity(btVector3(0, 0, 0));
            b.clearForces();
            if (b.getBroadphaseHandle()) {
                world.getBroadphase()->getOverlappingPairCache()->cleanProxyFromPairs(b.getBroadphaseHandle(),
                                                                                      world.getDispatcher());
                b.forceActivationState(ISLAND_SLEEPING); // an AABB overflow disabled it: updateSingleAabb skips those
                world.updateSingleAabb(&b);
            }
        }
        for (const auto& fb : m_owner.m_feedback) *fb = btJointFeedback();
        for (const auto& c : m_owner.m_constraints) c->internalSetAppliedImpulse(0);
        if (m_owner.m_manager) detail::RagdollWorldLink::restartWarmStarting(*m_owner.m_manager, m_owner);
        m_owner.putToRest();
    }
    void report(const GuardTrip& t) {
        ++trips;
        lastTrip = t;
        if (guard.onTrip) guard.onTrip(m_owner, t);
    }

  private:
    Ragdoll& m_owner;
    bool m_comeToRest;
    RestTest m_rest{m_owner.figure().rest};
    std::vector<BodySample> m_samples;
};

} // namespace afb::bullet
