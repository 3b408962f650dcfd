#pragma once
// Constraints Bullet has no class for, written as btTypedConstraint / btActionInterface (docs/format.md §4), and the
// slider as Bullet's own class sets it up (shared by bullet::Ragdoll and sim::RawRagdoll).
#include <memory>

#include <btBulletDynamicsCommon.h>

#include "afb/figure/Figure.h"

namespace afb::bullet {

/// One row of a one-sided angular limit: the excess grows at `axisWorld · (ωA − ωB)`.
struct LimitRow {
    btVector3 axisWorld;
    btScalar excess; ///< radians past the limit (> 0), or minus the gap still left before it (≤ 0, speculative)
};

/// Shapes of a direction limit (docs/format.md §4.3).
enum class LimitShape { Cone, Pyramid };

/// The rows of a direction limit on `shaftWorld` (unit) against `basisWorld` (columns f, l, u; a cone's axis is
/// f): a cone (angle from f ≤ half1) or a true pyramid (planar angles in span(f, l) ≤ half1 and in span(f, u) ≤
/// half2, exact atan2 angles so the corners are a pyramid's). Rows whose excess is above −`marginRad` are
/// returned (0: only violated ones). Returns the row count (≤ 2).
int directionLimitRows(const btVector3& shaftWorld, const btMatrix3x3& basisWorld, LimitShape shape, btScalar half1Rad,
                       btScalar half2Rad, btScalar marginRad, LimitRow rows[2]);

/// The row of a hinge range: φ (the rotation of frame A relative to frame B about B's Z axis, docs/format.md §4.5)
/// within [lowerRad, upperRad]. Rows whose excess is above −`marginRad` are returned. Returns 0 or 1.
int hingeRangeRow(const btMatrix3x3& frameAWorld, const btMatrix3x3& frameBWorld, btScalar lowerRad, btScalar upperRad,
                  btScalar marginRad, LimitRow& row);

/// How limit rows correct: error reduction per step past the limit, and speculation before it.
struct LimitRowPolicy {
    btScalar errorReduction = btScalar(0.3); ///< the engine's LIMIT_ERROR_REDUCTION
    /// Rows exist before the limit is reached and allow only the remaining gap to close in one step.
    bool speculative = false;
};

/// A one-sided limit on a direction (the "shaft", fixed in body A) against an axis or basis fixed in body B
/// (or the world): a cone or a true pyramid (directionLimitRows). Angular rows only; twist stays free.
class DirectionLimitConstraint : public btTypedConstraint {
  public:
    using Shape = LimitShape;

    /// `shaftInA`: unit, in A's frame. `basisInB`: columns f, l, u (cone: column 0 is the axis), in B's frame.
    DirectionLimitConstraint(btRigidBody& a, btRigidBody& b, const btVector3& shaftInA, const btMatrix3x3& basisInB,
                             Shape shape, btScalar halfAngle1Rad, btScalar halfAngle2Rad, LimitRowPolicy policy = {});

    void getInfo1(btConstraintInfo1* info) override;
    void getInfo2(btConstraintInfo2* info) override;
    void setParam(int, btScalar, int) override {}
    btScalar getParam(int, int) const override { return 0; }

    /// Current violation, radians (0 when within the limit): the largest of the limit's angle excesses.
    btScalar violation() const;

  private:
    int rows(LimitRow out[2], btScalar margin) const;

    btVector3 m_shaftInA;
    btMatrix3x3 m_basisInB;
    Shape m_shape;
    btScalar m_half1, m_half2;
    LimitRowPolicy m_policy;
    btScalar m_lastStep = btScalar(1.0 / 60.0); ///< the last step's length, for the speculative margin
    btScalar m_margin = 0;                      ///< the margin getInfo1 counted rows with (getInfo2 agrees)
};

/// A hinge range as its own one-sided row (used for speculative limits; btHingeConstraint's own limit row
/// appears only after the overshoot): φ of frame A relative to frame B about B's Z within [lower, upper].
class HingeRangeConstraint : public btTypedConstraint {
  public:
    HingeRangeConstraint(btRigidBody& a, btRigidBody& b, const btTransform& frameInA, const btTransform& frameInB,
                         btScalar lowerRad, btScalar upperRad, LimitRowPolicy policy);
    void getInfo1(btConstraintInfo1* info) override;
    void getInfo2(btConstraintInfo2* info) override;
    void setParam(int, btScalar, int) override {}
    btScalar getParam(int, int) const override { return 0; }

  private:
    int row(LimitRow& out, btScalar margin) const;
    btMatrix3x3 m_frameInA, m_frameInB;
    btScalar m_lower, m_upper;
    LimitRowPolicy m_policy;
    btScalar m_lastStep = btScalar(1.0 / 60.0); ///< the last step's length, for the speculative margin
    btScalar m_margin = 0;                      ///< the margin getInfo1 counted rows with (getInfo2 agrees)
};

/// A universal joint (docs/format.md §4.4) as four rows that always exist: the anchors together (three rows, as
/// btPoint2PointConstraint) and no relative spin about the bisector of the two shafts (the constant-velocity
/// condition), with the twist between the two frames, each turned halfway through their swing, as its position
/// error (twist()). Frames' X axes are the shafts (A's shaft 1, B's −shaft 2: aligned at the load pose).
class UniversalConstraint : public btTypedConstraint {
  public:
    UniversalConstraint(btRigidBody& a, btRigidBody& b, const btTransform& frameInA, const btTransform& frameInB);
    void getInfo1(btConstraintInfo1* info) override;
    void getInfo2(btConstraintInfo2* info) override;
    void setParam(int, btScalar, int) override {}
    btScalar getParam(int, int) const override { return 0; }
    /// The twist of frame A against frame B about the bisector of their X axes, both turned halfway through the
    /// swing onto it, radians (0 at the load pose; 0 after any pure swing).
    btScalar twist() const;

  private:
    btTransform m_frameInA, m_frameInB;
};

/// Joint friction (docs/format.md §4.8): rows that resist the relative angular velocity on the free axes, each bounded
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

/// A spring (docs/format.md §4.7) between anchors fixed in A and B: the quadratic force F = k·ΔL² (stretch above the
/// rest length, compress below) minus D = damping·|Δv·n|/L, plus one-sided length rows below `minLength` and above
/// `maxLength` (when > 0). The force enters the solver as a row whose impulse is pinned to F·dt, so it is integrated
/// exactly where gravity is (an impulse applied outside the step would meet Bullet's damping first and settle at F =
/// m·g / damping factor instead of m·g).
///
/// Hostile numbers (docs/stability.md): an explicit force is stable only while k·|ΔL|·dt² stays below about the
/// effective mass of the row (the two bodies' inverse masses plus each anchor's lever arm through its inverse inertia).
/// A spring far beyond its rest length on an anchor far from its body's centre (a missing anchor2 defaults to the model
/// origin) exceeds that by orders of magnitude and overflows in a few steps. So each step's impulse is bounded: the
/// spring term by the impulse that would close the whole ΔL in that one step, the damping term by the impulse that
/// would stop the anchors' relative motion along the spring. Within the bounds (every bundled spring through a drop,
/// tests/sim/test_hostile_springs.cpp) the engine's force is applied unchanged.
class SpringConstraint : public btTypedConstraint {
  public:
    struct Params {
        btScalar stretch = 0, compress = 0; ///< N/m²
        /// N per m/s of relative speed along the spring, scaled as docs/format.md §4.7.
        btScalar damping = 0;
        btScalar restLength = 0, minLength = 0, maxLength = 0; ///< m
        /// The figure's spring (docs/format.md §4.7) in Bullet's precision; both backends build theirs from it.
        static Params of(const figure::SpringParams& spring);
    };
    SpringConstraint(btRigidBody& a, btRigidBody& b, const btVector3& anchorInA, const btVector3& anchorInB,
                     const Params& params);
    void getInfo1(btConstraintInfo1* info) override;
    void getInfo2(btConstraintInfo2* info) override;
    void setParam(int, btScalar, int) override {}
    btScalar getParam(int, int) const override { return 0; }

    /// Current anchor separation, metres.
    btScalar length() const;
    /// The engine's spring force along the anchors at the current state, N (> 0 pulls them together).
    btScalar force() const;
    /// The impulse the spring applies in a step of `dt` seconds, N·s (> 0 pulls the anchors together): force()·dt
    /// with its spring and damping terms bounded as the class comment says.
    btScalar impulse(btScalar dt) const;

  private:
    struct State {
        btVector3 ra, rb, n;
        btScalar length;
    };
    /// The engine's force split into its terms (docs/format.md §4.7): pulls together by sign·(spring − damping), N.
    struct Terms {
        btScalar sign = 0;      ///< +1 stretched, −1 compressed, 0 when the active side has no stiffness
        btScalar spring = 0;    ///< k·ΔL², N
        btScalar damping = 0;   ///< damping·|Δv·n|/L, N
        btScalar deviation = 0; ///< |L − rest|, m
        btScalar speed = 0;     ///< |Δv·n|, m/s
    };
    State state() const;
    Terms terms(const State& st) const;
    btVector3 m_anchorA, m_anchorB;
    Params m_params;
};

/// The slider of docs/format.md §4.6 as Bullet's own constraint: free along the frames' X axis, no rotation.
std::unique_ptr<btSliderConstraint> makeSlider(btRigidBody& a, btRigidBody& b, const btTransform& frameInA,
                                               const btTransform& frameInB);

} // namespace afb::bullet
