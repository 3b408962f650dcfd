// The multibody backend's trees (Multibody.h): which joints are tree edges and which bodies are bases (by what each
// joint holds, figure::freedomOf), the links as MultibodyJoints.h describes them (docs/format.md §4), the colliders
// with the §6.2 collision rules, and the joint coordinates that place the trees at given body states.
#include <algorithm>

#include <BulletDynamics/Featherstone/btMultiBody.h>
#include <BulletDynamics/Featherstone/btMultiBodyDynamicsWorld.h>
#include <BulletDynamics/Featherstone/btMultiBodyLinkCollider.h>

#include "EngineFriction.h"
#include "Multibody.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/detail/Convert.h"
#include "afb/figure/Collision.h"
#include "afb/figure/Vocabulary.h"

namespace afb::bullet::detail {

using figure::FigureConstraint;

namespace {

// Generalised velocities a link may reach (Bullet clamps every coordinate velocity to this after each step; its
// default of 100 would clip a foot's spin at impact and hide an instability instead of showing it).
constexpr btScalar kMaxCoordinateVelocity = 1000;

// A joint that holds its two anchors together joins its bodies in a tree; one that holds none (a spring) does not.
bool joinsBodies(const FigureConstraint& c) {
    return figure::freedomOf(c.type).anchor != figure::AnchorHold::None && c.body2 >= 0 && c.body1 != c.body2;
}

// A joint that holds the point and every rotation: to the world, it makes its body a fixed base.
bool holdsEverything(const FigureConstraint& c) {
    const figure::JointFreedom f = figure::freedomOf(c.type);
    return f.anchor == figure::AnchorHold::Point && f.rotation == figure::RotationHold::All;
}

} // namespace

// A link's collider with the figure's §6.2 rules between the ragdoll's own bodies (Bullet's own rule knows only
// parent–child pairs of one tree).
class MultibodyRagdoll::LinkCollider : public btMultiBodyLinkCollider {
  public:
    LinkCollider(btMultiBody* tree, int link, const MultibodyRagdoll& owner, int body)
        : btMultiBodyLinkCollider(tree, link), m_owner(owner), m_body(body) {
        m_checkCollideWith = 1; // Bullet asks checkCollideWithOverride for every pair
    }
    bool checkCollideWithOverride(const btCollisionObject* co) const override {
        const int b = m_owner.bodyOfCollider(co);
        if (b < 0) return true;
        return std::binary_search(m_owner.m_colliding.begin(), m_owner.m_colliding.end(),
                                  std::make_pair(std::min(m_body, b), std::max(m_body, b)));
    }
    int body() const { return m_body; }

  private:
    const MultibodyRagdoll& m_owner;
    int m_body;
};

int MultibodyRagdoll::bodyOfCollider(const btCollisionObject* o) const {
    const btMultiBodyLinkCollider* link = btMultiBodyLinkCollider::upcast(o);
    if (link == nullptr) return -1;
    for (const Part& p : m_parts)
        if (p.body.get() == link->m_multiBody) return static_cast<const LinkCollider*>(link)->body();
    return -1;
}

std::vector<MultibodyJointParts> MultibodyRagdoll::jointParts() const {
    const figure::Figure& f = m_asset->figure();
    std::vector<MultibodyJointParts> out;
    out.reserve(f.constraints.size());
    for (std::size_t ci = 0; ci < f.constraints.size(); ++ci) {
        const FigureConstraint& c = f.constraints[ci];
        const auto& [fa, fb] = m_frames[ci];
        // Directions fixed in body2 as frame B's parent sees them: the world's are model space, turned by the spawn.
        const btMatrix3x3 body2Rotation = c.body2 >= 0 ? btMatrix3x3::getIdentity() : m_spawn.getBasis();
        out.push_back(buildMultibodyJoint(c, {fa, fb, body2Rotation}));
    }
    return out;
}

void MultibodyRagdoll::layoutTrees(std::span<const MultibodyJointParts> joints) {
    const figure::Figure& f = m_asset->figure();
    const std::size_t n = f.bodies.size();
    m_bodies.assign(n, {});
    // Tree edges: joints between two bodies, breadth first from each part's first body, in constraint order, so the
    // origin body is the first tree's base and the build is deterministic.
    std::vector<std::vector<std::pair<int, int>>> adjacent(n); // (constraint, body)
    // A body fixed to the world is its tree's base, and that base is fixed: the attachment is then exact.
    std::vector<int> fixedToWorld(n, -1); // the constraint, per body
    for (std::size_t ci = 0; ci < f.constraints.size(); ++ci) {
        const FigureConstraint& c = f.constraints[ci];
        if (joinsBodies(c)) {
            adjacent[static_cast<std::size_t>(c.body1)].emplace_back(static_cast<int>(ci), c.body2);
            adjacent[static_cast<std::size_t>(c.body2)].emplace_back(static_cast<int>(ci), c.body1);
        }
        if (holdsEverything(c) && c.body2 < 0 && fixedToWorld[static_cast<std::size_t>(c.body1)] < 0)
            fixedToWorld[static_cast<std::size_t>(c.body1)] = static_cast<int>(ci);
    }
    m_treeEdge.assign(f.constraints.size(), false);
    std::vector<int> roots;
    for (std::size_t b = 0; b < n; ++b)
        if (fixedToWorld[b] >= 0) roots.push_back(static_cast<int>(b));
    for (std::size_t b = 0; b < n; ++b)
        if (fixedToWorld[b] < 0) roots.push_back(static_cast<int>(b));
    std::vector<bool> reached(n, false);
    for (const int root : roots) {
        if (reached[static_cast<std::size_t>(root)]) continue;
        Part part;
        part.root = root;
        part.fixedBase = fixedToWorld[static_cast<std::size_t>(root)] >= 0;
        if (part.fixedBase) m_treeEdge[static_cast<std::size_t>(fixedToWorld[static_cast<std::size_t>(root)])] = true;
        reached[static_cast<std::size_t>(root)] = true;
        const int partIndex = static_cast<int>(m_parts.size());
        m_bodies[static_cast<std::size_t>(root)] = {partIndex, -1};
        std::vector<int> queue{root};
        for (std::size_t q = 0; q < queue.size(); ++q) {
            const int p = queue[q];
            for (const auto& [ci, child] : adjacent[static_cast<std::size_t>(p)]) {
                if (reached[static_cast<std::size_t>(child)]) continue;
                reached[static_cast<std::size_t>(child)] = true;
                m_treeEdge[static_cast<std::size_t>(ci)] = true;
                Joint j = treeJoint(ci, p, child, joints[static_cast<std::size_t>(ci)]);
                j.link = static_cast<int>(part.joints.size());
                m_bodies[static_cast<std::size_t>(child)] = {partIndex, j.link};
                part.joints.push_back(j);
                queue.push_back(child);
            }
        }
        m_parts.push_back(std::move(part));
    }
}

MultibodyRagdoll::Joint MultibodyRagdoll::treeJoint(int ci, int parent, int child,
                                                    const MultibodyJointParts& parts) const {
    const figure::Figure& f = m_asset->figure();
    const FigureConstraint& c = f.constraints[static_cast<std::size_t>(ci)];
    auto rotation = [&](int b) { return toBt(f.bodies[static_cast<std::size_t>(b)].loadPose.rotation); };
    const btTransform inChild = toBt(child == c.body1 ? c.frameInBody1 : c.frameInBody2);
    const btTransform inParent = toBt(child == c.body1 ? c.frameInBody2 : c.frameInBody1);
    Joint j;
    j.kind = parts.link;
    j.twistRow = parts.twistRow;
    j.child = child;
    j.parent = parent;
    j.zeroParentToChild = rotation(child).transpose() * rotation(parent);
    j.axisInChild = child == c.body1 ? parts.axisInBody1 : parts.axisInBody2;
    j.parentToPivot = inParent.getOrigin();
    j.pivotToChild = -inChild.getOrigin();
    j.frameInParent = inParent.getBasis();
    j.frameInChild = inChild.getBasis();
    return j;
}

void MultibodyRagdoll::buildTree(Part& part, const SpawnOptions& options) {
    const figure::Figure& f = m_asset->figure();
    const figure::FigureBody& base = f.bodies[static_cast<std::size_t>(part.root)];
    part.body = std::make_unique<btMultiBody>(static_cast<int>(part.joints.size()), static_cast<btScalar>(base.massKg),
                                              toBt(base.inertiaKgM2), part.fixedBase, false);
    btMultiBody& mb = *part.body;
    const btTransform baseWorld = m_spawn * toBt(base.loadPose);
    mb.setBasePos(baseWorld.getOrigin());
    mb.setWorldToBaseRot(quatOf(baseWorld.getBasis()).inverse());
    for (const Joint& j : part.joints) {
        const figure::FigureBody& b = f.bodies[static_cast<std::size_t>(j.child)];
        const btScalar m = static_cast<btScalar>(b.massKg);
        const btVector3 inertia = toBt(b.inertiaKgM2);
        const int parentLink = m_bodies[static_cast<std::size_t>(j.parent)].link;
        const btQuaternion q0 = quatOf(j.zeroParentToChild);
        switch (j.kind) {
        case LinkKind::Fixed:
            mb.setupFixed(j.link, m, inertia, parentLink, q0, j.parentToPivot, j.pivotToChild, true);
            break;
        case LinkKind::Spherical:
            mb.setupSpherical(j.link, m, inertia, parentLink, q0, j.parentToPivot, j.pivotToChild, true);
            break;
        case LinkKind::Revolute:
            mb.setupRevolute(j.link, m, inertia, parentLink, q0, j.axisInChild, j.parentToPivot, j.pivotToChild, true);
            break;
        case LinkKind::Prismatic:
            mb.setupPrismatic(j.link, m, inertia, parentLink, q0, j.axisInChild, j.parentToPivot, j.pivotToChild, true);
            break;
        }
    }
    mb.finalizeMultiDof();
    mb.setLinearDamping(0); // damping is the figure's, see dampVelocities
    mb.setAngularDamping(0);
    mb.setMaxCoordinateVelocity(kMaxCoordinateVelocity);
    mb.setHasSelfCollision(true); // pairs are decided by LinkCollider
    m_world.addMultiBody(part.body.get(), options.collisionGroup, options.collisionMask);
}

void MultibodyRagdoll::addColliders(const SpawnOptions& options) {
    const figure::Figure& f = m_asset->figure();
    for (std::size_t i = 0; i < f.bodies.size(); ++i) {
        const figure::FigureBody& b = f.bodies[i];
        const BodyRef ref = m_bodies[i];
        btMultiBody& mb = *m_parts[static_cast<std::size_t>(ref.part)].body;
        auto col = std::make_unique<LinkCollider>(&mb, ref.link, *this, static_cast<int>(i));
        col->setCollisionShape(m_asset->shape(static_cast<int>(i)));
        col->setWorldTransform(m_spawn * toBt(b.loadPose));
        col->setFriction(static_cast<btScalar>(b.contactFriction));
        col->setRestitution(static_cast<btScalar>(kBodyRestitution));
        int mask = options.collisionMask;
        if (figure::attachedToWorld(f, static_cast<int>(i))) mask &= ~btBroadphaseProxy::StaticFilter;
        if (b.clipMask == 0) mask = 0; // §6.2: a body with clipMask 0 does no collision tests
        if (options.engineContactFriction) {
            col->setUserIndex2(kEngineFrictionMarker);
            col->setCollisionFlags(col->getCollisionFlags() | btCollisionObject::CF_CUSTOM_MATERIAL_CALLBACK);
        }
        m_world.addCollisionObject(col.get(), options.collisionGroup, mask);
        if (ref.link < 0) mb.setBaseCollider(col.get());
        else mb.getLink(ref.link).m_collider = col.get();
        m_colliders.push_back(std::move(col));
    }
    btAlignedObjectArray<btScalar> r;
    btAlignedObjectArray<btVector3> v;
    btAlignedObjectArray<btMatrix3x3> m;
    for (Part& p : m_parts) {
        refreshTransforms(*p.body);
        // The articulated-body caches (what an impulse before the first step needs), with no force and no time.
        p.body->computeAccelerationsArticulatedBodyAlgorithmMultiDof(0, r, v, m, false, false, false);
    }
}

void MultibodyRagdoll::setJointCoordinates(btMultiBody& mb, const Joint& j, const figure::BodyState& parent,
                                           const figure::BodyState& child) {
    const btTransform tp = toBt(parent.pose), tc = toBt(child.pose);
    const btVector3 wRel = toBt(child.angularVelocity) - toBt(parent.angularVelocity);
    // Zero coordinates put the child at R_P·R0ᵀ; a revolute coordinate q turns it about its axis by q
    // (btMultibodyLink::updateCacheMultiDof), a spherical one by its quaternion, both in the child's frame.
    const btMatrix3x3 local = j.zeroParentToChild * tp.getBasis().transpose() * tc.getBasis();
    switch (j.kind) {
    case LinkKind::Fixed: break;
    case LinkKind::Revolute: {
        const btQuaternion q = quatOf(local);
        const btScalar along = btVector3(q.x(), q.y(), q.z()).dot(j.axisInChild);
        mb.setJointPos(j.link, 2 * btAtan2(along, q.w()));
        mb.setJointVel(j.link, (tc.getBasis() * j.axisInChild).dot(wRel));
        break;
    }
    case LinkKind::Prismatic: {
        const btVector3 offset = tc.getOrigin() - tp.getOrigin();
        const btVector3 inChild = tc.getBasis().transpose() * (offset - tp.getBasis() * j.parentToPivot);
        mb.setJointPos(j.link, (inChild - j.pivotToChild).dot(j.axisInChild));
        const btVector3 rel =
            toBt(child.linearVelocity) - toBt(parent.linearVelocity) - toBt(parent.angularVelocity).cross(offset);
        mb.setJointVel(j.link, (tc.getBasis() * j.axisInChild).dot(rel));
        break;
    }
    case LinkKind::Spherical: { // a universal joint's too; its twist row pulls a twisted pose back
        const btQuaternion q = quatOf(local);
        btScalar pos[4] = {q.x(), q.y(), q.z(), q.w()};
        mb.setJointPosMultiDof(j.link, pos);
        const btVector3 w = tc.getBasis().transpose() * wRel;
        btScalar vel[3] = {w.x(), w.y(), w.z()};
        mb.setJointVelMultiDof(j.link, vel);
        break;
    }
    }
}

void MultibodyRagdoll::setBodyStates(std::span<const figure::BodyState> states) {
    auto state = [&](int b) -> const figure::BodyState& { return states[static_cast<std::size_t>(b)]; };
    for (Part& p : m_parts) {
        btMultiBody& mb = *p.body;
        if (!p.fixedBase) { // a fixed base stays where the world holds it
            const figure::BodyState& s = state(p.root);
            const btTransform base = toBt(s.pose);
            mb.setBasePos(base.getOrigin());
            mb.setWorldToBaseRot(quatOf(base.getBasis()).inverse());
            mb.setBaseVel(toBt(s.linearVelocity));
            mb.setBaseOmega(toBt(s.angularVelocity));
        }
        for (const Joint& j : p.joints) setJointCoordinates(mb, j, state(j.parent), state(j.child));
        refreshTransforms(mb);
    }
    wake();
    recordMotion();
    publishVelocities(samples());
}

} // namespace afb::bullet::detail
