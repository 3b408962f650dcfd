#pragma once
// A joint motor as Bullet rows (JointMotor.cpp): frame B driven toward a target pose relative to frame A by an
// implicit spring and damper (afb/bullet/Motor.h).
#include <btBulletDynamicsCommon.h>

#include "afb/bullet/Motor.h"

namespace afb::bullet {

/// The highest motor frequency, as a fraction of the step rate (ω·h ≤ π/2; JointMotorConstraint).
inline constexpr double kMaxFrequencyPerStepRate = 0.25;

/// Up to three angular rows (or one linear row) between two rigid bodies, each a soft constraint toward the
/// target: with the row's mass m (the inertia the joint carries about the row's axis when the ragdoll set it,
/// setCarriedInverseInertia, else the row's effective mass over the two bodies), natural frequency ω = 2π·f and
/// damping ratio ζ, the impulse λ of a step h satisfies J·v + λ·cfm/m = (ω·e + 2ζ·v*)/(h·ω + 2ζ) with cfm = 1/(h·(h·ω²
/// + 2ζ·ω)), where e is the error to the target and v* the target velocity: the spring k = m·ω² and damper c = 2m·ζ·ω
/// evaluated at the end of the step. The frequency is held to a quarter of the step rate (kMaxFrequencyPerStepRate):
/// above it the rows correct nearly the whole error in one step, and a figure's coupled rows, solved by iterations with
/// its contacts, then gain energy (a humanoid held at 400 Hz by motors on a 15 Hz step does). Bullet's own row update
/// is unstable once cfm exceeds 1 (a soft motor at a fast step); RagdollSolver rescales the rows of a constraint
/// tracked as soft so its update is exact (RagdollSolver::track), so the motor must be solved by a RagdollSolver.
class JointMotorConstraint : public btTypedConstraint {
  public:
    /// What the motor drives.
    enum class Axes {
        Rotation,       ///< the whole relative rotation (three rows about the world axes)
        RotationAboutZ, ///< the rotation about frame B's Z (hinges: one row)
        Swing, ///< the rotation about the two axes across the bisector of the frames' X axes (universal joints, which
               ///< lock the twist about it: two rows)
        SlideAlongX, ///< the offset of frame B's origin from frame A's along frame B's X (sliders: one row)
    };
    /// Frames as the joint's: fixed in A and in B (b's is in the world when b is Bullet's fixed body).
    JointMotorConstraint(btRigidBody& a, btRigidBody& b, const btTransform& frameInA, const btTransform& frameInB,
                         Axes axes);
    void getInfo1(btConstraintInfo1* info) override;
    void getInfo2(btConstraintInfo2* info) override;
    void setParam(int, btScalar, int) override {}
    btScalar getParam(int, int) const override { return 0; }

    void setGains(const MotorGains& gains) { m_gains = gains; }
    /// The inverse inertia the joint carries (CarriedInertia), world axes, 1/(kg·m²): each angular row's spring
    /// and damper are then set on it instead of on the two bodies' own inertia. Null: the two bodies' own.
    void setCarriedInverseInertia(const btMatrix3x3* w) {
        m_hasCarried = w != nullptr;
        if (w) m_carried = *w;
    }
    /// Whether the gains give the motor any rows (a frequency above 0).
    bool active() const { return rowCount() > 0; }
    const MotorGains& gains() const { return m_gains; }
    /// Target rotation of frame B relative to frame A (Rotation, RotationAboutZ: only the part about Z counts)
    /// and target angular velocity of B relative to A, in frame A, rad/s.
    void setRotationTarget(const btQuaternion& frameBInFrameA, const btVector3& angularVelocityInFrameA);
    /// Target offset along the slide axis, m, and target speed along it, m/s (SlideAlongX).
    void setSlideTarget(btScalar offsetM, btScalar speedMps);
    Axes axes() const { return m_axes; }

  private:
    int rowCount() const;
    void rotationRows(btConstraintInfo2* info, btScalar rate, btScalar bias, btScalar bound) const;
    void slideRow(btConstraintInfo2* info, btScalar rate, btScalar bias, btScalar bound) const;

    btScalar rowCfm(btScalar cfm, const btVector3& axis) const;

    btTransform m_frameInA, m_frameInB;
    btMatrix3x3 m_carried;
    bool m_hasCarried = false;
    Axes m_axes;
    MotorGains m_gains;
    btQuaternion m_target = btQuaternion::getIdentity();
    btVector3 m_targetVelocity{0, 0, 0};
    btScalar m_targetOffset = 0;
    btScalar m_targetSpeed = 0;
};

} // namespace afb::bullet
