// Plain Bullet's version of a figure (the chart's reference): the mapping of docs/format.md §4 a plain Bullet user
// would write, on the same bodies as bullet::Ragdoll. RawRagdoll.h lists every choice.
#include "afb/sim/RawRagdoll.h"

#include <algorithm>

#include "afb/detail/Constraints.h"
#include "afb/detail/Convert.h"
#include "afb/figure/Collision.h"

namespace afb::sim {

using figure::FigureConstraint;
using figure::JointType;

bullet::Method rawMethod() {
    bullet::Method m;
    m.name = std::string(kRawMethodName);
    // btContactSolverInfo's defaults (Bullet 3.24): 10 iterations, split impulse, ERP 0.2 for contacts and
    // joints, warm starting 0.85; stepSimulation once per frame.
    m.substeps = 1;
    m.iterations = 10;
    m.splitImpulse = true;
    m.contactErp = 0.2;
    m.jointErp = 0.2;
    m.warmStarting = true;
    m.warmStartingFactor = 0.85;
    m.frictionDirections = 1; // one friction row per contact point (SOLVER_USE_2_FRICTION_DIRECTIONS unset)
    // btDefaultCollisionConfiguration's default: one new contact point per step on a plane.
    m.multipointContacts = false;
    // btTypedConstraint's default: the world's iterations; btHinge/btConeTwist setLimit's default bias 0.3.
    m.jointIterations = 0;
    m.limitErp = 0.3;
    m.ccd = bullet::CcdPolicy::Off;
    // afbullet's own techniques: plain Bullet has none of them.
    m.positionIterations = 0;
    m.positionTree = 0;
    m.directJoints = false;
    m.figureIterations = 0;
    m.frictionThroughFigure = false;
    m.jointSpace = false;
    m.separatedPairs = false;
    m.impactSubsteps = 1;
    m.speculativeContacts = false;
    m.speculativeLimits = false;
    m.jointWarmStarting = false;
    m.limitWarmStarting = false;
    m.positionVelocity = false;
    m.mergeFixed = false;
    m.exemptOverlapping = false;
    m.constantVelocityUniversal = false;
    return m;
}

bool isRaw(const bullet::Method& method) { return method.name == kRawMethodName; }

std::string rawMethodError(const bullet::Method& m) {
    if (!isRaw(m)) return {};
    std::string knobs;
    if (m.positionIterations > 0) knobs += " position-iterations";
    if (m.positionTree > 0) knobs += " position-tree";
    if (m.positionVelocity) knobs += " position-velocity";
    if (m.directJoints) knobs += " direct-joints";
    if (m.figureIterations > 0) knobs += " figure-iterations";
    if (m.speculativeContacts) knobs += " speculative-contacts";
    if (m.speculativeLimits) knobs += " speculative-limits";
    if (m.jointWarmStarting) knobs += " joint-warm-starting";
    if (m.limitWarmStarting) knobs += " limit-warm-starting";
    if (m.mergeFixed) knobs += " merge-fixed";
    if (m.exemptOverlapping) knobs += " exempt-overlapping";
    if (m.constantVelocityUniversal) knobs += " constant-velocity-universal";
    if (m.frictionThroughFigure) knobs += " friction-through-figure";
    if (m.jointSpace) knobs += " joint-space";
    if (m.separatedPairs) knobs += " separated-pairs";
    if (m.impactSubsteps > 1) knobs += " impact-substeps";
    if (knobs.empty()) return {};
    return "method raw (plain Bullet) has no" + knobs + ": leave them off";
}

std::vector<std::string_view> methodNames() {
    std::vector<std::string_view> names(bullet::methodPresetNames().begin(), bullet::methodPresetNames().end());
    names.push_back(kRawMethodName);
    return names;
}

std::optional<bullet::Method> methodByName(std::string_view name) {
    if (name == kRawMethodName) return rawMethod();
    return bullet::methodPreset(name);
}

// The figure's rest rules as a measurement: atRest latches once they hold; the bodies are left to Bullet.
class RawRagdoll::Observer : public btActionInterface {
  public:
    Observer(RawRagdoll& owner, bool enabled, bool startAtRest)
        : atRest(enabled && startAtRest), m_owner(owner), m_rest(owner.figure().rest), m_enabled(enabled) {}
    bool atRest;

    void updateAction(btCollisionWorld*, btScalar dt) override {
        if (!m_enabled || atRest) return;
        m_activeSeconds += dt;
        atRest = m_rest.update(m_owner.m_bodyList, dt, m_activeSeconds);
    }
    void debugDraw(btIDebugDraw*) override {}

  private:
    RawRagdoll& m_owner;
    bullet::RestTest m_rest;
    bool m_enabled;
    double m_activeSeconds = 0;
};

RawRagdoll::RawRagdoll(std::shared_ptr<const bullet::RagdollAsset> asset, btDynamicsWorld& world,
                       const bullet::SpawnOptions& options)
    : m_asset(std::move(asset)), m_world(world), m_spawn(options.entityTransform) {
    m_observer = std::make_unique<Observer>(*this, options.comeToRest, options.startAtRest);
    addBodies(options, options.method);
    addConstraints(options.method);
    filterPairs();
    m_world.addAction(m_observer.get());
    if (options.startAtRest)
        for (const auto& b : m_bodies) b->forceActivationState(ISLAND_SLEEPING);
}

RawRagdoll::~RawRagdoll() {
    m_world.removeAction(m_observer.get());
    for (auto it = m_constraints.rbegin(); it != m_constraints.rend(); ++it) m_world.removeConstraint(it->get());
    for (auto it = m_bodies.rbegin(); it != m_bodies.rend(); ++it) m_world.removeRigidBody(it->get());
}

void RawRagdoll::addBodies(const bullet::SpawnOptions& options, const bullet::Method& method) {
    const figure::Figure& f = figure();
    for (std::size_t i = 0; i < f.bodies.size(); ++i) {
        const figure::FigureBody& b = f.bodies[i];
        btRigidBody::btRigidBodyConstructionInfo info(static_cast<btScalar>(b.massKg), nullptr,
                                                      m_asset->shape(static_cast<int>(i)), bullet::toBt(b.inertiaKgM2));
        info.m_startWorldTransform = m_spawn * bullet::toBt(b.loadPose);
        info.m_friction = static_cast<btScalar>(b.contactFriction);
        info.m_restitution = static_cast<btScalar>(bullet::kBodyRestitution);
        info.m_linearDamping = static_cast<btScalar>(b.linearDamping);
        info.m_angularDamping = static_cast<btScalar>(b.angularDamping);
        auto body = std::make_unique<btRigidBody>(info); // Bullet's default sleeping thresholds
        if (!options.comeToRest) body->setActivationState(DISABLE_DEACTIVATION);
        if (method.ccd == bullet::CcdPolicy::FastBodies) {
            const btScalar r = static_cast<btScalar>(m_asset->innerRadius(static_cast<int>(i)));
            body->setCcdMotionThreshold(r);
            body->setCcdSweptSphereRadius(r);
        }
        int mask = options.collisionMask;
        if (figure::attachedToWorld(f, static_cast<int>(i))) mask &= ~btBroadphaseProxy::StaticFilter;
        if (b.clipMask == 0) mask = 0; // §6.2
        m_world.addRigidBody(body.get(), options.collisionGroup, mask);
        m_bodyList.push_back(body.get());
        m_bodies.push_back(std::move(body));
    }
}

namespace {

// A cone-twist whose cone is frame B's X (`basisB`, in body B's Bullet frame) and whose shaft is frame A's X:
// frame A is frame B turned along the shortest arc from the cone axis to the shaft at the spawn pose, so the
// twist starts at 0. Swing span 1 limits the swing in frame B's X–Y plane, span 2 in its X–Z plane (Bullet's
// convention); a negative twist span leaves twist free.
std::unique_ptr<btConeTwistConstraint> coneTwist(btRigidBody& a, btRigidBody& b, const btVector3& anchorA,
                                                 const btVector3& anchorB, const btMatrix3x3& basisB,
                                                 const btVector3& shaftA, btScalar span1, btScalar span2,
                                                 btScalar twistSpan, btScalar bias) {
    const btMatrix3x3& aWorld = a.getCenterOfMassTransform().getBasis();
    const btMatrix3x3& bWorld = b.getCenterOfMassTransform().getBasis();
    const btVector3 axisW = bWorld * basisB.getColumn(0), shaftW = aWorld * shaftA;
    const btMatrix3x3 frameAWorld = bullet::shortestArc(axisW, shaftW) * (bWorld * basisB);
    auto ct = std::make_unique<btConeTwistConstraint>(a, b, btTransform(aWorld.transpose() * frameAWorld, anchorA),
                                                      btTransform(basisB, anchorB));
    ct->setLimit(span1, span2, twistSpan, btScalar(1), bias, btScalar(1)); // softness, relaxation: Bullet's
    return ct;
}

} // namespace

void RawRagdoll::addConstraints(const bullet::Method& method) {
    const figure::Figure& f = figure();
    const btScalar bias = static_cast<btScalar>(method.limitErp);
    for (const FigureConstraint& c : f.constraints) {
        btRigidBody& a = *m_bodies[static_cast<std::size_t>(c.body1)];
        btRigidBody& b =
            c.body2 >= 0 ? *m_bodies[static_cast<std::size_t>(c.body2)] : btTypedConstraint::getFixedBody();
        const btTransform fa = bullet::toBt(c.frameInBody1);
        // Body2's frame: body-local, or world for a world constraint (model space moved by the spawn).
        const btTransform fb = c.body2 >= 0 ? bullet::toBt(c.frameInBody2) : m_spawn * bullet::toBt(c.frameInBody2);
        m_frames.emplace_back(fa, fb);
        const btMatrix3x3 b2Rot = c.body2 >= 0 ? btMatrix3x3::getIdentity() : m_spawn.getBasis();
        const auto* cone = std::get_if<figure::ConeLimit>(&c.limit);
        const auto* pyramid = std::get_if<figure::PyramidLimit>(&c.limit);
        std::unique_ptr<btTypedConstraint> main;
        switch (c.type) {
        case JointType::Fixed: main = std::make_unique<btFixedConstraint>(a, b, fa, fb); break;
        case JointType::BallAndSocket:
        case JointType::Universal: {
            const btScalar twist = c.type == JointType::Universal ? btScalar(0) : btScalar(-1); // locked : free
            if (cone) {
                const btScalar h = static_cast<btScalar>(cone->halfAngleRad);
                main = coneTwist(a, b, fa.getOrigin(), fb.getOrigin(),
                                 bullet::basisWithX(b2Rot * bullet::toBt(cone->axisInBody2)),
                                 bullet::toBt(cone->shaftInBody1), h, h, twist, bias);
            } else if (pyramid) {
                main = coneTwist(a, b, fa.getOrigin(), fb.getOrigin(), b2Rot * bullet::toBt(pyramid->basisInBody2),
                                 bullet::toBt(pyramid->shaftInBody1), static_cast<btScalar>(pyramid->halfAngle1Rad),
                                 static_cast<btScalar>(pyramid->halfAngle2Rad), twist, bias);
            } else if (c.type == JointType::Universal) {
                // The figure's frames: X along shaft 1 (body1) and −shaft 2 (body2); swing free.
                auto ct = std::make_unique<btConeTwistConstraint>(a, b, fa, fb);
                ct->setLimit(SIMD_PI, SIMD_PI, 0);
                main = std::move(ct);
            } else {
                main = std::make_unique<btPoint2PointConstraint>(a, b, fa.getOrigin(), fb.getOrigin());
            }
            break;
        }
        case JointType::Hinge: {
            auto h = std::make_unique<btHingeConstraint>(a, b, fa, fb, false);
            if (const auto* range = std::get_if<figure::HingeRange>(&c.limit))
                h->setLimit(static_cast<btScalar>(range->lowerRad), static_cast<btScalar>(range->upperRad),
                            btScalar(0.9), bias); // softness 0.9 and relaxation 1: btHinge's defaults
            main = std::move(h);
            break;
        }
        case JointType::Slider: main = bullet::makeSlider(a, b, fa, fb); break;
        case JointType::Spring: break; // no plain-Bullet counterpart
        }
        m_main.push_back(main.get());
        if (!main) continue;
        if (method.jointIterations > 0) main->setOverrideNumSolverIterations(method.jointIterations);
        m_world.addConstraint(main.get(), c.disablesCollision);
        m_constraints.push_back(std::move(main));
    }
}

// §6.2, as bullet::Ragdoll filters: pairs the figure's rules keep apart, beyond those a joint already disables.
void RawRagdoll::filterPairs() {
    const std::vector<std::pair<int, int>> colliding = figure::selfCollisionPairs(figure());
    const int n = bodyCount();
    for (int i = 0; i < n; ++i)
        for (int j = i + 1; j < n; ++j) {
            if (std::binary_search(colliding.begin(), colliding.end(), std::make_pair(i, j))) continue;
            body(i).setIgnoreCollisionCheck(&body(j), true);
            body(j).setIgnoreCollisionCheck(&body(i), true);
        }
}

std::pair<btTransform, btTransform> RawRagdoll::constraintFramesWorld(int i) const {
    return bullet::constraintFramesWorldOf(figure().constraints[static_cast<std::size_t>(i)], m_bodyList,
                                           m_frames[static_cast<std::size_t>(i)]);
}

bullet::JointError RawRagdoll::jointError(int i) const {
    return bullet::jointErrorOf(figure().constraints[static_cast<std::size_t>(i)], m_bodyList,
                                m_frames[static_cast<std::size_t>(i)], m_spawn);
}

std::vector<figure::Transform> RawRagdoll::bodyTransforms() const { return bullet::bodyTransformsOf(m_bodyList); }
std::vector<figure::BodyState> RawRagdoll::bodyStates() const { return bullet::bodyStatesOf(m_bodyList); }
bool RawRagdoll::setBodyVelocities(std::span<const bullet::BodyVelocity> velocities) {
    if (velocities.size() != m_bodies.size()) return false;
    for (std::size_t i = 0; i < m_bodies.size(); ++i) {
        m_bodies[i]->setLinearVelocity(velocities[i].linearMps);
        m_bodies[i]->setAngularVelocity(velocities[i].angularRadps);
        m_bodies[i]->activate(true);
    }
    return true;
}

bool RawRagdoll::applyBodyImpulse(int body, const btVector3& impulse, const btVector3& worldPoint,
                                  bullet::ImpulseRule rule) {
    if (body < 0 || body >= bodyCount()) return false;
    if (rule == bullet::ImpulseRule::EngineThreshold && impulse.length() < 500.0 * figure().units.metresPerUnit)
        return false;
    btRigidBody& b = *m_bodies[static_cast<std::size_t>(body)];
    b.activate(true);
    b.applyImpulse(impulse, worldPoint - b.getCenterOfMassPosition());
    return true;
}

int RawRagdoll::awakeBodyCount() const { return bullet::awakeCountOf(m_bodyList); }
bool RawRagdoll::atRest() const { return m_observer->atRest; }

} // namespace afb::sim
