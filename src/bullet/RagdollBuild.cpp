// Building a ragdoll's Bullet bodies and constraints from its figure: docs/format.md §4 (constraint mapping),
// §4.7 (springs), §4.8 (friction), §6.2 (collision filtering).
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <BulletCollision/NarrowPhaseCollision/btGjkEpa2.h>

#include "EngineFriction.h"
#include "JointBuilders.h"
#include "Multibody.h"
#include "ObjectArena.h"
#include "RagdollAction.h"
#include "RagdollWorldLink.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/detail/Constraints.h"
#include "afb/detail/Convert.h"
#include "afb/figure/Collision.h"

namespace afb::bullet {

using figure::FigureConstraint;
using figure::JointType;

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

std::pair<btVector3, btVector3> Ragdoll::anchorsWorld(int i) const {
    if (m_multibody) {
        const auto [a, b] = m_multibody->constraintFramesWorld(i);
        return {a.getOrigin(), b.getOrigin()};
    }
    // The same arithmetic as the frames' origins: T(origin) is the origin of T · frame.
    const figure::FigureConstraint& c = figure().constraints[static_cast<std::size_t>(i)];
    const auto& rigidFrames = m_rigidFrames[static_cast<std::size_t>(i)];
    const btVector3 a = body(c.body1).getCenterOfMassTransform()(rigidFrames.first.getOrigin());
    const btVector3 b = c.body2 >= 0 ? body(c.body2).getCenterOfMassTransform()(rigidFrames.second.getOrigin())
                                     : rigidFrames.second.getOrigin();
    return {a, b};
}

void Ragdoll::addConstraints() {
    const figure::Figure& f = figure();
    const JointPolicy policy{{static_cast<btScalar>(m_method.limitErp), m_method.speculativeLimits},
                             m_method.constantVelocityUniversal};
    // At most a main constraint, its friction and a limit per joint.
    m_frames.reserve(f.constraints.size());
    m_rigidFrames.reserve(f.constraints.size());
    m_main.reserve(f.constraints.size());
    m_constraints.reserve(3 * f.constraints.size());
    m_roles.reserve(3 * f.constraints.size());
    for (std::size_t ci = 0; ci < f.constraints.size(); ++ci) {
        const FigureConstraint& c = f.constraints[ci];
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
        const JointSite site{body(c.body1),
                             other(c.body2),
                             fa,
                             fb,
                             offsetA.getBasis(),
                             c.body2 >= 0 ? bodyInRigid(c.body2).getBasis() : m_spawn.getBasis()};
        addJoint(c, buildJoint(*m_arena, c, site, policy));
    }
    if (!m_motorGains.empty()) addMotors(); // rebuilt with a level of detail
}

// The joint's constraints into the world in a fixed order (main, its friction, its limit), each with its role.
void Ragdoll::addJoint(const FigureConstraint& c, const JointParts& parts) {
    btTypedConstraint* const main = parts.main;
    btTypedConstraint* const limit = parts.limit;
    m_main.push_back(main);
    if (m_method.jointIterations > 0) {
        if (main) main->setOverrideNumSolverIterations(m_method.jointIterations);
        if (limit) limit->setOverrideNumSolverIterations(m_method.jointIterations);
    }
    const auto add = [this](btTypedConstraint* constraint, RowRole role) {
        m_world.addConstraint(constraint);
        m_constraints.push_back(constraint);
        m_roles.push_back(role);
    };
    if (main) {
        // Collision between the joint's bodies is off through filterPairs (RigidLayout::ignoredPairs has every
        // pair a joint disables, §6.2), not through Bullet's constraint references, which would add the same
        // entry to each body's list again, with a linear search per constraint and body, at every spawn.
        add(main, parts.mainRole);
        if (c.friction > 0 && parts.frictionRows > 0) {
            auto* feedback = m_arena->make<btJointFeedback>();
            main->setJointFeedback(feedback);
            btRigidBody& a = body(c.body1);
            btRigidBody& b = other(c.body2);
            auto* friction = m_arena->make<JointFrictionConstraint>(a, b, parts.frictionAxes, parts.frictionRows);
            const btScalar lever = static_cast<btScalar>(figure().units.metresPerUnit);
            m_action->frictions.push_back({friction, feedback, static_cast<btScalar>(c.friction) * lever});
            m_feedback.push_back(feedback);
            add(friction, RowRole::Friction);
        }
    }
    if (limit) add(limit, RowRole::Limit);
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
