// Keyframed bodies of the rigid backend (Ragdoll::setBodyMode, Ragdoll::setKeyframeTargets; docs/motors.md,
// "Keyframed bodies and partial ragdolls").
//
// A keyframed rigid body is a Bullet kinematic body (CF_KINEMATIC_OBJECT, inverse mass and inertia 0), not a
// dynamic body with its inverse mass zeroed. Bullet's solver gives a body of inverse mass 0 a solver body of its
// own, carrying its velocity, only when it is kinematic; any other such body becomes the one fixed solver body, at
// rest. Only a kinematic body's velocity therefore reaches the contact and joint rows that push and drag its
// neighbours. The rest of the rigid backend needs nothing new for it: the direct joint solve takes a body of
// inverse mass 0 as the immovable end of a joint (as the world), the position pass holds it at its pose, the
// explosion guard watches its speed like any other body's, and rest freezes it as static with the others.
//
// Bullet does not integrate kinematic bodies: it expects the game to place them and derives their velocity once
// per stepSimulation from the move (btRigidBody::saveKinematicState, interpolation transform to world transform
// over the frame). Placed at its target before the step, a body would sit at its end pose through every substep
// while its neighbours start from theirs. Here it moves with them instead: when a RagdollWorld::step begins it
// takes the constant velocity that reaches its target at the step's end, and after each substep's integration it
// moves by that velocity. The last substep lands it on the target exactly; every other one aims it again over the
// time left, so that rounding does not add up. Its interpolation transform is set to where that velocity would
// have had it one step earlier, so that Bullet's derivation gives the same velocity back.
#include <algorithm>
#include <cmath>

#include "RagdollAction.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/detail/Convert.h"

namespace afb::bullet {
namespace {

// The rotation vector (axis times angle, rad) that turns `from` into `to` the short way. From the quaternion's
// vector part and an atan2, which stay exact for the small turns of one step (acos of w does not).
btVector3 turnBetween(const btQuaternion& from, const btQuaternion& to) {
    btQuaternion d = to * from.inverse();
    if (d.w() < 0) d = -d;
    const btVector3 v(d.x(), d.y(), d.z());
    const btScalar s = v.length();
    if (!(s > 0)) return btVector3(0, 0, 0);
    return v * (2 * btAtan2(s, d.w()) / s);
}

// The quaternion of a rotation vector (rad).
btQuaternion turnOf(const btVector3& rotation) {
    const btScalar angle = rotation.length();
    if (!(angle > 0)) return btQuaternion::getIdentity();
    const btVector3 v = rotation * (btSin(angle / 2) / angle);
    return btQuaternion(v.x(), v.y(), v.z(), btCos(angle / 2));
}

// A target the solver can take: finite, with a proper rotation (orthonormal to well within a float's rounding).
bool validTarget(const figure::BodyState& s) {
    const Eigen::Matrix3d& r = s.pose.rotation;
    return s.pose.position.allFinite() && r.allFinite() && s.linearVelocity.allFinite() &&
           s.angularVelocity.allFinite() && (r.transpose() * r - Eigen::Matrix3d::Identity()).norm() < 1e-4 &&
           r.determinant() > 0;
}

} // namespace

int Ragdoll::keyframeSource(std::size_t rigid) const {
    if (m_keyframes.keyframed == 0 || rigid >= m_layout->rigids.size()) return -1;
    for (const int i : m_layout->rigids[rigid].bodies)
        if (m_keyframes.modes[static_cast<std::size_t>(i)] == BodyMode::Keyframed) return i;
    return -1;
}

BodyMode Ragdoll::bodyMode(int body) const {
    if (body < 0 || static_cast<std::size_t>(body) >= m_keyframes.modes.size()) return BodyMode::Simulated;
    return m_keyframes.modes[static_cast<std::size_t>(body)];
}

// Kinematic while one of its bodies is keyframed, dynamic with its own mass otherwise. Frozen bodies are static
// (freezeBodies); thawing applies the modes again.
void Ragdoll::applyRigidMode(std::size_t rigid) {
    if (m_frozen) return;
    btRigidBody& b = *m_bodies[rigid];
    if (keyframeSource(rigid) >= 0) {
        b.setMassProps(0, btVector3(0, 0, 0)); // flags it static too: kinematic instead
        b.setCollisionFlags((b.getCollisionFlags() & ~btCollisionObject::CF_STATIC_OBJECT) |
                            btCollisionObject::CF_KINEMATIC_OBJECT);
    } else if (b.isKinematicObject()) {
        const RigidLayout::Rigid& r = m_layout->rigids[rigid];
        b.setMassProps(static_cast<btScalar>(r.massKg), toBt(r.inertiaKgM2));
        b.setCollisionFlags(b.getCollisionFlags() & ~btCollisionObject::CF_KINEMATIC_OBJECT);
    } else {
        return;
    }
    b.updateInertiaTensor();
    b.activate(true);
}

bool Ragdoll::setBodyMode(int body, BodyMode mode) {
    if (!keyframesAllowed() || body < 0 || body >= bodyCount() ||
        (mode != BodyMode::Simulated && mode != BodyMode::Keyframed))
        return false;
    if (bodyMode(body) == mode) return true;
    Keyframes& kf = m_keyframes;
    if (kf.modes.empty()) {
        kf.modes.assign(static_cast<std::size_t>(bodyCount()), BodyMode::Simulated);
        kf.targets = bodyStates();
    }
    const auto i = static_cast<std::size_t>(body);
    const auto k = static_cast<std::size_t>(rigidIndexOf(body));
    const bool wasKeyframed = keyframeSource(k) >= 0;
    if (mode == BodyMode::Keyframed) kf.targets[i] = bodyState(body); // it holds where it is
    kf.modes[i] = mode;
    kf.keyframed += mode == BodyMode::Keyframed ? 1 : -1;
    kf.linear.resize(m_bodies.size(), btVector3(0, 0, 0));
    kf.angular.resize(m_bodies.size(), btVector3(0, 0, 0));
    if (!wasKeyframed) { // until the next step aims it: at rest where it is
        kf.linear[k].setZero();
        kf.angular[k].setZero();
    }
    applyRigidMode(k);
    return true;
}

bool Ragdoll::setKeyframeTargets(std::span<const figure::BodyState> targets) {
    if (!keyframesAllowed() || targets.size() != static_cast<std::size_t>(bodyCount()) ||
        !std::all_of(targets.begin(), targets.end(), validTarget))
        return false;
    if (m_keyframes.modes.empty()) m_keyframes.modes.assign(targets.size(), BodyMode::Simulated);
    m_keyframes.targets.assign(targets.begin(), targets.end());
    return true;
}

void Ragdoll::beginKeyframeStep(double stepSeconds) {
    Keyframes& kf = m_keyframes;
    if (kf.keyframed == 0 || m_multibody) return;
    kf.stepSeconds = stepSeconds;
    kf.elapsedSeconds = 0;
    kf.moving = false;
    kf.linear.resize(m_bodies.size(), btVector3(0, 0, 0));
    kf.angular.resize(m_bodies.size(), btVector3(0, 0, 0));
    if (!(stepSeconds > 0 && std::isfinite(stepSeconds))) return;
    const auto seconds = static_cast<btScalar>(stepSeconds);
    for (std::size_t k = 0; k < m_bodies.size(); ++k) {
        const int source = keyframeSource(k);
        if (source < 0) continue;
        const auto i = static_cast<std::size_t>(source);
        const btTransform target = toBt(kf.targets[i].pose) * m_layout->bodyInRigidBt[i].inverse();
        const btTransform& now = m_bodies[k]->getCenterOfMassTransform();
        kf.linear[k] = (target.getOrigin() - now.getOrigin()) / seconds;
        kf.angular[k] = turnBetween(now.getRotation(), target.getRotation()) / seconds;
        kf.moving = kf.moving || !kf.linear[k].isZero() || !kf.angular[k].isZero();
    }
    if (kf.moving && m_action->atRest) wake(); // a keyframed body has somewhere to go
    if (m_action->atRest) return;
    for (std::size_t k = 0; k < m_bodies.size(); ++k) {
        if (keyframeSource(k) < 0) continue;
        btRigidBody& b = *m_bodies[k];
        b.setLinearVelocity(kf.linear[k]);
        b.setAngularVelocity(kf.angular[k]);
        // Where this velocity had the body one step ago: Bullet's saveKinematicState derives it back from there.
        const btTransform& now = b.getCenterOfMassTransform();
        b.setInterpolationWorldTransform(btTransform(turnOf(-kf.angular[k] * seconds) * now.getRotation(),
                                                     now.getOrigin() - kf.linear[k] * seconds));
    }
}

void Ragdoll::advanceKeyframes(btScalar dt) {
    Keyframes& kf = m_keyframes;
    if (kf.keyframed == 0 || m_multibody || m_action->atRest) return;
    kf.linear.resize(m_bodies.size(), btVector3(0, 0, 0));
    kf.angular.resize(m_bodies.size(), btVector3(0, 0, 0));
    kf.elapsedSeconds += double(dt);
    const double left = kf.stepSeconds - kf.elapsedSeconds;
    // The step's last substep (or no RagdollWorld::step under way): on the target exactly.
    const bool last = !(left > 0.5 * double(dt));
    for (std::size_t k = 0; k < m_bodies.size(); ++k) {
        const int source = keyframeSource(k);
        if (source < 0) continue;
        const auto i = static_cast<std::size_t>(source);
        btRigidBody& b = *m_bodies[k];
        const btTransform target = toBt(kf.targets[i].pose) * m_layout->bodyInRigidBt[i].inverse();
        btTransform pose = target;
        if (!last) {
            const btTransform& now = b.getCenterOfMassTransform();
            pose = btTransform(turnOf(kf.angular[k] * dt) * now.getRotation(), now.getOrigin() + kf.linear[k] * dt);
            const auto time = static_cast<btScalar>(left);
            kf.linear[k] = (target.getOrigin() - pose.getOrigin()) / time;
            kf.angular[k] = turnBetween(pose.getRotation(), target.getRotation()) / time;
        }
        b.setWorldTransform(pose);
        b.setInterpolationWorldTransform(pose);
        b.setLinearVelocity(kf.linear[k]);
        b.setAngularVelocity(kf.angular[k]);
        if (b.getBroadphaseHandle()) m_world.updateSingleAabb(&b); // a ray test between steps sees it here
    }
}

} // namespace afb::bullet
