// The multibody backend's position sweeps (Multibody.h): after each substep, limits and twists first, then the
// contacts of the ragdoll's bodies, each closed by moving its tree along M⁻¹Jᵀ (velocities untouched).
#include <algorithm>

#include <BulletDynamics/Featherstone/btMultiBody.h>
#include <BulletDynamics/Featherstone/btMultiBodyDynamicsWorld.h>
#include <BulletDynamics/Featherstone/btMultiBodyLinkCollider.h>

#include "Multibody.h"

namespace afb::bullet::detail {

namespace {

// The position sweeps' contacts, as the rigid backend's position pass (PositionPass.cpp): only what is deeper than
// the slop, half of it per sweep, so resting contacts are not pushed apart and re-made every substep; depths below
// the tolerance are left alone.
constexpr btScalar kSweepContactSlopM = btScalar(0.002);
constexpr btScalar kSweepContactFraction = btScalar(0.5);
constexpr btScalar kSweepToleranceM = btScalar(1e-4);

} // namespace

void MultibodyRagdoll::correctPositions() {
    if (m_positionIterations <= 0) return;
    // This substep's contacts of the ragdoll's bodies (found at the start of the substep; their depths are
    // recomputed from the bodies' poses as the sweeps move them).
    m_sweepContacts.clear();
    btDispatcher& dispatcher = *m_world.getDispatcher();
    for (int i = 0, n = dispatcher.getNumManifolds(); i < n; ++i) {
        btPersistentManifold* m = dispatcher.getManifoldByIndexInternal(i);
        if (m->getNumContacts() == 0) continue;
        const int a = bodyOfCollider(m->getBody0()), b = bodyOfCollider(m->getBody1());
        if (a >= 0 || b >= 0) m_sweepContacts.push_back({m, a, b});
    }
    btAlignedObjectArray<btScalar> r;
    btAlignedObjectArray<btVector3> v;
    btAlignedObjectArray<btMatrix3x3> m;
    btAlignedObjectArray<btQuaternion> q;
    btAlignedObjectArray<btVector3> o;
    for (int sweep = 0; sweep < m_positionIterations; ++sweep) {
        btScalar worst = 0;
        bool corrected = false;
        for (MultibodyLimit* c : m_swept) worst = std::max(worst, c->correctPositions(r, v, m, q, o));
        // Contacts last, so that a sweep ends with the limbs the limits moved out of the ground again.
        for (const SweepContact& c : m_sweepContacts)
            for (int k = 0; k < c.manifold->getNumContacts(); ++k)
                corrected = correctContact(c, c.manifold->getContactPoint(k), r, v, m, q, o) || corrected;
        if (worst == 0 && !corrected) break;
    }
}

bool MultibodyRagdoll::correctContact(const SweepContact& c, const btManifoldPoint& cp,
                                      btAlignedObjectArray<btScalar>& r, btAlignedObjectArray<btVector3>& v,
                                      btAlignedObjectArray<btMatrix3x3>& m, btAlignedObjectArray<btQuaternion>& q,
                                      btAlignedObjectArray<btVector3>& o) {
    // The depth now: the ragdoll's sides carry their points along, other objects keep the world points found.
    const btVector3 pa = c.bodyA >= 0
                             ? m_colliders[static_cast<std::size_t>(c.bodyA)]->getWorldTransform() * cp.m_localPointA
                             : cp.m_positionWorldOnA;
    const btVector3 pb = c.bodyB >= 0
                             ? m_colliders[static_cast<std::size_t>(c.bodyB)]->getWorldTransform() * cp.m_localPointB
                             : cp.m_positionWorldOnB;
    const btVector3& n = cp.m_normalWorldOnB; // from B towards A
    const btScalar depth = -(pa - pb).dot(n) - kSweepContactSlopM;
    if (depth <= kSweepToleranceM) return false;
    const BodyRef refA = c.bodyA >= 0 ? m_bodies[static_cast<std::size_t>(c.bodyA)] : BodyRef{-1, -1};
    const BodyRef refB = c.bodyB >= 0 ? m_bodies[static_cast<std::size_t>(c.bodyB)] : BodyRef{-1, -1};
    bool corrected = false;
    // One tree at a time: a contact between two bodies of one tree is one row over it (J_A − J_B); between two
    // trees (parts joined by a spring only), each tree takes half, the other counted immovable.
    for (const int side : {0, 1}) {
        const BodyRef& ref = side == 0 ? refA : refB;
        const int body = side == 0 ? c.bodyA : c.bodyB;
        if (body < 0 || (side == 1 && refA.part == refB.part && c.bodyA >= 0)) continue;
        btMultiBody& mb = *m_parts[static_cast<std::size_t>(ref.part)].body;
        const std::size_t ndof = static_cast<std::size_t>(mb.getNumDofs() + 6);
        m_sweepJac.assign(ndof, 0);
        m_sweepJacB.resize(ndof);
        m_sweepMove.resize(ndof);
        // J·q̇ = (v_A − v_B)·n: the rate at which the depth falls.
        mb.fillContactJacobianMultiDof(ref.link, side == 0 ? pa : pb, side == 0 ? n : -n, m_sweepJac.data(), r, v, m);
        const bool both = c.bodyA >= 0 && c.bodyB >= 0 && refA.part == refB.part;
        if (both) {
            mb.fillContactJacobianMultiDof(refB.link, pb, -n, m_sweepJacB.data(), r, v, m);
            for (std::size_t k = 0; k < ndof; ++k) m_sweepJac[k] += m_sweepJacB[k];
        }
        mb.calcAccelerationDeltasMultiDof(m_sweepJac.data(), m_sweepMove.data(), r, v);
        btScalar w = 0;
        for (std::size_t k = 0; k < ndof; ++k) w += m_sweepJac[k] * m_sweepMove[k];
        if (!(w > SIMD_EPSILON)) continue;
        const bool shared = c.bodyA >= 0 && c.bodyB >= 0 && !both;
        const btScalar close = kSweepContactFraction * depth * (shared ? btScalar(0.5) : btScalar(1));
        for (btScalar& x : m_sweepMove) x *= close / w;
        mb.stepPositionsMultiDof(1, nullptr, m_sweepMove.data());
        mb.forwardKinematics(q, o);
        mb.updateCollisionObjectWorldTransforms(q, o);
        corrected = true;
    }
    return corrected;
}

} // namespace afb::bullet::detail
