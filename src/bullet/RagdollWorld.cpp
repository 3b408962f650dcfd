// The world-level half of a method: solver settings, the engine's contact friction guard, the position pass.
#include "afb/bullet/RagdollWorld.h"

#include <algorithm>
#include <atomic>
#include <mutex>

#include <BulletDynamics/Featherstone/btMultiBodyConstraintSolver.h>
#include <BulletDynamics/Featherstone/btMultiBodyDynamicsWorld.h>

#include "BoxBoxCollision.h"
#include "CompoundCollision.h"
#include "EngineFriction.h"
#include "HullPlaneCollision.h"
#include "PositionPass.h"
#include "RagdollWorldLink.h"
#include "SeparatedPairs.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/bullet/RagdollSolver.h"
#include "afb/detail/Constraints.h"
#include "afb/detail/Convert.h"

namespace afb::bullet {
namespace {

bool isEngineFrictionBody(const btCollisionObject* o) {
    return o->getUserIndex2() == kEngineFrictionMarker || o->getUserIndex2() == kSpeculativeFrictionMarker;
}
bool isSpeculativeBody(const btCollisionObject* o) { return o->getUserIndex2() == kSpeculativeFrictionMarker; }

// docs/format.md §4.8: min(f1, f2) between two ragdoll bodies, the ragdoll body's own value against anything else.
bool engineContactFriction(btManifoldPoint& cp, const btCollisionObjectWrapper* w0, int, int,
                           const btCollisionObjectWrapper* w1, int, int) {
    const btCollisionObject* a = w0->getCollisionObject();
    const btCollisionObject* b = w1->getCollisionObject();
    const bool ra = isEngineFrictionBody(a), rb = isEngineFrictionBody(b);
    if (ra && rb) cp.m_combinedFriction = btMin(a->getFriction(), b->getFriction());
    else if (ra) cp.m_combinedFriction = a->getFriction();
    else if (rb) cp.m_combinedFriction = b->getFriction();
    // A speculative contact (not touching yet) must not bounce: restitution is for the impact itself.
    if ((isSpeculativeBody(a) || isSpeculativeBody(b)) && cp.getDistance() > 0) cp.m_combinedRestitution = 0;
    return true;
}

// A contact point this close (metres; a speculative contact stops an approaching body at about 0) wakes a frozen
// ragdoll.
constexpr double kWakeDistanceM = 0.01;
// Substeps a frozen ragdoll stays in the world with nothing active near before it sinks (Ragdoll::sunk): half a
// second at 60 Hz, so that an object passing by does not make it go in and out of the world every substep.
constexpr int kSinkAfterSubsteps = 30;

// The farthest a speculative contact reaches, metres: beyond it, continuous collision takes over.
constexpr double kMaxSpeculativeM = 0.5;
// How far a body can come within a step: its speed (centre plus spin at its bounding radius) times the step, with a
// 25 % allowance for the acceleration within the step.
constexpr btScalar kReachAllowance = btScalar(1.25);
// The least gravity the self-contact cap (Method::selfContactCap) scales with, m/s².
constexpr btScalar kStandardGravityMps2 = btScalar(9.81);

// The one write of the process-wide callback (EngineContactFriction::install): done once, never undone.
std::once_flag gFrictionOnce;
std::atomic<bool> gFrictionInstalled{false};

} // namespace

EngineContactFriction::EngineContactFriction() : m_active(install()) {}

bool EngineContactFriction::install() {
    std::call_once(gFrictionOnce, [] {
        if (gContactAddedCallback != nullptr) return; // the game's own callback stays
        gContactAddedCallback = &engineContactFriction;
        gFrictionInstalled.store(true, std::memory_order_release);
    });
    return installed();
}

bool EngineContactFriction::installed() {
    // The flag's acquire orders this read after the one write; a game that replaced the callback since is seen.
    return gFrictionInstalled.load(std::memory_order_acquire) && gContactAddedCallback == &engineContactFriction;
}

WorldParts makeWorld(const Method& method, btDispatcher& dispatcher, btBroadphaseInterface& broadphase,
                     btCollisionConfiguration& configuration) {
    WorldParts parts;
    if (method.backend == Backend::Multibody) {
        auto solver = std::make_unique<btMultiBodyConstraintSolver>();
        parts.world =
            std::make_unique<btMultiBodyDynamicsWorld>(&dispatcher, &broadphase, solver.get(), &configuration);
        parts.solver = std::move(solver);
    } else {
        parts.solver = std::make_unique<RagdollSolver>();
        parts.world =
            std::make_unique<btDiscreteDynamicsWorld>(&dispatcher, &broadphase, parts.solver.get(), &configuration);
    }
    return parts;
}

void applyWorldKnobs(btDynamicsWorld& world, const Method& m) {
    btContactSolverInfo& info = world.getSolverInfo();
    info.m_numIterations = m.iterations;
    info.m_leastSquaresResidualThreshold = static_cast<btScalar>(m.solverTolerance);
    info.m_splitImpulse = m.splitImpulse ? 1 : 0;
    info.m_erp2 = static_cast<btScalar>(m.contactErp);
    info.m_erp = static_cast<btScalar>(m.jointErp);
    info.m_warmstartingFactor = static_cast<btScalar>(m.warmStartingFactor);
    info.m_articulatedWarmstartingFactor = static_cast<btScalar>(m.warmStartingFactor);
    // Bullet's multibody solver warm-starts its rows only under its own flag (and starts every multibody contact
    // from zero otherwise: a figure standing on its feet then sinks while 20 iterations rebuild its weight).
    if (m.warmStarting) info.m_solverMode |= SOLVER_USE_WARMSTARTING | SOLVER_USE_ARTICULATED_WARMSTARTING;
    else info.m_solverMode &= ~(SOLVER_USE_WARMSTARTING | SOLVER_USE_ARTICULATED_WARMSTARTING);
    if (m.frictionDirections >= 2) info.m_solverMode |= SOLVER_USE_2_FRICTION_DIRECTIONS;
    else info.m_solverMode &= ~SOLVER_USE_2_FRICTION_DIRECTIONS;
    if (auto* solver = dynamic_cast<RagdollSolver*>(world.getConstraintSolver())) {
        solver->setDirectJoints(m.directJoints);
        solver->setFigureBlock(m.directJoints ? m.figureIterations : 0, m.figureSweeps);
        solver->setFrictionThroughGroups(m.frictionThroughFigure);
        solver->setJointSpace(m.jointSpace);
    }
    // The direct solve takes a batch of islands (Bullet batches small islands up to m_minimumSolverBatchSize
    // constraints) through its own path when a ragdoll is in it and through Bullet's otherwise, and the two round
    // differently: a game's box alone in its island then moved by 10⁻⁸ m differently when a ragdoll elsewhere
    // froze. One island per solve keeps every island's result independent of the others (docs/methods.md).
    if (m.directJoints) info.m_minimumSolverBatchSize = 1;
    // Bullet's defaults are (1, 0) for convex–plane and (0, 3) for convex–convex: no perturbed points.
    if (auto* dispatcher = dynamic_cast<btCollisionDispatcher*>(world.getDispatcher()))
        if (auto* config = dynamic_cast<btDefaultCollisionConfiguration*>(dispatcher->getCollisionConfiguration())) {
            // Convex–convex pairs (bodies on bodies) keep Bullet's default: perturbing GJK three more times
            // per pair tripled the collision cost of a ragdoll and did not change its accuracy.
            if (m.multipointContacts) config->setPlaneConvexMultipointIterations(3, 3);
            else config->setPlaneConvexMultipointIterations(1, 0);
            // Hulls against planes: every vertex within reach (a body on an edge knows its far corners).
            detail::useVertexHullPlaneContacts(*dispatcher, m.multipointContacts, *config);
            // Boxes against boxes: speculative points while apart (Bullet's detector reports overlap only).
            detail::useSpeculativeBoxBoxContacts(*dispatcher, m.speculativeContacts, *config);
            // Convex pairs plainly apart skip GJK: the same contacts, found cheaper.
            detail::useSeparatedPairSkip(*dispatcher, m.separatedPairs, *config, m.speculativeContacts);
        }
}

// After each substep's integration (Bullet runs actions then), the position pass over every ragdoll.
class RagdollWorld::PositionAction : public btActionInterface {
  public:
    explicit PositionAction(RagdollWorld& owner) : m_owner(owner) {}

    void updateAction(btCollisionWorld* world, btScalar dt) override {
        if (m_owner.m_ragdolls.empty()) return;
        // Keyframed bodies move with the simulated ones (Bullet does not integrate kinematic bodies), before the
        // position pass measures the joints between them.
        for (Ragdoll* r : m_owner.m_ragdolls) detail::RagdollWorldLink::advanceKeyframes(*r, dt);
        wakeTouched(world);
        const int iterations = m_owner.m_method.positionIterations;
        if (iterations > 0 || m_owner.m_method.positionTree > 0) positionPass(world, iterations, dt);
        if (m_owner.m_method.speculativeContacts) {
            publishMultibodyVelocities();
            widenContacts(world, dt);
        }
    }

    // A multibody ragdoll publishes its bodies' velocities on their colliders after its own substep work, which
    // Bullet runs after this action (actions run in the order added): published here too, so the reach is this
    // substep's.
    void publishMultibodyVelocities() {
        for (Ragdoll* r : m_owner.m_ragdolls) {
            if (r->backend() != Backend::Multibody || r->atRest()) continue;
            const std::vector<figure::BodyState> states = r->bodyStates();
            for (int i = 0; i < r->bodyCount(); ++i) {
                btCollisionObject& o = r->collisionObject(i);
                o.setInterpolationLinearVelocity(toBt(states[static_cast<std::size_t>(i)].linearVelocity));
                o.setInterpolationAngularVelocity(toBt(states[static_cast<std::size_t>(i)].angularVelocity));
            }
        }
    }

    // A frozen ragdoll (Ragdoll::frozen) wakes when an active object moving faster than the figure's rest speed
    // touches one of its bodies: a contact point within kWakeDistanceM. Woken after the pass over the manifolds, since
    // waking re-adds its bodies.
    void wakeTouched(btCollisionWorld* world) {
        m_toWake.clear();
        m_toSurface.clear();
        m_near.assign(m_owner.m_ragdolls.size(), 0);
        btDispatcher* dispatcher = world->getDispatcher();
        btPersistentManifold** manifolds = dispatcher->getInternalManifoldPointer();
        for (int i = 0, n = dispatcher->getNumManifolds(); i < n; ++i) {
            const btPersistentManifold* m = manifolds[i];
            for (const auto& [resting, toucher] :
                 {std::pair{m->getBody0(), m->getBody1()}, {m->getBody1(), m->getBody0()}}) {
                if (!toucher->isActive() || !resting->isStaticObject()) continue;
                // A sunk ragdoll's box met by an active object: its bodies come back (frozen).
                if (Ragdoll* sunk = sunkOwner(resting)) {
                    m_toSurface.push_back(sunk);
                    continue;
                }
                const int r = owner(resting);
                if (r < 0 || !m_owner.m_ragdolls[static_cast<std::size_t>(r)]->frozen()) continue;
                m_near[static_cast<std::size_t>(r)] = 1; // an active object's box overlaps one of its bodies'
                if (m->getNumContacts() == 0) continue;
                // A toucher slower than the frozen figure's own rest speed does not wake it (two ragdolls coming to
                // rest against each other would wake each other in turn forever).
                if (const btRigidBody* b = btRigidBody::upcast(toucher);
                    b && b->getLinearVelocity().length() <
                             m_owner.m_ragdolls[static_cast<std::size_t>(r)]->figure().rest.linearSpeedMps)
                    continue;
                bool touching = false;
                for (int c = 0; c < m->getNumContacts(); ++c)
                    touching = touching || m->getContactPoint(c).getDistance() <= btScalar(kWakeDistanceM);
                if (touching) m_toWake.push_back(r);
            }
        }
        for (const int r : m_toWake)
            if (m_owner.m_ragdolls[static_cast<std::size_t>(r)]->frozen())
                m_owner.m_ragdolls[static_cast<std::size_t>(r)]->wake();
        for (Ragdoll* r : m_toSurface) {
            r->surface();
            detail::RagdollWorldLink::calmSubsteps(*r) = 0;
        }
        // A frozen ragdoll with nothing active near it for kSinkAfterSubsteps substeps sinks (Ragdoll::sunk).
        for (std::size_t k = 0; k < m_owner.m_ragdolls.size(); ++k) {
            Ragdoll& r = *m_owner.m_ragdolls[k];
            if (!m_owner.m_sinking || !r.frozen() || r.sunk() || r.backend() != Backend::Rigid) continue;
            int& calm = detail::RagdollWorldLink::calmSubsteps(r);
            if (m_near[k]) calm = 0;
            else if (++calm >= kSinkAfterSubsteps) detail::RagdollWorldLink::sink(r);
        }
    }

    // The ragdoll whose sunk box `o` is, if it is one.
    Ragdoll* sunkOwner(const btCollisionObject* o) const {
        if (!(o->getCollisionFlags() & btCollisionObject::CF_NO_CONTACT_RESPONSE) || o->getUserPointer() == nullptr)
            return nullptr;
        for (const auto& r : m_owner.m_ragdolls)
            if (detail::RagdollWorldLink::sunkBox(*r) == o) return r;
        return nullptr;
    }

    // How a body moves, for the speculative reach: a ragdoll body's velocity (a multibody link's is on its
    // collider, refreshed in updateAction before widenContacts), its speed plus its angular speed times its
    // bounding radius (how fast any point of its surface can move), and its angular part alone.
    struct Motion {
        bool ragdoll = false, link = false;
        btVector3 velocity{0, 0, 0};
        btScalar speed = 0, spin = 0;
    };
    // Speculative contacts for the next substep: every manifold of a ragdoll body keeps (and finds) points up
    // to the distance its bodies can close in one substep at their current speeds, plus Bullet's own threshold.
    void widenContacts(btCollisionWorld* world, btScalar dt) {
        m_gravityDt = m_owner.m_world.getGravity().length() * dt;
        btDispatcher* dispatcher = world->getDispatcher();
        btPersistentManifold** manifolds = dispatcher->getInternalManifoldPointer();
        for (int i = 0, n = dispatcher->getNumManifolds(); i < n; ++i) {
            btPersistentManifold* m = manifolds[i];
            const Motion a = motionOf(m->getBody0()), b = motionOf(m->getBody1());
            if (!a.ragdoll && !b.ragdoll) continue;
            const btScalar reach = kReachAllowance * (a.speed + b.speed) * dt;
            if (reach <= 0) continue;
            const btScalar threshold = btMin(btScalar(kMaxSpeculativeM), gContactBreakingThreshold + reach);
            m->setContactBreakingThreshold(threshold);
            if (a.link || b.link) m->setContactProcessingThreshold(processingThreshold(*m, a, b, threshold, dt));
        }
    }
    // Each row of a multibody contact costs passes over the whole tree, so the solver gets a point above the
    // surface only when its bodies can close that distance in this substep: along the contact normals at their
    // velocities, plus what their spin and gravity can add (a body resting or sliding on the ground keeps its far
    // points in the manifold for later steps, but they cost nothing now). Measured on the humanoid: the same
    // penetration as solving every point within the speculative reach, for 20 % fewer instructions per step (and
    // as many as Bullet's own 2 cm threshold without speculative contacts). Rigid bodies' contacts are all solved
    // (a row is cheap there).
    btScalar processingThreshold(const btPersistentManifold& m, const Motion& a, const Motion& b, btScalar breaking,
                                 btScalar dt) {
        if (m.getNumContacts() == 0) return breaking; // points found next time: as far as they could come
        btScalar approach = 0;                        // m/s, along the normals (B towards A)
        for (int k = 0; k < m.getNumContacts(); ++k)
            approach = btMax(approach, -(a.velocity - b.velocity).dot(m.getContactPoint(k).m_normalWorldOnB));
        approach += a.spin + b.spin + m_gravityDt;
        return btMin(breaking, kReachAllowance * approach * dt);
    }
    Motion motionOf(const btCollisionObject* o) const {
        Motion out;
        const BodyOwner* owned = m_owner.ownerOf(o);
        if (owned == nullptr) return out;
        const btRigidBody* b = btRigidBody::upcast(o);
        out.ragdoll = true;
        out.link = b == nullptr;
        out.velocity = b ? b->getLinearVelocity() : o->getInterpolationLinearVelocity();
        const btVector3& w = b ? b->getAngularVelocity() : o->getInterpolationAngularVelocity();
        out.spin = w.length() * owned->boundingRadius;
        out.speed = out.velocity.length() + out.spin;
        return out;
    }

    void positionPass(btCollisionWorld* world, int iterations, btScalar dt) {
        // Contacts per ragdoll, in the dispatcher's order: one pass over the manifolds for all ragdolls.
        m_contacts.resize(m_owner.m_ragdolls.size());
        for (auto& list : m_contacts) list.clear();
        btDispatcher* dispatcher = world->getDispatcher();
        btPersistentManifold** manifolds = dispatcher->getInternalManifoldPointer();
        for (int i = 0, n = dispatcher->getNumManifolds(); i < n; ++i) {
            btPersistentManifold* m = manifolds[i];
            if (m->getNumContacts() == 0) continue;
            const int r0 = owner(m->getBody0()), r1 = owner(m->getBody1());
            if (r0 >= 0) m_contacts[static_cast<std::size_t>(r0)].push_back(m);
            if (r1 >= 0 && r1 != r0) m_contacts[static_cast<std::size_t>(r1)].push_back(m);
        }
        for (std::size_t k = 0; k < m_owner.m_ragdolls.size(); ++k) {
            Ragdoll& r = *m_owner.m_ragdolls[k];
            // A multibody ragdoll's tree joints hold by construction; the pass moves rigid bodies only.
            if (r.atRest() || r.backend() == Backend::Multibody) continue;
            detail::positionPass(r, iterations, m_owner.m_method.positionTree, m_contacts[k], dt,
                                 m_owner.m_method.positionVelocity);
        }
    }
    void debugDraw(btIDebugDraw*) override {}

  private:
    int owner(const btCollisionObject* o) const {
        const BodyOwner* owned = m_owner.ownerOf(o);
        return owned ? owned->ragdoll : -1;
    }

    RagdollWorld& m_owner;
    btScalar m_gravityDt = 0; ///< the speed gravity adds in a substep, m/s
    std::vector<std::vector<btPersistentManifold*>> m_contacts;
    std::vector<int> m_toWake;
    std::vector<Ragdoll*> m_toSurface;
    std::vector<char> m_near;
};

// The world's answers to the merged-body algorithm (detail::CompoundCollision): which compounds are merged ragdoll
// bodies, which of their children may touch what, and how far their contacts reach.
class RagdollWorld::MergedBodies : public detail::CompoundRules {
  public:
    MergedBodies(RagdollWorld& owner, btCollisionDispatcher& dispatcher)
        : m_owner(owner), m_collision(dispatcher, *dispatcher.getCollisionConfiguration(), *this) {}

    bool handles(const btCollisionObject& compound) const override {
        const BodyOwner* owned = m_owner.ownerOf(&compound);
        return owned != nullptr &&
               m_owner.m_ragdolls[static_cast<std::size_t>(owned->ragdoll)]->backend() == Backend::Rigid;
    }

    bool mayTouch(const btCollisionObject& compound, int child, const btCollisionObject& other,
                  int otherChild) const override {
        const BodyOwner* a = m_owner.ownerOf(&compound);
        const BodyOwner* b = m_owner.ownerOf(&other);
        if (a == nullptr || b == nullptr || a->ragdoll != b->ragdoll) return true;
        // Two rigid bodies of one ragdoll: as their figure bodies would, unmerged (RagdollAsset::contactPairs).
        const Ragdoll& r = *m_owner.m_ragdolls[static_cast<std::size_t>(a->ragdoll)];
        const std::vector<int>* bodiesA = bodiesOf(r, compound);
        const std::vector<int>* bodiesB = bodiesOf(r, other);
        if (bodiesA == nullptr || bodiesB == nullptr || child < 0 || child >= static_cast<int>(bodiesA->size()) ||
            otherChild >= static_cast<int>(bodiesB->size()))
            return true;
        const int i = (*bodiesA)[static_cast<std::size_t>(child)];
        const auto& pairs = r.asset()->contactPairs();
        const auto& overlapping = r.asset()->overlappingPairs();
        for (std::size_t k = 0; k < bodiesB->size(); ++k) {
            if (otherChild >= 0 && static_cast<int>(k) != otherChild) continue;
            const int j = (*bodiesB)[k];
            const std::pair pair(std::min(i, j), std::max(i, j));
            if (!std::binary_search(pairs.begin(), pairs.end(), pair)) continue;
            if (r.method().exemptOverlapping && std::binary_search(overlapping.begin(), overlapping.end(), pair))
                continue;
            return true;
        }
        return false;
    }

    btScalar breakingThreshold(const btCollisionObject& a, const btCollisionObject& b, btScalar dt) const override {
        return m_owner.breakingThreshold(&a, &b, dt);
    }

  private:
    // The figure bodies a rigid body of `r` carries (in its compound's child order), or null.
    static const std::vector<int>* bodiesOf(const Ragdoll& r, const btCollisionObject& o) {
        if (r.backend() != Backend::Rigid) return nullptr;
        for (int k = 0; k < r.rigidBodyCount(); ++k)
            if (&r.rigidBody(k) == &o) return &r.layout().rigids[static_cast<std::size_t>(k)].bodies;
        return nullptr;
    }

    RagdollWorld& m_owner;
    detail::CompoundCollision m_collision;
};

Method methodInForce(const Method& method, bool ragdollSolver) {
    if (!ragdollSolver && method.backend == Backend::Rigid && method.directJoints) return iterativeJoints(method);
    return method;
}

RagdollWorld::RagdollWorld(btDiscreteDynamicsWorld& world, const Method& method)
    : m_world(world),
      m_method(methodInForce(method, dynamic_cast<RagdollSolver*>(world.getConstraintSolver()) != nullptr)),
      m_action(std::make_unique<PositionAction>(*this)) {
    applyWorldKnobs(m_world, m_method);
    if (auto* solver = dynamic_cast<RagdollSolver*>(m_world.getConstraintSolver());
        solver && m_method.selfContactCap > 0)
        solver->setContactWarmStartCap([this](const btPersistentManifold& m, btScalar dt) {
            // Self-collision only: the game's contacts, and those between two ragdolls, keep Bullet's warm start.
            const BodyOwner* a = ownerOf(m.getBody0());
            const BodyOwner* b = ownerOf(m.getBody1());
            if (a == nullptr || b == nullptr || a->ragdoll != b->ragdoll) return btScalar(-1);
            const btRigidBody* ra = btRigidBody::upcast(m.getBody0());
            const btRigidBody* rb = btRigidBody::upcast(m.getBody1());
            if (ra == nullptr || rb == nullptr) return btScalar(-1);
            // At least standard gravity: in a weightless world the pair still carries what pushes it together
            // (a cap of 0 would cold-start every self-contact, and an arm pressed to the torso needs its warm start).
            const btScalar g = std::max(m_world.getGravity().length(), kStandardGravityMps2);
            const btScalar weight = (ra->getMass() + rb->getMass()) * g * dt;
            return static_cast<btScalar>(m_method.selfContactCap) * weight;
        });
    m_world.addAction(m_action.get());
    if (auto* dispatcher = dynamic_cast<btCollisionDispatcher*>(m_world.getDispatcher()))
        m_mergedBodies = std::make_unique<MergedBodies>(*this, *dispatcher);
}

RagdollWorld::~RagdollWorld() {
    if (auto* solver = dynamic_cast<RagdollSolver*>(m_world.getConstraintSolver())) solver->setContactWarmStartCap({});
    m_mergedBodies.reset();
    m_world.removeAction(m_action.get());
}

// Linear speed plus angular speed times the shape's bounding radius, with a 25 % allowance for the acceleration
// within the step.
btScalar RagdollWorld::reachOf(const btCollisionObject* o, btScalar dt) const {
    const BodyOwner* owned = ownerOf(o);
    if (owned == nullptr) return 0;
    // A multibody link's velocity is on its collider (MultibodyRagdoll::publishVelocities).
    const btRigidBody* b = btRigidBody::upcast(o);
    const btVector3& v = b ? b->getLinearVelocity() : o->getInterpolationLinearVelocity();
    const btVector3& w = b ? b->getAngularVelocity() : o->getInterpolationAngularVelocity();
    const btScalar speed = v.length() + w.length() * owned->boundingRadius;
    return kReachAllowance * speed * dt;
}

btScalar RagdollWorld::breakingThreshold(const btCollisionObject* a, const btCollisionObject* b, btScalar dt) const {
    if (!m_method.speculativeContacts) return gContactBreakingThreshold;
    return btMin(btScalar(kMaxSpeculativeM), gContactBreakingThreshold + reachOf(a, dt) + reachOf(b, dt));
}

namespace {
bool named(const std::vector<const btCollisionObject*>& objects, const btCollisionObject* o) {
    return !objects.empty() && std::find(objects.begin(), objects.end(), o) != objects.end();
}
} // namespace

int RagdollWorld::substepsFor(double dtSeconds) const {
    const int least = std::max(1, m_method.substeps);
    if (m_method.impactSubsteps <= least) return least;
    // How fast the last step's contacts between a ragdoll body and another object's dynamic body close, along
    // their normals (a speculative point of a pair about to meet counts: its manifold holds it already).
    btScalar closing = 0;
    btDispatcher& dispatcher = *m_world.getDispatcher();
    for (int i = 0, n = dispatcher.getNumManifolds(); i < n; ++i) {
        const btPersistentManifold& m = *dispatcher.getManifoldByIndexInternal(i);
        if (m.getNumContacts() == 0 || named(m_goneObjects, m.getBody0()) || named(m_goneObjects, m.getBody1()))
            continue;
        const btRigidBody* a = btRigidBody::upcast(m.getBody0());
        const btRigidBody* b = btRigidBody::upcast(m.getBody1());
        if (a == nullptr || b == nullptr || a->isStaticOrKinematicObject() || b->isStaticOrKinematicObject()) continue;
        const BodyOwner* ownerA = ownerOf(a);
        const BodyOwner* ownerB = ownerOf(b);
        if ((ownerA == nullptr && ownerB == nullptr) || (ownerA && ownerB && ownerA->ragdoll == ownerB->ragdoll))
            continue;
        const btVector3 relative = a->getLinearVelocity() - b->getLinearVelocity();
        for (int k = 0; k < m.getNumContacts(); ++k)
            closing = btMax(closing, -relative.dot(m.getContactPoint(k).m_normalWorldOnB));
    }
    const double travel = double(closing) * dtSeconds / least;
    if (!(travel > kImpactTravelM)) return least;
    return static_cast<int>(std::min<double>(m_method.impactSubsteps, std::ceil(least * travel / kImpactTravelM)));
}

void RagdollWorld::step(double dtSeconds) {
    for (Ragdoll* r : m_ragdolls) {
        r->checkGuard(); // what the game wrote since the last step
        detail::RagdollWorldLink::beginKeyframeStep(*r, dtSeconds);
        detail::RagdollWorldLink::beginMotorStep(*r);
    }
    const int substeps = substepsFor(dtSeconds);
    m_lastSubsteps = substeps;
    // The step's first substep releases the manifolds that may name them; objects destroyed from now on (a sunk
    // ragdoll surfacing within the step, say) are kept for the next frame's substepsFor.
    m_goneObjects.clear();
    m_world.stepSimulation(static_cast<btScalar>(dtSeconds), substeps, static_cast<btScalar>(dtSeconds / substeps));
}

Ragdoll* RagdollWorld::ragdollOf(const btCollisionObject* object) const {
    if (object == nullptr) return nullptr;
    if (const BodyOwner* owned = ownerOf(object)) return m_ragdolls[static_cast<std::size_t>(owned->ragdoll)];
    for (Ragdoll* r : m_ragdolls)
        if (detail::RagdollWorldLink::sunkBox(*r) == object) return r;
    return nullptr;
}

std::unique_ptr<Ragdoll> RagdollWorld::spawn(std::shared_ptr<const RagdollAsset> asset, const SpawnOptions& options) {
    auto ragdoll = std::make_unique<Ragdoll>(std::move(asset), static_cast<btDynamicsWorld&>(m_world), options);
    detail::RagdollWorldLink::join(*ragdoll, *this);
    attach(*ragdoll);
    if (options.startAtRest) ragdoll->putToRest(); // frozen now that this world can wake it
    return ragdoll;
}

void RagdollWorld::attach(Ragdoll& r) {
    markSpeculative(r);
    trackJoints(r);
    m_ragdolls.push_back(&r);
    addOwners(r, static_cast<int>(m_ragdolls.size()) - 1);
}

void RagdollWorld::markSpeculative(Ragdoll& r) {
    if (m_method.speculativeContacts)
        for (int i = 0; i < r.bodyCount(); ++i)
            if (r.collisionObject(i).getUserIndex2() == kEngineFrictionMarker)
                r.collisionObject(i).setUserIndex2(kSpeculativeFrictionMarker);
}

void RagdollWorld::detachBodies(Ragdoll& r) {
    untrackJoints(r);
    const auto it = std::find(m_ragdolls.begin(), m_ragdolls.end(), &r);
    if (it == m_ragdolls.end()) return;
    const int index = static_cast<int>(it - m_ragdolls.begin());
    m_owners.removeRagdoll(index, false, m_goneObjects);
}

void RagdollWorld::attachBodies(Ragdoll& r) {
    const auto it = std::find(m_ragdolls.begin(), m_ragdolls.end(), &r);
    if (it == m_ragdolls.end()) return;
    markSpeculative(r);
    trackJoints(r);
    addOwners(r, static_cast<int>(it - m_ragdolls.begin()));
}

void RagdollWorld::trackJoints(Ragdoll& r) {
    if (auto* solver = dynamic_cast<RagdollSolver*>(m_world.getConstraintSolver()))
        for (int k = 0; k < r.bulletConstraintCount(); ++k) {
            // Limit rows by their own knob (Method::limitWarmStarting); a limit row is never part of the direct
            // solve's block (its rows are bounded), so it is tracked only to be warm-started. Joint, friction and
            // spring rows by the joint knobs (the direct solve takes only unbounded rows). Motor rows are soft
            // (JointMotor.h): tracked as soft always, warm-started and solved directly with the joints (a motor
            // without a torque bound joins the block; a bounded one is solved as joint friction is).
            const RowRole role = r.bulletConstraintRole(k);
            const bool limit = role == RowRole::Limit, motor = role == RowRole::Motor;
            const bool warm = limit ? r.method().limitWarmStarting : r.method().jointWarmStarting;
            const bool direct = !limit && r.method().directJoints;
            if (warm || direct || motor) solver->track(r.bulletConstraint(k), warm, direct, motor);
        }
}

void RagdollWorld::untrackJoints(Ragdoll& r) {
    if (auto* solver = dynamic_cast<RagdollSolver*>(m_world.getConstraintSolver()))
        for (int k = 0; k < r.bulletConstraintCount(); ++k) solver->untrack(r.bulletConstraint(k));
}

void RagdollWorld::restartWarmStarting(Ragdoll& r) {
    untrackJoints(r);
    trackJoints(r);
}

void RagdollWorld::detach(Ragdoll& r) {
    untrackJoints(r);
    const auto it = std::find(m_ragdolls.begin(), m_ragdolls.end(), &r);
    if (it == m_ragdolls.end()) return;
    const int gone = static_cast<int>(it - m_ragdolls.begin());
    m_ragdolls.erase(it);
    // Its bodies leave the owner table, later ragdolls move down one place: no re-sort, no shape queries.
    m_owners.removeRagdoll(gone, true, m_goneObjects);
}

// The ragdoll's collision objects (one per rigid body: merged bodies share one) join the owner table.
void RagdollWorld::addOwners(Ragdoll& r, int index) {
    if (r.backend() == Backend::Rigid) {
        for (int k = 0; k < r.rigidBodyCount(); ++k) // radii from the asset
            m_owners.insert({&r.rigidBody(k), index,
                             static_cast<btScalar>(r.layout().rigids[static_cast<std::size_t>(k)].boundingRadius)});
    } else {
        for (int i = 0; i < r.bodyCount(); ++i) {
            const btCollisionObject& body = r.collisionObject(i);
            btVector3 centre;
            btScalar radius = 0;
            body.getCollisionShape()->getBoundingSphere(centre, radius);
            m_owners.insert({&body, index, radius});
        }
    }
}

} // namespace afb::bullet
