// The multibody backend's constraints (Multibody.h): loops and world attachments, docs/format.md §4.3/§4.5 limits
// and §4.4 twists on the links, §4.8 joint friction with its bound from each joint's reaction, §4.7 springs, and one
// energy guard per tree; each with the role of its rows (RowRole), as MultibodyJoints.h gives them.
#include <algorithm>

#include <BulletDynamics/Featherstone/btMultiBody.h>
#include <BulletDynamics/Featherstone/btMultiBodyDynamicsWorld.h>
#include <BulletDynamics/Featherstone/btMultiBodyFixedConstraint.h>
#include <BulletDynamics/Featherstone/btMultiBodyLinkCollider.h>
#include <BulletDynamics/Featherstone/btMultiBodyPoint2Point.h>

#include "Multibody.h"
#include "afb/detail/Convert.h"
#include "afb/figure/Vocabulary.h"

namespace afb::bullet::detail {

using figure::FigureConstraint;

btMultiBodyConstraint* MultibodyRagdoll::add(std::unique_ptr<btMultiBodyConstraint> constraint,
                                             std::optional<RowRole> role) {
    btMultiBodyConstraint* const added = constraint.get();
    m_world.addMultiBodyConstraint(added);
    m_constraints.push_back({std::move(constraint), role});
    return added;
}

std::vector<RowRole> MultibodyRagdoll::rowRoles() const {
    std::vector<RowRole> out;
    for (const Owned& o : m_constraints)
        if (o.role) out.push_back(*o.role);
    return out;
}

void MultibodyRagdoll::addConstraints(const Method& method, std::span<const MultibodyJointParts> joints) {
    const figure::Figure& f = m_asset->figure();
    const LimitRowPolicy policy{static_cast<btScalar>(method.limitErp), method.speculativeLimits};
    for (std::size_t ci = 0; ci < f.constraints.size(); ++ci) {
        const FigureConstraint& c = f.constraints[ci];
        const MultibodyJointParts& parts = joints[ci];
        const auto& [fa, fb] = m_frames[ci];
        if (parts.mainRole == RowRole::Spring) {
            addSpring(c, fa, fb);
            continue;
        }
        const int partA = m_bodies[static_cast<std::size_t>(c.body1)].part;
        const bool sameTree = c.body2 < 0 || m_bodies[static_cast<std::size_t>(c.body2)].part == partA;
        if (!m_treeEdge[ci]) {
            // Into the world before its friction rows, owned after them (the order the world removes them in).
            std::unique_ptr<btMultiBodyConstraint> loop = makeLoop(c, m_frames[ci]);
            m_world.addMultiBodyConstraint(loop.get());
            if (sameTree) addFriction(static_cast<int>(ci), parts, loop.get());
            m_constraints.push_back({std::move(loop), RowRole::Joint});
        } else {
            addFriction(static_cast<int>(ci), parts, nullptr);
        }
        // A limit or friction across two trees: not modelled (no corpus figure has one).
        if (sameTree && parts.limit) addLimit(c, *parts.limit, policy);
    }
    addTwistRows(policy);
    for (Part& p : m_parts) {
        auto guard =
            std::make_unique<EnergyGuard>(p.body.get(), *m_colliders[static_cast<std::size_t>(p.root)], m_world);
        m_guards.push_back(guard.get());
        add(std::move(guard), std::nullopt);
    }
    recordMotion();
}

std::unique_ptr<btMultiBodyConstraint> MultibodyRagdoll::makeLoop(const FigureConstraint& c,
                                                                  const std::pair<btTransform, btTransform>& frames) {
    const auto& [fa, fb] = frames;
    const figure::JointFreedom freedom = figure::freedomOf(c.type);
    const bool holdsFrames =
        freedom.anchor == figure::AnchorHold::Point && freedom.rotation == figure::RotationHold::All;
    const BodyRef a = m_bodies[static_cast<std::size_t>(c.body1)];
    btMultiBody* treeA = m_parts[static_cast<std::size_t>(a.part)].body.get();
    std::unique_ptr<btMultiBodyConstraint> joint;
    if (c.body2 >= 0) {
        const BodyRef b = m_bodies[static_cast<std::size_t>(c.body2)];
        btMultiBody* treeB = m_parts[static_cast<std::size_t>(b.part)].body.get();
        if (holdsFrames)
            joint = std::make_unique<btMultiBodyFixedConstraint>(treeA, a.link, treeB, b.link, fa.getOrigin(),
                                                                 fb.getOrigin(), fa.getBasis(), fb.getBasis());
        else
            joint =
                std::make_unique<btMultiBodyPoint2Point>(treeA, a.link, treeB, b.link, fa.getOrigin(), fb.getOrigin());
    } else {
        auto* world = static_cast<btRigidBody*>(nullptr);
        if (holdsFrames)
            joint = std::make_unique<btMultiBodyFixedConstraint>(treeA, a.link, world, fa.getOrigin(), fb.getOrigin(),
                                                                 fa.getBasis(), fb.getBasis());
        else joint = std::make_unique<btMultiBodyPoint2Point>(treeA, a.link, world, fa.getOrigin(), fb.getOrigin());
    }
    joint->setMaxAppliedImpulse(BT_LARGE_FLOAT); // Bullet's default caps it at 100 N·s
    return joint;
}

void MultibodyRagdoll::addLimit(const FigureConstraint& c, const MultibodyLimit::Kind& limit,
                                const LimitRowPolicy& policy) {
    // The rigid backend's rows (JointBuilders.cpp), on the links.
    const BodyRef a = m_bodies[static_cast<std::size_t>(c.body1)];
    const MultibodyLimit::Side sideA{a.link, m_colliders[static_cast<std::size_t>(c.body1)].get(),
                                     &m_angularVelocity[static_cast<std::size_t>(c.body1)]};
    MultibodyLimit::Side sideB;
    if (c.body2 >= 0)
        sideB = {m_bodies[static_cast<std::size_t>(c.body2)].link, m_colliders[static_cast<std::size_t>(c.body2)].get(),
                 &m_angularVelocity[static_cast<std::size_t>(c.body2)]};
    auto row = std::make_unique<MultibodyLimit>(m_parts[static_cast<std::size_t>(a.part)].body.get(), sideA, sideB,
                                                limit, policy);
    m_swept.push_back(row.get());
    add(std::move(row), RowRole::Limit);
}

void MultibodyRagdoll::addTwistRows(const LimitRowPolicy& policy) {
    for (Part& p : m_parts)
        for (const Joint& j : p.joints) {
            if (!j.twistRow) continue;
            const MultibodyLimit::Side parent{m_bodies[static_cast<std::size_t>(j.parent)].link,
                                              m_colliders[static_cast<std::size_t>(j.parent)].get(), nullptr};
            const MultibodyLimit::Side child{j.link, m_colliders[static_cast<std::size_t>(j.child)].get(), nullptr};
            auto row = std::make_unique<MultibodyLimit>(p.body.get(), parent, child,
                                                        MultibodyLimit::Twist{j.frameInParent, j.frameInChild}, policy);
            m_swept.push_back(row.get());
            add(std::move(row), RowRole::Joint); // an equality: it holds what the spherical link leaves free
        }
}

std::optional<std::vector<int>> MultibodyRagdoll::subtreeOf(const FigureConstraint& c) const {
    // The tree edge's child: the joint of the part whose two bodies are the constraint's.
    const int part = m_bodies[static_cast<std::size_t>(c.body1)].part;
    const std::vector<Joint>& joints = m_parts[static_cast<std::size_t>(part)].joints;
    int child = -1;
    for (const Joint& j : joints)
        if ((j.child == c.body1 && j.parent == c.body2) || (j.child == c.body2 && j.parent == c.body1)) child = j.child;
    if (child < 0) return std::nullopt;
    std::vector<int> out;
    for (int b = 0; b < bodyCount(); ++b) {
        if (m_bodies[static_cast<std::size_t>(b)].part != part) continue;
        int up = b;
        while (up >= 0 && up != child) {
            const auto it = std::find_if(joints.begin(), joints.end(), [&](const Joint& j) { return j.child == up; });
            up = it == joints.end() ? -1 : it->parent;
        }
        if (up == child) out.push_back(b);
    }
    return out;
}

void MultibodyRagdoll::addFriction(int ci, const MultibodyJointParts& parts, btMultiBodyConstraint* loop) {
    const figure::Figure& f = m_asset->figure();
    const FigureConstraint& c = f.constraints[static_cast<std::size_t>(ci)];
    // Fixed and slider joints have no friction (§4.6), springs none (§4.7).
    if (!(c.friction > 0) || parts.frictionRows == 0) return;
    const BodyRef a = m_bodies[static_cast<std::size_t>(c.body1)];
    Friction fr;
    fr.coefficientTimesLever = static_cast<btScalar>(c.friction * f.units.metresPerUnit);
    fr.loop = loop;
    if (!loop) {
        // A tree joint: its reaction is what the child's subtree needs beyond gravity and its contacts.
        std::optional<std::vector<int>> subtree = subtreeOf(c);
        if (!subtree) return;
        fr.subtree = std::move(*subtree);
    }
    std::optional<int> linkB;
    const btCollisionObject* bodyB = nullptr;
    if (c.body2 >= 0) {
        linkB = m_bodies[static_cast<std::size_t>(c.body2)].link;
        bodyB = m_colliders[static_cast<std::size_t>(c.body2)].get();
    }
    auto rows = std::make_unique<MultibodyFriction>(m_parts[static_cast<std::size_t>(a.part)].body.get(), a.link,
                                                    *m_colliders[static_cast<std::size_t>(c.body1)], linkB, bodyB,
                                                    parts.frictionAxes, parts.frictionRows);
    fr.rows = rows.get();
    add(std::move(rows), RowRole::Friction);
    m_frictions.push_back(std::move(fr));
}

void MultibodyRagdoll::addSpring(const FigureConstraint& c, const btTransform& fa, const btTransform& fb) {
    const SpringConstraint::Params p = SpringConstraint::Params::of(c.spring);
    auto end = [&](int body, const btVector3& anchor) {
        MultibodySpring::End e;
        e.anchor = anchor;
        if (body < 0) return e;
        const BodyRef ref = m_bodies[static_cast<std::size_t>(body)];
        e.tree = m_parts[static_cast<std::size_t>(ref.part)].body.get();
        e.link = ref.link;
        e.body = m_colliders[static_cast<std::size_t>(body)].get();
        return e;
    };
    add(std::make_unique<MultibodySpring>(end(c.body1, fa.getOrigin()), end(c.body2, fb.getOrigin()), p),
        RowRole::Spring);
}

void MultibodyRagdoll::gatherContactImpulses() {
    m_contactImpulse.assign(m_bodies.size(), btVector3(0, 0, 0));
    btDispatcher& dispatcher = *m_world.getDispatcher();
    for (int i = 0, n = dispatcher.getNumManifolds(); i < n; ++i) {
        const btPersistentManifold* m = dispatcher.getManifoldByIndexInternal(i);
        if (m->getNumContacts() == 0) continue;
        const int a = bodyOfCollider(m->getBody0()), b = bodyOfCollider(m->getBody1());
        if (a < 0 && b < 0) continue;
        for (int k = 0; k < m->getNumContacts(); ++k) {
            const btManifoldPoint& cp = m->getContactPoint(k);
            // On body 0 (A): along the normal from B towards A, and the two friction directions.
            const btVector3 p = cp.m_normalWorldOnB * cp.m_appliedImpulse +
                                cp.m_lateralFrictionDir1 * cp.m_appliedImpulseLateral1 +
                                cp.m_lateralFrictionDir2 * cp.m_appliedImpulseLateral2;
            if (a >= 0) m_contactImpulse[static_cast<std::size_t>(a)] += p;
            if (b >= 0) m_contactImpulse[static_cast<std::size_t>(b)] -= p;
        }
    }
}

void MultibodyRagdoll::updateFrictionBounds(btScalar dt) {
    if (m_frictions.empty() || !(dt > 0)) return;
    // §4.8 as the rigid backend: each row's bound is friction × the joint's reaction force in the step just
    // solved, in SI (× metres per unit), times the step. A tree joint has no constraint force of its own: its
    // reaction is the force the child's subtree needed beyond gravity and its contacts, Σ(m·Δv − m·g·dt − p)/dt
    // (Bullet's joint feedback counts the velocity-product terms twice: 4·m·g at the bottom of a rod's swing for
    // the exact 2.5·m·g). A loop or world joint's reaction is its constraint's applied impulse.
    const std::vector<BodySample> now = samples();
    gatherContactImpulses();
    const btVector3 g = m_world.getGravity();
    const figure::Figure& f = m_asset->figure();
    for (const Friction& fr : m_frictions) {
        btVector3 impulse(0, 0, 0);
        if (fr.loop) {
            for (int i = 0; i < std::min(3, fr.loop->getNumRows()); ++i) impulse[i] = fr.loop->getAppliedImpulse(i);
        } else {
            for (const int b : fr.subtree) {
                const std::size_t k = static_cast<std::size_t>(b);
                const btScalar m = static_cast<btScalar>(f.bodies[k].massKg);
                impulse += (now[k].linearVelocity - m_linearVelocity[k]) * m - g * (m * dt) - m_contactImpulse[k];
            }
        }
        const btScalar force = impulse.length() / dt;
        fr.rows->setMaxImpulse(fr.coefficientTimesLever * force * dt);
    }
}

} // namespace afb::bullet::detail
