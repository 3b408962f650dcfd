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

#include <Eigen/Dense>

#include "BlockTree.h"
#include "RowKernels.h"

namespace afb::bullet {

// ---- Direct joint solve (Method::directJoints) --------------------------------------------------------------------
//
// The rows of the tracked constraints that have no bounds (a joint's anchor and locked axes) form, per connected
// group of bodies (a ragdoll), a linear system (A + C) λ = e with A = J M⁻¹ Jᵀ: solved exactly (LDLᵀ, factored
// once per solve), every joint of the group holds at the velocity level after each iteration whatever the other
// rows did. Every other row touching the group (contacts and limits) is solved one at a time as in Bullet, but its
// impulse moves the whole group as the joints let it (contact and joint friction, and contacts of a group with
// itself, keep Bullet's response, see buildDirect): its response is
// u = M⁻¹Jᵣᵀ − M⁻¹Jᵀ (A + C)⁻¹ J M⁻¹Jᵣᵀ (the joints' reaction included) and its effective mass is Jᵣ u. A foot
// that lands then stops the body above it in one row update instead of one link per iteration (Baraff, "Linear-
// time dynamics using Lagrange multipliers", 1996, for the block; this is its dense form, per ragdoll).
namespace {

using Vec = Eigen::VectorXd;
using Mat = Eigen::MatrixXd;

// One side of a row at one body: the linear and angular Jacobian and M⁻¹ times them (as Bullet stores them).
struct SideJ {
    btVector3 lin, ang;       // J
    btVector3 linInv, angInv; // M⁻¹ Jᵀ: invMass ∘ lin (linear factor included), the row's angular component
};

SideJ sideA(const btSolverConstraint& c, const btSolverBody& b) {
    return {c.m_contactNormal1, c.m_relpos1CrossNormal, c.m_contactNormal1 * b.internalGetInvMass(),
            c.m_angularComponentA};
}
SideJ sideB(const btSolverConstraint& c, const btSolverBody& b) {
    return {c.m_contactNormal2, c.m_relpos2CrossNormal, c.m_contactNormal2 * b.internalGetInvMass(),
            c.m_angularComponentB};
}

// v += u · s over x, y and z, rounded as btVector3's `v += u * s` rounds (a product, then a sum, per component):
// with SSE the four lanes at once (the fourth is btVector3's padding, which no operation reads).
inline void addScaled(btVector3& v, const btVector3& u, btScalar s) {
#if defined(__SSE2__) && !defined(BT_USE_DOUBLE_PRECISION)
    _mm_storeu_ps(v.m_floats,
                  _mm_add_ps(_mm_loadu_ps(v.m_floats), _mm_mul_ps(_mm_loadu_ps(u.m_floats), _mm_set1_ps(s))));
#else
    v += u * s;
#endif
}

double dot(const SideJ& row, const SideJ& other) { // J_row · M⁻¹ J_otherᵀ at a shared body
    return double(row.lin.dot(other.linInv)) + double(row.ang.dot(other.angInv));
}

} // namespace

struct RagdollSolver::Direct {
    // A joint row of a group: its pool index and its two sides (side b absent for a body outside the group).
    struct JointRow {
        int pool;
        int bodyA = -1, bodyB = -1; // local body indices, −1 when that side is not in the group
        SideJ a{}, b{};
    };
    struct Group {
        std::vector<int> bodies; // solver body ids
        std::vector<JointRow> rows;
        std::vector<std::vector<std::pair<int, int>>> rowsAt; // per local body: (joint row, side 0 = A / 1 = B)
        Eigen::LDLT<Mat> ldlt; // the dense factor, when the tree's cannot be used (a loop, two world joints)
        // The sparse factor: the bodies (nodes 0…n−1) and one node per jointed body pair (its rows), a tree when
        // the figure has no loop. H = [[M, −Jᵀ], [−J, −C]]; `rowAt` is each joint row's entry in its vectors.
        BlockTree tree;
        bool useTree = false;
        std::vector<int> rowAt;
        Vec cfm;           // C's diagonal
        Vec target;        // each row's rhs / jacDiagABInv: the velocity it asks for (fixed for the solve)
        Vec lambda;        // the rows' accumulated impulses (without the reactions to free rows unless `soft`)
        bool soft = false; // a row has a cfm: its reactions are kept up to date (the block solve needs them)
        // The tree's layout, kept from step to step while the rows join the same body pairs in the same order
        // (a figure's joints do): `layoutKey` is the bodies' count then each row's two local bodies.
        std::vector<int> layoutKey, dims, parent;
        std::vector<std::vector<int>> nodeRows; // per joint node: its rows (the first pairs.size())
        std::vector<std::pair<int, int>> pairs; // per joint node: its body pair (−1: the world)
        std::vector<std::vector<int>> adjacent; // layOut's scratch: per node, its neighbours
        std::vector<int> queue;
        bool layoutTree = false; // the layout is a tree (else the dense factor is used)

        // Empties the group for the next step, keeping its buffers and its layout.
        void clear() {
            bodies.clear();
            rows.clear();
            for (auto& at : rowsAt) at.clear();
            useTree = false;
            soft = false;
        }
    };
    // A row solved one at a time, with its response through the groups it touches.
    struct FreeRow {
        btSolverConstraint* c = nullptr;
        int group[2] = {-1, -1};     // group of side A, of side B (−1: a plain body)
        int response[2] = {-1, -1};  // offsets in `responses` (linear, angular per group body), per distinct group
        int reaction[2] = {-1, -1};  // offsets in `reactions` (one per group joint row)
        double invEffectiveMass = 0; // 1 / (Jᵣ u + cfm′), 0: skip
        double cfmVel = 0;           // the row's cfm in velocity units
        double plain = 0;            // J M⁻¹ Jᵀ of the touching bodies alone (the row's scale)
        btScalar start = 0;          // the row's impulse before the iterations (warm start)
        bool pending = false;        // its responses through the groups are not computed yet (complete())
    };

    static bool layOut(Group& group);
    static bool factorTree(Group& group, const btAlignedObjectArray<btSolverBody>& bodyPool, double epsilon);
    // A row's response through one group whose tree is factored (side s's slot; withA, withB: which of its
    // bodies are in the group), its part of Jᵣ u added to the row's invEffectiveMass (still the sum w).
    void treeColumn(FreeRow& fr, int s, bool withA, bool withB, const btAlignedObjectArray<btSolverBody>& bodyPool);
    // The row's effective mass from w, the sum of its parts.
    static void finish(FreeRow& fr);
    // Appends the response in `response` (6 per group body) to `responses` as side s's, and its Jᵣ u to the
    // row's w.
    void keepResponse(FreeRow& fr, int s, int xa, const SideJ& sa, int xb, const SideJ& sb, std::size_t nb);
    // A pending row's responses through every group it touches, and its effective mass.
    void complete(FreeRow& fr, const btAlignedObjectArray<btSolverBody>& bodyPool);
    // Whether a row update ends with no change whatever the row's effective mass: the velocity still to go
    // pushes the impulse past a bound of 0 it already sits at (a contact or limit not touching), or there is
    // none left to go. Only rows bounded at 0 are decided this way, so that the result is the one the full
    // update gives bit for bit.
    static bool heldAtZeroBound(double toGo, double applied, double lower, double upper) {
        if (toGo < 0) return applied == 0 && lower == 0;
        if (toGo > 0) return applied == 0 && upper == 0;
        return toGo == 0 && applied >= lower && applied <= upper;
    }

    bool enabled = false;
    bool frictionThroughGroups = false; // Method::frictionThroughFigure
    // The groups of this step are the first `used`; the others wait, with their buffers, for a later step.
    std::vector<Group> groups;
    std::size_t used = 0;
    std::span<Group> live() { return {groups.data(), used}; }
    std::vector<int> groupOf, localOf; // per solver body
    std::vector<FreeRow> nonContact, contact, friction;
    std::vector<btVector3> responses; // M⁻¹-weighted velocity change per unit impulse, per group body
    std::vector<double> reactions;
    std::vector<double> response; // one response being computed, 6 per group body
    std::vector<double> scratch;
    std::vector<char> bilateral; // per non-contact pool row: in a group's block
    // Per step scratch, kept for its capacity.
    struct Column {
        FreeRow* row;
        int side; // the response slot (0: side A's group, which covers B too when it is the same group)
        bool withA, withB;
    };
    std::vector<std::vector<Column>> columns; // per group
    std::vector<int> unionParent, groupOfRoot;
    std::vector<double> solveX;
    std::vector<double> e; // one group's joint errors

    void clear() {
        for (Group& g : live()) g.clear();
        used = 0;
        nonContact.clear();
        contact.clear();
        friction.clear();
        responses.clear();
        reactions.clear();
    }
};

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
    if (!tree.reset(dims, parent)) return false;
    // Bodies: M = diag(m, m, m, I_world).
    for (int x = 0; x < bodies; ++x) {
        const btRigidBody* rb = bodyPool[group.bodies[static_cast<std::size_t>(x)]].m_originalBody;
        const btMatrix3x3& invInertia = rb->getInvInertiaTensorWorld();
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
                    (up ? e[slot * 6 + q] : e[q * k + slot]) += v;
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

bool RagdollSolver::buildDirect() {
    Direct& d = *m_direct;
    d.clear();
    const int bodyCount = m_tmpSolverBodyPool.size();
    d.groupOf.assign(static_cast<std::size_t>(bodyCount), -1);
    d.localOf.assign(static_cast<std::size_t>(bodyCount), -1);
    auto& pool = m_tmpSolverNonContactConstraintPool;
    d.bilateral.assign(static_cast<std::size_t>(pool.size()), 0);
    const btVector3 one(1, 1, 1);
    auto dynamic = [&](int id) {
        const btSolverBody& b = m_tmpSolverBodyPool[id];
        return b.m_originalBody != nullptr && b.m_originalBody->getInvMass() > 0;
    };
    auto unit = [&](int id) {
        const btSolverBody& b = m_tmpSolverBodyPool[id];
        return b.m_linearFactor == one && b.m_angularFactor == one;
    };
    // Union–find over the bodies the unbounded rows of tracked constraints join.
    std::vector<int>& parent = d.unionParent;
    parent.resize(static_cast<std::size_t>(bodyCount));
    for (int i = 0; i < bodyCount; ++i) parent[static_cast<std::size_t>(i)] = i;
    auto root = [&](int i) {
        while (parent[static_cast<std::size_t>(i)] != i)
            i = parent[static_cast<std::size_t>(i)] =
                parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(i)])];
        return i;
    };
    const btScalar unbounded = btScalar(1e30);
    bool any = false;
    for (int j = 0; j < pool.size(); ++j) {
        const btSolverConstraint& c = pool[j];
        if (c.m_lowerLimit > -unbounded || c.m_upperLimit < unbounded || c.m_jacDiagABInv == 0) continue;
        const Tracked* tracked = m_rows.find(btHashPtr(c.m_originalContactPoint));
        if (tracked == nullptr || !tracked->direct) continue;
        const bool da = dynamic(c.m_solverBodyIdA), db = dynamic(c.m_solverBodyIdB);
        if ((!da && !db) || (da && !unit(c.m_solverBodyIdA)) || (db && !unit(c.m_solverBodyIdB))) continue;
        d.bilateral[static_cast<std::size_t>(j)] = 1;
        any = true;
        if (da && db) parent[static_cast<std::size_t>(root(c.m_solverBodyIdA))] = root(c.m_solverBodyIdB);
    }
    if (!any) return false;
    // Groups, their bodies and their joint rows.
    std::vector<int>& groupOfRoot = d.groupOfRoot;
    groupOfRoot.assign(static_cast<std::size_t>(bodyCount), -1);
    auto groupFor = [&](int id) {
        const int r = root(id);
        int& g = groupOfRoot[static_cast<std::size_t>(r)];
        if (g < 0) {
            g = static_cast<int>(d.used++);
            if (d.groups.size() < d.used) d.groups.emplace_back();
        }
        if (d.groupOf[static_cast<std::size_t>(id)] < 0) {
            Direct::Group& group = d.groups[static_cast<std::size_t>(g)];
            d.groupOf[static_cast<std::size_t>(id)] = g;
            d.localOf[static_cast<std::size_t>(id)] = static_cast<int>(group.bodies.size());
            group.bodies.push_back(id);
            if (group.rowsAt.size() < group.bodies.size()) group.rowsAt.emplace_back(); // else cleared
        }
        return g;
    };
    for (int j = 0; j < pool.size(); ++j) {
        if (!d.bilateral[static_cast<std::size_t>(j)]) continue;
        const btSolverConstraint& c = pool[j];
        const bool da = dynamic(c.m_solverBodyIdA), db = dynamic(c.m_solverBodyIdB);
        const int g = da ? groupFor(c.m_solverBodyIdA) : groupFor(c.m_solverBodyIdB);
        if (da && db) groupFor(c.m_solverBodyIdB);
        Direct::Group& group = d.groups[static_cast<std::size_t>(g)];
        Direct::JointRow row{j};
        const int k = static_cast<int>(group.rows.size());
        if (da) {
            row.bodyA = d.localOf[static_cast<std::size_t>(c.m_solverBodyIdA)];
            row.a = sideA(c, m_tmpSolverBodyPool[c.m_solverBodyIdA]);
            group.rowsAt[static_cast<std::size_t>(row.bodyA)].push_back({k, 0});
        }
        if (db) {
            row.bodyB = d.localOf[static_cast<std::size_t>(c.m_solverBodyIdB)];
            row.b = sideB(c, m_tmpSolverBodyPool[c.m_solverBodyIdB]);
            group.rowsAt[static_cast<std::size_t>(row.bodyB)].push_back({k, 1});
        }
        group.rows.push_back(row);
    }
    // A + C per group, factored: along the figure's tree when it has one, densely otherwise.
    for (Direct::Group& group : d.live()) {
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
        // A joint loop makes A singular; a relative regularisation keeps the factor finite.
        const double epsilon = 1e-9 * largest;
        group.useTree = Direct::factorTree(group, m_tmpSolverBodyPool, epsilon);
        if (!group.useTree) {
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
    // The other rows, with their responses through the groups.
    // Friction rows keep Bullet's response unless frictionThroughGroups (the next block solve restores the joints
    // they disturb, but the last iteration's friction leaves them disturbed; README: Methods, point 20).
    auto addFree = [&](std::vector<Direct::FreeRow>& out, btSolverConstraint& c, bool throughGroups) {
        Direct::FreeRow fr;
        fr.c = &c;
        fr.start = c.m_appliedImpulse;
        if (throughGroups) {
            fr.group[0] = d.groupOf[static_cast<std::size_t>(c.m_solverBodyIdA)];
            fr.group[1] = d.groupOf[static_cast<std::size_t>(c.m_solverBodyIdB)];
        }
        out.push_back(fr);
    };
    for (int j = 0; j < pool.size(); ++j)
        if (!d.bilateral[static_cast<std::size_t>(j)]) {
            // Joint friction (a row bounded on both sides: ±friction · the joint's last reaction) keeps Bullet's
            // response as contact friction does; limits (bounded on one side) move the whole group. Through the
            // group it was a third of the columns to solve each step and held nothing better: without it `exact`
            // costs 19 % less and passes more of the stress matrix (README: Methods, point 17).
            const btSolverConstraint& c = pool[j];
            const bool jointFriction = c.m_lowerLimit < 0 && c.m_upperLimit > 0 && c.m_upperLimit < unbounded;
            addFree(d.nonContact, pool[j], !jointFriction);
        }
    // A contact between two bodies of one group (a ragdoll touching itself) keeps Bullet's response too: the
    // joints between the two often all but lock the contact's direction, and its effective mass through the group
    // is then a thousand times the bodies' own; against a penetration bias that asks for a separation the joints
    // forbid, such a row pumped impulses of kN·s into the joints (a humanoid came apart in the air after a 100 m
    // drop).
    auto betweenGroups = [&](const btSolverConstraint& c) {
        const int ga = d.groupOf[static_cast<std::size_t>(c.m_solverBodyIdA)];
        return ga < 0 || ga != d.groupOf[static_cast<std::size_t>(c.m_solverBodyIdB)];
    };
    for (int j = 0; j < m_tmpSolverContactConstraintPool.size(); ++j) {
        btSolverConstraint& c = m_tmpSolverContactConstraintPool[j];
        addFree(d.contact, c, betweenGroups(c));
    }
    for (int j = 0; j < m_tmpSolverContactFrictionConstraintPool.size(); ++j) {
        btSolverConstraint& c = m_tmpSolverContactFrictionConstraintPool[j];
        addFree(d.friction, c, d.frictionThroughGroups && betweenGroups(c));
    }
    // Per group, the columns J M⁻¹ Jᵣᵀ of the free rows touching it. A row that touches only groups factored
    // along their trees waits until an update first needs its effective mass (complete()): a contact or limit row
    // that stays apart for the whole solve never pays for its responses (46 % of the columns of `exact`'s
    // 4-humanoid drop; README: Methods, point 18). A row touching a densely factored group is solved here, with
    // that group's other columns, in one batch.
    std::vector<std::vector<Direct::Column>>& columns = d.columns;
    if (columns.size() < d.used) columns.resize(d.used);
    for (std::size_t g = 0; g < d.used; ++g) columns[g].clear();
    for (auto* list : {&d.nonContact, &d.contact, &d.friction})
        for (Direct::FreeRow& fr : *list) {
            btSolverConstraint& c = *fr.c;
            if (c.m_jacDiagABInv == 0) continue; // invEffectiveMass 0: the row is skipped, as Bullet would
            fr.cfmVel = double(c.m_cfm) / double(c.m_jacDiagABInv);
            double w = fr.cfmVel;
            fr.plain = 1.0 / double(c.m_jacDiagABInv);
            bool treesOnly = true, throughGroup = false;
            for (int s = 0; s < 2; ++s) {
                const int g = fr.group[s];
                if (g < 0) { // a body of no group: Bullet's own response
                    const SideJ side = s ? sideB(c, m_tmpSolverBodyPool[c.m_solverBodyIdB])
                                         : sideA(c, m_tmpSolverBodyPool[c.m_solverBodyIdA]);
                    w += dot(side, side);
                    continue;
                }
                throughGroup = true;
                treesOnly = treesOnly && d.groups[static_cast<std::size_t>(g)].useTree;
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
    for (std::size_t g = 0; g < d.used; ++g) {
        Direct::Group& group = d.groups[g];
        const std::vector<Direct::Column>& cols = columns[g];
        if (cols.empty()) continue; // no other row touches the group (Eigen's solve of a 0-column matrix is UB)
        if (group.useTree) {
            for (const Direct::Column& col : cols)
                d.treeColumn(*col.row, col.side, col.withA, col.withB, m_tmpSolverBodyPool);
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
                gather(d.localOf[static_cast<std::size_t>(c.m_solverBodyIdA)],
                       sideA(c, m_tmpSolverBodyPool[c.m_solverBodyIdA]));
            if (cols[col].withB)
                gather(d.localOf[static_cast<std::size_t>(c.m_solverBodyIdB)],
                       sideB(c, m_tmpSolverBodyPool[c.m_solverBodyIdB]));
        }
        const Mat y = group.ldlt.solve(gm);
        for (std::size_t col = 0; col < cols.size(); ++col) {
            Direct::FreeRow& fr = *cols[col].row;
            const btSolverConstraint& c = *fr.c;
            const int s = cols[col].side;
            const int xa = cols[col].withA ? d.localOf[static_cast<std::size_t>(c.m_solverBodyIdA)] : -1;
            const int xb = cols[col].withB ? d.localOf[static_cast<std::size_t>(c.m_solverBodyIdB)] : -1;
            const SideJ sa = sideA(c, m_tmpSolverBodyPool[c.m_solverBodyIdA]);
            const SideJ sb = sideB(c, m_tmpSolverBodyPool[c.m_solverBodyIdB]);
            fr.reaction[s] = static_cast<int>(d.reactions.size());
            d.reactions.resize(d.reactions.size() + static_cast<std::size_t>(k));
            double* reaction = d.reactions.data() + fr.reaction[s];
            // u = M⁻¹Jᵣᵀ − M⁻¹Jᵀ y, per group body
            d.response.assign(6 * nb, 0.0);
            double* u = d.response.data();
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
            d.keepResponse(fr, s, xa, sa, xb, sb, nb);
        }
    }
    for (auto* list : {&d.nonContact, &d.contact, &d.friction})
        for (Direct::FreeRow& fr : *list)
            if (!fr.pending && fr.c->m_jacDiagABInv != 0 && (fr.group[0] >= 0 || fr.group[1] >= 0)) Direct::finish(fr);
    return true;
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
    group.tree.solve(x.data());
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

btScalar RagdollSolver::solveDirectIteration(int iteration, const btContactSolverInfo& infoGlobal) {
    Direct& d = *m_direct;
    auto& pool = m_tmpSolverNonContactConstraintPool;
    double residual = 0;
    auto relVel = [&](const btSolverConstraint& c) {
        return double(detail::rowVelocitySum<detail::RowTarget::Velocity>(m_tmpSolverBodyPool[c.m_solverBodyIdA],
                                                                          m_tmpSolverBodyPool[c.m_solverBodyIdB], c));
    };
    // The joints of every group, exactly.
    for (Direct::Group& group : d.live()) {
        const Eigen::Index n = static_cast<Eigen::Index>(group.rows.size());
        d.e.resize(static_cast<std::size_t>(n));
        Eigen::Map<Vec> e(d.e.data(), n);
        double largest = residual; // kept in a register over the rows
        for (Eigen::Index i = 0; i < n; ++i) {
            const btSolverConstraint& c = pool[group.rows[static_cast<std::size_t>(i)].pool];
            e(i) = group.target(i) - group.cfm(i) * group.lambda(i) - relVel(c);
            largest = std::max(largest, e(i) * e(i));
        }
        residual = largest;
        if (group.useTree) {
            // H [Δv; Δλ] = [0; −e]: the bodies' velocity changes come out with the impulses.
            d.scratch.assign(static_cast<std::size_t>(group.tree.size()), 0.0);
            for (Eigen::Index i = 0; i < n; ++i)
                d.scratch[static_cast<std::size_t>(group.rowAt[static_cast<std::size_t>(i)])] = -e(i);
            group.tree.solve(d.scratch.data());
            if (!std::all_of(d.scratch.begin(), d.scratch.end(), [](double v) { return std::isfinite(v); })) continue;
            for (Eigen::Index i = 0; i < n; ++i)
                group.lambda(i) += d.scratch[static_cast<std::size_t>(group.rowAt[static_cast<std::size_t>(i)])];
            for (std::size_t xb = 0; xb < group.bodies.size(); ++xb) {
                btSolverBody& b = m_tmpSolverBodyPool[group.bodies[xb]];
                const double* dv = d.scratch.data() + 6 * xb;
                b.m_deltaLinearVelocity += btVector3(btScalar(dv[0]), btScalar(dv[1]), btScalar(dv[2]));
                b.m_deltaAngularVelocity += btVector3(btScalar(dv[3]), btScalar(dv[4]), btScalar(dv[5]));
            }
            continue;
        }
        const Vec dl = group.ldlt.solve(e);
        if (!dl.allFinite()) continue;
        group.lambda += dl;
        for (Eigen::Index i = 0; i < n; ++i) {
            const Direct::JointRow& jr = group.rows[static_cast<std::size_t>(i)];
            const btScalar l = static_cast<btScalar>(dl(i));
            const btSolverConstraint& c = pool[jr.pool];
            if (jr.bodyA >= 0) {
                btSolverBody& b = m_tmpSolverBodyPool[c.m_solverBodyIdA];
                b.m_deltaLinearVelocity += jr.a.linInv * l;
                b.m_deltaAngularVelocity += jr.a.angInv * l;
            }
            if (jr.bodyB >= 0) {
                btSolverBody& b = m_tmpSolverBodyPool[c.m_solverBodyIdB];
                b.m_deltaLinearVelocity += jr.b.linInv * l;
                b.m_deltaAngularVelocity += jr.b.angInv * l;
            }
        }
    }
    // One free row: Bullet's update with the effective mass and the response of the whole group.
    btSolverBody* const bodies = &m_tmpSolverBodyPool[0];
    // Returns the row's residual term, dl² / invEffectiveMass² (0: no change); the caller keeps the largest.
    auto resolve = [&](Direct::FreeRow& fr) -> double {
        btSolverConstraint& c = *fr.c;
        if (!fr.pending && fr.invEffectiveMass == 0) return 0;
        const double target =
            (double(c.m_rhs) - double(c.m_cfm) * double(c.m_appliedImpulse)) / double(c.m_jacDiagABInv);
        const double toGo = target - relVel(c);
        if (fr.pending) {
            if (Direct::heldAtZeroBound(toGo, double(c.m_appliedImpulse), double(c.m_lowerLimit),
                                        double(c.m_upperLimit)))
                return 0;
            d.complete(fr, m_tmpSolverBodyPool);
            if (fr.invEffectiveMass == 0) return 0;
        }
        double dl = toGo * fr.invEffectiveMass;
        const double sum = double(c.m_appliedImpulse) + dl;
        if (sum < double(c.m_lowerLimit)) dl = double(c.m_lowerLimit) - double(c.m_appliedImpulse);
        else if (sum > double(c.m_upperLimit)) dl = double(c.m_upperLimit) - double(c.m_appliedImpulse);
        if (dl == 0) return 0;
        c.m_appliedImpulse = c.m_appliedImpulse + static_cast<btScalar>(dl);
        for (int s = 0; s < 2; ++s) {
            const int id = s ? c.m_solverBodyIdB : c.m_solverBodyIdA;
            const int g = fr.group[s];
            if (g < 0) {
                btSolverBody& b = m_tmpSolverBodyPool[id];
                if (s == 0)
                    detail::applyRowImpulse<detail::RowTarget::Velocity>(b, c.m_contactNormal1, c.m_angularComponentA,
                                                                         btScalar(dl));
                else
                    detail::applyRowImpulse<detail::RowTarget::Velocity>(b, c.m_contactNormal2, c.m_angularComponentB,
                                                                         btScalar(dl));
                continue;
            }
            if (fr.response[s] < 0) continue; // covered by side A's response
            Direct::Group& group = d.groups[static_cast<std::size_t>(g)];
            const btVector3* u = d.responses.data() + fr.response[s];
            const btScalar impulse = btScalar(dl);
            const int* ids = group.bodies.data();
            for (std::size_t x = 0, n = group.bodies.size(); x < n; ++x) {
                btSolverBody& b = bodies[ids[x]];
                addScaled(b.m_deltaLinearVelocity, u[2 * x], impulse);
                addScaled(b.m_deltaAngularVelocity, u[2 * x + 1], impulse);
            }
            if (group.soft) {
                const double* y = d.reactions.data() + fr.reaction[s];
                for (Eigen::Index i = 0; i < group.lambda.size(); ++i) group.lambda(i) -= y[i] * dl;
            }
        }
        return dl * dl / (fr.invEffectiveMass * fr.invEffectiveMass);
    };
    for (Direct::FreeRow& fr : d.nonContact)
        if (iteration < fr.c->m_overrideNumSolverIterations) residual = std::max(residual, resolve(fr));
    if (iteration < infoGlobal.m_numIterations) {
        for (Direct::FreeRow& fr : d.contact) residual = std::max(residual, resolve(fr));
        for (Direct::FreeRow& fr : d.friction) {
            const btScalar total = m_tmpSolverContactConstraintPool[fr.c->m_frictionIndex].m_appliedImpulse;
            if (total <= 0) continue;
            fr.c->m_lowerLimit = -(fr.c->m_friction * total);
            fr.c->m_upperLimit = fr.c->m_friction * total;
            residual = std::max(residual, resolve(fr));
        }
        for (int j = 0; j < m_tmpSolverContactRollingFrictionConstraintPool.size(); ++j) {
            btSolverConstraint& c = m_tmpSolverContactRollingFrictionConstraintPool[j];
            const btScalar total = m_tmpSolverContactConstraintPool[c.m_frictionIndex].m_appliedImpulse;
            if (total <= 0) continue;
            const btScalar magnitude = btMin(c.m_friction * total, c.m_friction);
            c.m_lowerLimit = -magnitude;
            c.m_upperLimit = magnitude;
            const btScalar r = m_resolveSingleConstraintRowGeneric(m_tmpSolverBodyPool[c.m_solverBodyIdA],
                                                                   m_tmpSolverBodyPool[c.m_solverBodyIdB], c);
            residual = std::max(residual, double(r) * double(r));
        }
    }
    return static_cast<btScalar>(residual);
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
                for (std::size_t x = 0; x < group.bodies.size(); ++x) {
                    btSolverBody& body = m_tmpSolverBodyPool[group.bodies[x]];
                    addScaled(body.m_pushVelocity, u[2 * x], impulse);
                    addScaled(body.m_turnVelocity, u[2 * x + 1], impulse);
                }
            }
        }
        if (residual <= infoGlobal.m_leastSquaresResidualThreshold) break;
    }
}

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
    const int iterations = std::max(m_maxOverrideNumSolverIterations, infoGlobal.m_numIterations);
    for (int iteration = 0; iteration < iterations; ++iteration) {
        m_leastSquaresResidual = solveDirectIteration(iteration, infoGlobal);
        if (m_leastSquaresResidual <= infoGlobal.m_leastSquaresResidualThreshold) break;
    }
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

void RagdollSolver::track(const btTypedConstraint& constraint, bool warmStart, bool direct) {
    const btHashPtr key(&constraint);
    if (Tracked* t = m_rows.find(key)) {
        t->warmStart = warmStart;
        t->direct = direct;
        return;
    }
    Tracked t;
    t.warmStart = warmStart;
    t.direct = direct;
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

void RagdollSolver::untrack(const btTypedConstraint& constraint) { m_rows.remove(btHashPtr(&constraint)); }

void RagdollSolver::convertJoints(btTypedConstraint** constraints, int numConstraints,
                                  const btContactSolverInfo& infoGlobal) {
    btSequentialImpulseConstraintSolver::convertJoints(constraints, numConstraints, infoGlobal);
    if (m_rows.size() == 0 || (infoGlobal.m_solverMode & SOLVER_USE_WARMSTARTING) == 0) return;
    // The base class lays the rows out constraint by constraint, in the order given, m_numConstraintRows each.
    int row = 0;
    for (int i = 0; i < numConstraints; ++i) {
        const int rows = m_tmpConstraintSizesPool[i].m_numConstraintRows;
        const Tracked* t = m_rows.find(btHashPtr(constraints[i]));
        if (t != nullptr && t->warmStart && t->rows == rows) {
            for (int k = 0; k < rows; ++k) {
                btSolverConstraint& c = m_tmpSolverNonContactConstraintPool[row + k];
                const btScalar start = t->impulses[k] * infoGlobal.m_warmstartingFactor;
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
