// The direct joint solve's joint-space path (DirectSolve.h, ArticulatedTree.h): a group whose joints are point
// joints with locked axes (ball, universal, hinge), soft rows only as motors about them, is solved by eliminating
// each joint's free motions rather than its rows. The same system, solved exactly either way; this way the factor
// works on 1 to 3 free motions per joint where the tree of bodies and joints works on 6 per body and 3 to 5 per
// joint, and a row's response walks only its own path to the root upwards.
#include <Eigen/Dense>

#include "DirectSolve.h"

namespace afb::bullet {

bool RagdollSolver::Direct::factorArticulated(Group& group, const btAlignedObjectArray<btSolverBody>& bodyPool) {
    if (group.heldTwice) return false; // rows softened against each other, not motors
    std::vector<ArticulatedTree::Body>& bodies = group.articulatedBodies;
    bodies.clear();
    for (const int id : group.bodies) {
        const btRigidBody* rb = bodyPool[id].m_originalBody;
        const btMatrix3x3& invInertia = rb->getInvInertiaTensorWorld();
        Eigen::Matrix3d ii;
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) ii(r, c) = double(invInertia[r][c]);
        if (!(rb->getInvMass() > 0) || !(ii.determinant() > 0)) return false;
        bodies.push_back({1.0 / double(rb->getInvMass()), ii.inverse()});
    }
    std::vector<ArticulatedTree::Row>& rows = group.articulatedRows;
    rows.clear();
    for (std::size_t i = 0; i < group.rows.size(); ++i) {
        const JointRow& jr = group.rows[i];
        ArticulatedTree::Row& row = rows.emplace_back();
        row.a = jr.bodyA;
        row.b = jr.bodyB;
        row.cfm = group.cfm(static_cast<Eigen::Index>(i));
        if (row.cfm > 0) group.softRows.push_back(static_cast<int>(i));
        for (int q = 0; q < 3; ++q) {
            row.ja[q] = double(jr.a.lin[q]);
            row.ja[3 + q] = double(jr.a.ang[q]);
            row.jb[q] = double(jr.b.lin[q]);
            row.jb[3 + q] = double(jr.b.ang[q]);
        }
    }
    if (group.articulated.build(bodies, rows) && group.articulated.factor()) return true;
    group.softRows.clear(); // the caller factors the rows as a tree of bodies and joints instead
    return false;
}

void RagdollSolver::Direct::articulatedColumn(FreeRow& fr, int s, bool withA, bool withB,
                                              const btAlignedObjectArray<btSolverBody>& bodyPool) {
    const Group& group = groups[static_cast<std::size_t>(fr.group[s])];
    const btSolverConstraint& c = *fr.c;
    const int xa = withA ? localOf[static_cast<std::size_t>(c.m_solverBodyIdA)] : -1;
    const int xb = withB ? localOf[static_cast<std::size_t>(c.m_solverBodyIdB)] : -1;
    const SideJ sa = sideA(c, bodyPool[c.m_solverBodyIdA]);
    const SideJ sb = sideB(c, bodyPool[c.m_solverBodyIdB]);
    auto impulse = [](const SideJ& side) {
        ArticulatedTree::Vec6 f;
        f << double(side.lin.x()), double(side.lin.y()), double(side.lin.z()), double(side.ang.x()),
            double(side.ang.y()), double(side.ang.z());
        return f;
    };
    const std::size_t nb = group.bodies.size();
    response.resize(6 * nb);
    group.articulated.solveImpulse(xa, impulse(sa), xb, impulse(sb), response);
    // The joints' impulses come from the bodies' momentum (articulatedImpulses), but a soft row's is part of what a
    // projection asks: its reaction, −(J u)/cfm per unit impulse, is kept (apply()).
    fr.reaction[s] = -1;
    if (!group.softRows.empty()) {
        fr.reaction[s] = static_cast<int>(reactions.size());
        for (const int i : group.softRows) {
            const JointRow& jr = group.rows[static_cast<std::size_t>(i)];
            double v = 0;
            for (const auto& [x, side] : {std::pair{jr.bodyA, &jr.a}, std::pair{jr.bodyB, &jr.b}}) {
                if (x < 0) continue;
                const double* u = response.data() + 6 * static_cast<std::size_t>(x);
                for (int q = 0; q < 3; ++q) v += double(side->lin[q]) * u[q] + double(side->ang[q]) * u[3 + q];
            }
            reactions.push_back(v / group.cfm(i));
        }
    }
    keepResponse(fr, s, xa, sa, xb, sb, nb);
}

void RagdollSolver::Direct::articulatedImpulses(
    const btAlignedObjectArray<btSolverBody>& bodyPool,
    std::initializer_list<const btAlignedObjectArray<btSolverConstraint>*> pools,
    const btAlignedObjectArray<btSolverConstraint>& jointPool) {
    bool any = false;
    groupRow.assign(static_cast<std::size_t>(jointPool.size()), 0);
    for (const Group& group : live()) {
        if (!group.useArticulated) continue;
        any = true;
        for (const JointRow& jr : group.rows) groupRow[static_cast<std::size_t>(jr.pool)] = 1;
    }
    if (!any) return;
    // Every other row's impulse on the groups' bodies (6 per body, at the body's offset among all groups' bodies).
    std::vector<int>& firstOf = articulatedFirst;
    firstOf.assign(used + 1, 0);
    for (std::size_t g = 0; g < used; ++g) firstOf[g + 1] = firstOf[g] + 6 * static_cast<int>(groups[g].bodies.size());
    articulatedF.assign(static_cast<std::size_t>(firstOf[used]), 0.0);
    auto add = [&](const btSolverConstraint& c) {
        const double l = double(c.m_appliedImpulse);
        if (l == 0) return;
        for (int s = 0; s < 2; ++s) {
            const int id = s ? c.m_solverBodyIdB : c.m_solverBodyIdA;
            const int g = groupOf[static_cast<std::size_t>(id)];
            if (g < 0 || !groups[static_cast<std::size_t>(g)].useArticulated) continue;
            const SideJ side = s ? sideB(c, bodyPool[id]) : sideA(c, bodyPool[id]);
            double* f =
                articulatedF.data() + firstOf[static_cast<std::size_t>(g)] + 6 * localOf[static_cast<std::size_t>(id)];
            for (int q = 0; q < 3; ++q) {
                f[q] += double(side.lin[q]) * l;
                f[3 + q] += double(side.ang[q]) * l;
            }
        }
    };
    for (const auto* pool : pools)
        for (int i = 0; i < pool->size(); ++i)
            if (pool != &jointPool || !groupRow[static_cast<std::size_t>(i)]) add((*pool)[i]);
    for (std::size_t g = 0; g < used; ++g) {
        Group& group = groups[g];
        if (!group.useArticulated) continue;
        const std::size_t nb = group.bodies.size();
        articulatedDv.resize(6 * nb);
        for (std::size_t x = 0; x < nb; ++x) {
            const btSolverBody& b = bodyPool[group.bodies[x]];
            for (int q = 0; q < 3; ++q) {
                articulatedDv[6 * x + static_cast<std::size_t>(q)] = double(b.m_deltaLinearVelocity[q]);
                articulatedDv[6 * x + 3 + static_cast<std::size_t>(q)] = double(b.m_deltaAngularVelocity[q]);
            }
        }
        articulatedLambda.assign(group.lambda.data(), group.lambda.data() + group.lambda.size()); // soft rows' kept
        group.articulated.jointImpulses(std::span<const double>(articulatedF.data() + firstOf[g], 6 * nb),
                                        articulatedDv, articulatedLambda);
        for (std::size_t i = 0; i < group.rows.size(); ++i)
            group.lambda(static_cast<Eigen::Index>(i)) = articulatedLambda[i];
    }
}

} // namespace afb::bullet
