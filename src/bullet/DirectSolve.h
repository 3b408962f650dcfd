// The direct joint solve's data (Method::directJoints): internal to RagdollSolver, shared by its source files.
#pragma once

#include <initializer_list>
#include <span>
#include <utility>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <Eigen/Dense>
#include <btBulletDynamicsCommon.h>

#include "ArticulatedTree.h"
#include "BlockTree.h"
#include "RowKernels.h"
#include "afb/bullet/RagdollSolver.h"

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
namespace direct {

using Vec = Eigen::VectorXd;
using Mat = Eigen::MatrixXd;

// One side of a row at one body: the linear and angular Jacobian and M⁻¹ times them (as Bullet stores them).
struct SideJ {
    btVector3 lin, ang;       // J
    btVector3 linInv, angInv; // M⁻¹ Jᵀ: invMass ∘ lin (linear factor included), the row's angular component
};

inline SideJ sideA(const btSolverConstraint& c, const btSolverBody& b) {
    return {c.m_contactNormal1, c.m_relpos1CrossNormal, c.m_contactNormal1 * b.internalGetInvMass(),
            c.m_angularComponentA};
}
inline SideJ sideB(const btSolverConstraint& c, const btSolverBody& b) {
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

inline double dot(const SideJ& row, const SideJ& other) { // J_row · M⁻¹ J_otherᵀ at a shared body
    return double(row.lin.dot(other.linInv)) + double(row.ang.dot(other.angInv));
}

// J v of a row over its two bodies' velocities (as Bullet's row update reads them).
inline double rowVelocity(const btAlignedObjectArray<btSolverBody>& bodyPool, const btSolverConstraint& c) {
    return double(detail::rowVelocitySum<detail::RowTarget::Velocity>(bodyPool[c.m_solverBodyIdA],
                                                                      bodyPool[c.m_solverBodyIdB], c));
}

// The velocity a row still asks for: its target (rhs less its cfm's share of the impulse so far) less J v.
inline double velocityToGo(const btAlignedObjectArray<btSolverBody>& bodyPool, const btSolverConstraint& c) {
    const double target = (double(c.m_rhs) - double(c.m_cfm) * double(c.m_appliedImpulse)) / double(c.m_jacDiagABInv);
    return target - rowVelocity(bodyPool, c);
}

} // namespace direct

struct RagdollSolver::Direct {
    using Vec = direct::Vec;
    using Mat = direct::Mat;
    using SideJ = direct::SideJ;
    // A joint row of a group: its pool index and its two sides (side b absent for a body outside the group).
    struct JointRow {
        int pool;
        int bodyA = -1, bodyB = -1; // local body indices, −1 when that side is not in the group
        SideJ a{}, b{};
    };
    struct Group {
        std::vector<int> bodies;           // solver body ids
        std::vector<btSolverBody*> bodyOf; // the same bodies in the pool (the iterations' applies walk them)
        std::vector<JointRow> rows;
        std::vector<std::vector<std::pair<int, int>>> rowsAt; // per local body: (joint row, side 0 = A / 1 = B)
        Eigen::LDLT<Mat> ldlt; // the dense factor, when the tree's cannot be used (a loop, two world joints)
        // The sparse factor: the bodies (nodes 0…n−1) and one node per jointed body pair (its rows), a tree when
        // the figure has no loop. H = [[M, −Jᵀ], [−J, −C]]; `rowAt` is each joint row's entry in its vectors.
        BlockTree tree;
        bool useTree = false;
        // The joint-space solve of the same system (ArticulatedTree), used instead of the tree's factor when the
        // joints are point joints with locked axes (and soft rows only as motors about them): the joints' impulses
        // then come from the bodies' momentum once the iterations end (articulatedImpulses) rather than from each
        // row's reaction, but for the soft rows', which are kept up to date.
        ArticulatedTree articulated;
        bool useArticulated = false;
        std::vector<int> softRows; // a joint-space group's soft rows (motors): their reactions are kept (`soft`)
        bool heldTwice = false;    // softenRedundantHolds softened rows (the joint-space solve then declines)
        std::vector<ArticulatedTree::Body> articulatedBodies;
        std::vector<ArticulatedTree::Row> articulatedRows;
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
            useArticulated = false;
            softRows.clear();
            heldTwice = false;
            soft = false;
        }
    };
    // A row solved one at a time, with its response through the groups it touches.
    struct FreeRow {
        btSolverConstraint* c = nullptr;
        int group[2] = {-1, -1};     // group of side A, of side B (−1: a plain body)
        int response[2] = {-1, -1};  // offsets in `responses` (linear, angular per group body), per distinct group
        int reaction[2] = {-1, -1};  // offsets in `reactions` (one per group joint row; per soft row in joint space)
        double invEffectiveMass = 0; // 1 / (Jᵣ u + cfm′), 0: skip
        double cfmVel = 0;           // the row's cfm in velocity units
        double targetVel = 0;        // rhs / jacDiagABInv: the velocity the row asks for while its cfm is 0
        double plain = 0;            // J M⁻¹ Jᵀ of the touching bodies alone (the row's scale)
        btScalar start = 0;          // the row's impulse before the iterations (warm start)
        bool pending = false;        // its responses through the groups are not computed yet (complete())
        int blockIndex = -1;         // its index among the figure block's rows (−1: not in it yet)
        int normal = -1;             // a friction row in the block: its contact's block index (−1: none)
        SideJ side[2]{};             // its Jacobian at body A and B, kept when it joins the block (couplingOf)
        btSolverBody* at[2] = {nullptr, nullptr}; // its bodies in the pool (buildDirect)
    };

    // buildDirect's parts, in order: the joint rows' groups (false: none), each group's factor, the other rows,
    // their responses (pending or computed at once for densely factored groups).
    bool groupJointRows(const btAlignedObjectArray<btSolverBody>& bodyPool,
                        const btAlignedObjectArray<btSolverConstraint>& pool,
                        const btHashMap<btHashPtr, Tracked>& trackedRows);
    bool groupRows(const btAlignedObjectArray<btSolverBody>& bodyPool,
                   const btAlignedObjectArray<btSolverConstraint>& pool);
    void factorGroups(const btAlignedObjectArray<btSolverBody>& bodyPool,
                      const btAlignedObjectArray<btSolverConstraint>& pool);
    void collectFreeRows(btAlignedObjectArray<btSolverConstraint>& pool,
                         btAlignedObjectArray<btSolverConstraint>& contactPool,
                         btAlignedObjectArray<btSolverConstraint>& frictionPool);
    void prepareColumns(const btAlignedObjectArray<btSolverBody>& bodyPool);
    void denseColumns(const btAlignedObjectArray<btSolverBody>& bodyPool);
    // The iterations' parts (DirectIterations.cpp): the exact joint solve of every group (its residual: the joint
    // rows' velocity error it met; none for a group solved in joint space, which reads no row); the
    // application of an impulse dl to a free row; the rows through the groups as one
    // block, `figureSweeps` sweeps over their couplings (FigureBlock.cpp); each returns its largest residual.
    double solveJoints(btAlignedObjectArray<btSolverBody>& bodyPool,
                       const btAlignedObjectArray<btSolverConstraint>& pool);
    void apply(FreeRow& fr, double dl);
    double solveFigureBlock(btAlignedObjectArray<btSolverBody>& bodyPool, int iteration, bool contacts);
    // Whether some free row joins two bodies of no group (InTurn::OutsideGroups would take it).
    bool anyOutsideGroups() const;
    // Which free rows an in-turn pass takes: all of them; in block mode those outside the block; or only the rows
    // between bodies of no group (a game's bodies among themselves), which block mode iterates further alone.
    enum class InTurn { All, OutsideBlock, OutsideGroups };
    // The free rows taken one at a time in an iteration.
    double resolveInTurn(btAlignedObjectArray<btSolverBody>& bodyPool,
                         btAlignedObjectArray<btSolverConstraint>& contactPool,
                         btAlignedObjectArray<btSolverConstraint>& rollingPool, btSingleConstraintRowSolver rolling,
                         int iteration, bool contacts, InTurn which);
    // This iteration's rows of the block (joining it those that would move) and their velocity still to go.
    void gatherBlock(btAlignedObjectArray<btSolverBody>& bodyPool, int iteration, bool contacts);
    // Adds a completed row to the block with its couplings.
    void join(FreeRow& fr, const btAlignedObjectArray<btSolverBody>& bodyPool);
    // The change of row r's velocity per unit impulse of row s (both joined: their sides are kept).
    double couplingOf(const FreeRow& r, const FreeRow& s) const;
    // The velocity a free row still asks for (direct::velocityToGo, its target taken once per step when it has no
    // cfm: the same value without a division).
    static double toGoOf(const FreeRow& fr, const btAlignedObjectArray<btSolverBody>& bodyPool) {
        const btSolverConstraint& c = *fr.c;
        if (c.m_cfm != 0) return direct::velocityToGo(bodyPool, c);
        return fr.targetVel - double(detail::rowVelocitySum<detail::RowTarget::Velocity>(*fr.at[0], *fr.at[1], c));
    }
    static bool dynamicBody(const btSolverBody& b) {
        return b.m_originalBody != nullptr && b.m_originalBody->getInvMass() > 0;
    }
    int unionRoot(int i) { // with path halving
        while (unionParent[static_cast<std::size_t>(i)] != i)
            i = unionParent[static_cast<std::size_t>(i)] =
                unionParent[static_cast<std::size_t>(unionParent[static_cast<std::size_t>(i)])];
        return i;
    }
    // Rows that hold a group to bodies outside it through more than one constraint get a small compliance
    // (kRedundantHoldCompliance of their own inverse effective mass, added to `cfm`; DirectSolve.cpp).
    static void softenRedundantHolds(Group& group, const btAlignedObjectArray<btSolverConstraint>& pool);
    static bool layOut(Group& group);
    static bool factorTree(Group& group, const btAlignedObjectArray<btSolverBody>& bodyPool, double epsilon);
    // DirectArticulated.cpp: the group's joint-space solve built and factored (false: the caller factors H);
    // a row's response through it; the joints' impulses of every such group once the iterations end.
    static bool factorArticulated(Group& group, const btAlignedObjectArray<btSolverBody>& bodyPool);
    void articulatedColumn(FreeRow& fr, int s, bool withA, bool withB,
                           const btAlignedObjectArray<btSolverBody>& bodyPool);
    void articulatedImpulses(const btAlignedObjectArray<btSolverBody>& bodyPool,
                             std::initializer_list<const btAlignedObjectArray<btSolverConstraint>*> pools,
                             const btAlignedObjectArray<btSolverConstraint>& jointPool);
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
    bool jointSpace = true;             // setJointSpace: groups of point joints solved in joint space
    int figureIterations = 0;           // Method::figureIterations (0: the rows through groups one at a time)
    int figureSweeps = 0;               // Method::figureSweeps
    double figureTolerance = 0;         // the block's sweeps stop once no row's velocity moves by its root (m²/s²)
    // The figure block (solveFigureBlock) of this step: every row that has joined it (a row joins when it first
    // would move, and stays), its couplings with the rows it shares a group or a body with (the other row's index
    // and the change of this row's velocity per unit impulse of that one, itself included), the block's rows per
    // group, and per iteration the rows taken, their velocity still to go and the impulse each has added.
    struct Block {
        std::vector<FreeRow*> rows;
        std::vector<std::vector<std::pair<int, double>>> links;
        std::vector<std::vector<int>> ofGroup;
        std::vector<int> plainDynamic; // rows with a side on a dynamic body of no group
        std::vector<int> seen, taken;
        std::vector<double> toGo, added;
        // A taken row as the sweeps read it, laid out once per iteration: its fixed numbers and its couplings.
        struct Sweep {
            const std::pair<int, double>* link;
            const std::pair<int, double>* linkEnd;
            double toGo, cfmVel, invEffectiveMass, applied, lower, upper, friction;
            int row, normal; // its block index; a friction row's contact's (−1: none)
        };
        std::vector<Sweep> sweep;
        void clear(std::size_t groupCount) {
            rows.clear();
            plainDynamic.clear();
            seen.clear(); // join() marks with row indices, which the next step reuses
            if (ofGroup.size() < groupCount) ofGroup.resize(groupCount);
            for (std::size_t g = 0; g < groupCount; ++g) ofGroup[g].clear();
        }
    };
    Block block;
    // The groups of this step are the first `used`; the others wait, with their buffers, for a later step.
    std::vector<Group> groups;
    std::size_t used = 0;
    std::span<Group> live() { return {groups.data(), used}; }
    std::vector<int> groupOf, localOf; // per solver body
    std::vector<char> bodyKind;        // per solver body: groupJointRows' (not dynamic, unit factors, others)
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
    std::vector<double> e;            // one group's joint errors
    std::vector<double> softKept;     // one group's soft rows' impulses before a projection
    std::vector<double> articulatedF; // articulatedImpulses()' impulses and velocity changes, 6 per group body
    std::vector<double> articulatedDv, articulatedLambda;
    std::vector<int> articulatedFirst; // per group: its bodies' first entry in articulatedF
    std::vector<char> groupRow;        // per joint pool row: a row of a joint-space group

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

} // namespace afb::bullet
