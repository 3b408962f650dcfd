// The rows through the groups solved as one block (Method::figureSweeps; DirectSolve.h).
//
// Within one iteration, after the joint solve, the contact and limit rows that move whole groups are taken
// together: their couplings W (the change of one row's velocity per unit impulse of another, through the groups'
// responses) are gathered once, Gauss–Seidel sweeps run on W alone, and the impulses they find are applied to the
// bodies once. A sweep then costs a product of the block's rows, not a pass over every body of the figure per row.
#include <algorithm>
#include <cmath>

#include "DirectSolve.h"
#include "RowKernels.h"

namespace afb::bullet {

using direct::sideA;
using direct::sideB;
using direct::SideJ;

double RagdollSolver::Direct::couplingOf(const FreeRow& r, const FreeRow& s) const {
    const btSolverConstraint& cr = *r.c;
    const btSolverConstraint& cs = *s.c;
    double w = 0;
    for (int q = 0; q < 2; ++q) {
        const int id = q ? cr.m_solverBodyIdB : cr.m_solverBodyIdA;
        const SideJ& jr = r.side[q];
        for (int t = 0; t < 2; ++t) {
            const int g = s.group[t];
            if (g < 0) { // a body of no group: its own response, when it is this side's body
                const int sid = t ? cs.m_solverBodyIdB : cs.m_solverBodyIdA;
                if (sid != id) continue;
                const SideJ& js = s.side[t];
                w += double(jr.lin.dot(js.linInv)) + double(jr.ang.dot(js.angInv));
                continue;
            }
            if (s.response[t] < 0 || groupOf[static_cast<std::size_t>(id)] != g) continue;
            const btVector3* u = responses.data() + s.response[t] + 2 * localOf[static_cast<std::size_t>(id)];
            w += double(jr.lin.dot(u[0])) + double(jr.ang.dot(u[1]));
        }
    }
    return w;
}

void RagdollSolver::Direct::join(FreeRow& fr, const btAlignedObjectArray<btSolverBody>& bodyPool) {
    const int k = static_cast<int>(block.rows.size());
    fr.blockIndex = k;
    fr.side[0] = sideA(*fr.c, bodyPool[fr.c->m_solverBodyIdA]);
    fr.side[1] = sideB(*fr.c, bodyPool[fr.c->m_solverBodyIdB]);
    block.rows.push_back(&fr);
    if (block.links.size() < block.rows.size()) block.links.emplace_back();
    auto& mine = block.links[static_cast<std::size_t>(k)];
    mine.clear();
    block.seen.resize(block.rows.size(), -1);
    block.seen[static_cast<std::size_t>(k)] = k;
    auto link = [&](int j) {
        if (block.seen[static_cast<std::size_t>(j)] == k) return;
        block.seen[static_cast<std::size_t>(j)] = k;
        // W is symmetric (J_r H⁻¹ J_sᵀ with H symmetric): one product serves both directions.
        const double w = couplingOf(fr, *block.rows[static_cast<std::size_t>(j)]);
        mine.emplace_back(j, w);
        block.links[static_cast<std::size_t>(j)].emplace_back(k, w);
    };
    for (int t = 0; t < 2; ++t)
        if (fr.group[t] >= 0)
            for (const int j : block.ofGroup[static_cast<std::size_t>(fr.group[t])]) link(j);
    auto plainDynamic = [&](const FreeRow& row, int t) {
        const int id = t ? row.c->m_solverBodyIdB : row.c->m_solverBodyIdA;
        return row.group[t] < 0 && dynamicBody(bodyPool[id]) ? id : -1;
    };
    const int mineA = plainDynamic(fr, 0), mineB = plainDynamic(fr, 1);
    if (mineA >= 0 || mineB >= 0) {
        for (const int j : block.plainDynamic) {
            const FreeRow& other = *block.rows[static_cast<std::size_t>(j)];
            for (int t = 0; t < 2; ++t) {
                const int id = plainDynamic(other, t);
                if (id >= 0 && (id == mineA || id == mineB)) link(j);
            }
        }
        block.plainDynamic.push_back(k);
    }
    mine.emplace_back(k, couplingOf(fr, fr));
    for (int t = 0; t < 2; ++t)
        if (fr.group[t] >= 0 && !(t == 1 && fr.group[0] == fr.group[1]))
            block.ofGroup[static_cast<std::size_t>(fr.group[t])].push_back(k);
    block.toGo.resize(block.rows.size());
}

void RagdollSolver::Direct::gatherBlock(btAlignedObjectArray<btSolverBody>& bodyPool, int iteration, bool contacts) {
    block.taken.clear();
    // Takes the row into this iteration's block when it would move (or has moved); false when it stays out.
    auto consider = [&](FreeRow& fr) {
        if (fr.group[0] < 0 && fr.group[1] < 0) return false;
        btSolverConstraint& c = *fr.c;
        if (!fr.pending && fr.invEffectiveMass == 0) return false;
        const double toGo = toGoOf(fr, bodyPool);
        if (fr.pending) {
            if (heldAtZeroBound(toGo, double(c.m_appliedImpulse), double(c.m_lowerLimit), double(c.m_upperLimit)))
                return false;
            complete(fr, bodyPool);
            if (fr.invEffectiveMass == 0) return false;
        }
        if (fr.blockIndex < 0) join(fr, bodyPool);
        block.taken.push_back(fr.blockIndex);
        block.toGo[static_cast<std::size_t>(fr.blockIndex)] = toGo;
        return true;
    };
    for (FreeRow& fr : nonContact)
        if (iteration < fr.c->m_overrideNumSolverIterations) consider(fr);
    if (contacts) {
        for (FreeRow& fr : contact) consider(fr);
        // Friction rows through the groups (Method::frictionThroughFigure): bounded by their contact's impulse,
        // which the sweeps update; a friction row joins while its contact pushes.
        for (FreeRow& fr : friction) {
            if (fr.group[0] < 0 && fr.group[1] < 0) continue;
            const FreeRow& normal = contact[static_cast<std::size_t>(fr.c->m_frictionIndex)];
            if (normal.blockIndex < 0 && normal.c->m_appliedImpulse <= 0) continue;
            const btScalar total = normal.c->m_appliedImpulse;
            fr.c->m_lowerLimit = -(fr.c->m_friction * total);
            fr.c->m_upperLimit = fr.c->m_friction * total;
            if (consider(fr)) fr.normal = normal.blockIndex;
        }
    }
    block.added.assign(block.rows.size(), 0.0);
}

double RagdollSolver::Direct::solveFigureBlock(btAlignedObjectArray<btSolverBody>& bodyPool, int iteration,
                                               bool contacts) {
    gatherBlock(bodyPool, iteration, contacts);
    if (block.taken.empty()) return 0;
    double* added = block.added.data();
    // The impulses so far and the bounds stay as they are through the sweeps: read once (each row's own, and a
    // friction row's contact impulse as `applied` of that contact's entry).
    std::vector<Block::Sweep>& rows = block.sweep;
    rows.clear();
    for (const int r : block.taken) {
        const FreeRow& fr = *block.rows[static_cast<std::size_t>(r)];
        const btSolverConstraint& c = *fr.c;
        const auto& links = block.links[static_cast<std::size_t>(r)];
        rows.push_back({links.data(), links.data() + links.size(), block.toGo[static_cast<std::size_t>(r)], fr.cfmVel,
                        fr.invEffectiveMass, double(c.m_appliedImpulse), double(c.m_lowerLimit), double(c.m_upperLimit),
                        double(c.m_friction), r, fr.normal});
    }
    const auto appliedOf = [this](int r) {
        return double(block.rows[static_cast<std::size_t>(r)]->c->m_appliedImpulse);
    };
    double residual = 0;
    for (int sweep = 0; sweep < figureSweeps; ++sweep) {
        double largest = 0;
        for (const Block::Sweep& q : rows) {
            // The couplings' sum in link order, four links a turn (the same sum, less loop).
            double v = 0;
            const std::pair<int, double>* l = q.link;
            for (; q.linkEnd - l >= 4; l += 4) {
                v += l[0].second * added[l[0].first];
                v += l[1].second * added[l[1].first];
                v += l[2].second * added[l[2].first];
                v += l[3].second * added[l[3].first];
            }
            for (; l != q.linkEnd; ++l) v += l->second * added[l->first];
            double dl = (q.toGo - q.cfmVel * added[q.row] - v) * q.invEffectiveMass;
            const double applied = q.applied + added[q.row];
            double lower = q.lower, upper = q.upper;
            if (q.normal >= 0) { // a friction row: ± friction × its contact's impulse so far
                const double total = std::max(0.0, appliedOf(q.normal) + added[q.normal]);
                upper = q.friction * total;
                lower = -upper;
            }
            if (applied + dl < lower) dl = lower - applied;
            else if (applied + dl > upper) dl = upper - applied;
            added[q.row] += dl;
            largest = std::max(largest, dl * dl / (q.invEffectiveMass * q.invEffectiveMass));
        }
        if (sweep == 0) residual = largest;
        if (largest <= figureTolerance) break;
    }
    for (const int r : block.taken) {
        if (added[r] == 0) continue;
        FreeRow& fr = *block.rows[static_cast<std::size_t>(r)];
        fr.c->m_appliedImpulse = fr.c->m_appliedImpulse + static_cast<btScalar>(added[r]);
        apply(fr, added[r]);
    }
    return residual;
}

} // namespace afb::bullet
