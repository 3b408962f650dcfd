// The multibody backend's rows other than limits (MultibodyRows.h): the energy guard, docs/format.md §4.8 joint
// friction and §4.7 springs, and what they share (a tree's motion, the Jacobian of a relative motion, adding a row).
#include "MultibodyRows.h"

#include <algorithm>
#include <cmath>

namespace afb::bullet::detail {

btQuaternion quatOf(const btMatrix3x3& m) {
    btQuaternion q;
    m.getRotation(q);
    return q;
}

TreeMotion treeMotion(const btMultiBody& mb) {
    const std::size_t n = static_cast<std::size_t>(mb.getNumLinks() + 1);
    btAlignedObjectArray<btVector3> w, v;
    w.resize(static_cast<int>(n));
    v.resize(static_cast<int>(n));
    mb.compTreeLinkVelocities(&w[0], &v[0]); // in each link's frame
    TreeMotion out;
    for (int k = 0; k < static_cast<int>(n); ++k) {
        const bool base = k == 0;
        const btScalar m = base ? mb.getBaseMass() : mb.getLinkMass(k - 1);
        const btVector3& inertia = base ? mb.getBaseInertia() : mb.getLinkInertia(k - 1);
        const btMatrix3x3 toWorld =
            base ? btMatrix3x3(mb.getWorldToBaseRot().inverse()) : mb.getLink(k - 1).m_cachedWorldTransform.getBasis();
        out.energy += 0.5 * static_cast<double>(m * v[k].length2() + w[k].dot(inertia * w[k]));
        out.momentum += toWorld * v[k] * m;
        out.mass += m;
    }
    return out;
}

void relativeJacobian(btMultiBody& tree, int linkA, const btVector3& pointA, std::optional<int> linkB,
                      const btVector3& pointB, const btVector3& axisWorld, const btVector3& normalWorld,
                      std::vector<btScalar>& jac, std::vector<btScalar>& scratch, btAlignedObjectArray<btScalar>& r,
                      btAlignedObjectArray<btVector3>& v, btAlignedObjectArray<btMatrix3x3>& m) {
    const std::size_t ndof = static_cast<std::size_t>(tree.getNumDofs() + 6);
    jac.resize(ndof);
    scratch.resize(ndof);
    tree.fillConstraintJacobianMultiDof(linkA, pointA, axisWorld, normalWorld, jac.data(), r, v, m);
    if (!linkB) return;
    tree.fillConstraintJacobianMultiDof(*linkB, pointB, axisWorld, normalWorld, scratch.data(), r, v, m);
    for (std::size_t k = 0; k < ndof; ++k) jac[k] -= scratch[k];
}

btMultiBodySolverConstraint& TreeRows::addRow(btMultiBodyConstraintArray& rows, btMultiBodyJacobianData& data,
                                              const btContactSolverInfo& info, const Row& r, int index) {
    btMultiBodySolverConstraint& row = rows.expandNonInitializing();
    row.m_solverBodyIdA = data.m_fixedBodyId;
    row.m_solverBodyIdB = data.m_fixedBodyId;
    fillMultiBodyConstraint(row, data, r.jacA, r.jacB, r.angular, r.linear, r.pointA, r.pointB, r.positionError, info,
                            r.lower, r.upper, r.angularOnly, 1, false, 0, 0, 1);
    row.m_orgConstraint = this;
    row.m_orgDofIndex = index;
    return row;
}

void EnergyGuard::record() {
    const TreeMotion t = treeMotion(*m_bodyA);
    m_energy = t.energy;
    m_momentum = t.momentum;
}

void EnergyGuard::createConstraintRows(btMultiBodyConstraintArray&, btMultiBodyJacobianData& data,
                                       const btContactSolverInfo& info) {
    btMultiBody& mb = *m_bodyA;
    const TreeMotion now = treeMotion(mb);
    const double dt = info.m_timeStep;
    const btVector3 g = m_world.getGravity();
    // Gravity's work in one semi-implicit step: g·p·dt + ½·M·g²·dt² (exact for a free fall); a small relative
    // slack keeps the guard out of ordinary motion.
    const double fall = 0.5 * static_cast<double>(now.mass * g.length2()) * dt * dt;
    const double allowed =
        m_energy + static_cast<double>(g.dot(m_momentum)) * dt + fall + kSlack * (m_energy + fall) + 1e-9;
    if (!(now.energy > allowed)) return;
    const btVector3 vCom = mb.hasFixedBase() || !(now.mass > 0) ? btVector3(0, 0, 0) : now.momentum / now.mass;
    const double translation = 0.5 * static_cast<double>(now.mass * vCom.length2());
    const double relative = now.energy - translation;
    if (!(relative > 0)) return;
    const btScalar k = static_cast<btScalar>(std::sqrt(std::max(0.0, allowed - translation) / relative));
    // The change, in Bullet's layout of a tree's velocities: base ω, base v (world), then every joint's.
    const int n = mb.getNumDofs() + 6;
    m_delta.resize(static_cast<std::size_t>(n));
    const btScalar* q = mb.getVelocityVector();
    for (int i = 0; i < n; ++i) m_delta[static_cast<std::size_t>(i)] = (k - 1) * q[i];
    if (mb.hasFixedBase()) std::fill(m_delta.begin(), m_delta.begin() + 6, btScalar(0));
    else
        for (int i = 3; i < 6; ++i) m_delta[static_cast<std::size_t>(i)] = (k - 1) * (q[i] - vCom[i - 3]);
    // Contacts and limits have already built their rows from the velocities (the solver converts contacts before
    // any multibody constraint), so the change goes in as a solver velocity change, as an impulse's would: every row
    // then sees it. A tree no row touches yet takes it directly.
    const int companion = mb.getCompanionId();
    if (companion >= 0) {
        for (int i = 0; i < n; ++i) data.m_deltaVelocities[companion + i] += m_delta[static_cast<std::size_t>(i)];
        mb.applyDeltaVeeMultiDof2(m_delta.data(), 1);
    } else {
        mb.applyDeltaVeeMultiDof(m_delta.data(), 1);
    }
}

void MultibodyFriction::createConstraintRows(btMultiBodyConstraintArray& rows, btMultiBodyJacobianData& data,
                                             const btContactSolverInfo& info) {
    if (!(m_maxImpulse > 0)) return;
    finalizeOnce();
    const btMatrix3x3 rotB = m_bodyBObject ? m_bodyBObject->getWorldTransform().getBasis() : btMatrix3x3::getIdentity();
    const btVector3 zero(0, 0, 0);
    const btVector3 point = m_bodyAObject.getWorldTransform().getOrigin();
    for (int i = 0; i < m_count; ++i) {
        const btVector3 axis = rotB * m_axesInB.getColumn(i);
        relativeJacobian(*m_bodyA, m_linkA, point, m_linkBOpt, point, axis, zero, m_jac, m_scratch, data.scratch_r,
                         data.scratch_v, data.scratch_m);
        addRow(rows, data, info,
               {m_jac.data(), nullptr, axis, zero, point, point, 0, -m_maxImpulse, m_maxImpulse, true}, i);
    }
}

btMultiBodySolverConstraint& MultibodySpring::lengthRow(btMultiBodyConstraintArray& rows, btMultiBodyJacobianData& data,
                                                        const btContactSolverInfo& info, const btVector3& pa,
                                                        const btVector3& pb, const btVector3& n, btScalar posError,
                                                        btScalar lo, btScalar hi, int index) {
    const btVector3 zero(0, 0, 0);
    const bool oneTree = m_bodyB == nullptr;
    relativeJacobian(*m_bodyA, m_linkA, pa, oneTree && m_b.tree ? std::optional<int>(m_linkB) : std::nullopt, pb, zero,
                     n, m_jacA, m_scratch, data.scratch_r, data.scratch_v, data.scratch_m);
    if (!oneTree) {
        relativeJacobian(*m_bodyB, m_linkB, pb, std::nullopt, pb, zero, -n, m_jacB, m_scratch, data.scratch_r,
                         data.scratch_v, data.scratch_m);
    }
    return addRow(rows, data, info,
                  {m_jacA.data(), oneTree ? nullptr : m_jacB.data(), zero, n, pa, pb, posError, lo, hi, false}, index);
}

void MultibodySpring::createConstraintRows(btMultiBodyConstraintArray& rows, btMultiBodyJacobianData& data,
                                           const btContactSolverInfo& info) {
    finalizeOnce();
    const btVector3 pa = pointA(), pb = pointB();
    const btVector3 d = pb - pa;
    const btScalar length = d.length();
    if (!(length > SIMD_EPSILON)) return;
    const btVector3 n = d / length;
    const btScalar dt = info.m_timeStep;
    // The force: the engine's terms from the anchors' relative speed along n (the row's velocity), each bounded
    // through the row's effective mass (SpringConstraint::impulse). A positive impulse pulls the anchors together.
    const btScalar rest = m_params.restLength;
    const btScalar k = length > rest ? m_params.stretch : m_params.compress;
    if (k > 0) {
        btMultiBodySolverConstraint& row = lengthRow(rows, data, info, pa, pb, n, 0, 0, 0, 0);
        const btScalar speed = btFabs(rowVelocity());
        const btScalar sign = length > rest ? 1 : -1;
        const btScalar deviation = btFabs(length - rest);
        btScalar spring = k * deviation * deviation * dt;
        btScalar damping = m_params.damping * speed / length * dt;
        const btScalar mass = row.m_jacDiagABInv; // 1 / (J·M⁻¹·Jᵀ); 0 for a row nothing can move
        if (mass > 0) {
            spring = btMin(spring, mass * deviation / dt);
            damping = btMin(damping, mass * speed);
        }
        const btScalar pull = sign * (spring - damping);
        row.m_rhs = 0;
        row.m_lowerLimit = pull;
        row.m_upperLimit = pull;
    }
    if (length < m_params.minLength)
        lengthRow(rows, data, info, pa, pb, n, m_params.minLength - length, -SIMD_INFINITY, 0, 1);
    else if (m_params.maxLength > 0 && length > m_params.maxLength)
        lengthRow(rows, data, info, pa, pb, n, m_params.maxLength - length, 0, SIMD_INFINITY, 1);
}

btScalar MultibodySpring::rowVelocity() const {
    btScalar v = 0;
    const btScalar* q = m_bodyA->getVelocityVector();
    for (std::size_t i = 0; i < m_jacA.size(); ++i) v += m_jacA[i] * q[i];
    if (m_bodyB) {
        const btScalar* qb = m_bodyB->getVelocityVector();
        for (std::size_t i = 0; i < m_jacB.size(); ++i) v += m_jacB[i] * qb[i];
    }
    return v;
}

} // namespace afb::bullet::detail
