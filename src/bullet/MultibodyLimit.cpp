// Limit and twist rows on the trees (MultibodyRows.h): docs/format.md §4.3 and §4.5 limits, §4.4 the universal
// joint's twist, as rows over the whole tree and as position sweeps.
#include <cmath>

#include "MultibodyRows.h"

namespace afb::bullet::detail {

namespace {

// The twist of frame B relative to frame A about their X axes, as a row in directionLimitRows' convention: the
// excess grows at axis·(ωA − ωB).
int twistRow(const btMatrix3x3& frameA, const btMatrix3x3& frameB, LimitRow& out) {
    btQuaternion q = quatOf(frameA.transpose() * frameB);
    if (q.w() < 0) q = -q;
    const btVector3 bisector = frameA.getColumn(0) + frameB.getColumn(0);
    if (bisector.length2() < btScalar(1e-6)) return 0; // swung 180°: no twist axis (a limit prevents it)
    out.axisWorld = -bisector.normalized();
    out.excess = 2 * btAtan2(q.x(), q.w());
    return 1;
}

} // namespace

void MultibodyLimit::createConstraintRows(btMultiBodyConstraintArray& rows, btMultiBodyJacobianData& data,
                                          const btContactSolverInfo& info) {
    finalizeOnce();
    const btScalar dt = info.m_timeStep;
    btScalar margin = 0;
    if (m_policy.speculative && m_a.angularVelocity) {
        // As the rigid rows: the angle the joint can turn in about two steps at its current rate.
        const btVector3 wB = m_b.angularVelocity ? *m_b.angularVelocity : btVector3(0, 0, 0);
        margin = (*m_a.angularVelocity - wB).length() * dt * 2 + btScalar(0.01);
    }
    LimitRow found[2];
    const int n = rowsNow(margin, found);
    const auto* twist = std::get_if<Twist>(&m_limit);
    const btVector3 zero(0, 0, 0);
    const btVector3 pointA = m_a.body->getWorldTransform().getOrigin();
    for (int i = 0; i < n; ++i) {
        const LimitRow& r = found[i];
        fillJacobian(r.axisWorld, data.scratch_r, data.scratch_v, data.scratch_m);
        // Target row velocity: past the limit, Baumgarte recovery of the limit ERP per step; before it
        // (speculative), the joint may close at most the remaining gap in this step. Bullet turns the
        // position error e into the target −e·erp/dt with the world's joint ERP, so e is scaled by it.
        // A twist row is an equality: the joint ERP's Baumgarte recovery of its angle, both ways.
        const btScalar target = twist          ? info.m_erp * r.excess / dt
                                : r.excess > 0 ? m_policy.errorReduction * r.excess / dt
                                               : r.excess / dt;
        const btScalar erp = info.m_erp > 0 ? info.m_erp : btScalar(1);
        addRow(rows, data, info,
               {m_jac.data(), nullptr, -r.axisWorld, zero, pointA, pointA, -target * dt / erp,
                twist ? -SIMD_INFINITY : 0, SIMD_INFINITY, true},
               i);
    }
}

btScalar MultibodyLimit::correctPositions(btAlignedObjectArray<btScalar>& r, btAlignedObjectArray<btVector3>& v,
                                          btAlignedObjectArray<btMatrix3x3>& m, btAlignedObjectArray<btQuaternion>& q,
                                          btAlignedObjectArray<btVector3>& o) {
    finalizeOnce();
    const bool twist = std::holds_alternative<Twist>(m_limit);
    btScalar worst = 0;
    for (int pass = 0; pass < 2; ++pass) { // a pyramid's corner: both rows, each from the pose the other left
        LimitRow found[2];
        const int n = rowsNow(0, found);
        const LimitRow* row = nullptr;
        for (int i = 0; i < n; ++i)
            if ((found[i].excess > 0 || (twist && std::abs(found[i].excess) > kTwistSlopRad)) &&
                (!row || std::abs(found[i].excess) > std::abs(row->excess)))
                row = &found[i];
        if (!row) break;
        const btScalar excess = row->excess;
        if (pass == 0) worst = std::abs(excess);
        fillJacobian(row->axisWorld, r, v, m);
        m_move.resize(m_jac.size());
        m_bodyA->calcAccelerationDeltasMultiDof(m_jac.data(), m_move.data(), r, v);
        btScalar w = 0;
        for (std::size_t k = 0; k < m_jac.size(); ++k) w += m_jac[k] * m_move[k];
        if (!(w > SIMD_EPSILON)) break;
        // J·Δq is how far the excess falls (the row's velocity times one), so Δq = M⁻¹Jᵀ·excess/w closes it.
        for (btScalar& x : m_move) x *= excess / w;
        m_bodyA->stepPositionsMultiDof(1, nullptr, m_move.data());
        m_bodyA->forwardKinematics(q, o);
        m_bodyA->updateCollisionObjectWorldTransforms(q, o);
    }
    return worst;
}

// The rows of this limit at the present pose (the colliders' transforms), with the speculative margin.
int MultibodyLimit::rowsNow(btScalar margin, LimitRow found[2]) const {
    const btMatrix3x3 rotA = m_a.body->getWorldTransform().getBasis();
    const btMatrix3x3 rotB = m_b.body ? m_b.body->getWorldTransform().getBasis() : btMatrix3x3::getIdentity();
    if (const auto* d = std::get_if<Direction>(&m_limit))
        return directionLimitRows(rotA * d->shaftInA, rotB * d->basisInB, d->shape, d->half1, d->half2, margin, found);
    if (const auto* h = std::get_if<Hinge>(&m_limit))
        return hingeRangeRow(rotA * h->frameInA, rotB * h->frameInB, h->lower, h->upper, margin, found[0]);
    const Twist& t = std::get<Twist>(m_limit);
    return twistRow(rotA * t.frameInA, rotB * t.frameInB, found[0]);
}

// m_jac = the Jacobian of a row about `axisWorld` over the whole tree. The excess grows at axis·(ωA − ωB): the row's
// velocity J·q̇ = (ωB − ωA)·axis, so a positive impulse reduces the excess (as setLimitRow's rows for rigid bodies).
void MultibodyLimit::fillJacobian(const btVector3& axisWorld, btAlignedObjectArray<btScalar>& r,
                                  btAlignedObjectArray<btVector3>& v, btAlignedObjectArray<btMatrix3x3>& m) {
    const int ndof = m_bodyA->getNumDofs() + 6;
    m_jac.resize(static_cast<std::size_t>(ndof));
    m_jacB.resize(static_cast<std::size_t>(ndof));
    const btVector3 zero(0, 0, 0);
    const btVector3 pointA = m_a.body->getWorldTransform().getOrigin();
    m_bodyA->fillConstraintJacobianMultiDof(m_a.link, pointA, axisWorld, zero, m_jac.data(), r, v, m);
    if (m_b.body) {
        m_bodyA->fillConstraintJacobianMultiDof(m_b.link, pointA, axisWorld, zero, m_jacB.data(), r, v, m);
        for (int k = 0; k < ndof; ++k) m_jac[static_cast<std::size_t>(k)] = m_jacB[k] - m_jac[k];
    } else {
        for (int k = 0; k < ndof; ++k) m_jac[static_cast<std::size_t>(k)] = -m_jac[k];
    }
}

} // namespace afb::bullet::detail
