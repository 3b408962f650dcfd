// Spawning a figure into a Bullet world: docs/format.md §4 (constraint mapping), §4.7 (springs), §4.8 (friction),
// §6.2 (collision filtering).
#include "afb/bullet/Ragdoll.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <BulletCollision/NarrowPhaseCollision/btGjkEpa2.h>

#include "EngineFriction.h"
#include "Multibody.h"
#include "ObjectArena.h"
#include "RagdollWorldLink.h"
#include "afb/detail/Constraints.h"
#include "afb/detail/Convert.h"
#include "afb/figure/Collision.h"

namespace afb::bullet {

using figure::FigureConstraint;
using figure::JointType;

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
        if (m_comeToRest && restNow(dt)) m_owner.putToRest();
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
                if (fc.type == JointType::Spring || m_owner.m_layout->internal[static_cast<std::size_t>(c)]) continue;
                if (fc.type == JointType::Slider) gap = m_owner.jointError(c).anchorM;
                else {
                    const auto [frame1, frame2] = m_owner.constraintFramesWorld(c);
                    gap = (frame1.getOrigin() - frame2.getOrigin()).length();
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
bool Ragdoll::bulletConstraintIsLimit(int k) const {
    requireRigid("bulletConstraintIsLimit");
    return m_limitRows[static_cast<std::size_t>(k)];
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
        m_world.addRigidBody(&b, m_group, m_masks[i]);
        b.setSleepingThresholds(0, 0);
    }
    for (btTypedConstraint* constraint : m_constraints) m_world.addConstraint(constraint);
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
    m_limitRows.clear();
    m_main.clear();
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

namespace {

// A btRigidBody whose list of bodies it does not collide with (btCollisionObject::setIgnoreCollisionCheck) can be
// sized before it is filled: filterPairs adds up to a dozen entries per body, each growing the array otherwise.
class FigureRigidBody : public btRigidBody {
  public:
    using btRigidBody::btRigidBody;
    void reserveIgnored(int count) { m_objectsWithoutCollisionCheck.reserve(count); }
};

thread_local std::vector<int> t_ignoredCount; // filterPairs' scratch

} // namespace

void Ragdoll::addBodies() {
    const figure::Figure& f = figure();
    m_bodies.reserve(m_layout->rigids.size());
    m_masks.reserve(m_layout->rigids.size());
    for (const RigidLayout::Rigid& r : m_layout->rigids) {
        // A merged rigid takes its heaviest body's surface and damping (the engine gives one body one value).
        const figure::FigureBody& b = f.bodies[static_cast<std::size_t>(r.representative)];
        btRigidBody::btRigidBodyConstructionInfo info(static_cast<btScalar>(r.massKg), nullptr, r.shape,
                                                      toBt(r.inertiaKgM2));
        info.m_startWorldTransform = m_lodLayout ? toBt(r.loadPose) : m_spawn * toBt(r.loadPose); // see loadPose
        info.m_friction = static_cast<btScalar>(b.contactFriction);
        info.m_restitution = static_cast<btScalar>(kBodyRestitution);
        info.m_linearDamping = static_cast<btScalar>(b.linearDamping);
        info.m_angularDamping = static_cast<btScalar>(b.angularDamping);
        FigureRigidBody* body = m_arena->make<FigureRigidBody>(info);
        body->setSleepingThresholds(0, 0); // rest is decided by the figure's own rules (§6.1), not Bullet's
        if (m_method.ccd == CcdPolicy::FastBodies) {
            // A body that moves more than its inner radius in a step is swept as a sphere of that radius, so a
            // fast thin limb cannot pass into or through the ground between two steps.
            const btScalar radius = static_cast<btScalar>(r.innerRadius);
            body->setCcdMotionThreshold(radius);
            body->setCcdSweptSphereRadius(radius);
        }
        int mask = m_spawnMask;
        bool tests = false;
        for (const int i : r.bodies) {
            if (figure::attachedToWorld(f, i)) mask &= ~btBroadphaseProxy::StaticFilter;
            tests = tests || f.bodies[static_cast<std::size_t>(i)].clipMask != 0;
        }
        if (!tests) mask = 0; // §6.2: a body with clipMask 0 does no collision tests
        if (m_engineFriction) {
            body->setUserIndex2(kEngineFrictionMarker);
            body->setCollisionFlags(body->getCollisionFlags() | btCollisionObject::CF_CUSTOM_MATERIAL_CALLBACK);
        }
        m_world.addRigidBody(body, m_group, mask);
        m_bodies.push_back(body);
        m_masks.push_back(mask);
    }
}

btRigidBody& Ragdoll::other(int body2) const {
    return body2 >= 0 ? *m_bodies[static_cast<std::size_t>(rigidIndexOf(body2))] : btTypedConstraint::getFixedBody();
}

// Body2's frame: body-local, or world for a world constraint (model space moved by the spawn transform).
btTransform Ragdoll::frameOfBody2(const FigureConstraint& c) const {
    return c.body2 >= 0 ? toBt(c.frameInBody2) : m_spawn * toBt(c.frameInBody2);
}

std::pair<btTransform, btTransform> Ragdoll::constraintFramesWorld(int i) const {
    if (m_multibody) return m_multibody->constraintFramesWorld(i);
    const figure::FigureConstraint& c = figure().constraints[static_cast<std::size_t>(i)];
    const auto& rigidFrames = m_rigidFrames[static_cast<std::size_t>(i)];
    const btTransform a = body(c.body1).getCenterOfMassTransform() * rigidFrames.first;
    const btTransform b =
        c.body2 >= 0 ? body(c.body2).getCenterOfMassTransform() * rigidFrames.second : rigidFrames.second;
    return {a, b};
}

void Ragdoll::addConstraints() {
    const figure::Figure& f = figure();
    detail::ObjectArena& arena = *m_arena;
    const int iterations = m_method.jointIterations;
    const LimitRowPolicy policy{static_cast<btScalar>(m_method.limitErp), m_method.speculativeLimits};
    // At most a main constraint, its friction and a limit per joint.
    m_frames.reserve(f.constraints.size());
    m_rigidFrames.reserve(f.constraints.size());
    m_main.reserve(f.constraints.size());
    m_constraints.reserve(3 * f.constraints.size());
    m_limitRows.reserve(3 * f.constraints.size());
    const btScalar lever = static_cast<btScalar>(f.units.metresPerUnit);
    for (std::size_t ci = 0; ci < f.constraints.size(); ++ci) {
        const FigureConstraint& c = f.constraints[ci];
        btRigidBody& a = body(c.body1);
        btRigidBody& b = other(c.body2);
        m_frames.emplace_back(toBt(c.frameInBody1), frameOfBody2(c));
        // The frames in the rigid bodies' frames (a merged body sits at an offset in its rigid).
        const btTransform& offsetA = bodyInRigid(c.body1);
        const btTransform fa = offsetA * m_frames.back().first;
        const btTransform fb = c.body2 >= 0 ? bodyInRigid(c.body2) * m_frames.back().second : m_frames.back().second;
        m_rigidFrames.emplace_back(fa, fb);
        if (m_layout->internal[ci]) { // both bodies in one rigid: the joint holds by construction
            m_main.push_back(nullptr);
            continue;
        }
        // Directions fixed in body1 and in body2 as Bullet sees the rigid bodies' frames (world for the world).
        const btMatrix3x3& b1Rot = offsetA.getBasis();
        const btMatrix3x3 b2Rot = c.body2 >= 0 ? bodyInRigid(c.body2).getBasis() : m_spawn.getBasis();
        btTypedConstraint* main = nullptr;
        btTypedConstraint* limit = nullptr;
        btMatrix3x3 frictionAxes = fb.getBasis();
        int frictionRows = 0;

        switch (c.type) {
        case JointType::Fixed: main = arena.make<btFixedConstraint>(a, b, fa, fb); break;
        case JointType::BallAndSocket:
            frictionAxes = btMatrix3x3::getIdentity() * b2Rot;
            frictionRows = 3;
            if (const auto* cone = std::get_if<figure::ConeLimit>(&c.limit)) {
                // btConeTwistConstraint: twist about X is free (span < 0), swing keeps the X axes within the
                // half-angle: frame B's X is the cone axis (body2), frame A's X the shaft (body1), and frame A
                // is frame B turned along the shortest arc, so the twist starts at 0.
                const btVector3 axisB = b2Rot * toBt(cone->axisInBody2);
                const btVector3 shaftA = b1Rot * toBt(cone->shaftInBody1);
                const btMatrix3x3 frameBRot = basisWithX(axisB);
                const btTransform bWorld = b.getCenterOfMassTransform();
                const btTransform aWorld = a.getCenterOfMassTransform();
                const btVector3 axisW = bWorld.getBasis() * axisB, shaftW = aWorld.getBasis() * shaftA;
                const btMatrix3x3 frameAWorld = shortestArc(axisW, shaftW) * (bWorld.getBasis() * frameBRot);
                const btTransform frameA(aWorld.getBasis().transpose() * frameAWorld, fa.getOrigin());
                const btTransform frameB(frameBRot, fb.getOrigin());
                const btScalar h = static_cast<btScalar>(cone->halfAngleRad);
                if (policy.speculative) {
                    // Our own cone row (speculative); the anchor alone is a point-to-point.
                    main = arena.make<btPoint2PointConstraint>(a, b, fa.getOrigin(), fb.getOrigin());
                    limit = arena.make<DirectionLimitConstraint>(a, b, shaftA, frameBRot, LimitShape::Cone, h,
                                                                 btScalar(0), policy);
                } else {
                    auto* ct = arena.make<btConeTwistConstraint>(a, b, frameA, frameB);
                    ct->setLimit(h, h, btScalar(-1), btScalar(1), policy.errorReduction, btScalar(1));
                    main = ct;
                }
            } else {
                main = arena.make<btPoint2PointConstraint>(a, b, fa.getOrigin(), fb.getOrigin());
            }
            break;
        case JointType::Universal: {
            // No relative spin about the shafts (homokinetic, §4.4), swing free: our constant-velocity constraint
            // (Method::constantVelocityUniversal), or cone-twist with twist locked; frames' X axes are shaft 1
            // (body1) and −shaft 2 (body2), aligned at the load pose.
            if (m_method.constantVelocityUniversal) main = arena.make<UniversalConstraint>(a, b, fa, fb);
            else {
                auto* ct = arena.make<btConeTwistConstraint>(a, b, fa, fb);
                ct->setLimit(SIMD_PI, SIMD_PI, 0);
                main = ct;
            }
            frictionRows = 2;
            frictionAxes.setValue(fb.getBasis()[0][1], fb.getBasis()[0][2], 0, fb.getBasis()[1][1], fb.getBasis()[1][2],
                                  0, fb.getBasis()[2][1], fb.getBasis()[2][2], 0);
            break;
        }
        case JointType::Hinge: {
            auto* h = arena.make<btHingeConstraint>(a, b, fa, fb, false);
            if (const auto* range = std::get_if<figure::HingeRange>(&c.limit)) {
                const btScalar lo = static_cast<btScalar>(range->lowerRad), hi = static_cast<btScalar>(range->upperRad);
                if (policy.speculative) limit = arena.make<HingeRangeConstraint>(a, b, fa, fb, lo, hi, policy);
                else h->setLimit(lo, hi, 1, policy.errorReduction, 1);
            }
            main = h;
            frictionRows = 1;
            frictionAxes.setValue(fb.getBasis()[0][2], 0, 0, fb.getBasis()[1][2], 0, 0, fb.getBasis()[2][2], 0, 0);
            break;
        }
        case JointType::Slider: main = arena.adopt(makeSlider(a, b, fa, fb)); break;
        case JointType::Spring: {
            const SpringConstraint::Params p = SpringConstraint::Params::of(c.spring);
            main = arena.make<SpringConstraint>(a, b, fa.getOrigin(), fb.getOrigin(), p);
            break;
        }
        }

        // Pyramid limits (ball) and every universal limit: our direction-limit rows.
        if (c.type == JointType::Universal || c.type == JointType::BallAndSocket) {
            if (const auto* p = std::get_if<figure::PyramidLimit>(&c.limit))
                limit = arena.make<DirectionLimitConstraint>(a, b, b1Rot * toBt(p->shaftInBody1),
                                                             b2Rot * toBt(p->basisInBody2),
                                                             DirectionLimitConstraint::Shape::Pyramid,
                                                             static_cast<btScalar>(p->halfAngle1Rad),
                                                             static_cast<btScalar>(p->halfAngle2Rad), policy);
            const auto* cone = std::get_if<figure::ConeLimit>(&c.limit);
            if (cone && c.type == JointType::Universal)
                limit = arena.make<DirectionLimitConstraint>(a, b, b1Rot * toBt(cone->shaftInBody1),
                                                             basisWithX(b2Rot * toBt(cone->axisInBody2)),
                                                             DirectionLimitConstraint::Shape::Cone,
                                                             static_cast<btScalar>(cone->halfAngleRad), btScalar(0),
                                                             policy);
        }

        m_main.push_back(main);
        if (iterations > 0) {
            if (main) main->setOverrideNumSolverIterations(iterations);
            if (limit) limit->setOverrideNumSolverIterations(iterations);
        }
        if (main) {
            // Collision between the joint's bodies is off through filterPairs (RigidLayout::ignoredPairs has every
            // pair a joint disables, §6.2), not through Bullet's constraint references, which would add the same
            // entry to each body's list again, with a linear search per constraint and body, at every spawn.
            m_world.addConstraint(main);
            if (c.friction > 0 && frictionRows > 0) {
                auto* fb2 = arena.make<btJointFeedback>();
                main->setJointFeedback(fb2);
                auto* fr = arena.make<JointFrictionConstraint>(a, b, frictionAxes, frictionRows);
                m_action->frictions.push_back({fr, fb2, static_cast<btScalar>(c.friction) * lever});
                m_feedback.push_back(fb2);
                m_constraints.push_back(main);
                m_world.addConstraint(fr);
                m_constraints.push_back(fr);
            } else {
                m_constraints.push_back(main);
            }
        }
        m_limitRows.resize(m_constraints.size(), false);
        if (limit) {
            m_world.addConstraint(limit);
            m_constraints.push_back(limit);
            m_limitRows.push_back(true);
        }
    }
}

// §6.2: every pair of the ragdoll's bodies that does not test contact (RigidLayout::ignoredPairs, computed once per
// figure): the pairs the figure's rules keep apart, those a joint disables among them (Bullet's own constraint
// references are not used for it, see addConstraints), the pairs its joints keep apart anyway
// (RagdollAsset::prunedPairs), and under Method::exemptOverlapping the pairs that overlap at the load pose.
void Ragdoll::filterPairs() {
    const std::vector<std::pair<int, int>>& ignored =
        m_method.exemptOverlapping ? m_layout->ignoredPairsApart : m_layout->ignoredPairs;
    std::vector<int>& count = t_ignoredCount;
    count.assign(m_bodies.size(), 0);
    for (const auto& [i, j] : ignored) {
        ++count[static_cast<std::size_t>(i)];
        ++count[static_cast<std::size_t>(j)];
    }
    for (std::size_t i = 0; i < m_bodies.size(); ++i)
        static_cast<FigureRigidBody&>(*m_bodies[i]).reserveIgnored(count[i]);
    for (const auto& [i, j] : ignored) {
        btRigidBody& a = *m_bodies[static_cast<std::size_t>(i)];
        btRigidBody& b = *m_bodies[static_cast<std::size_t>(j)];
        a.setIgnoreCollisionCheck(&b, true);
        b.setIgnoreCollisionCheck(&a, true);
    }
}

} // namespace afb::bullet
