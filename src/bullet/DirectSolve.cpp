// The direct joint solve: groups, their factorisation and the other rows' responses (DirectSolve.h).
#include "DirectSolve.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "RowKernels.h"

namespace afb::bullet {

namespace {
constexpr btScalar unbounded = btScalar(1e30); // Bullet's bound of an unbounded row
} // namespace

using direct::dot;
using direct::Mat;
using direct::sideA;
using direct::sideB;
using direct::SideJ;

// The compliance of a row holding a group redundantly, per unit of its own inverse effective mass
// (softenRedundantHolds).
constexpr double kRedundantHoldCompliance = 1e-2;

// The group's tree: a node per body and per jointed body pair, rooted at the joint to the world if there is one.
// False when the rows do not form one tree (a loop, more than one joint to the world).
bool RagdollSolver::Direct::layOut(Group& group) {
    const int bodies = static_cast<int>(group.bodies.size());
    // Joint nodes in the order their pairs first appear (a figure has a few dozen: a linear search is enough).
    std::vector<std::vector<int>>& nodeRows = group.nodeRows;
    std::vector<std::pair<int, int>>& pairs = group.pairs;
    pairs.clear();
    for (std::size_t i = 0; i < group.rows.size(); ++i) {
        const JointRow& row = group.rows[i];
        const std::pair<int, int> key{std::min(row.bodyA, row.bodyB), std::max(row.bodyA, row.bodyB)};
        const std::size_t node = static_cast<std::size_t>(std::find(pairs.begin(), pairs.end(), key) - pairs.begin());
        if (node == pairs.size()) {
            pairs.push_back(key);
            if (nodeRows.size() < pairs.size()) nodeRows.emplace_back();
            nodeRows[node].clear();
        }
        nodeRows[node].push_back(static_cast<int>(i));
    }
    const int nodes = bodies + static_cast<int>(pairs.size());
    std::vector<std::vector<int>>& adjacent = group.adjacent;
    if (adjacent.size() < static_cast<std::size_t>(nodes)) adjacent.resize(static_cast<std::size_t>(nodes));
    for (std::size_t i = 0; i < static_cast<std::size_t>(nodes); ++i) adjacent[i].clear();
    int edges = 0, root = 0, toWorld = 0;
    for (std::size_t j = 0; j < pairs.size(); ++j) {
        const int node = bodies + static_cast<int>(j);
        for (const int b : {pairs[j].first, pairs[j].second}) {
            if (b < 0) {
                root = node;
                ++toWorld;
                continue;
            }
            adjacent[static_cast<std::size_t>(node)].push_back(b);
            adjacent[static_cast<std::size_t>(b)].push_back(node);
            ++edges;
        }
    }
    if (toWorld > 1 || edges != nodes - 1) return false;
    std::vector<int>& parent = group.parent;
    std::vector<int>& queue = group.queue;
    queue.assign(1, root);
    parent.assign(static_cast<std::size_t>(nodes), -2);
    parent[static_cast<std::size_t>(root)] = -1;
    for (std::size_t q = 0; q < queue.size(); ++q)
        for (const int next : adjacent[static_cast<std::size_t>(queue[q])])
            if (parent[static_cast<std::size_t>(next)] == -2) {
                parent[static_cast<std::size_t>(next)] = queue[q];
                queue.push_back(next);
            }
    if (static_cast<int>(queue.size()) != nodes) return false;
    group.dims.assign(static_cast<std::size_t>(nodes), 6);
    for (std::size_t j = 0; j < pairs.size(); ++j)
        group.dims[static_cast<std::size_t>(bodies) + j] = static_cast<int>(nodeRows[j].size());
    return true;
}

// The group's H as a tree of body and joint nodes, factored (BlockTree). False when the group has a loop, more
// than one joint to the world (a leaf joint's pivot would be −C, zero), a body whose inertia cannot be inverted, or
// a pivot that is singular: the caller then factors A + C densely.
bool RagdollSolver::Direct::factorTree(Group& group, const btAlignedObjectArray<btSolverBody>& bodyPool,
                                       double epsilon) {
    const int bodies = static_cast<int>(group.bodies.size());
    std::vector<int>& key = group.layoutKey;
    bool same = key.size() == 1 + 2 * group.rows.size() && key[0] == bodies;
    for (std::size_t i = 0; same && i < group.rows.size(); ++i)
        same = key[1 + 2 * i] == group.rows[i].bodyA && key[2 + 2 * i] == group.rows[i].bodyB;
    if (!same) {
        key.assign(1, bodies);
        for (const JointRow& row : group.rows) key.insert(key.end(), {row.bodyA, row.bodyB});
        group.layoutTree = layOut(group);
    }
    if (!group.layoutTree) return false;
    const std::vector<int>& dims = group.dims;
    const std::vector<int>& parent = group.parent;
    const std::vector<std::pair<int, int>>& pairs = group.pairs;
    const std::vector<std::vector<int>>& nodeRows = group.nodeRows;
    BlockTree& tree = group.tree;
    // Every entry of every block is written below (the edges' by exactly one side of one row each).
    if (!tree.reset(dims, parent, false)) return false;
    // Bodies: M = diag(m, m, m, I_world); a leaf's pivot is M itself, so it gets M⁻¹ as Bullet keeps it.
    for (int x = 0; x < bodies; ++x) {
        std::fill(tree.diag(x), tree.diag(x) + 36, 0.0);
        const btRigidBody* rb = bodyPool[group.bodies[static_cast<std::size_t>(x)]].m_originalBody;
        const btMatrix3x3& invInertia = rb->getInvInertiaTensorWorld();
        const btVector3& local = rb->getInvInertiaDiagLocal();
        if (tree.leaf(x) && local.x() > 0 && local.y() > 0 && local.z() > 0) {
            double* inverseT = tree.diag(x);
            for (int q = 0; q < 3; ++q) inverseT[7 * q] = double(rb->getInvMass());
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c) inverseT[6 * (3 + r) + 3 + c] = double(invInertia[c][r]);
            tree.setInverted(x);
            continue;
        }
        Eigen::Matrix3d ii;
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) ii(r, c) = double(invInertia[r][c]);
        if (!(ii.determinant() > 0)) return false;
        const Eigen::Matrix3d inertia = ii.inverse();
        double* m = tree.diag(x);
        for (int q = 0; q < 3; ++q) m[7 * q] = 1.0 / double(rb->getInvMass());
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) m[6 * (3 + r) + 3 + c] = inertia(r, c);
    }
    // Joints: −(C + ε) on the diagonal, −J to the bodies.
    group.rowAt.assign(group.rows.size(), 0);
    for (std::size_t j = 0; j < pairs.size(); ++j) {
        const int node = bodies + static_cast<int>(j);
        const int k = dims[static_cast<std::size_t>(node)];
        std::fill(tree.diag(node), tree.diag(node) + k * k, 0.0);
        for (int slot = 0; slot < k; ++slot) {
            const int i = nodeRows[j][static_cast<std::size_t>(slot)];
            group.rowAt[static_cast<std::size_t>(i)] = tree.offset(node) + slot;
            tree.diag(node)[slot * k + slot] = -(group.cfm(i) + epsilon);
            const JointRow& row = group.rows[static_cast<std::size_t>(i)];
            for (int s = 0; s < 2; ++s) {
                const int b = s ? row.bodyB : row.bodyA;
                if (b < 0) continue;
                const SideJ& side = s ? row.b : row.a;
                const bool up = parent[static_cast<std::size_t>(node)] == b; // joint → body edge, else body → joint
                double* e = up ? tree.toParent(node) : tree.toParent(b);
                for (int q = 0; q < 6; ++q) {
                    const double v = -double(q < 3 ? side.lin[q] : side.ang[q - 3]);
                    (up ? e[slot * 6 + q] : e[q * k + slot]) = v;
                }
            }
        }
    }
    return tree.factor();
}

void RagdollSolver::setDirectJoints(bool on) { m_direct->enabled = on; }
bool RagdollSolver::directJoints() const { return m_direct->enabled; }
void RagdollSolver::setFrictionThroughGroups(bool on) { m_direct->frictionThroughGroups = on; }
bool RagdollSolver::frictionThroughGroups() const { return m_direct->frictionThroughGroups; }
void RagdollSolver::setJointSpace(bool on) { m_direct->jointSpace = on; }
bool RagdollSolver::jointSpace() const { return m_direct->jointSpace; }

bool RagdollSolver::buildDirect() {
    Direct& d = *m_direct;
    d.clear();
    if (!d.groupJointRows(m_tmpSolverBodyPool, m_tmpSolverNonContactConstraintPool, m_rows)) return false;
    d.factorGroups(m_tmpSolverBodyPool, m_tmpSolverNonContactConstraintPool);
    // Block mode (figureIterations) takes ragdolls with motors too: an unbounded motor is a soft row of the joint
    // solve (its cfm in the factorisation, its reactions kept up to date), a bounded one a soft row of the block.
    d.collectFreeRows(m_tmpSolverNonContactConstraintPool, m_tmpSolverContactConstraintPool,
                      m_tmpSolverContactFrictionConstraintPool);
    d.prepareColumns(m_tmpSolverBodyPool);
    d.denseColumns(m_tmpSolverBodyPool);
    d.block.clear(d.used);
    // The pool stays where it is until the step ends: the iterations reach the bodies through pointers.
    for (Direct::Group& group : d.live()) {
        group.bodyOf.clear();
        for (const int id : group.bodies) group.bodyOf.push_back(&m_tmpSolverBodyPool[id]);
    }
    for (auto* list : {&d.nonContact, &d.contact, &d.friction})
        for (Direct::FreeRow& fr : *list) {
            fr.at[0] = &m_tmpSolverBodyPool[fr.c->m_solverBodyIdA];
            fr.at[1] = &m_tmpSolverBodyPool[fr.c->m_solverBodyIdB];
        }
    return true;
}

// The unbounded rows of tracked constraints (joints): the bodies they join, in groups (union–find).
bool RagdollSolver::Direct::groupJointRows(const btAlignedObjectArray<btSolverBody>& bodyPool,
                                           const btAlignedObjectArray<btSolverConstraint>& pool,
                                           const btHashMap<btHashPtr, Tracked>& trackedRows) {
    const int bodyCount = bodyPool.size();
    groupOf.assign(static_cast<std::size_t>(bodyCount), -1);
    localOf.assign(static_cast<std::size_t>(bodyCount), -1);
    bilateral.assign(static_cast<std::size_t>(pool.size()), 0);
    // Per body, once: 0 not dynamic, 1 dynamic with unit factors, 2 dynamic with others (no group).
    const btVector3 one(1, 1, 1);
    bodyKind.resize(static_cast<std::size_t>(bodyCount));
    for (int i = 0; i < bodyCount; ++i) {
        const btSolverBody& b = bodyPool[i];
        bodyKind[static_cast<std::size_t>(i)] =
            !dynamicBody(b) ? 0 : (b.m_linearFactor == one && b.m_angularFactor == one ? 1 : 2);
    }
    auto dynamic = [&](int id) { return bodyKind[static_cast<std::size_t>(id)] != 0; };
    auto unit = [&](int id) { return bodyKind[static_cast<std::size_t>(id)] == 1; };
    // Union–find over the bodies the unbounded rows of tracked constraints join.
    std::vector<int>& parent = unionParent;
    parent.resize(static_cast<std::size_t>(bodyCount));
    for (int i = 0; i < bodyCount; ++i) parent[static_cast<std::size_t>(i)] = i;
    auto root = [this](int i) { return unionRoot(i); };
    bool any = false;
    // A constraint's rows are consecutive in the pool: one lookup per constraint, not per row.
    const void* lastConstraint = nullptr;
    bool lastDirect = false;
    for (int j = 0; j < pool.size(); ++j) {
        const btSolverConstraint& c = pool[j];
        if (c.m_lowerLimit > -unbounded || c.m_upperLimit < unbounded || c.m_jacDiagABInv == 0) continue;
        if (c.m_originalContactPoint != lastConstraint || lastConstraint == nullptr) {
            const Tracked* tracked = trackedRows.find(btHashPtr(c.m_originalContactPoint));
            lastConstraint = c.m_originalContactPoint;
            lastDirect = tracked != nullptr && tracked->direct;
        }
        if (!lastDirect) continue;
        const bool da = dynamic(c.m_solverBodyIdA), db = dynamic(c.m_solverBodyIdB);
        if ((!da && !db) || (da && !unit(c.m_solverBodyIdA)) || (db && !unit(c.m_solverBodyIdB))) continue;
        bilateral[static_cast<std::size_t>(j)] = 1;
        any = true;
        if (da && db) parent[static_cast<std::size_t>(root(c.m_solverBodyIdA))] = root(c.m_solverBodyIdB);
    }
    if (!any) return false;
    return groupRows(bodyPool, pool);
}

// Each group's bodies and joint rows (after groupJointRows' union–find).
bool RagdollSolver::Direct::groupRows(const btAlignedObjectArray<btSolverBody>& bodyPool,
                                      const btAlignedObjectArray<btSolverConstraint>& pool) {
    const int bodyCount = bodyPool.size();
    auto dynamic = [&](int id) { return bodyKind[static_cast<std::size_t>(id)] != 0; }; // groupJointRows'
    auto root = [this](int i) { return unionRoot(i); };
    groupOfRoot.assign(static_cast<std::size_t>(bodyCount), -1);
    auto groupFor = [&](int id) {
        const int r = root(id);
        int& g = groupOfRoot[static_cast<std::size_t>(r)];
        if (g < 0) {
            g = static_cast<int>(used++);
            if (groups.size() < used) groups.emplace_back();
        }
        if (groupOf[static_cast<std::size_t>(id)] < 0) {
            Direct::Group& group = groups[static_cast<std::size_t>(g)];
            groupOf[static_cast<std::size_t>(id)] = g;
            localOf[static_cast<std::size_t>(id)] = static_cast<int>(group.bodies.size());
            group.bodies.push_back(id);
            if (group.rowsAt.size() < group.bodies.size()) group.rowsAt.emplace_back(); // else cleared
        }
        return g;
    };
    for (int j = 0; j < pool.size(); ++j) {
        if (!bilateral[static_cast<std::size_t>(j)]) continue;
        const btSolverConstraint& c = pool[j];
        const bool da = dynamic(c.m_solverBodyIdA), db = dynamic(c.m_solverBodyIdB);
        const int g = da ? groupFor(c.m_solverBodyIdA) : groupFor(c.m_solverBodyIdB);
        if (da && db) groupFor(c.m_solverBodyIdB);
        Direct::Group& group = groups[static_cast<std::size_t>(g)];
        Direct::JointRow row{j};
        const int k = static_cast<int>(group.rows.size());
        if (da) {
            row.bodyA = localOf[static_cast<std::size_t>(c.m_solverBodyIdA)];
            row.a = sideA(c, bodyPool[c.m_solverBodyIdA]);
            group.rowsAt[static_cast<std::size_t>(row.bodyA)].push_back({k, 0});
        }
        if (db) {
            row.bodyB = localOf[static_cast<std::size_t>(c.m_solverBodyIdB)];
            row.b = sideB(c, bodyPool[c.m_solverBodyIdB]);
            group.rowsAt[static_cast<std::size_t>(row.bodyB)].push_back({k, 1});
        }
        group.rows.push_back(row);
    }
    return true;
}

// A group held to bodies outside it (the world, a keyframed or a static body) through two constraints or more: a
// body of a partial ragdoll between two keyframed ones (the pelvis above keyframed thighs) or a figure pinned to the
// world twice. Their hard rows can then outnumber the group's freedoms (two universal hips: eight rows on the
// pelvis's six) and agree only as far as the outside bodies keep what the joints hold; keyframed bodies move by
// themselves, along an animation interpolated between its frames, in float, that keeps it only nearly. The exact
// solve of contradicting rows has no solution: its only regularisation, 1e-9 of the largest diagonal, meets the
// contradiction with an impulse a billion times the row's, the iterations add as much again each time the residual
// comes back, warm starting carries it from step to step, and in float those impulses cancel only to their
// rounding, which kicks the bodies (the pelvis of the humanoid on keyframed legs turned 0.84 rad/s off its walk).
// These rows get a compliance of kRedundantHoldCompliance times their own inverse effective mass instead, in the
// row's cfm (its residual as well as the factor): the solve then meets a contradiction as a least-squares
// compromise with a bounded impulse, the same every iteration, and a row the others do not contradict reaches the
// velocity it asks for within that fraction (the position pass closes what is left). At 1e-3 the rounding still
// kicked the pelvis 0.29 rad/s at a 240 Hz step; at 1e-2 it follows its walk within 0.02 rad/s at 60 Hz and 0.05
// rad/s at 240 Hz. A group held through one constraint (a figure hanging from the world, from a keyframed root)
// keeps its hard rows bit for bit.
void RagdollSolver::Direct::softenRedundantHolds(Group& group, const btAlignedObjectArray<btSolverConstraint>& pool) {
    const void* first = nullptr;
    bool redundant = false;
    for (const JointRow& row : group.rows) {
        const btSolverConstraint& c = pool[row.pool];
        if ((row.bodyA < 0) == (row.bodyB < 0) || c.m_cfm != 0) continue; // inside the group, or soft already
        if (first == nullptr) first = c.m_originalContactPoint;
        else redundant = redundant || c.m_originalContactPoint != first;
    }
    if (!redundant) return;
    for (std::size_t i = 0; i < group.rows.size(); ++i) {
        const JointRow& row = group.rows[i];
        if ((row.bodyA < 0) == (row.bodyB < 0) || pool[row.pool].m_cfm != 0) continue;
        const double own = row.bodyA >= 0 ? dot(row.a, row.a) : dot(row.b, row.b);
        group.cfm(static_cast<Eigen::Index>(i)) += kRedundantHoldCompliance * own;
        group.soft = true;
        group.heldTwice = true;
    }
}

void RagdollSolver::Direct::factorGroups(const btAlignedObjectArray<btSolverBody>& bodyPool,
                                         const btAlignedObjectArray<btSolverConstraint>& pool) {
    // A + C per group, factored: along the figure's tree when it has one, densely otherwise.
    for (Direct::Group& group : live()) {
        const int n = static_cast<int>(group.rows.size());
        group.cfm.resize(n);
        group.target.resize(n);
        double largest = 0;
        for (int i = 0; i < n; ++i) {
            const Direct::JointRow& row = group.rows[static_cast<std::size_t>(i)];
            const btSolverConstraint& c = pool[row.pool];
            largest = std::max(largest,
                               (row.bodyA >= 0 ? dot(row.a, row.a) : 0.0) + (row.bodyB >= 0 ? dot(row.b, row.b) : 0.0));
            group.cfm(i) = double(c.m_cfm) / double(c.m_jacDiagABInv);
            group.target(i) = double(c.m_rhs) / double(c.m_jacDiagABInv);
            group.soft = group.soft || group.cfm(i) != 0;
        }
        softenRedundantHolds(group, pool);
        // A joint loop makes A singular; a relative regularisation keeps the factor finite.
        const double epsilon = 1e-9 * largest;
        group.useArticulated = jointSpace && Direct::factorArticulated(group, bodyPool);
        if (group.useArticulated) group.articulated.setTargets(std::span<const double>(group.target.data(), n));
        group.useTree = !group.useArticulated && Direct::factorTree(group, bodyPool, epsilon);
        if (!group.useTree && !group.useArticulated) {
            Mat a = Mat::Zero(n, n);
            for (const auto& at : group.rowsAt)
                for (const auto& [r1, s1] : at)
                    for (const auto& [r2, s2] : at) {
                        const Direct::JointRow& x = group.rows[static_cast<std::size_t>(r1)];
                        const Direct::JointRow& y = group.rows[static_cast<std::size_t>(r2)];
                        a(r1, r2) += dot(s1 ? x.b : x.a, s2 ? y.b : y.a);
                    }
            for (int i = 0; i < n; ++i) a(i, i) += group.cfm(i) + epsilon;
            group.ldlt.compute(a);
        }
        group.lambda.resize(n);
        for (int i = 0; i < n; ++i)
            group.lambda(i) = double(pool[group.rows[static_cast<std::size_t>(i)].pool].m_appliedImpulse);
    }
}

void RagdollSolver::Direct::collectFreeRows(btAlignedObjectArray<btSolverConstraint>& pool,
                                            btAlignedObjectArray<btSolverConstraint>& contactPool,
                                            btAlignedObjectArray<btSolverConstraint>& frictionPool) {
    // The other rows, with their responses through the groups.
    // Friction rows keep Bullet's response unless frictionThroughGroups (the next block solve restores the joints
    // they disturb, but the last iteration's friction leaves them disturbed; docs/methods.md).
    auto addFree = [&](std::vector<Direct::FreeRow>& out, btSolverConstraint& c, bool throughGroups) {
        Direct::FreeRow fr;
        fr.c = &c;
        fr.start = c.m_appliedImpulse;
        if (throughGroups) {
            fr.group[0] = groupOf[static_cast<std::size_t>(c.m_solverBodyIdA)];
            fr.group[1] = groupOf[static_cast<std::size_t>(c.m_solverBodyIdB)];
        }
        out.push_back(fr);
    };
    for (int j = 0; j < pool.size(); ++j)
        if (!bilateral[static_cast<std::size_t>(j)]) {
            // Joint friction (a row bounded on both sides: ±friction · the joint's last reaction) keeps Bullet's
            // response as contact friction does; limits (bounded on one side) move the whole group. Through the
            // group it was a third of the columns to solve each step and held nothing better: without it `exact`
            // costs 19 % less and passes more of the stress matrix (docs/methods.md).
            const btSolverConstraint& c = pool[j];
            const bool jointFriction = c.m_lowerLimit < 0 && c.m_upperLimit > 0 && c.m_upperLimit < unbounded;
            addFree(nonContact, pool[j], !jointFriction);
        }
    // A contact between two bodies of one group (a ragdoll touching itself) keeps Bullet's response too: the
    // joints between the two often all but lock the contact's direction, and its effective mass through the group
    // is then a thousand times the bodies' own; against a penetration bias that asks for a separation the joints
    // forbid, such a row pumped impulses of kN·s into the joints (a humanoid came apart in the air after a 100 m
    // drop).
    auto betweenGroups = [&](const btSolverConstraint& c) {
        const int ga = groupOf[static_cast<std::size_t>(c.m_solverBodyIdA)];
        return ga < 0 || ga != groupOf[static_cast<std::size_t>(c.m_solverBodyIdB)];
    };
    for (int j = 0; j < contactPool.size(); ++j) {
        btSolverConstraint& c = contactPool[j];
        addFree(contact, c, betweenGroups(c));
    }
    for (int j = 0; j < frictionPool.size(); ++j) {
        btSolverConstraint& c = frictionPool[j];
        addFree(friction, c, frictionThroughGroups && betweenGroups(c));
    }
}

void RagdollSolver::Direct::prepareColumns(const btAlignedObjectArray<btSolverBody>& bodyPool) {
    // Per group, the columns J M⁻¹ Jᵣᵀ of the free rows touching it. A row that touches only groups factored
    // along their trees waits until an update first needs its effective mass (complete()): a contact or limit row
    // that stays apart for the whole solve never pays for its responses (46 % of the columns of `exact`'s
    // 4-humanoid drop; docs/performance.md). A row touching a densely factored group is solved here, with
    // that group's other columns, in one batch.
    if (columns.size() < used) columns.resize(used);
    for (std::size_t g = 0; g < used; ++g) columns[g].clear();
    for (auto* list : {&nonContact, &contact, &friction})
        for (Direct::FreeRow& fr : *list) {
            btSolverConstraint& c = *fr.c;
            if (c.m_jacDiagABInv == 0) continue; // invEffectiveMass 0: the row is skipped, as Bullet would
            fr.cfmVel = double(c.m_cfm) / double(c.m_jacDiagABInv);
            fr.targetVel = double(c.m_rhs) / double(c.m_jacDiagABInv);
            double w = fr.cfmVel;
            fr.plain = 1.0 / double(c.m_jacDiagABInv);
            bool treesOnly = true, throughGroup = false;
            for (int s = 0; s < 2; ++s) {
                const int g = fr.group[s];
                if (g < 0) { // a body of no group: Bullet's own response
                    const SideJ side =
                        s ? sideB(c, bodyPool[c.m_solverBodyIdB]) : sideA(c, bodyPool[c.m_solverBodyIdA]);
                    w += dot(side, side);
                    continue;
                }
                throughGroup = true;
                treesOnly = treesOnly && (groups[static_cast<std::size_t>(g)].useTree ||
                                          groups[static_cast<std::size_t>(g)].useArticulated);
            }
            fr.invEffectiveMass = w; // completed below, or by complete()
            if (!throughGroup) {
                Direct::finish(fr);
                continue;
            }
            if (treesOnly) {
                fr.pending = true;
                continue;
            }
            for (int s = 0; s < 2; ++s) {
                const int g = fr.group[s];
                if (g < 0 || (s == 1 && fr.group[0] == g)) continue; // one response covers both sides
                columns[static_cast<std::size_t>(g)].push_back({&fr, s, fr.group[0] == g, fr.group[1] == g});
            }
        }
}

void RagdollSolver::Direct::denseColumns(const btAlignedObjectArray<btSolverBody>& bodyPool) {
    for (std::size_t g = 0; g < used; ++g) {
        Direct::Group& group = groups[g];
        const std::vector<Direct::Column>& cols = columns[g];
        if (cols.empty()) continue; // no other row touches the group (Eigen's solve of a 0-column matrix is UB)
        if (group.useTree || group.useArticulated) {
            for (const Direct::Column& col : cols) treeColumn(*col.row, col.side, col.withA, col.withB, bodyPool);
            continue;
        }
        const Eigen::Index k = static_cast<Eigen::Index>(group.rows.size());
        const std::size_t nb = group.bodies.size();
        // The right-hand sides J M⁻¹ Jᵣᵀ, one per column, solved in one batch.
        Mat gm = Mat::Zero(k, static_cast<Eigen::Index>(cols.size()));
        for (std::size_t col = 0; col < cols.size(); ++col) {
            const btSolverConstraint& c = *cols[col].row->c;
            auto gather = [&](int xb, const SideJ& rs) {
                for (const auto& [i, si] : group.rowsAt[static_cast<std::size_t>(xb)]) {
                    const Direct::JointRow& jr = group.rows[static_cast<std::size_t>(i)];
                    gm(i, static_cast<Eigen::Index>(col)) += dot(si ? jr.b : jr.a, rs);
                }
            };
            if (cols[col].withA)
                gather(localOf[static_cast<std::size_t>(c.m_solverBodyIdA)], sideA(c, bodyPool[c.m_solverBodyIdA]));
            if (cols[col].withB)
                gather(localOf[static_cast<std::size_t>(c.m_solverBodyIdB)], sideB(c, bodyPool[c.m_solverBodyIdB]));
        }
        const Mat y = group.ldlt.solve(gm);
        for (std::size_t col = 0; col < cols.size(); ++col) {
            Direct::FreeRow& fr = *cols[col].row;
            const btSolverConstraint& c = *fr.c;
            const int s = cols[col].side;
            const int xa = cols[col].withA ? localOf[static_cast<std::size_t>(c.m_solverBodyIdA)] : -1;
            const int xb = cols[col].withB ? localOf[static_cast<std::size_t>(c.m_solverBodyIdB)] : -1;
            const SideJ sa = sideA(c, bodyPool[c.m_solverBodyIdA]);
            const SideJ sb = sideB(c, bodyPool[c.m_solverBodyIdB]);
            fr.reaction[s] = static_cast<int>(reactions.size());
            reactions.resize(reactions.size() + static_cast<std::size_t>(k));
            double* reaction = reactions.data() + fr.reaction[s];
            // u = M⁻¹Jᵣᵀ − M⁻¹Jᵀ y, per group body
            response.assign(6 * nb, 0.0);
            double* u = response.data();
            const Eigen::Index ci = static_cast<Eigen::Index>(col);
            for (Eigen::Index i = 0; i < k; ++i) reaction[i] = y(i, ci);
            auto add = [&](int xb2, const btVector3& lin, const btVector3& ang, double f) {
                for (int q = 0; q < 3; ++q) {
                    u[6 * xb2 + q] += f * double(lin[q]);
                    u[6 * xb2 + 3 + q] += f * double(ang[q]);
                }
            };
            if (xa >= 0) add(xa, sa.linInv, sa.angInv, 1);
            if (xb >= 0) add(xb, sb.linInv, sb.angInv, 1);
            for (Eigen::Index i = 0; i < k; ++i) {
                const Direct::JointRow& jr = group.rows[static_cast<std::size_t>(i)];
                if (jr.bodyA >= 0) add(jr.bodyA, jr.a.linInv, jr.a.angInv, -reaction[i]);
                if (jr.bodyB >= 0) add(jr.bodyB, jr.b.linInv, jr.b.angInv, -reaction[i]);
            }
            keepResponse(fr, s, xa, sa, xb, sb, nb);
        }
    }
    for (auto* list : {&nonContact, &contact, &friction})
        for (Direct::FreeRow& fr : *list)
            if (!fr.pending && fr.c->m_jacDiagABInv != 0 && (fr.group[0] >= 0 || fr.group[1] >= 0)) Direct::finish(fr);
}

void RagdollSolver::Direct::keepResponse(FreeRow& fr, int s, int xa, const SideJ& sa, int xb, const SideJ& sb,
                                         std::size_t nb) {
    const double* u = response.data();
    auto jdotu = [&](int x, const SideJ& rs) {
        double v = 0;
        for (int q = 0; q < 3; ++q) v += double(rs.lin[q]) * u[6 * x + q] + double(rs.ang[q]) * u[6 * x + 3 + q];
        return v;
    };
    if (xa >= 0) fr.invEffectiveMass += jdotu(xa, sa);
    if (xb >= 0) fr.invEffectiveMass += jdotu(xb, sb);
    // Stored in Bullet's precision and layout: the iterations apply it as Bullet applies its own.
    fr.response[s] = static_cast<int>(responses.size());
    for (std::size_t x = 0; x < nb; ++x) {
        const double* ux = u + 6 * x;
        responses.emplace_back(btScalar(ux[0]), btScalar(ux[1]), btScalar(ux[2]));
        responses.emplace_back(btScalar(ux[3]), btScalar(ux[4]), btScalar(ux[5]));
    }
}

void RagdollSolver::Direct::treeColumn(FreeRow& fr, int s, bool withA, bool withB,
                                       const btAlignedObjectArray<btSolverBody>& bodyPool) {
    Group& group = groups[static_cast<std::size_t>(fr.group[s])];
    if (group.useArticulated) {
        articulatedColumn(fr, s, withA, withB, bodyPool);
        return;
    }
    const btSolverConstraint& c = *fr.c;
    const std::size_t nb = group.bodies.size();
    const int k = static_cast<int>(group.rows.size());
    const int xa = withA ? localOf[static_cast<std::size_t>(c.m_solverBodyIdA)] : -1;
    const int xb = withB ? localOf[static_cast<std::size_t>(c.m_solverBodyIdB)] : -1;
    const SideJ sa = sideA(c, bodyPool[c.m_solverBodyIdA]);
    const SideJ sb = sideB(c, bodyPool[c.m_solverBodyIdB]);
    // H [u; λ] = [Jᵣᵀ; 0]: u is the response, λ = −y the joints' reaction.
    std::vector<double>& x = solveX;
    x.assign(static_cast<std::size_t>(group.tree.size()), 0.0);
    auto put = [&](int xb2, const SideJ& rs) {
        for (int q = 0; q < 3; ++q) {
            x[static_cast<std::size_t>(6 * xb2 + q)] += double(rs.lin[q]);
            x[static_cast<std::size_t>(6 * xb2 + 3 + q)] += double(rs.ang[q]);
        }
    };
    if (xa >= 0) put(xa, sa);
    if (xb >= 0) put(xb, sb);
    group.tree.solveFrom(x.data(), xa, xb);
    fr.reaction[s] = static_cast<int>(reactions.size());
    reactions.resize(reactions.size() + static_cast<std::size_t>(k));
    double* reaction = reactions.data() + fr.reaction[s];
    for (int i = 0; i < k; ++i) reaction[i] = -x[static_cast<std::size_t>(group.rowAt[static_cast<std::size_t>(i)])];
    response.assign(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(6 * nb));
    keepResponse(fr, s, xa, sa, xb, sb, nb);
}

void RagdollSolver::Direct::finish(FreeRow& fr) {
    // A row the joints already hold (friction about a locked axis, a limit on a locked direction) has no
    // effective mass left, only rounding: it is skipped rather than given an impulse of 1/rounding.
    const double w = fr.invEffectiveMass; // the effective mass's inverse, summed
    fr.invEffectiveMass = w > 1e-6 * std::abs(fr.plain) ? 1.0 / w : 0.0;
}

void RagdollSolver::Direct::complete(FreeRow& fr, const btAlignedObjectArray<btSolverBody>& bodyPool) {
    // In the order of the groups, as the batch of buildDirect sums a row's parts.
    const bool swap = fr.group[0] >= 0 && fr.group[1] >= 0 && fr.group[1] < fr.group[0];
    for (int i = 0; i < 2; ++i) {
        const int s = swap ? 1 - i : i;
        const int g = fr.group[s];
        if (g < 0 || (s == 1 && fr.group[0] == g)) continue;
        treeColumn(fr, s, fr.group[0] == g, fr.group[1] == g, bodyPool);
    }
    finish(fr);
    fr.pending = false;
}

} // namespace afb::bullet
