// The direct joint solve's iterations (DirectSolve.h).
#include <algorithm>
#include <cmath>
#include <limits>

#include "DirectSolve.h"
#include "RowKernels.h"

namespace afb::bullet {

using direct::addScaled;
using direct::Vec;

namespace {

// Whether every entry is finite: 0·x is NaN exactly when x is not, and NaN stays NaN through a sum.
bool allFinite(const std::vector<double>& v) {
    double zero = 0;
    for (const double x : v) zero += 0 * x;
    return zero == 0;
}

} // namespace

double RagdollSolver::Direct::solveJoints(btAlignedObjectArray<btSolverBody>& bodyPool,
                                          const btAlignedObjectArray<btSolverConstraint>& pool) {
    double residual = 0;
    for (Group& group : live()) {
        if (group.useArticulated) {
            // The velocity changes projected onto the rows' targets, M Δv′ = M Δv + Jᵀλ and J Δv′ = target, without
            // reading a row (the impulses follow from the momentum at the end). The solve is exact: the residual
            // the joints leave is the other rows' disturbance, which their own residual measures.
            const std::size_t nb = group.bodies.size();
            solveX.resize(6 * nb);
            for (std::size_t xb = 0; xb < nb; ++xb) {
                const btSolverBody& b = *group.bodyOf[xb];
                double* dv = solveX.data() + 6 * xb;
                for (int q = 0; q < 3; ++q) {
                    dv[q] = double(b.m_deltaLinearVelocity[q]);
                    dv[3 + q] = double(b.m_deltaAngularVelocity[q]);
                }
            }
            // Soft rows (motors) read and update their impulses; a projection that fails gives them theirs back.
            softKept.clear();
            for (const int i : group.softRows) softKept.push_back(group.lambda(i));
            group.articulated.project(solveX, std::span<double>(group.lambda.data(), group.rows.size()));
            if (!allFinite(solveX)) {
                for (std::size_t m = 0; m < softKept.size(); ++m) group.lambda(group.softRows[m]) = softKept[m];
                continue;
            }
            for (std::size_t xb = 0; xb < nb; ++xb) {
                btSolverBody& b = *group.bodyOf[xb];
                const double* dv = solveX.data() + 6 * xb;
                b.m_deltaLinearVelocity = btVector3(btScalar(dv[0]), btScalar(dv[1]), btScalar(dv[2]));
                b.m_deltaAngularVelocity = btVector3(btScalar(dv[3]), btScalar(dv[4]), btScalar(dv[5]));
            }
            continue;
        }
        const Eigen::Index n = static_cast<Eigen::Index>(group.rows.size());
        e.resize(static_cast<std::size_t>(n));
        Eigen::Map<Vec> err(e.data(), n);
        double largest = residual; // kept in a register over the rows
        for (Eigen::Index i = 0; i < n; ++i) {
            const btSolverConstraint& c = pool[group.rows[static_cast<std::size_t>(i)].pool];
            err(i) = group.target(i) - group.cfm(i) * group.lambda(i) - direct::rowVelocity(bodyPool, c);
            largest = std::max(largest, err(i) * err(i));
        }
        residual = largest;
        if (group.useTree) {
            // H [Δv; Δλ] = [0; −e]: the bodies' velocity changes come out with the impulses.
            scratch.assign(static_cast<std::size_t>(group.tree.size()), 0.0);
            for (Eigen::Index i = 0; i < n; ++i)
                scratch[static_cast<std::size_t>(group.rowAt[static_cast<std::size_t>(i)])] = -err(i);
            group.tree.solve(scratch.data());
            if (!allFinite(scratch)) continue;
            for (Eigen::Index i = 0; i < n; ++i)
                group.lambda(i) += scratch[static_cast<std::size_t>(group.rowAt[static_cast<std::size_t>(i)])];
            for (std::size_t xb = 0; xb < group.bodies.size(); ++xb) {
                btSolverBody& b = bodyPool[group.bodies[xb]];
                const double* dv = scratch.data() + 6 * xb;
                b.m_deltaLinearVelocity += btVector3(btScalar(dv[0]), btScalar(dv[1]), btScalar(dv[2]));
                b.m_deltaAngularVelocity += btVector3(btScalar(dv[3]), btScalar(dv[4]), btScalar(dv[5]));
            }
            continue;
        }
        const Vec dl = group.ldlt.solve(err);
        if (!dl.allFinite()) continue;
        group.lambda += dl;
        for (Eigen::Index i = 0; i < n; ++i) {
            const JointRow& jr = group.rows[static_cast<std::size_t>(i)];
            const btScalar l = static_cast<btScalar>(dl(i));
            const btSolverConstraint& c = pool[jr.pool];
            if (jr.bodyA >= 0) {
                btSolverBody& b = bodyPool[c.m_solverBodyIdA];
                b.m_deltaLinearVelocity += jr.a.linInv * l;
                b.m_deltaAngularVelocity += jr.a.angInv * l;
            }
            if (jr.bodyB >= 0) {
                btSolverBody& b = bodyPool[c.m_solverBodyIdB];
                b.m_deltaLinearVelocity += jr.b.linInv * l;
                b.m_deltaAngularVelocity += jr.b.angInv * l;
            }
        }
    }
    return residual;
}

void RagdollSolver::Direct::apply(FreeRow& fr, double dl) {
    btSolverConstraint& c = *fr.c;
    for (int s = 0; s < 2; ++s) {
        const int g = fr.group[s];
        if (g < 0) {
            btSolverBody& b = *fr.at[s];
            if (s == 0)
                detail::applyRowImpulse<detail::RowTarget::Velocity>(b, c.m_contactNormal1, c.m_angularComponentA,
                                                                     btScalar(dl));
            else
                detail::applyRowImpulse<detail::RowTarget::Velocity>(b, c.m_contactNormal2, c.m_angularComponentB,
                                                                     btScalar(dl));
            continue;
        }
        if (fr.response[s] < 0) continue; // covered by side A's response
        Group& group = groups[static_cast<std::size_t>(g)];
        const btVector3* u = responses.data() + fr.response[s];
        const btScalar impulse = btScalar(dl);
        for (btSolverBody* b : group.bodyOf) {
            addScaled(b->m_deltaLinearVelocity, u[0], impulse);
            addScaled(b->m_deltaAngularVelocity, u[1], impulse);
            u += 2;
        }
        if (group.soft && fr.reaction[s] >= 0) {
            const double* y = reactions.data() + fr.reaction[s];
            if (group.useArticulated)
                for (std::size_t m = 0; m < group.softRows.size(); ++m) group.lambda(group.softRows[m]) -= y[m] * dl;
            else
                for (Eigen::Index i = 0; i < group.lambda.size(); ++i) group.lambda(i) -= y[i] * dl;
        }
    }
}

bool RagdollSolver::Direct::anyOutsideGroups() const {
    for (const auto* list : {&nonContact, &contact})
        for (const FreeRow& fr : *list)
            if (groupOf[static_cast<std::size_t>(fr.c->m_solverBodyIdA)] < 0 &&
                groupOf[static_cast<std::size_t>(fr.c->m_solverBodyIdB)] < 0)
                return true;
    return false;
}

double RagdollSolver::Direct::resolveInTurn(btAlignedObjectArray<btSolverBody>& bodyPool,
                                            btAlignedObjectArray<btSolverConstraint>& contactPool,
                                            btAlignedObjectArray<btSolverConstraint>& rollingPool,
                                            btSingleConstraintRowSolver rolling, int iteration, bool contacts,
                                            InTurn which) {
    // In block mode the rows through the groups are the block's; the others are taken here.
    const auto outsideGroups = [this](const btSolverConstraint& c) {
        return groupOf[static_cast<std::size_t>(c.m_solverBodyIdA)] < 0 &&
               groupOf[static_cast<std::size_t>(c.m_solverBodyIdB)] < 0;
    };
    // One row: Bullet's update with the row's effective mass (through the groups it moves) and its response.
    // Returns the row's residual term, dl² / invEffectiveMass² (0: no change).
    auto resolve = [this, &bodyPool](FreeRow& fr) -> double {
        btSolverConstraint& c = *fr.c;
        if (!fr.pending && fr.invEffectiveMass == 0) return 0;
        const double toGo = toGoOf(fr, bodyPool);
        if (fr.pending) {
            if (heldAtZeroBound(toGo, double(c.m_appliedImpulse), double(c.m_lowerLimit), double(c.m_upperLimit)))
                return 0;
            complete(fr, bodyPool);
            if (fr.invEffectiveMass == 0) return 0;
        }
        double dl = toGo * fr.invEffectiveMass;
        const double sum = double(c.m_appliedImpulse) + dl;
        if (sum < double(c.m_lowerLimit)) dl = double(c.m_lowerLimit) - double(c.m_appliedImpulse);
        else if (sum > double(c.m_upperLimit)) dl = double(c.m_upperLimit) - double(c.m_appliedImpulse);
        if (dl == 0) return 0;
        c.m_appliedImpulse = c.m_appliedImpulse + static_cast<btScalar>(dl);
        apply(fr, dl);
        return dl * dl / (fr.invEffectiveMass * fr.invEffectiveMass);
    };
    // The pass over the rows `inTurn` takes (a separate loop per kind of filter, so that taking every row costs
    // no test per row).
    auto pass = [&](auto inTurn) {
        double residual = 0;
        for (FreeRow& fr : nonContact)
            if (iteration < fr.c->m_overrideNumSolverIterations && inTurn(fr))
                residual = std::max(residual, resolve(fr));
        if (!contacts) return residual;
        for (FreeRow& fr : contact)
            if (inTurn(fr)) residual = std::max(residual, resolve(fr));
        for (FreeRow& fr : friction) {
            if (!inTurn(fr)) continue;
            const btScalar total = contactPool[fr.c->m_frictionIndex].m_appliedImpulse;
            if (total <= 0) continue;
            fr.c->m_lowerLimit = -(fr.c->m_friction * total);
            fr.c->m_upperLimit = fr.c->m_friction * total;
            residual = std::max(residual, resolve(fr));
        }
        for (int j = 0; j < rollingPool.size(); ++j) {
            btSolverConstraint& c = rollingPool[j];
            if (which == InTurn::OutsideGroups && !outsideGroups(c)) continue;
            const btScalar total = contactPool[c.m_frictionIndex].m_appliedImpulse;
            if (total <= 0) continue;
            const btScalar magnitude = btMin(c.m_friction * total, c.m_friction);
            c.m_lowerLimit = -magnitude;
            c.m_upperLimit = magnitude;
            const btScalar r = rolling(bodyPool[c.m_solverBodyIdA], bodyPool[c.m_solverBodyIdB], c);
            residual = std::max(residual, double(r) * double(r));
        }
        return residual;
    };
    switch (which) {
    case InTurn::All: return pass([](const FreeRow&) { return true; });
    case InTurn::OutsideBlock: return pass([](const FreeRow& fr) { return fr.group[0] < 0 && fr.group[1] < 0; });
    case InTurn::OutsideGroups: return pass([&outsideGroups](const FreeRow& fr) { return outsideGroups(*fr.c); });
    }
    return 0;
}

btScalar RagdollSolver::solveDirectIteration(int iteration, const btContactSolverInfo& infoGlobal) {
    Direct& d = *m_direct;
    auto& bodies = m_tmpSolverBodyPool;
    auto& joints = m_tmpSolverNonContactConstraintPool;
    auto inTurn = [&](bool contacts) {
        return d.resolveInTurn(bodies, m_tmpSolverContactConstraintPool,
                               m_tmpSolverContactRollingFrictionConstraintPool, m_resolveSingleConstraintRowGeneric,
                               iteration, contacts,
                               d.figureIterations == 0 ? Direct::InTurn::All : Direct::InTurn::OutsideBlock);
    };
    if (d.figureIterations == 0) {
        // The joints exactly, then every other row in turn, those through the groups with the groups' response.
        const double residual = d.solveJoints(bodies, joints);
        return static_cast<btScalar>(std::max(residual, inTurn(iteration < infoGlobal.m_numIterations)));
    }
    // Block mode: the rows of Bullet's response in turn, the joints exactly, then the block, which keeps them
    // exact; the iteration ends with joints and the block's contacts and limits solved. The joints are solved
    // first too on the first iteration only (afterwards the last block left them exact).
    double residual = iteration == 0 ? d.solveJoints(bodies, joints) : 0.0;
    residual = std::max(residual, inTurn(true));
    residual = std::max(residual, d.solveJoints(bodies, joints));
    residual = std::max(residual, d.solveFigureBlock(bodies, iteration, true));
    return static_cast<btScalar>(residual);
}

// Block mode's few iterations are the ragdolls'; a game's bodies among themselves (a stack of crates a ragdoll lies
// on) keep the world's count. Their rows move no ragdoll body, so the joints stay as the block left them.
void RagdollSolver::solveDirectOutsideGroups(int firstIteration, const btContactSolverInfo& infoGlobal) {
    Direct& d = *m_direct;
    if (!d.anyOutsideGroups()) return;
    const int world = std::max(m_maxOverrideNumSolverIterations, infoGlobal.m_numIterations);
    for (int iteration = firstIteration; iteration < world; ++iteration) {
        const double residual =
            d.resolveInTurn(m_tmpSolverBodyPool, m_tmpSolverContactConstraintPool,
                            m_tmpSolverContactRollingFrictionConstraintPool, m_resolveSingleConstraintRowGeneric,
                            iteration, iteration < infoGlobal.m_numIterations, Direct::InTurn::OutsideGroups);
        if (residual <= double(infoGlobal.m_leastSquaresResidualThreshold)) break;
    }
}

void RagdollSolver::solveDirectSplitImpulse(const btContactSolverInfo& infoGlobal) {
    Direct& d = *m_direct;
    for (int iteration = 0; iteration < infoGlobal.m_numIterations; ++iteration) {
        double residual = 0;
        for (Direct::FreeRow& fr : d.contact) {
            btSolverConstraint& c = *fr.c;
            if ((!fr.pending && fr.invEffectiveMass == 0) || c.m_rhsPenetration == 0) continue;
            const double rel =
                double(detail::rowVelocitySum<detail::RowTarget::Push>(m_tmpSolverBodyPool[c.m_solverBodyIdA],
                                                                       m_tmpSolverBodyPool[c.m_solverBodyIdB], c));
            const double target = (double(c.m_rhsPenetration) - double(c.m_cfm) * double(c.m_appliedPushImpulse)) /
                                  double(c.m_jacDiagABInv);
            const double toGo = target - rel;
            if (fr.pending) {
                // The push impulse has no upper bound.
                if (Direct::heldAtZeroBound(toGo, double(c.m_appliedPushImpulse), double(c.m_lowerLimit),
                                            std::numeric_limits<double>::infinity()))
                    continue;
                d.complete(fr, m_tmpSolverBodyPool);
                if (fr.invEffectiveMass == 0) continue;
            }
            double dl = toGo * fr.invEffectiveMass;
            if (double(c.m_appliedPushImpulse) + dl < double(c.m_lowerLimit))
                dl = double(c.m_lowerLimit) - double(c.m_appliedPushImpulse);
            if (dl == 0) continue;
            c.m_appliedPushImpulse += static_cast<btScalar>(dl);
            residual = std::max(residual, dl * dl / (fr.invEffectiveMass * fr.invEffectiveMass));
            for (int s = 0; s < 2; ++s) {
                const int id = s ? c.m_solverBodyIdB : c.m_solverBodyIdA;
                const int g = fr.group[s];
                if (g < 0) {
                    btSolverBody& body = m_tmpSolverBodyPool[id];
                    if (s == 0)
                        detail::applyRowImpulse<detail::RowTarget::Push>(body, c.m_contactNormal1,
                                                                         c.m_angularComponentA, btScalar(dl));
                    else
                        detail::applyRowImpulse<detail::RowTarget::Push>(body, c.m_contactNormal2,
                                                                         c.m_angularComponentB, btScalar(dl));
                    continue;
                }
                if (fr.response[s] < 0) continue;
                const Direct::Group& group = d.groups[static_cast<std::size_t>(g)];
                const btVector3* u = d.responses.data() + fr.response[s];
                const btScalar impulse = btScalar(dl);
                for (btSolverBody* body : group.bodyOf) {
                    addScaled(body->m_pushVelocity, u[0], impulse);
                    addScaled(body->m_turnVelocity, u[1], impulse);
                    u += 2;
                }
            }
        }
        if (residual <= infoGlobal.m_leastSquaresResidualThreshold) break;
    }
}

} // namespace afb::bullet
