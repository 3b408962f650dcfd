// The reduced-coordinate backend (Multibody.h): the instance (spawn, removal), its per-substep action (damping,
// friction bounds, position sweeps, §6.1 rest) and its state (body samples, joint errors, impulses, rest). The
// trees, the constraints and the sweeps are in MultibodyTree.cpp, MultibodyConstraints.cpp and MultibodySweeps.cpp.
#include "Multibody.h"

#include <algorithm>
#include <stdexcept>

#include <BulletDynamics/Featherstone/btMultiBody.h>
#include <BulletDynamics/Featherstone/btMultiBodyDynamicsWorld.h>
#include <BulletDynamics/Featherstone/btMultiBodyLinkCollider.h>

#include "afb/bullet/Ragdoll.h"
#include "afb/detail/Convert.h"
#include "afb/figure/Collision.h"

namespace afb::bullet::detail {

// Per substep (Bullet runs actions after integration): the damping, the angular velocities the limits' margins
// read, and the figure's rest rules (§6.1).
class MultibodyRagdoll::Action : public btActionInterface {
  public:
    Action(MultibodyRagdoll& owner, bool comeToRest) : m_owner(owner), m_comeToRest(comeToRest) {}
    bool atRest = false;
    double activeTime = 0;

    void updateAction(btCollisionWorld*, btScalar dt) override {
        if (atRest) {
            for (const auto& c : m_owner.m_colliders)
                if (c->isActive()) {
                    wake();
                    break;
                }
            m_owner.recordMotion();
            return;
        }
        activeTime += dt;
        m_owner.updateFrictionBounds(dt);
        m_owner.dampVelocities(dt);
        m_owner.correctPositions();
        const std::vector<BodySample> samples = m_owner.samples();
        for (std::size_t i = 0; i < samples.size(); ++i) m_owner.m_angularVelocity[i] = samples[i].angularVelocity;
        m_owner.publishVelocities(samples);
        if (m_comeToRest && m_rest.update(samples, dt, activeTime)) m_owner.putToRest();
        m_owner.recordMotion();
    }
    void debugDraw(btIDebugDraw*) override {}

    void wake() {
        atRest = false;
        activeTime = 0;
        m_rest.reset();
        for (Part& p : m_owner.m_parts) {
            p.body->setCanSleep(false);
            p.body->wakeUp();
        }
        for (const auto& c : m_owner.m_colliders) c->activate(true);
    }

  private:
    MultibodyRagdoll& m_owner;
    bool m_comeToRest;
    RestTest m_rest{m_owner.m_asset->figure().rest};
};

MultibodyRagdoll::MultibodyRagdoll(std::shared_ptr<const RagdollAsset> asset, btDynamicsWorld& world,
                                   const SpawnOptions& options)
    : m_asset(std::move(asset)), m_world([&]() -> btMultiBodyDynamicsWorld& {
          auto* w = dynamic_cast<btMultiBodyDynamicsWorld*>(&world);
          if (w == nullptr) throw std::invalid_argument(kNeedsMultiBodyWorld);
          return *w;
      }()),
      m_spawn(options.entityTransform) {
    const figure::Figure& f = m_asset->figure();
    m_colliding = figure::selfCollisionPairs(f);
    if (options.method.exemptOverlapping)
        std::erase_if(m_colliding, [&](const std::pair<int, int>& pair) {
            const auto& overlapping = m_asset->overlappingPairs();
            return std::binary_search(overlapping.begin(), overlapping.end(), pair);
        });
    m_angularVelocity.assign(f.bodies.size(), btVector3(0, 0, 0));
    m_linearVelocity.assign(f.bodies.size(), btVector3(0, 0, 0));
    m_positionIterations = std::max(0, options.method.positionIterations);
    m_action = std::make_unique<Action>(*this, options.comeToRest);
    for (const figure::FigureConstraint& c : f.constraints)
        m_frames.emplace_back(toBt(c.frameInBody1),
                              c.body2 >= 0 ? toBt(c.frameInBody2) : m_spawn * toBt(c.frameInBody2));
    const std::vector<MultibodyJointParts> joints = jointParts();
    layoutTrees(joints);
    meanDamping();
    for (Part& p : m_parts) buildTree(p, options);
    addColliders(options);
    addConstraints(options.method, joints);
    m_world.addAction(m_action.get());
    if (options.startAtRest) putToRest();
}

MultibodyRagdoll::~MultibodyRagdoll() {
    m_world.removeAction(m_action.get());
    for (auto it = m_constraints.rbegin(); it != m_constraints.rend(); ++it)
        m_world.removeMultiBodyConstraint(it->constraint.get());
    for (auto it = m_colliders.rbegin(); it != m_colliders.rend(); ++it) m_world.removeCollisionObject(it->get());
    for (auto it = m_parts.rbegin(); it != m_parts.rend(); ++it) m_world.removeMultiBody(it->body.get());
}

void MultibodyRagdoll::publishVelocities(std::span<const BodySample> samples) {
    m_linearVelocity.resize(samples.size());
    for (std::size_t i = 0; i < samples.size(); ++i) {
        m_linearVelocity[i] = samples[i].linearVelocity;
        m_colliders[i]->setInterpolationLinearVelocity(samples[i].linearVelocity);
        m_colliders[i]->setInterpolationAngularVelocity(samples[i].angularVelocity);
    }
}

void MultibodyRagdoll::recordMotion() {
    for (EnergyGuard* g : m_guards) g->record();
}

void MultibodyRagdoll::refreshTransforms(btMultiBody& body) {
    btAlignedObjectArray<btQuaternion> q;
    btAlignedObjectArray<btVector3> o;
    body.forwardKinematics(q, o);
    body.updateCollisionObjectWorldTransforms(q, o);
}

// Damping: the rigid backend scales each body's velocities by (1 − d)^dt per step (btRigidBody's model). In reduced
// coordinates the same factor on every generalised velocity scales every body's linear and angular velocity alike:
// exact when the figure's moving bodies have one damping (every bundled and corpus figure: the §3.4 friction of
// settings), otherwise their mass-weighted mean. A base fixed to the world does not move and does not count (a
// frictionless bar hung from a fixed body with the settings' friction swings undamped, as on the rigid backend).
void MultibodyRagdoll::meanDamping() {
    const figure::Figure& f = m_asset->figure();
    double mass = 0, linear = 0, angular = 0;
    for (std::size_t i = 0; i < f.bodies.size(); ++i) {
        const BodyRef& ref = m_bodies[i];
        if (ref.link < 0 && m_parts[static_cast<std::size_t>(ref.part)].fixedBase) continue;
        const figure::FigureBody& b = f.bodies[i];
        mass += b.massKg;
        linear += b.massKg * b.linearDamping;
        angular += b.massKg * b.angularDamping;
    }
    if (mass > 0) {
        m_linearDamping = static_cast<btScalar>(linear / mass);
        m_angularDamping = static_cast<btScalar>(angular / mass);
    }
}

void MultibodyRagdoll::dampVelocities(btScalar dt) {
    if (m_linearDamping <= 0 && m_angularDamping <= 0) return;
    const btScalar d = btScalar(0.5) * (m_linearDamping + m_angularDamping);
    const btScalar k = btPow(btScalar(1) - d, dt);
    for (Part& p : m_parts) {
        btMultiBody& mb = *p.body;
        mb.setBaseVel(mb.getBaseVel() * k);
        mb.setBaseOmega(mb.getBaseOmega() * k);
        for (int l = 0; l < mb.getNumLinks(); ++l) {
            btScalar* v = mb.getJointVelMultiDof(l);
            for (int dof = 0; dof < mb.getLink(l).m_dofCount; ++dof) v[dof] *= k;
        }
    }
}

btCollisionObject& MultibodyRagdoll::collider(int i) { return *m_colliders[static_cast<std::size_t>(i)]; }
const btCollisionObject& MultibodyRagdoll::collider(int i) const { return *m_colliders[static_cast<std::size_t>(i)]; }

std::vector<BodySample> MultibodyRagdoll::samples() const {
    std::vector<BodySample> out(m_bodies.size());
    std::vector<btVector3> omega, vel;
    for (std::size_t k = 0; k < m_parts.size(); ++k) {
        const btMultiBody& mb = *m_parts[k].body;
        omega.resize(static_cast<std::size_t>(mb.getNumLinks() + 1));
        vel.resize(omega.size());
        mb.compTreeLinkVelocities(omega.data(), vel.data()); // in each link's frame
        for (std::size_t i = 0; i < m_bodies.size(); ++i) {
            if (m_bodies[i].part != static_cast<int>(k)) continue;
            const btTransform& t = m_colliders[i]->getWorldTransform();
            const std::size_t slot = static_cast<std::size_t>(m_bodies[i].link + 1);
            out[i] = {t, t.getBasis() * vel[slot], t.getBasis() * omega[slot]};
        }
    }
    return out;
}

std::vector<btTransform> MultibodyRagdoll::transforms() const {
    std::vector<btTransform> out;
    out.reserve(m_colliders.size());
    for (const auto& c : m_colliders) out.push_back(c->getWorldTransform());
    return out;
}

std::pair<btTransform, btTransform> MultibodyRagdoll::constraintFramesWorld(int i) const {
    const std::vector<btTransform> t = transforms();
    return constraintFramesWorldOf(m_asset->figure().constraints[static_cast<std::size_t>(i)], t,
                                   m_frames[static_cast<std::size_t>(i)]);
}

JointError MultibodyRagdoll::jointError(int i) const {
    return jointErrorOf(m_asset->figure().constraints[static_cast<std::size_t>(i)], transforms(),
                        m_frames[static_cast<std::size_t>(i)], m_spawn);
}

int MultibodyRagdoll::awakeBodyCount() const {
    int n = 0;
    for (const auto& c : m_colliders) n += c->isActive() ? 1 : 0;
    return n;
}

void MultibodyRagdoll::applyImpulse(int i, const btVector3& impulse, const btVector3& worldPoint) {
    const BodyRef ref = m_bodies[static_cast<std::size_t>(i)];
    btMultiBody& mb = *m_parts[static_cast<std::size_t>(ref.part)].body;
    const btScalar magnitude = impulse.length();
    if (!(magnitude > 0)) return;
    const int ndof = mb.getNumDofs() + 6;
    std::vector<btScalar> jac(static_cast<std::size_t>(ndof)), delta(static_cast<std::size_t>(ndof));
    btAlignedObjectArray<btScalar> r;
    btAlignedObjectArray<btVector3> v;
    btAlignedObjectArray<btMatrix3x3> m;
    // Δq̇ = M⁻¹·Jᵀ·|p| for the direction of p at the point: how the solver applies a contact impulse.
    mb.fillContactJacobianMultiDof(ref.link, worldPoint, impulse / magnitude, jac.data(), r, v, m);
    for (btScalar& x : jac) x *= magnitude;
    mb.calcAccelerationDeltasMultiDof(jac.data(), delta.data(), r, v);
    mb.applyDeltaVeeMultiDof(delta.data(), 1);
    recordMotion();
    publishVelocities(samples());
}

bool MultibodyRagdoll::atRest() const { return m_action->atRest; }
double MultibodyRagdoll::activeSeconds() const { return m_action->activeTime; }

void MultibodyRagdoll::putToRest() {
    for (Part& p : m_parts) {
        btMultiBody& mb = *p.body;
        mb.setBaseVel(btVector3(0, 0, 0));
        mb.setBaseOmega(btVector3(0, 0, 0));
        for (int l = 0; l < mb.getNumLinks(); ++l) {
            btScalar* v = mb.getJointVelMultiDof(l);
            for (int dof = 0; dof < mb.getLink(l).m_dofCount; ++dof) v[dof] = 0;
        }
        mb.setCanSleep(true);
        mb.goToSleep();
    }
    for (const auto& c : m_colliders) c->forceActivationState(ISLAND_SLEEPING);
    m_action->atRest = true;
    recordMotion();
    publishVelocities(samples());
}

void MultibodyRagdoll::wake() { m_action->wake(); }

} // namespace afb::bullet::detail
