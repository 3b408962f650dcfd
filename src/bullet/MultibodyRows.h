#pragma once
// The rows the multibody backend adds to Bullet's multibody solver as btMultiBodyConstraints of its own: limits and
// universal twists (MultibodyLimit.cpp), and the energy guard, joint friction and springs (MultibodyRows.cpp).
// Internal to the multibody backend (Multibody.h).
#include <optional>
#include <variant>
#include <vector>

#include <BulletDynamics/Featherstone/btMultiBody.h>
#include <BulletDynamics/Featherstone/btMultiBodyConstraint.h>
#include <btBulletDynamicsCommon.h>

#include "afb/detail/Constraints.h"

namespace afb::bullet::detail {

/// The rotation of `m` as a quaternion.
btQuaternion quatOf(const btMatrix3x3& m);

/// A tree's kinetic energy (J), linear momentum (N·s, world) and mass (kg), from its link velocities.
struct TreeMotion {
    double energy = 0;
    btVector3 momentum{0, 0, 0};
    btScalar mass = 0;
};
TreeMotion treeMotion(const btMultiBody& mb);

/// The Jacobian over a whole tree of a row about `axisWorld` (angular) or along `normalWorld` at two points (linear):
/// the rate of body A's motion minus body B's (B the world when `linkB` is absent). Rows within one tree take both
/// sides in one piece (Bullet's two half-Jacobians of one tree lose the cross terms).
void relativeJacobian(btMultiBody& tree, int linkA, const btVector3& pointA, std::optional<int> linkB,
                      const btVector3& pointB, const btVector3& axisWorld, const btVector3& normalWorld,
                      std::vector<btScalar>& jac, std::vector<btScalar>& scratch, btAlignedObjectArray<btScalar>& r,
                      btAlignedObjectArray<btVector3>& v, btAlignedObjectArray<btMatrix3x3>& m);

/// What every constraint of ours on the trees shares: Bullet's Jacobian storage, the islands of the colliders it
/// acts on, and one way to add a row.
class TreeRows : public btMultiBodyConstraint {
  public:
    /// Rows on link `linkA` of `treeA` and `linkB` of `treeB` (nullptr: of `treeA`), in the islands of `islandA` and
    /// `islandB`.
    TreeRows(btMultiBody* treeA, btMultiBody* treeB, int linkA, int linkB, int maxRows, bool unilateral,
             const btCollisionObject& islandA, const btCollisionObject& islandB)
        : btMultiBodyConstraint(treeA, treeB, linkA, linkB, maxRows, unilateral, MULTIBODY_CONSTRAINT_LIMIT),
          m_islandA(islandA), m_islandB(islandB) {}

    void finalizeMultiDof() override {
        allocateJacobiansMultiDof();
        m_numDofsFinalized = m_jacSizeBoth;
    }
    int getIslandIdA() const override { return m_islandA.getIslandTag(); }
    int getIslandIdB() const override { return m_islandB.getIslandTag(); }
    void debugDraw(btIDebugDraw*) override {}

  protected:
    /// A row for fillMultiBodyConstraint: Jacobians over tree A and tree B (nullptr: one tree), its normal (angular,
    /// or linear at the two points), position error and impulse bounds.
    struct Row {
        btScalar* jacA;
        btScalar* jacB;
        btVector3 angular, linear, pointA, pointB;
        btScalar positionError, lower, upper;
        bool angularOnly;
    };
    /// Appends `row` to `rows` as row `index` of this constraint, between Bullet's fixed solver bodies (the
    /// Jacobians carry the trees).
    btMultiBodySolverConstraint& addRow(btMultiBodyConstraintArray& rows, btMultiBodyJacobianData& data,
                                        const btContactSolverInfo& info, const Row& row, int index);
    void finalizeOnce() {
        if (m_numDofsFinalized != m_jacSizeBoth) finalizeMultiDof();
    }

  private:
    const btCollisionObject& m_islandA;
    const btCollisionObject& m_islandB;
};

/// A limit of a figure constraint on two links of one multibody (or one link against the world): the same rows as
/// the rigid backend's DirectionLimitConstraint and HingeRangeConstraint (directionLimitRows, hingeRangeRow: one
/// definition of a limit's excess and of its rate), each row's Jacobian taken over the whole tree, so the row's
/// effective mass is the articulated one (Bullet's own limits fill two Jacobians of one tree and lose the cross
/// terms).
class MultibodyLimit : public TreeRows {
  public:
    struct Side {
        int link = -1;                              ///< link of the body (−1: base)
        const btCollisionObject* body = nullptr;    ///< its collider (world transform); nullptr: the world
        const btVector3* angularVelocity = nullptr; ///< its angular velocity at the end of the last substep
    };
    struct Direction {
        LimitShape shape;
        btVector3 shaftInA;
        btMatrix3x3 basisInB; ///< world for a world constraint
        btScalar half1, half2;
    };
    struct Hinge {
        btMatrix3x3 frameInA, frameInB; ///< frame B world for a world constraint
        btScalar lower, upper;
    };
    /// §4.4's "no relative spin about the shafts" of a universal joint built as a spherical link: the twist of
    /// frame B relative to frame A about their X axes (shaft 1) held at zero by an equality row about the bisector
    /// of the two X axes (the axis a homokinetic joint does not turn about).
    struct Twist {
        btMatrix3x3 frameInA, frameInB;
    };
    using Kind = std::variant<Direction, Hinge, Twist>;

    /// `a.body` is never null.
    MultibodyLimit(btMultiBody* tree, Side a, Side b, Kind limit, LimitRowPolicy policy)
        : TreeRows(tree, nullptr, a.link, b.body ? b.link : a.link, 2, !std::holds_alternative<Twist>(limit), *a.body,
                   *a.body),
          m_a(a), m_b(b), m_limit(limit), m_policy(policy) {}

    void createConstraintRows(btMultiBodyConstraintArray& rows, btMultiBodyJacobianData& data,
                              const btContactSolverInfo& info) override;

    /// One nonlinear Gauss–Seidel step on positions (velocities untouched): the tree moves along M⁻¹Jᵀ of each
    /// violated row until that row's excess is closed (as far as the linearisation reaches). Returns the largest
    /// excess found, rad.
    btScalar correctPositions(btAlignedObjectArray<btScalar>& r, btAlignedObjectArray<btVector3>& v,
                              btAlignedObjectArray<btMatrix3x3>& m, btAlignedObjectArray<btQuaternion>& q,
                              btAlignedObjectArray<btVector3>& o);

  private:
    static constexpr btScalar kTwistSlopRad = btScalar(0.01); ///< a twist the position sweeps leave to the row

    int rowsNow(btScalar margin, LimitRow found[2]) const;
    void fillJacobian(const btVector3& axisWorld, btAlignedObjectArray<btScalar>& r, btAlignedObjectArray<btVector3>& v,
                      btAlignedObjectArray<btMatrix3x3>& m);

    Side m_a, m_b;
    Kind m_limit;
    LimitRowPolicy m_policy;
    std::vector<btScalar> m_jac, m_jacB, m_move;
};

/// Bullet integrates a btMultiBody's velocity-product terms (Coriolis, centripetal, gyroscopic) explicitly: once
/// a limb spins at tens of rad/s (ω·dt of a radian per step, as at a hard landing), each step's unconstrained
/// update multiplies the tree's kinetic energy (measured: ×1.6, ×2.8, ×6 in three steps) until it explodes. No
/// force but gravity does work in that update (joint forces do none; damping and contacts come after), so the
/// guard, called between Bullet's unconstrained update and the constraint solve, holds the update to gravity's
/// work: past it, the motion relative to the centre of mass is scaled down (linear momentum kept). It adds no rows.
class EnergyGuard : public TreeRows {
  public:
    EnergyGuard(btMultiBody* tree, const btCollisionObject& base, const btDynamicsWorld& world)
        : TreeRows(tree, nullptr, -1, -1, 0, false, base, base), m_world(world) {}

    /// The tree's motion now, the reference of the next check (after each step, and after any change of the
    /// velocities from outside: impulses, body states).
    void record();

    void createConstraintRows(btMultiBodyConstraintArray& rows, btMultiBodyJacobianData& data,
                              const btContactSolverInfo& info) override;

  private:
    static constexpr double kSlack = 1e-3;
    const btDynamicsWorld& m_world;
    double m_energy = 0;
    btVector3 m_momentum{0, 0, 0};
    std::vector<btScalar> m_delta;
};

/// Joint friction (docs/format.md §4.8) on a joint within one tree: rows resisting the relative angular velocity of
/// the two bodies about the free axes (JointParts' friction axes: ball 3, universal 2 perpendicular to shaft 1,
/// hinge 1), target velocity 0, each impulse bounded by `maxImpulse` per step (MultibodyRagdoll sets it from the
/// joint's reaction force as the rigid backend's JointFrictionConstraint).
class MultibodyFriction : public TreeRows {
  public:
    /// `axesInB`: the rows' axes as columns, fixed in body B's frame (world for a world joint); `count` used.
    MultibodyFriction(btMultiBody* tree, int linkA, const btCollisionObject& bodyA, std::optional<int> linkB,
                      const btCollisionObject* bodyB, const btMatrix3x3& axesInB, int count)
        : TreeRows(tree, nullptr, linkA, linkB ? *linkB : linkA, count, false, bodyA, bodyA), m_bodyAObject(bodyA),
          m_bodyBObject(bodyB), m_linkBOpt(linkB), m_axesInB(axesInB), m_count(count) {}

    /// The bound of each row for the coming step, N·m·s.
    void setMaxImpulse(btScalar impulse) { m_maxImpulse = impulse; }

    void createConstraintRows(btMultiBodyConstraintArray& rows, btMultiBodyJacobianData& data,
                              const btContactSolverInfo& info) override;

  private:
    const btCollisionObject& m_bodyAObject;
    const btCollisionObject* m_bodyBObject; ///< nullptr: the world
    std::optional<int> m_linkBOpt;          ///< absent: the world
    btMatrix3x3 m_axesInB;
    int m_count;
    btScalar m_maxImpulse = 0;
    std::vector<btScalar> m_jac, m_scratch;
};

/// A spring (docs/format.md §4.7) between anchors fixed in two bodies (of one tree, of two trees, or one body and
/// the world): the rigid backend's SpringConstraint law (the quadratic force minus the damping term, each step's
/// impulse bounded by what closes the whole deviation or stops the relative motion in that step) as a row whose
/// impulse is pinned to F·dt, so it is integrated inside the solver step where gravity is; plus the one-sided
/// min/max length rows with the world's joint ERP.
class MultibodySpring : public TreeRows {
  public:
    struct End {
        btMultiBody* tree = nullptr; ///< nullptr: the world
        int link = -1;
        const btCollisionObject* body = nullptr; ///< nullptr: the world
        btVector3 anchor{0, 0, 0};               ///< in the body's frame (world for the world)
    };
    /// `a` is a body's end (never the world).
    MultibodySpring(const End& a, const End& b, const SpringConstraint::Params& params)
        : TreeRows(a.tree, b.tree && b.tree != a.tree ? b.tree : nullptr, a.link, b.tree ? b.link : a.link, 2, false,
                   *a.body, b.body ? *b.body : *a.body),
          m_a(a), m_b(b), m_params(params) {}

    void createConstraintRows(btMultiBodyConstraintArray& rows, btMultiBodyJacobianData& data,
                              const btContactSolverInfo& info) override;

  private:
    btVector3 pointA() const { return m_a.body->getWorldTransform() * m_a.anchor; }
    btVector3 pointB() const { return m_b.body ? m_b.body->getWorldTransform() * m_b.anchor : m_b.anchor; }
    /// A row along `n` between the anchors `pa` and `pb` (its velocity n·(v_A − v_B) = −dL/dt).
    btMultiBodySolverConstraint& lengthRow(btMultiBodyConstraintArray& rows, btMultiBodyJacobianData& data,
                                           const btContactSolverInfo& info, const btVector3& pa, const btVector3& pb,
                                           const btVector3& n, btScalar posError, btScalar lo, btScalar hi, int index);
    /// J·q̇ of the row lengthRow filled last (its velocity now).
    btScalar rowVelocity() const;

    End m_a, m_b;
    SpringConstraint::Params m_params;
    std::vector<btScalar> m_jacA, m_jacB, m_scratch;
};

} // namespace afb::bullet::detail
