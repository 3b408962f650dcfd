// Warm-started joint rows (RagdollSolver.h).
#include "afb/bullet/RagdollSolver.h"

namespace afb::bullet {

void RagdollSolver::track(const btTypedConstraint& constraint) { m_rows.try_emplace(&constraint); }

void RagdollSolver::untrack(const btTypedConstraint& constraint) { m_rows.erase(&constraint); }

void RagdollSolver::convertJoints(btTypedConstraint** constraints, int numConstraints,
                                  const btContactSolverInfo& infoGlobal) {
    btSequentialImpulseConstraintSolver::convertJoints(constraints, numConstraints, infoGlobal);
    if (m_rows.empty() || (infoGlobal.m_solverMode & SOLVER_USE_WARMSTARTING) == 0) return;
    // The base class lays the rows out constraint by constraint, in the order given, m_numConstraintRows each.
    int row = 0;
    for (int i = 0; i < numConstraints; ++i) {
        const int rows = m_tmpConstraintSizesPool[i].m_numConstraintRows;
        const auto it = m_rows.find(constraints[i]);
        if (it != m_rows.end() && static_cast<int>(it->second.size()) == rows) {
            for (int k = 0; k < rows; ++k) {
                btSolverConstraint& c = m_tmpSolverNonContactConstraintPool[row + k];
                const btScalar start = it->second[static_cast<std::size_t>(k)] * infoGlobal.m_warmstartingFactor;
                c.m_appliedImpulse = btMax(c.m_lowerLimit, btMin(c.m_upperLimit, start));
                if (c.m_appliedImpulse == 0) continue;
                // As a solver iteration applies a row's impulse (resolveSingleConstraintRowGeneric).
                btSolverBody& a = m_tmpSolverBodyPool[c.m_solverBodyIdA];
                btSolverBody& b = m_tmpSolverBodyPool[c.m_solverBodyIdB];
                a.internalApplyImpulse(c.m_contactNormal1 * a.internalGetInvMass(), c.m_angularComponentA,
                                       c.m_appliedImpulse);
                b.internalApplyImpulse(c.m_contactNormal2 * b.internalGetInvMass(), c.m_angularComponentB,
                                       c.m_appliedImpulse);
            }
        }
        row += rows;
    }
}

btScalar RagdollSolver::solveGroupCacheFriendlyFinish(btCollisionObject** bodies, int numBodies,
                                                      const btContactSolverInfo& infoGlobal) {
    if (!m_rows.empty()) {
        // Rows of one constraint are consecutive; each row names its constraint.
        std::vector<btScalar>* impulses = nullptr;
        const void* current = nullptr;
        for (int j = 0; j < m_tmpSolverNonContactConstraintPool.size(); ++j) {
            const btSolverConstraint& c = m_tmpSolverNonContactConstraintPool[j];
            if (c.m_originalContactPoint != current) {
                current = c.m_originalContactPoint;
                const auto it = m_rows.find(static_cast<const btTypedConstraint*>(current));
                impulses = it != m_rows.end() ? &it->second : nullptr;
                if (impulses) impulses->clear();
            }
            if (impulses) impulses->push_back(c.m_appliedImpulse);
        }
    }
    return btSequentialImpulseConstraintSolver::solveGroupCacheFriendlyFinish(bodies, numBodies, infoGlobal);
}

} // namespace afb::bullet
