#pragma once
// Constraints Bullet has no class for, written as btTypedConstraint / btActionInterface (af-format §4).
#include <btBulletDynamicsCommon.h>

namespace afb::bullet {

/// A one-sided limit on a direction (the "shaft", fixed in body A) against an axis or basis fixed in body B
/// (or the world): a cone (angle from the axis ≤ halfAngle1) or a true pyramid (the shaft's planar angles in the
/// basis' (f, l) and (f, u) planes ≤ halfAngle1 and halfAngle2; af-format §4.3). Angular rows only, active only
/// while violated, exact angle errors so the pyramid's corners are a pyramid's. Twist stays free.
class DirectionLimitConstraint : public btTypedConstraint {
  public:
    enum class Shape { Cone, Pyramid };

    /// `shaftInA`: unit, in A's frame. `basisInB`: columns f, l, u (cone: column 0 is the axis), in B's frame.
    DirectionLimitConstraint(btRigidBody& a, btRigidBody& b, const btVector3& shaftInA, const btMatrix3x3& basisInB,
                             Shape shape, btScalar halfAngle1Rad, btScalar halfAngle2Rad);

    void getInfo1(btConstraintInfo1* info) override;
    void getInfo2(btConstraintInfo2* info) override;
    void setParam(int, btScalar, int) override {}
    btScalar getParam(int, int) const override { return 0; }

    /// Error reduction per step of the limit rows (the engine's LIMIT_ERROR_REDUCTION).
    static constexpr btScalar kErrorReduction = btScalar(0.3);

    /// Current violation, radians (0 when within the limit): the largest of the limit's angle excesses.
    btScalar violation() const;

  private:
    struct Row {
        btVector3 axisWorld; ///< the excess grows at axisWorld · (ωA − ωB)
        btScalar excess;     ///< how far past the limit, radians (> 0)
    };
    int activeRows(Row rows[2]) const;

    btVector3 m_shaftInA;
    btMatrix3x3 m_basisInB;
    Shape m_shape;
    btScalar m_half1, m_half2;
};

/// Joint friction (af-format §4.8): rows that resist the relative angular velocity on the free axes, each bounded
/// by `maxImpulse` per step (set from the joint's own reaction, see Ragdoll). Axes are fixed in body B (world for
/// a world joint); `count` of the three columns of `axesInB` are used (ball 3, universal 2, hinge 1).
class JointFrictionConstraint : public btTypedConstraint {
  public:
    JointFrictionConstraint(btRigidBody& a, btRigidBody& b, const btMatrix3x3& axesInB, int count);
    void getInfo1(btConstraintInfo1* info) override;
    void getInfo2(btConstraintInfo2* info) override;
    void setParam(int, btScalar, int) override {}
    btScalar getParam(int, int) const override { return 0; }

    /// The bound of each row for the coming step, N·m·s.
    void setMaxImpulse(btScalar impulse) { m_maxImpulse = impulse; }

  private:
    btMatrix3x3 m_axesInB;
    int m_count;
    btScalar m_maxImpulse = 0;
};

/// A spring (af-format §4.7) between anchors fixed in A and B: the quadratic force F = k·ΔL² (stretch above the
/// rest length, compress below) minus D = damping·|Δv·n|/L, plus one-sided length rows below `minLength` and
/// above `maxLength` (when > 0). The force enters the solver as a row whose impulse is pinned to F·dt, so it is
/// integrated exactly where gravity is (an impulse applied outside the step would meet Bullet's damping first and
/// settle at F = m·g / damping factor instead of m·g).
class SpringConstraint : public btTypedConstraint {
  public:
    struct Params {
        btScalar stretch = 0, compress = 0; ///< N/m²
        btScalar damping = 0;               ///< N per m/s of relative speed along the spring, scaled as §4.7
        btScalar restLength = 0, minLength = 0, maxLength = 0; ///< m
    };
    SpringConstraint(btRigidBody& a, btRigidBody& b, const btVector3& anchorInA, const btVector3& anchorInB,
                     const Params& params);
    void getInfo1(btConstraintInfo1* info) override;
    void getInfo2(btConstraintInfo2* info) override;
    void setParam(int, btScalar, int) override {}
    btScalar getParam(int, int) const override { return 0; }

    /// Current anchor separation, metres.
    btScalar length() const;
    /// The spring force along the anchors at the current state, N (> 0 pulls them together).
    btScalar force() const;

  private:
    struct State {
        btVector3 ra, rb, n;
        btScalar length;
    };
    State state() const;
    btVector3 m_anchorA, m_anchorB;
    Params m_params;
};

} // namespace afb::bullet
