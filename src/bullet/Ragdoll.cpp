// Spawning a figure into a Bullet world: docs/format.md §4 (constraint mapping), §4.7 (springs), §4.8 (friction),
// §6.2 (collision filtering).
#include "afb/bullet/Ragdoll.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <BulletCollision/NarrowPhaseCollision/btGjkEpa2.h>

#include "CarriedInertia.h"
#include "EngineFriction.h"
#include "JointMotor.h"
#include "Multibody.h"
#include "ObjectArena.h"
#include "RagdollAction.h"
#include "RagdollWorldLink.h"
#include "afb/detail/Constraints.h"
#include "afb/detail/Convert.h"
#include "afb/figure/Collision.h"

namespace afb::bullet {

using figure::FigureConstraint;
using figure::JointType;

Ragdoll::Ragdoll(std::shared_ptr<const RagdollAsset> asset, btDynamicsWorld& world, const SpawnOptions& options)
    : m_asset(std::move(asset)), m_world(world), m_method(options.method),
      m_engineFriction(options.engineContactFriction), m_spawn(options.entityTransform),
      m_action(std::make_unique<Action>(*this, options.comeToRest, options.guard, options.velocityClamp)) {
    m_layout = &m_asset->layout(m_method.mergeFixed && m_method.backend == Backend::Rigid);
    if (m_method.backend == Backend::Multibody) {
        m_multibody = std::make_unique<detail::MultibodyRagdoll>(m_asset, world, options);
        for (std::size_t i = 0; i < figure().constraints.size(); ++i)
            m_frames.push_back(m_multibody->constraintFramesLocal(static_cast<int>(i)));
        return;
    }
    m_group = options.collisionGroup;
    m_spawnMask = options.collisionMask;
    // One arena for the instance's Bullet objects, sized by what the figure's last instance took.
    const auto [bytes, objects] = m_asset->instanceArenaHint();
    m_arena = std::make_unique<detail::ObjectArena>(bytes, objects);
    addBodies();
    m_action->remember();
    addConstraints();
    m_asset->noteInstanceArena(m_arena->bytesUsed(), m_arena->objectCount());
    filterPairs();
    m_world.addAction(m_action.get());
    if (options.startAtRest) putToRest();
}

bool Ragdoll::engineContactFriction() const { return m_engineFriction && EngineContactFriction::installed(); }

namespace {
bool finiteState(const figure::BodyState& s) {
    return s.pose.position.allFinite() && s.pose.rotation.allFinite() && s.linearVelocity.allFinite() &&
           s.angularVelocity.allFinite();
}
} // namespace

void Ragdoll::requireRigid(const char* accessor) const {
    if (m_multibody)
        throw std::logic_error(std::string("afb::bullet::Ragdoll::") + accessor +
                               ": the rigid backend's Bullet objects do not exist on a multibody ragdoll (bodyState, "
                               "collisionObject and applyBodyImpulse serve both backends)");
}

btRigidBody& Ragdoll::body(int i) {
    requireRigid("body");
    return *m_bodies[static_cast<std::size_t>(rigidIndexOf(i))];
}
const btRigidBody& Ragdoll::body(int i) const {
    requireRigid("body");
    return *m_bodies[static_cast<std::size_t>(rigidIndexOf(i))];
}
btRigidBody& Ragdoll::rigidBody(int k) {
    requireRigid("rigidBody");
    return *m_bodies[static_cast<std::size_t>(k)];
}
const btRigidBody& Ragdoll::rigidBody(int k) const {
    requireRigid("rigidBody");
    return *m_bodies[static_cast<std::size_t>(k)];
}
btTypedConstraint* Ragdoll::constraint(int i) {
    requireRigid("constraint");
    return m_main[static_cast<std::size_t>(i)];
}
const btTypedConstraint* Ragdoll::constraint(int i) const {
    requireRigid("constraint");
    return m_main[static_cast<std::size_t>(i)];
}
RowRole Ragdoll::bulletConstraintRole(int k) const {
    requireRigid("bulletConstraintRole");
    return m_roles[static_cast<std::size_t>(k)];
}
btTypedConstraint& Ragdoll::bulletConstraint(int k) {
    requireRigid("bulletConstraint");
    return *m_constraints[static_cast<std::size_t>(k)];
}
const btTypedConstraint& Ragdoll::bulletConstraint(int k) const {
    requireRigid("bulletConstraint");
    return *m_constraints[static_cast<std::size_t>(k)];
}

int Ragdoll::bodyCount() const {
    return m_multibody ? m_multibody->bodyCount() : static_cast<int>(m_layout->rigidOf.size());
}

btCollisionObject& Ragdoll::collisionObject(int i) {
    if (m_multibody) return m_multibody->collider(i);
    return body(i);
}

const btCollisionObject& Ragdoll::collisionObject(int i) const {
    if (m_multibody) return m_multibody->collider(i);
    return body(i);
}

std::vector<figure::BodyState> Ragdoll::bodyStates() const {
    if (!m_multibody && !merged()) return bodyStatesOf(m_bodies);
    std::vector<BodySample> samples;
    if (m_multibody) samples = m_multibody->samples();
    else figureBodySamples(samples);
    std::vector<figure::BodyState> out;
    for (const BodySample& s : samples)
        out.push_back({toEigen(s.transform), toEigen(s.linearVelocity), toEigen(s.angularVelocity)});
    return out;
}

figure::BodyState Ragdoll::bodyState(int i) const {
    if (m_multibody) return bodyStates()[static_cast<std::size_t>(i)];
    const btRigidBody& r = *m_bodies[static_cast<std::size_t>(rigidIndexOf(i))];
    const btTransform t = r.getCenterOfMassTransform() * bodyInRigid(i);
    const btVector3 v = r.getVelocityInLocalPoint(t.getOrigin() - r.getCenterOfMassPosition());
    return {toEigen(t), toEigen(v), toEigen(r.getAngularVelocity())};
}

std::vector<btTransform> Ragdoll::figureBodyTransforms() const {
    std::vector<btTransform> out;
    out.reserve(m_layout->rigidOf.size());
    for (std::size_t i = 0; i < m_layout->rigidOf.size(); ++i)
        out.push_back(m_bodies[static_cast<std::size_t>(m_layout->rigidOf[i])]->getCenterOfMassTransform() *
                      m_layout->bodyInRigidBt[i]);
    return out;
}

// A merged body moves with its rigid: its frame is the rigid's times its offset, its centre of mass moves with
// the rigid's velocity at that point.
void Ragdoll::figureBodySamples(std::vector<BodySample>& out) const {
    out.resize(m_layout->rigidOf.size());
    for (std::size_t i = 0; i < out.size(); ++i) {
        const btRigidBody& r = *m_bodies[static_cast<std::size_t>(m_layout->rigidOf[i])];
        const btTransform t = r.getCenterOfMassTransform() * m_layout->bodyInRigidBt[i];
        out[i] = {t, r.getVelocityInLocalPoint(t.getOrigin() - r.getCenterOfMassPosition()), r.getAngularVelocity()};
    }
}

int Ragdoll::awakeBodyCount() const {
    if (m_multibody) return m_multibody->awakeBodyCount();
    if (!merged()) return awakeCountOf(m_bodies);
    int n = 0; // figure bodies: a merged rigid counts each body it carries
    for (std::size_t k = 0; k < m_bodies.size(); ++k)
        if (m_bodies[k]->isActive()) n += static_cast<int>(m_layout->rigids[k].bodies.size());
    return n;
}

JointError Ragdoll::jointError(int i) const {
    if (m_multibody) return m_multibody->jointError(i);
    if (merged()) {
        // A fixed joint merged into one rigid body holds exactly; a level of detail's holds its error at the switch.
        if (m_layout->internal[static_cast<std::size_t>(i)] && !m_lodLayout) return {};
        return jointErrorOf(figure().constraints[static_cast<std::size_t>(i)], figureBodyTransforms(),
                            m_frames[static_cast<std::size_t>(i)], m_spawn);
    }
    return jointErrorOf(figure().constraints[static_cast<std::size_t>(i)], m_bodies,
                        m_frames[static_cast<std::size_t>(i)], m_spawn);
}

std::vector<figure::Transform> Ragdoll::bodyTransforms() const {
    if (!m_multibody && !merged()) return bodyTransformsOf(m_bodies);
    std::vector<figure::Transform> out;
    if (!m_multibody) {
        for (const btTransform& t : figureBodyTransforms()) out.push_back(toEigen(t));
        return out;
    }
    for (const btTransform& t : m_multibody->transforms()) out.push_back(toEigen(t));
    return out;
}

void Ragdoll::placeRigid(btRigidBody& b, const btTransform& t, const btVector3& v, const btVector3& w) {
    b.setCenterOfMassTransform(t);
    b.setInterpolationWorldTransform(t);
    b.setLinearVelocity(v);
    b.setAngularVelocity(w);
    b.setInterpolationLinearVelocity(v);
    b.setInterpolationAngularVelocity(w);
}

bool Ragdoll::setBodyStates(std::span<const figure::BodyState> states) {
    if (states.size() != static_cast<std::size_t>(bodyCount())) return false;
    if (m_multibody) {
        // No explosion guard watches the trees: a non-finite state is refused before Bullet sees it.
        for (const figure::BodyState& s : states)
            if (!finiteState(s)) return false;
        m_multibody->setBodyStates(states);
        return true;
    }
    for (std::size_t k = 0; k < m_bodies.size(); ++k) {
        // A merged rigid follows its representative body: frame and velocities carried to its centre of mass.
        const std::size_t i = static_cast<std::size_t>(m_layout->rigids[k].representative);
        btRigidBody& b = *m_bodies[k];
        const btTransform t = toBt(states[i].pose) * m_layout->bodyInRigidBt[i].inverse();
        const btVector3 w = toBt(states[i].angularVelocity);
        const btVector3 v = toBt(states[i].linearVelocity) + w.cross(t.getOrigin() - toBt(states[i].pose.position));
        placeRigid(b, t, v, w);
        m_world.getBroadphase()->getOverlappingPairCache()->cleanProxyFromPairs(b.getBroadphaseHandle(),
                                                                                m_world.getDispatcher());
    }
    m_action->remember();
    wake();
    return true;
}

bool Ragdoll::setBodyVelocities(std::span<const BodyVelocity> velocities) {
    if (velocities.size() != static_cast<std::size_t>(bodyCount())) return false;
    if (m_multibody) {
        for (const BodyVelocity& v : velocities)
            if (!std::isfinite(v.linearMps.length2()) || !std::isfinite(v.angularRadps.length2())) return false;
        std::vector<figure::BodyState> states = bodyStates();
        for (std::size_t i = 0; i < states.size(); ++i) {
            states[i].linearVelocity = toEigen(velocities[i].linearMps);
            states[i].angularVelocity = toEigen(velocities[i].angularRadps);
        }
        m_multibody->setBodyStates(states);
        m_multibody->wake();
        return true;
    }
    for (std::size_t k = 0; k < m_bodies.size(); ++k) {
        // A merged rigid takes its representative body's motion, carried to its own centre of mass.
        const std::size_t i = static_cast<std::size_t>(m_layout->rigids[k].representative);
        btRigidBody& b = *m_bodies[k];
        const btVector3 w = velocities[i].angularRadps;
        const btVector3 centre = (b.getCenterOfMassTransform() * bodyInRigid(static_cast<int>(i))).getOrigin();
        b.setLinearVelocity(velocities[i].linearMps + w.cross(b.getCenterOfMassPosition() - centre));
        b.setAngularVelocity(w);
    }
    wake();
    return true;
}

bool Ragdoll::applyImpulse(int joint, const btVector3& impulse, const btVector3& worldPoint) {
    const std::vector<int>& owners = figure().jointBody;
    if (joint < 0 || static_cast<std::size_t>(joint) >= owners.size()) return false;
    return applyBodyImpulse(owners[static_cast<std::size_t>(joint)], impulse, worldPoint);
}

bool Ragdoll::applyBodyImpulse(int body, const btVector3& impulse, const btVector3& worldPoint, ImpulseRule rule) {
    if (body < 0 || body >= bodyCount()) return false;
    if (rule == ImpulseRule::EngineThreshold && impulse.length() < impulseThresholdNs()) return false;
    if (m_multibody) {
        m_multibody->wake();
        m_multibody->applyImpulse(body, impulse, worldPoint);
        return true;
    }
    btRigidBody& b = *m_bodies[static_cast<std::size_t>(rigidIndexOf(body))];
    wake();
    b.applyImpulse(impulse, worldPoint - b.getCenterOfMassPosition());
    return true;
}

int Ragdoll::figureBodyOf(const btCollisionObject& object, const btVector3& worldPoint) const {
    if (m_multibody) {
        for (int i = 0; i < bodyCount(); ++i)
            if (&collisionObject(i) == &object) return i;
        return -1;
    }
    const auto rigid = std::find(m_bodies.begin(), m_bodies.end(), &object);
    if (rigid == m_bodies.end()) return -1;
    const RigidLayout::Rigid& r = m_layout->rigids[static_cast<std::size_t>(rigid - m_bodies.begin())];
    if (r.bodies.size() == 1) return r.bodies.front();
    // Several bodies in one compound: the one whose surface is nearest the point (deepest, for a point inside).
    int best = r.representative;
    btScalar nearest = BT_LARGE_FLOAT;
    const btTransform& frame = (*rigid)->getWorldTransform();
    for (const int b : r.bodies) {
        const auto* shape = static_cast<const btConvexShape*>(m_asset->shape(b));
        btGjkEpaSolver2::sResults result;
        const btScalar d = btGjkEpaSolver2::SignedDistance(worldPoint, 0, shape, frame * bodyInRigid(b), result);
        if (d < nearest) {
            nearest = d;
            best = b;
        }
    }
    return best;
}

bool Ragdoll::atRest() const { return m_multibody ? m_multibody->atRest() : m_action->atRest; }
double Ragdoll::activeSeconds() const { return m_multibody ? m_multibody->activeSeconds() : m_action->activeTime; }

void Ragdoll::putToRest() {
    if (m_multibody) return m_multibody->putToRest();
    for (const auto& b : m_bodies) {
        b->setLinearVelocity(btVector3(0, 0, 0));
        b->setAngularVelocity(btVector3(0, 0, 0));
        b->forceActivationState(ISLAND_SLEEPING);
    }
    m_action->atRest = true;
    if (m_manager) freezeBodies();
}

// A resting ragdoll of a RagdollWorld costs (almost) nothing per step: its constraints leave the world and its
// bodies become static objects in the StaticFilter group that test no pairs against static objects (so neither
// against the ground nor each other nor other resting ragdolls), until the world sees a contact with an active
// body (RagdollWorld) or the ragdoll is woken. Bullet's own sleeping leaves every sleeping body and constraint in
// its per-step loops, its island sort, and its pairs with the ground (docs/performance.md).
void Ragdoll::freezeBodies() {
    if (m_frozen) return;
    m_frozen = true;
    m_frozenContact = {};
    btDispatcher* dispatcher = m_world.getDispatcher();
    for (int k = 0; k < dispatcher->getNumManifolds(); ++k) {
        const btPersistentManifold* m = dispatcher->getManifoldByIndexInternal(k);
        const bool ours = std::any_of(m_bodies.begin(), m_bodies.end(),
                                      [&](const auto& b) { return b == m->getBody0() || b == m->getBody1(); });
        for (int c = 0; ours && c < m->getNumContacts(); ++c) {
            const double depth = -static_cast<double>(m->getContactPoint(c).getDistance());
            if (depth > m_frozenContact.depthM) m_frozenContact = {depth, m->getBody0(), m->getBody1()};
        }
    }
    for (auto it = m_constraints.rbegin(); it != m_constraints.rend(); ++it) m_world.removeConstraint(*it);
    for (std::size_t i = 0; i < m_bodies.size(); ++i) {
        btRigidBody& b = *m_bodies[i];
        m_world.removeRigidBody(&b);
        b.setMassProps(0, btVector3(0, 0, 0)); // sets CF_STATIC_OBJECT
        b.updateInertiaTensor();
        m_world.addRigidBody(&b, btBroadphaseProxy::StaticFilter, m_masks[i] & ~btBroadphaseProxy::StaticFilter);
    }
}

// Margin round the bodies' bounding boxes of the sunk ragdoll's box (metres): more than the wake distance of a
// frozen ragdoll's contacts (RagdollWorld), so that an active object comes back to the bodies before it can touch.
constexpr btScalar kRestProxyMarginM = btScalar(0.05);

void Ragdoll::sink() {
    if (!m_frozen || m_restProxy || m_multibody) return;
    btVector3 lo(BT_LARGE_FLOAT, BT_LARGE_FLOAT, BT_LARGE_FLOAT), hi = -lo;
    int mask = 0;
    for (std::size_t i = 0; i < m_bodies.size(); ++i) {
        btVector3 a, b;
        m_bodies[i]->getCollisionShape()->getAabb(m_bodies[i]->getWorldTransform(), a, b);
        lo.setMin(a);
        hi.setMax(b);
        mask |= m_masks[i];
    }
    const btVector3 margin(kRestProxyMarginM, kRestProxyMarginM, kRestProxyMarginM);
    lo -= margin;
    hi += margin;
    m_restProxyShape = std::make_unique<btBoxShape>((hi - lo) * btScalar(0.5));
    m_restProxy = std::make_unique<btCollisionObject>();
    m_restProxy->setCollisionShape(m_restProxyShape.get());
    m_restProxy->setWorldTransform(btTransform(btQuaternion::getIdentity(), (lo + hi) * btScalar(0.5)));
    m_restProxy->setCollisionFlags(btCollisionObject::CF_STATIC_OBJECT | btCollisionObject::CF_NO_CONTACT_RESPONSE);
    m_restProxy->setUserPointer(this);
    // Asleep, as Bullet makes a static rigid body: the world then skips its AABB (it never moves) like a sleeping
    // body's; an active object meeting it still gets a manifold (wakeTouched).
    m_restProxy->setActivationState(ISLAND_SLEEPING);
    for (auto it = m_bodies.rbegin(); it != m_bodies.rend(); ++it) m_world.removeRigidBody(*it);
    m_world.addCollisionObject(m_restProxy.get(), btBroadphaseProxy::StaticFilter,
                               mask & ~btBroadphaseProxy::StaticFilter);
}

void Ragdoll::surface() {
    if (!m_restProxy) return;
    m_world.removeCollisionObject(m_restProxy.get());
    if (m_manager) detail::RagdollWorldLink::forget(*m_manager, m_restProxy.get());
    m_restProxy.reset();
    m_restProxyShape.reset();
    for (std::size_t i = 0; i < m_bodies.size(); ++i)
        m_world.addRigidBody(m_bodies[i], btBroadphaseProxy::StaticFilter,
                             m_masks[i] & ~btBroadphaseProxy::StaticFilter);
}

void Ragdoll::thawBodies() {
    if (!m_frozen) return;
    surface();
    m_frozen = false;
    for (std::size_t i = 0; i < m_bodies.size(); ++i) {
        btRigidBody& b = *m_bodies[i];
        const RigidLayout::Rigid& r = m_layout->rigids[i];
        m_world.removeRigidBody(&b);
        b.setMassProps(static_cast<btScalar>(r.massKg), toBt(r.inertiaKgM2));
        b.updateInertiaTensor();
        if (!m_keyframes.modes.empty()) applyRigidMode(i); // a keyframed rigid is kinematic again
        m_world.addRigidBody(&b, m_group, m_masks[i]);
        b.setSleepingThresholds(0, 0);
    }
    for (std::size_t k = 0; k < m_constraints.size(); ++k)
        if (m_roles[k] != RowRole::Motor || static_cast<JointMotorConstraint*>(m_constraints[k])->active())
            m_world.addConstraint(m_constraints[k]); // a motor switched off stays out (applyMotorGains)
}

void Ragdoll::wake() {
    if (m_multibody) return m_multibody->wake();
    m_action->wake();
}

bool Ragdoll::checkGuard() {
    if (!m_action->guard.enabled || m_action->atRest) return false;
    const auto trip = m_action->check();
    if (!trip) return false;
    m_action->restore(m_world);
    m_action->report(*trip);
    return true;
}

void Ragdoll::freeze() { m_action->restore(m_world); }

void Ragdoll::rememberGoodState() { m_action->remember(); }

// Frozen, the constraints are out of the world already and the bodies are in it as static objects; sunk, they are
// brought back first.
void Ragdoll::removeBulletObjects() {
    surface();
    if (!m_frozen)
        for (auto it = m_constraints.rbegin(); it != m_constraints.rend(); ++it) m_world.removeConstraint(*it);
    for (auto it = m_bodies.rbegin(); it != m_bodies.rend(); ++it) m_world.removeRigidBody(*it);
    m_frozen = false;
    m_calmSubsteps = 0;
    m_action->frictions.clear();
    m_constraints.clear();
    m_roles.clear();
    m_main.clear();
    m_motors.clear();
    m_frames.clear();
    m_rigidFrames.clear();
    m_feedback.clear();
    m_bodies.clear();
    m_masks.clear();
    m_arena->clear(); // after the lists of its objects: the objects themselves
}

int Ragdoll::guardTrips() const { return m_action->trips; }

const std::optional<GuardTrip>& Ragdoll::lastGuardTrip() const { return m_action->lastTrip; }

std::string_view toString(GuardTrip::Cause cause) {
    switch (cause) {
    case GuardTrip::Cause::NonFinite: return "non-finite";
    case GuardTrip::Cause::Speed: return "speed";
    case GuardTrip::Cause::AnchorError: return "anchor-error";
    }
    return "?";
}

Ragdoll::~Ragdoll() {
    if (m_manager) detail::RagdollWorldLink::detach(*m_manager, *this);
    surface();               // its bodies back in the world, to be removed with the rest
    if (m_multibody) return; // its destructor removes its trees, colliders and constraints
    m_world.removeAction(m_action.get());
    for (auto it = m_constraints.rbegin(); it != m_constraints.rend(); ++it) m_world.removeConstraint(*it);
    for (auto it = m_bodies.rbegin(); it != m_bodies.rend(); ++it) m_world.removeRigidBody(*it);
}

} // namespace afb::bullet
