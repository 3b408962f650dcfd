#pragma once
// Bullet's sequential-impulse solver, with warm starting for the rows of the constraints it is told to track.
//
// Bullet warm-starts contacts (each point starts from a fraction of its last impulse) but starts every joint row
// from zero on every substep (btSequentialImpulseConstraintSolver::convertJoint). A ragdoll lying on the ground
// carries its own weight through its joints and limits, and the solver's iterations must rebuild those impulses
// along the chain every step; what they fail to rebuild shows as joints that sag apart and limits that give.
// This solver starts each tracked row from the world's warm-starting factor times its last impulse, as Bullet
// does for contacts (docs/methods.md).
#include <functional>
#include <memory>
#include <vector>

#include <LinearMath/btHashMap.h>
#include <btBulletDynamicsCommon.h>

namespace afb::bullet {

/// A drop-in replacement for btSequentialImpulseConstraintSolver (world.setConstraintSolver, or pass it to
/// btDiscreteDynamicsWorld's constructor). Untracked constraints and contacts are solved exactly as Bullet does.
/// RagdollWorld tracks the joint and friction constraints of the ragdolls spawned through it when their method
/// asks for joint warm starting (not their limit constraints, whose speculative rows must start from zero); a
/// row set is warm-started only when the constraint has as many rows as on the last step it was solved (a
/// Bullet limit that engages or releases starts its rows from zero). One world, one thread.
class RagdollSolver : public btSequentialImpulseConstraintSolver {
  public:
    /// A solver tracking nothing: until something is tracked, it solves as btSequentialImpulseConstraintSolver.
    RagdollSolver();
    /// Releases the tracking tables (the tracked constraints belong to their ragdolls).
    ~RagdollSolver() override;
    RagdollSolver(const RagdollSolver&) = delete;
    RagdollSolver& operator=(const RagdollSolver&) = delete;

    /// Track `constraint` from now on (until untrack): warm-start its rows (`warmStart`), let the direct joint
    /// solve take its unbounded rows (`direct`, see setDirectJoints), and solve its rows as soft constraints
    /// (`soft`): a row whose cfm is c (Bullet's convention: J·v + c·λ/m = rhs, m the row's effective mass) is
    /// updated with the effective mass m/(1 + c), which Bullet's update leaves out. That update converges for any
    /// c, where Bullet's oscillates and grows once c exceeds 1 (JointMotorConstraint's rows at a fast step).
    void track(const btTypedConstraint& constraint, bool warmStart = true, bool direct = false, bool soft = false);
    /// Forget `constraint` (call before it is destroyed).
    void untrack(const btTypedConstraint& constraint);
    /// How many constraints are tracked.
    std::size_t trackedCount() const { return static_cast<std::size_t>(m_rows.size()); }

    /// The direct joint solve (Method::directJoints): each iteration solves the unbounded rows of the constraints
    /// tracked with `direct` exactly, per connected group of bodies (an LDLᵀ factorisation of J M⁻¹ Jᵀ per group
    /// and solve), and the contact and limit rows touching a group move the whole group as its joints let it, with
    /// the group's effective mass at that row; contact friction (unless setFrictionThroughGroups) and joint friction
    /// keep Bullet's response, and the next joint solve restores what they disturb. Off: Bullet's iterations.
    void setDirectJoints(bool on);
    /// Whether the direct joint solve is on (setDirectJoints).
    bool directJoints() const;
    /// Block mode of the direct joint solve (Method::figureIterations, Method::figureSweeps): `iterations` iterations
    /// (0: off), each solving the rows of Bullet's response in turn, then the joints exactly, then the contact and
    /// limit rows that move whole groups together, `sweeps` Gauss–Seidel sweeps over their couplings with the
    /// impulses applied to the bodies once. Off: each of the world's iterations solves the joints, then every other
    /// row in turn.
    void setFigureBlock(int iterations, int sweeps);
    /// Block mode's iterations (0: off; setFigureBlock).
    int figureIterations() const;
    /// Block mode's sweeps per iteration (setFigureBlock).
    int figureSweeps() const;
    /// Under the direct joint solve, contact friction rows move the whole group too (Method::frictionThroughFigure),
    /// except between two bodies of one group; off (the default), they keep Bullet's one-body response.
    void setFrictionThroughGroups(bool on);
    /// Whether friction rows move the whole group (setFrictionThroughGroups).
    bool frictionThroughGroups() const;
    /// Under the direct joint solve, a group whose joints are point joints with some rotation axes locked (ball,
    /// universal, hinge) and whose rows are all stiff is solved in joint space (on, the default): each joint's free
    /// motions are eliminated rather than its rows, the same system for fewer instructions, and the joints' impulses
    /// are taken from the bodies' momentum after the iterations. Off: every group is factored as a tree of bodies
    /// and joints (the results differ by rounding).
    void setJointSpace(bool on);
    /// Whether the joint-space path is on (setJointSpace).
    bool jointSpace() const;

    /// The row update of Bullet's iterations (every row that the direct solve does not take): afbullet's SSE one
    /// (on, the default), which rounds bit for bit as Bullet's scalar reference that Debian's Bullet runs, with the
    /// islands of a solve taken in turn (islandsInTurn; each island's result unchanged to the bit), or that scalar
    /// reference itself in Bullet's loop and order (off; what `raw`, plain Bullet, runs). Off, the constraints' rows
    /// are also set up by Bullet's own code rather than the solver's (the same rows, at Bullet's price).
    void setSimdRows(bool on) { m_simdRows = on; }
    /// Whether the SIMD row update is on (setSimdRows).
    bool simdRows() const { return m_simdRows; }
    /// The most islands one solve of Bullet's iterations took in turn in the last step (a row of each; Bullet
    /// solves small islands together), 0 when every solve kept Bullet's order (SIMD rows off, one island per solve,
    /// or a solver mode that orders rows itself).
    int islandsInTurn() const { return m_mostIslandsInTurn; }

    /// The largest impulse (N·s) a contact point of `manifold` may start a step of `dt` seconds from (warm start),
    /// or a negative value for no bound; its friction impulses are scaled with it. Unset: no bound. RagdollWorld
    /// sets it from Method::selfContactCap.
    using ContactWarmStartCap = std::function<btScalar(const btPersistentManifold& manifold, btScalar dt)>;
    /// Sets the cap (see ContactWarmStartCap); an empty function removes it.
    void setContactWarmStartCap(ContactWarmStartCap cap) { m_contactCap = std::move(cap); }
    /// The cap in force; empty when unset.
    const ContactWarmStartCap& contactWarmStartCap() const { return m_contactCap; }

  protected:
    /// Bullet's once-per-step hook, before the step's solves: resets islandsInTurn.
    void prepareSolve(int, int) override { m_mostIslandsInTurn = 0; }
    /// Bounds each contact point's last impulse by the cap (its warm start), then Bullet's contact rows.
    void convertContacts(btPersistentManifold** manifoldPtr, int numManifolds,
                         const btContactSolverInfo& infoGlobal) override;
    /// The constraints' rows as Bullet sets them up (to the bit), each tracked constraint's warm-started from its
    /// last impulses (JointRows.cpp).
    void convertJoints(btTypedConstraint** constraints, int numConstraints,
                       const btContactSolverInfo& infoGlobal) override;
    /// Keeps each tracked constraint's row impulses for the next step, then Bullet's finish.
    btScalar solveGroupCacheFriendlyFinish(btCollisionObject** bodies, int numBodies,
                                           const btContactSolverInfo& infoGlobal) override;
    /// One iteration over every row: the direct joint solve's or Bullet's, in SIMD or Bullet's scalar rows.
    btScalar solveSingleIteration(int iteration, btCollisionObject** bodies, int numBodies,
                                  btPersistentManifold** manifoldPtr, int numManifolds, btTypedConstraint** constraints,
                                  int numConstraints, const btContactSolverInfo& infoGlobal,
                                  btIDebugDraw* debugDrawer) override;
    /// The direct joint solve's iterations when it is on, else Bullet's loop (islands in turn with SIMD rows).
    btScalar solveGroupCacheFriendlyIterations(btCollisionObject** bodies, int numBodies,
                                               btPersistentManifold** manifoldPtr, int numManifolds,
                                               btTypedConstraint** constraints, int numConstraints,
                                               const btContactSolverInfo& infoGlobal,
                                               btIDebugDraw* debugDrawer) override;

  private:
    ContactWarmStartCap m_contactCap;
    bool m_simdRows = true;
    /// A tracked constraint: its rows' last impulses, inline (a constraint has at most 12 rows: six axes, each
    /// with a limit and a motor; one with more is not warm-started).
    struct Tracked {
        static constexpr int kMaxRows = 12;
        btScalar impulses[kMaxRows] = {};
        int rows = -1; ///< how many impulses were kept on the last step (−1: none, or more than kMaxRows)
        bool warmStart = true;
        bool direct = false;
        bool soft = false;
    };
    /// The iterations' row order over the islands Bullet solves together (it batches small islands into one solve):
    /// each island's rows in Bullet's order, the islands taken in turn, a row of each, so that the next row rarely
    /// waits for the last one's bodies. Islands share no body that a row moves (the static world body is never
    /// written), so every island's result is the same to the bit. Built per solve when the SIMD rows are on.
    struct IslandOrder {
        std::vector<int> nonContact, contact, friction; ///< pool indices; empty: Bullet's order
        int islands = 0;                                ///< taken in turn (0: Bullet's order)
        std::vector<int> parent, island, rowIsland, first, end, byIsland, active; ///< scratch
        bool build(const btAlignedObjectArray<btSolverBody>& bodies,
                   const btAlignedObjectArray<btSolverConstraint>& nonContactPool,
                   const btAlignedObjectArray<btSolverConstraint>& contactPool,
                   const btAlignedObjectArray<btSolverConstraint>& frictionPool);
        void clear() {
            nonContact.clear();
            contact.clear();
            friction.clear();
            islands = 0;
        }
    };
    IslandOrder m_islandOrder;
    static void softenRow(btSolverConstraint& c);
    void setUpJointRows(btSolverConstraint* rows, btTypedConstraint& constraint, int count, int idA, int idB,
                        const btContactSolverInfo& infoGlobal);
    void startTrackedRows(btSolverConstraint* rows, int count, const Tracked& t, bool warmStarting, btScalar factor);
    int m_mostIslandsInTurn = 0;
    struct Direct;
    bool buildDirect();
    btScalar solveDirectIteration(int iteration, const btContactSolverInfo& infoGlobal);
    void solveDirectOutsideGroups(int firstIteration, const btContactSolverInfo& infoGlobal);
    void solveDirectSplitImpulse(const btContactSolverInfo& infoGlobal);

    // Flat (Bullet's open hash map): tracking a constraint at spawn allocates nothing once the table has grown,
    // where a node-based map allocated a node and an impulse vector per constraint.
    btHashMap<btHashPtr, Tracked> m_rows;
    std::unique_ptr<Direct> m_direct;
};

} // namespace afb::bullet
