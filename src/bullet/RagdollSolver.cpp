// Warm-started joint rows (RagdollSolver.h).
#include "afb/bullet/RagdollSolver.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <span>
#include <type_traits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "DirectSolve.h"
#include "RowKernels.h"

namespace afb::bullet {

btScalar RagdollSolver::solveGroupCacheFriendlyIterations(btCollisionObject** bodies, int numBodies,
                                                          btPersistentManifold** manifoldPtr, int numManifolds,
                                                          btTypedConstraint** constraints, int numConstraints,
                                                          const btContactSolverInfo& infoGlobal,
                                                          btIDebugDraw* debugDrawer) {
    // Bullet's setup chose its row functions for the solver mode (its scalar reference in Debian's build); with
    // SIMD rows, ours replace them for this solve (the iterations, split impulse included, call them).
    if (m_simdRows) {
        m_resolveSingleConstraintRowGeneric = detail::resolveRowGeneric;
        m_resolveSingleConstraintRowLowerLimit = detail::resolveRowLowerLimit;
        m_resolveSplitPenetrationImpulse = detail::resolveRowSplitPenetration;
    } else if (m_resolveSingleConstraintRowGeneric == detail::resolveRowGeneric) {
        setupSolverFunctions((infoGlobal.m_solverMode & SOLVER_SIMD) != 0); // what Bullet's setup installs
    }
    if (!m_direct->enabled || m_rows.size() == 0 || !buildDirect()) {
        // Our loop (solveSingleIteration) takes the islands in turn; Bullet's own modes that reorder keep its order.
        const int reordering = SOLVER_RANDMIZE_ORDER | SOLVER_INTERLEAVE_CONTACT_AND_FRICTION_CONSTRAINTS;
        if (!m_simdRows || (infoGlobal.m_solverMode & reordering) != 0 ||
            !m_islandOrder.build(m_tmpSolverBodyPool, m_tmpSolverNonContactConstraintPool,
                                 m_tmpSolverContactConstraintPool, m_tmpSolverContactFrictionConstraintPool))
            m_islandOrder.clear();
        m_mostIslandsInTurn = std::max(m_mostIslandsInTurn, m_islandOrder.islands);
        return btSequentialImpulseConstraintSolver::solveGroupCacheFriendlyIterations(bodies, numBodies, manifoldPtr,
                                                                                      numManifolds, constraints,
                                                                                      numConstraints, infoGlobal,
                                                                                      debugDrawer);
    }
    m_islandOrder.clear();
    // Contact penetration (split impulse: velocities that move the bodies this step and are then forgotten),
    // through the groups' responses too, so that lifting a foot out of the ground lifts the leg with it.
    if (infoGlobal.m_splitImpulse) solveDirectSplitImpulse(infoGlobal);
    // Block mode has its own count (Method::figureIterations); every row takes part in each of its iterations.
    const int iterations = m_direct->figureIterations > 0
                               ? m_direct->figureIterations
                               : std::max(m_maxOverrideNumSolverIterations, infoGlobal.m_numIterations);
    m_direct->figureTolerance = double(infoGlobal.m_leastSquaresResidualThreshold);
    for (int iteration = 0; iteration < iterations; ++iteration) {
        m_leastSquaresResidual = solveDirectIteration(iteration, infoGlobal);
        if (m_leastSquaresResidual <= infoGlobal.m_leastSquaresResidualThreshold) break;
    }
    if (m_direct->figureIterations > 0) solveDirectOutsideGroups(iterations, infoGlobal);
    // The joint rows' impulses (the block's and the reactions to the other rows) for warm starting and Bullet.
    for (auto* list : {&m_direct->nonContact, &m_direct->contact, &m_direct->friction})
        for (const Direct::FreeRow& fr : *list)
            for (int s = 0; s < 2; ++s) {
                if (fr.reaction[s] < 0) continue;
                Direct::Group& group = m_direct->groups[static_cast<std::size_t>(fr.group[s])];
                if (group.soft) continue;
                const double dl = double(fr.c->m_appliedImpulse) - double(fr.start);
                const double* y = m_direct->reactions.data() + fr.reaction[s];
                for (Eigen::Index i = 0; i < group.lambda.size(); ++i) group.lambda(i) -= y[i] * dl;
            }
    m_direct->articulatedImpulses(m_tmpSolverBodyPool,
                                  {&m_tmpSolverNonContactConstraintPool, &m_tmpSolverContactConstraintPool,
                                   &m_tmpSolverContactFrictionConstraintPool,
                                   &m_tmpSolverContactRollingFrictionConstraintPool},
                                  m_tmpSolverNonContactConstraintPool);
    for (const Direct::Group& group : m_direct->live())
        for (std::size_t i = 0; i < group.rows.size(); ++i)
            m_tmpSolverNonContactConstraintPool[group.rows[i].pool].m_appliedImpulse =
                static_cast<btScalar>(group.lambda(static_cast<Eigen::Index>(i)));
    return 0;
}

bool RagdollSolver::IslandOrder::build(const btAlignedObjectArray<btSolverBody>& bodies,
                                       const btAlignedObjectArray<btSolverConstraint>& nonContactPool,
                                       const btAlignedObjectArray<btSolverConstraint>& contactPool,
                                       const btAlignedObjectArray<btSolverConstraint>& frictionPool) {
    clear();
    const auto at = [](std::vector<int>& v, int i) -> int& { return v[static_cast<std::size_t>(i)]; };
    // Islands: bodies joined by a row, over the bodies a row can move (the static world body, which has no
    // original body, is read by many islands and written by none).
    const int n = bodies.size();
    parent.resize(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) at(parent, i) = i;
    const auto root = [&](int i) {
        while (at(parent, i) != i) i = at(parent, i) = at(parent, at(parent, i));
        return i;
    };
    const auto moves = [&](int id) { return bodies[id].m_originalBody != nullptr; };
    const btAlignedObjectArray<btSolverConstraint>* pools[3] = {&nonContactPool, &contactPool, &frictionPool};
    for (const auto* pool : pools)
        for (int j = 0; j < pool->size(); ++j) {
            const btSolverConstraint& c = (*pool)[j];
            if (moves(c.m_solverBodyIdA) && moves(c.m_solverBodyIdB))
                at(parent, root(c.m_solverBodyIdA)) = root(c.m_solverBodyIdB);
        }
    // Numbered by first appearance; rows that move no body (both sides static) form one more island.
    island.assign(static_cast<std::size_t>(n) + 1, -1);
    int found = 0;
    const auto islandOf = [&](const btSolverConstraint& c) {
        const int id = moves(c.m_solverBodyIdA)   ? root(c.m_solverBodyIdA)
                       : moves(c.m_solverBodyIdB) ? root(c.m_solverBodyIdB)
                                                  : n;
        int& k = at(island, id);
        if (k < 0) k = found++;
        return k;
    };
    // One island (a lone ragdoll, a batch of one): Bullet's order, before any sorting.
    for (const auto* pool : pools)
        for (int j = 0; j < pool->size(); ++j) islandOf((*pool)[j]);
    if (found < 2) {
        clear();
        return false;
    }
    std::vector<int>* orders[3] = {&nonContact, &contact, &friction};
    for (int p = 0; p < 3; ++p) {
        const auto& pool = *pools[p];
        std::vector<int>& order = *orders[p];
        const int rows = pool.size();
        // The rows by island, each island's in pool order (a counting sort into `byIsland`)...
        rowIsland.resize(static_cast<std::size_t>(rows));
        for (int j = 0; j < rows; ++j) at(rowIsland, j) = islandOf(pool[j]);
        first.assign(static_cast<std::size_t>(found) + 1, 0);
        for (int j = 0; j < rows; ++j) ++at(first, at(rowIsland, j) + 1);
        for (int k = 0; k < found; ++k) at(first, k + 1) += at(first, k);
        end.assign(first.begin(), first.end() - 1); // a cursor per island while filling, its end after
        byIsland.resize(static_cast<std::size_t>(rows));
        for (int j = 0; j < rows; ++j) at(byIsland, at(end, at(rowIsland, j))++) = j;
        // ...then a row of each island in turn, an island leaving the turn when its rows are out.
        active.clear();
        for (int k = 0; k < found; ++k)
            if (at(end, k) > at(first, k)) active.push_back(k);
        order.clear();
        order.reserve(static_cast<std::size_t>(rows));
        while (!active.empty()) {
            std::size_t kept = 0;
            for (const int k : active) {
                order.push_back(at(byIsland, at(first, k)++));
                if (at(first, k) < at(end, k)) active[kept++] = k;
            }
            active.resize(kept);
        }
    }
    islands = found;
    return true;
}

RagdollSolver::RagdollSolver() : m_direct(std::make_unique<Direct>()) {}

void RagdollSolver::setFigureBlock(int iterations, int sweeps) {
    m_direct->figureIterations = std::max(0, iterations);
    m_direct->figureSweeps = std::max(1, sweeps);
}
int RagdollSolver::figureIterations() const { return m_direct->figureIterations; }
int RagdollSolver::figureSweeps() const { return m_direct->figureSweeps; }

RagdollSolver::~RagdollSolver() = default;

// Bullet's solveSingleIteration (3.24) with the row update inlined: the same rows in the same order, the same
// residual, Bullet's calls to the constraints' obsolete solve kept; only the order randomisation is left to Bullet.
btScalar RagdollSolver::solveSingleIteration(int iteration, btCollisionObject** bodies, int numBodies,
                                             btPersistentManifold** manifoldPtr, int numManifolds,
                                             btTypedConstraint** constraints, int numConstraints,
                                             const btContactSolverInfo& infoGlobal, btIDebugDraw* debugDrawer) {
    if (!m_simdRows || (infoGlobal.m_solverMode & SOLVER_RANDMIZE_ORDER) != 0)
        return btSequentialImpulseConstraintSolver::solveSingleIteration(iteration, bodies, numBodies, manifoldPtr,
                                                                         numManifolds, constraints, numConstraints,
                                                                         infoGlobal, debugDrawer);
    using detail::resolveRow;
    using detail::RowTarget;
    btScalar residual = 0;
    auto keep = [&residual](btScalar r) { residual = btMax(residual, r * r); };
    auto solve = [this, &keep](const btSolverConstraint& c, auto upper) {
        keep(resolveRow<decltype(upper)::value, RowTarget::Velocity>(m_tmpSolverBodyPool[c.m_solverBodyIdA],
                                                                     m_tmpSolverBodyPool[c.m_solverBodyIdB], c));
    };
    using Generic = std::true_type;
    using LowerLimit = std::false_type;
    // The islands in turn (m_islandOrder) when it was built for this solve, else Bullet's order.
    const bool inTurn = m_islandOrder.islands > 0;
    const auto orderOf = [inTurn](const std::vector<int>& mine, const btAlignedObjectArray<int>& bullets) {
        return inTurn ? mine.data() : bullets.size() > 0 ? &bullets[0] : nullptr;
    };
    const int* nonContactOrder = orderOf(m_islandOrder.nonContact, m_orderNonContactConstraintPool);
    for (int j = 0; j < m_tmpSolverNonContactConstraintPool.size(); ++j) {
        const btSolverConstraint& c = m_tmpSolverNonContactConstraintPool[nonContactOrder[j]];
        if (iteration < c.m_overrideNumSolverIterations) solve(c, Generic{});
    }
    if (iteration >= infoGlobal.m_numIterations) return residual;
    for (int j = 0; j < numConstraints; ++j) {
        if (!constraints[j]->isEnabled()) continue;
        const int a = getOrInitSolverBody(constraints[j]->getRigidBodyA(), infoGlobal.m_timeStep);
        const int b = getOrInitSolverBody(constraints[j]->getRigidBodyB(), infoGlobal.m_timeStep);
        constraints[j]->solveConstraintObsolete(m_tmpSolverBodyPool[a], m_tmpSolverBodyPool[b], infoGlobal.m_timeStep);
    }
    auto friction = [&](btSolverConstraint& f, btScalar total) {
        if (!(total > btScalar(0))) return; // as Bullet's test (a NaN total solves nothing)
        f.m_lowerLimit = -(f.m_friction * total);
        f.m_upperLimit = f.m_friction * total;
        solve(f, Generic{});
    };
    const int contacts = m_tmpSolverContactConstraintPool.size();
    if (infoGlobal.m_solverMode & SOLVER_INTERLEAVE_CONTACT_AND_FRICTION_CONSTRAINTS) {
        const bool two = (infoGlobal.m_solverMode & SOLVER_USE_2_FRICTION_DIRECTIONS) != 0;
        const int multiplier = two ? 2 : 1;
        for (int j = 0; j < contacts; ++j) {
            const btSolverConstraint& c = m_tmpSolverContactConstraintPool[m_orderTmpConstraintPool[j]];
            solve(c, LowerLimit{});
            const btScalar total = c.m_appliedImpulse;
            friction(m_tmpSolverContactFrictionConstraintPool[m_orderFrictionConstraintPool[j * multiplier]], total);
            if (two)
                friction(m_tmpSolverContactFrictionConstraintPool[m_orderFrictionConstraintPool[j * multiplier + 1]],
                         total);
        }
    } else {
        const int* contactOrder = orderOf(m_islandOrder.contact, m_orderTmpConstraintPool);
        const int* frictionOrder = orderOf(m_islandOrder.friction, m_orderFrictionConstraintPool);
        for (int j = 0; j < contacts; ++j) solve(m_tmpSolverContactConstraintPool[contactOrder[j]], LowerLimit{});
        for (int j = 0; j < m_tmpSolverContactFrictionConstraintPool.size(); ++j) {
            btSolverConstraint& f = m_tmpSolverContactFrictionConstraintPool[frictionOrder[j]];
            friction(f, m_tmpSolverContactConstraintPool[f.m_frictionIndex].m_appliedImpulse);
        }
    }
    for (int j = 0; j < m_tmpSolverContactRollingFrictionConstraintPool.size(); ++j) {
        btSolverConstraint& r = m_tmpSolverContactRollingFrictionConstraintPool[j];
        const btScalar total = m_tmpSolverContactConstraintPool[r.m_frictionIndex].m_appliedImpulse;
        if (!(total > btScalar(0))) continue;
        btScalar magnitude = r.m_friction * total;
        if (magnitude > r.m_friction) magnitude = r.m_friction;
        r.m_lowerLimit = -magnitude;
        r.m_upperLimit = magnitude;
        solve(r, Generic{});
    }
    return residual;
}

void RagdollSolver::track(const btTypedConstraint& constraint, bool warmStart, bool direct, bool soft) {
    const btHashPtr key(&constraint);
    if (Tracked* t = m_rows.find(key)) {
        t->warmStart = warmStart;
        t->direct = direct;
        t->soft = soft;
        return;
    }
    Tracked t;
    t.warmStart = warmStart;
    t.direct = direct;
    t.soft = soft;
    m_rows.insert(key, t);
}

void RagdollSolver::convertContacts(btPersistentManifold** manifoldPtr, int numManifolds,
                                    const btContactSolverInfo& infoGlobal) {
    if (m_contactCap && (infoGlobal.m_solverMode & SOLVER_USE_WARMSTARTING))
        for (int i = 0; i < numManifolds; ++i) {
            btPersistentManifold& m = *manifoldPtr[i];
            if (m.getNumContacts() == 0) continue;
            const btScalar cap = m_contactCap(m, infoGlobal.m_timeStep);
            if (cap < 0) continue;
            for (int k = 0; k < m.getNumContacts(); ++k) {
                btManifoldPoint& cp = m.getContactPoint(k);
                if (cp.m_appliedImpulse <= cap) continue;
                const btScalar scale = cap / cp.m_appliedImpulse;
                cp.m_appliedImpulse = cap;
                cp.m_appliedImpulseLateral1 *= scale;
                cp.m_appliedImpulseLateral2 *= scale;
            }
        }
    btSequentialImpulseConstraintSolver::convertContacts(manifoldPtr, numManifolds, infoGlobal);
}

// A soft row's update with its cfm in the effective mass (track): Δλ = (rhs − J·v − c·λ/m) · m/(1 + c). Bullet
// set m_jacDiagABInv = m, m_rhs = m·(rhs − J·v₀) and m_cfm = c; scaling all three by 1/(1 + c) gives that update
// in Bullet's own row functions, and keeps m_cfm/m_jacDiagABInv and m_rhs/m_jacDiagABInv (what the direct
// solve reads) as they were.
void RagdollSolver::softenRow(btSolverConstraint& c) {
    if (!(c.m_cfm > 0)) return;
    const btScalar scale = 1 / (1 + c.m_cfm);
    c.m_jacDiagABInv *= scale;
    c.m_rhs *= scale;
    c.m_cfm *= scale;
}

void RagdollSolver::untrack(const btTypedConstraint& constraint) { m_rows.remove(btHashPtr(&constraint)); }

btScalar RagdollSolver::solveGroupCacheFriendlyFinish(btCollisionObject** bodies, int numBodies,
                                                      const btContactSolverInfo& infoGlobal) {
    if (m_rows.size() > 0) {
        // Rows of one constraint are consecutive; each row names its constraint.
        Tracked* t = nullptr;
        const void* current = nullptr;
        for (int j = 0; j < m_tmpSolverNonContactConstraintPool.size(); ++j) {
            const btSolverConstraint& c = m_tmpSolverNonContactConstraintPool[j];
            if (c.m_originalContactPoint != current) {
                current = c.m_originalContactPoint;
                t = m_rows.find(btHashPtr(current));
                if (t) t->rows = 0;
            }
            if (t == nullptr || t->rows < 0) continue;
            if (t->rows == Tracked::kMaxRows) t->rows = -1; // more rows than kept: not warm-started
            else t->impulses[t->rows++] = c.m_appliedImpulse;
        }
    }
    return btSequentialImpulseConstraintSolver::solveGroupCacheFriendlyFinish(bodies, numBodies, infoGlobal);
}

} // namespace afb::bullet
