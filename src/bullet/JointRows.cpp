// The rows of the world's constraints, set up by the solver itself (RagdollSolver.h): Bullet's arithmetic, in
// one pass per constraint that also warm-starts and softens a tracked constraint's rows.
//
// Bullet's own setup (btSequentialImpulseConstraintSolver::convertJoints) computes each row's angular
// components and its effective mass with four products of an inverse inertia by a torque axis, where two give
// the same result twice; it reads each body's velocity and external impulses again for every row; and the
// tracked constraints then need a second pass over every row. Here each product is taken once, a constraint's
// body velocities are read once, and a row is finished while it is in cache. Every value is rounded as Bullet
// rounds it (the same operations on the same operands in the same order), so the rows, and every result after
// them, are Bullet's to the bit. With SIMD rows off (setSimdRows: plain Bullet's reference, `raw`), Bullet's own
// setup runs instead, so that the reference costs what Bullet costs.
#include <cstring>
#include <typeinfo>

#include "afb/bullet/RagdollSolver.h"

namespace afb::bullet {

void RagdollSolver::convertJoints(btTypedConstraint** constraints, int numConstraints,
                                  const btContactSolverInfo& infoGlobal) {
    const bool warmStarting = (infoGlobal.m_solverMode & SOLVER_USE_WARMSTARTING) != 0;
    if (!m_simdRows) { // Bullet's own setup, so that plain Bullet's reference costs what Bullet costs
        btSequentialImpulseConstraintSolver::convertJoints(constraints, numConstraints, infoGlobal);
        if (m_rows.size() == 0) return;
        int row = 0;
        for (int i = 0; i < numConstraints; ++i) {
            const int rows = m_tmpConstraintSizesPool[i].m_numConstraintRows;
            if (const Tracked* t = m_rows.find(btHashPtr(constraints[i])); t != nullptr && rows > 0)
                startTrackedRows(&m_tmpSolverNonContactConstraintPool[row], rows, *t, warmStarting,
                                 infoGlobal.m_warmstartingFactor);
            row += rows;
        }
        return;
    }
    for (int j = 0; j < numConstraints; ++j) {
        // A point-to-point constraint's buildJacobian fills Jacobian entries that only Bullet's retired solve read
        // (getInfo2 works from the pivots): skipped for that exact class, called for every other.
        if (typeid(*constraints[j]) != typeid(btPoint2PointConstraint)) constraints[j]->buildJacobian();
        constraints[j]->internalSetAppliedImpulse(0);
    }
    int totalRows = 0;
    m_tmpConstraintSizesPool.resizeNoInitialize(numConstraints);
    for (int i = 0; i < numConstraints; ++i) {
        btTypedConstraint::btConstraintInfo1& info1 = m_tmpConstraintSizesPool[i];
        if (btJointFeedback* fb = constraints[i]->getJointFeedback()) {
            fb->m_appliedForceBodyA.setZero();
            fb->m_appliedTorqueBodyA.setZero();
            fb->m_appliedForceBodyB.setZero();
            fb->m_appliedTorqueBodyB.setZero();
        }
        if (constraints[i]->isEnabled()) {
            constraints[i]->getInfo1(&info1);
        } else {
            info1.m_numConstraintRows = 0;
            info1.nub = 0;
        }
        totalRows += info1.m_numConstraintRows;
    }
    m_tmpSolverNonContactConstraintPool.resizeNoInitialize(totalRows);
    int row = 0;
    for (int i = 0; i < numConstraints; ++i) {
        const btTypedConstraint::btConstraintInfo1& info1 = m_tmpConstraintSizesPool[i];
        const int rows = info1.m_numConstraintRows;
        if (rows == 0) continue;
        btTypedConstraint& constraint = *constraints[i];
        const int idA = getOrInitSolverBody(constraint.getRigidBodyA(), infoGlobal.m_timeStep);
        const int idB = getOrInitSolverBody(constraint.getRigidBodyB(), infoGlobal.m_timeStep);
        btSolverConstraint* first = &m_tmpSolverNonContactConstraintPool[row];
        setUpJointRows(first, constraint, rows, idA, idB, infoGlobal);
        // The row setup reads the rigid bodies' velocities, never the solver bodies' deltas that a warm start
        // writes: applying it here, constraint by constraint in the pool's order, sums the same impulses in the
        // same order as a pass after every row is set up.
        if (m_rows.size() > 0)
            if (const Tracked* t = m_rows.find(btHashPtr(&constraint)))
                startTrackedRows(first, rows, *t, warmStarting, infoGlobal.m_warmstartingFactor);
        row += rows;
    }
}

// btSequentialImpulseConstraintSolver::convertJoint's rows, each value rounded as there.
void RagdollSolver::setUpJointRows(btSolverConstraint* rows, btTypedConstraint& constraint, int count, int idA, int idB,
                                   const btContactSolverInfo& infoGlobal) {
    const btRigidBody& rbA = constraint.getRigidBodyA();
    const btRigidBody& rbB = constraint.getRigidBodyB();
    const btSolverBody& bodyA = m_tmpSolverBodyPool[idA];
    const btSolverBody& bodyB = m_tmpSolverBodyPool[idB];
    const int iterations = constraint.getOverrideNumSolverIterations() > 0 ? constraint.getOverrideNumSolverIterations()
                                                                           : infoGlobal.m_numIterations;
    if (iterations > m_maxOverrideNumSolverIterations) m_maxOverrideNumSolverIterations = iterations;
    for (int j = 0; j < count; ++j) {
        btSolverConstraint& c = rows[j];
        std::memset(static_cast<void*>(&c), 0, sizeof(btSolverConstraint)); // what getInfo2 leaves is zero
        c.m_lowerLimit = -SIMD_INFINITY;
        c.m_upperLimit = SIMD_INFINITY;
        c.m_solverBodyIdA = idA;
        c.m_solverBodyIdB = idB;
        c.m_overrideNumSolverIterations = iterations;
    }
    btTypedConstraint::btConstraintInfo2 info2;
    info2.fps = 1.f / infoGlobal.m_timeStep;
    info2.erp = infoGlobal.m_erp;
    info2.m_J1linearAxis = rows->m_contactNormal1;
    info2.m_J1angularAxis = rows->m_relpos1CrossNormal;
    info2.m_J2linearAxis = rows->m_contactNormal2;
    info2.m_J2angularAxis = rows->m_relpos2CrossNormal;
    info2.rowskip = sizeof(btSolverConstraint) / sizeof(btScalar);
    info2.m_constraintError = &rows->m_rhs;
    rows->m_cfm = infoGlobal.m_globalCfm;
    info2.m_damping = infoGlobal.m_damping;
    info2.cfm = &rows->m_cfm;
    info2.m_lowerLimit = &rows->m_lowerLimit;
    info2.m_upperLimit = &rows->m_upperLimit;
    info2.m_numIterations = infoGlobal.m_numIterations;
    constraint.getInfo2(&info2);

    const btScalar breaking = constraint.getBreakingImpulseThreshold();
    const btMatrix3x3& invInertiaA = rbA.getInvInertiaTensorWorld();
    const btMatrix3x3& invInertiaB = rbB.getInvInertiaTensorWorld();
    const btVector3 zero(0, 0, 0);
    const btVector3 linearA = rbA.getLinearVelocity() + (bodyA.m_originalBody ? bodyA.m_externalForceImpulse : zero);
    const btVector3 angularA = rbA.getAngularVelocity() + (bodyA.m_originalBody ? bodyA.m_externalTorqueImpulse : zero);
    const btVector3 linearB = rbB.getLinearVelocity() + (bodyB.m_originalBody ? bodyB.m_externalForceImpulse : zero);
    const btVector3 angularB = rbB.getAngularVelocity() + (bodyB.m_originalBody ? bodyB.m_externalTorqueImpulse : zero);
    for (int j = 0; j < count; ++j) {
        btSolverConstraint& c = rows[j];
        if (c.m_upperLimit >= breaking) c.m_upperLimit = breaking;
        if (c.m_lowerLimit <= -breaking) c.m_lowerLimit = -breaking;
        c.m_originalContactPoint = &constraint;
        const btVector3 turnA = invInertiaA * c.m_relpos1CrossNormal; // M⁻¹ of the angular Jacobian, side A
        const btVector3 turnB = invInertiaB * c.m_relpos2CrossNormal;
        c.m_angularComponentA = turnA * rbA.getAngularFactor();
        c.m_angularComponentB = turnB * rbB.getAngularFactor();
        btScalar sum = (c.m_contactNormal1 * rbA.getInvMass()).dot(c.m_contactNormal1);
        sum += turnA.dot(c.m_relpos1CrossNormal);
        sum += (c.m_contactNormal2 * rbB.getInvMass()).dot(c.m_contactNormal2);
        sum += turnB.dot(c.m_relpos2CrossNormal);
        c.m_jacDiagABInv = btFabs(sum) > SIMD_EPSILON ? 1.f / sum : 0.f;
        const btScalar velocityA = c.m_contactNormal1.dot(linearA) + c.m_relpos1CrossNormal.dot(angularA);
        const btScalar velocityB = c.m_contactNormal2.dot(linearB) + c.m_relpos2CrossNormal.dot(angularB);
        const btScalar relativeVelocity = velocityA + velocityB;
        const btScalar positionalError = c.m_rhs; // getInfo2's
        const btScalar velocityError = btScalar(0) - relativeVelocity * info2.m_damping;
        c.m_rhs = positionalError * c.m_jacDiagABInv + velocityError * c.m_jacDiagABInv;
        c.m_appliedImpulse = 0.f;
    }
}

// A tracked constraint's rows: softened when the constraint is soft, then started from their last impulses.
void RagdollSolver::startTrackedRows(btSolverConstraint* rows, int count, const Tracked& t, bool warmStarting,
                                     btScalar factor) {
    if (t.soft)
        for (int k = 0; k < count; ++k) softenRow(rows[k]);
    if (!warmStarting || !t.warmStart || t.rows != count) return;
    for (int k = 0; k < count; ++k) {
        btSolverConstraint& c = rows[k];
        const btScalar start = t.impulses[k] * factor;
        c.m_appliedImpulse = btMax(c.m_lowerLimit, btMin(c.m_upperLimit, start));
        if (c.m_appliedImpulse == 0) continue;
        // As a solver iteration applies a row's impulse (resolveSingleConstraintRowGeneric).
        btSolverBody& a = m_tmpSolverBodyPool[c.m_solverBodyIdA];
        btSolverBody& b = m_tmpSolverBodyPool[c.m_solverBodyIdB];
        a.internalApplyImpulse(c.m_contactNormal1 * a.internalGetInvMass(), c.m_angularComponentA, c.m_appliedImpulse);
        b.internalApplyImpulse(c.m_contactNormal2 * b.internalGetInvMass(), c.m_angularComponentB, c.m_appliedImpulse);
    }
}

} // namespace afb::bullet
