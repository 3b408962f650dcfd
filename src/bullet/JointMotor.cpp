// Joint motors as soft rows (JointMotor.h).
#include "JointMotor.h"

#include <algorithm>
#include <cmath>

namespace afb::bullet {
namespace {

// One row of an info2 block: J·v = n·(vB − vA) + angular terms, written as Bullet lays rows out.
struct RowWriter {
    btTypedConstraint::btConstraintInfo2* info;
    void angular(int row, const btVector3& axis) const {
        const int s = row * info->rowskip;
        for (int k = 0; k < 3; ++k) {
            info->m_J1angularAxis[s + k] = -axis[k];
            info->m_J2angularAxis[s + k] = axis[k];
        }
    }
    void soft(int row, btScalar rhs, btScalar cfm, btScalar bound) const {
        const int s = row * info->rowskip;
        info->m_constraintError[s] = rhs;
        info->cfm[s] = cfm;
        info->m_lowerLimit[s] = -bound;
        info->m_upperLimit[s] = bound;
    }
};

// The rotation vector of a unit quaternion (the shorter way round).
btVector3 rotationVector(btQuaternion q) {
    if (q.w() < 0) q = -q;
    const btScalar s = btVector3(q.x(), q.y(), q.z()).length();
    if (s < SIMD_EPSILON) return {q.x() * 2, q.y() * 2, q.z() * 2};
    return btVector3(q.x(), q.y(), q.z()) * (2 * btAtan2(s, q.w()) / s);
}

btScalar impulseBound(double perSecond, btScalar step) {
    return std::isfinite(perSecond) ? btScalar(std::max(0.0, perSecond)) * step : SIMD_INFINITY;
}

} // namespace

JointMotorConstraint::JointMotorConstraint(btRigidBody& a, btRigidBody& b, const btTransform& frameInA,
                                           const btTransform& frameInB, Axes axes)
    : btTypedConstraint(MAX_CONSTRAINT_TYPE, a, b), m_frameInA(frameInA), m_frameInB(frameInB), m_axes(axes) {}

void JointMotorConstraint::setRotationTarget(const btQuaternion& frameBInFrameA,
                                             const btVector3& angularVelocityInFrameA) {
    m_target = frameBInFrameA.normalized();
    m_targetVelocity = angularVelocityInFrameA;
}

void JointMotorConstraint::setSlideTarget(btScalar offsetM, btScalar speedMps) {
    m_targetOffset = offsetM;
    m_targetSpeed = speedMps;
}

int JointMotorConstraint::rowCount() const {
    if (!(m_gains.frequencyHz > 0) || !(m_gains.dampingRatio >= 0)) return 0;
    switch (m_axes) {
    case Axes::Rotation: return 3;
    case Axes::Swing: return 2;
    case Axes::RotationAboutZ:
    case Axes::SlideAlongX: return 1;
    }
    return 1;
}

void JointMotorConstraint::getInfo1(btConstraintInfo1* info) {
    info->m_numConstraintRows = rowCount();
    info->nub = 6 - info->m_numConstraintRows;
}

void JointMotorConstraint::getInfo2(btConstraintInfo2* info) {
    if (rowCount() == 0) return;
    // The spring and damper at the end of the step (module comment in JointMotor.h).
    const double h = 1.0 / double(info->fps);
    const double omega = 2 * SIMD_PI * std::min(m_gains.frequencyHz, kMaxFrequencyPerStepRate / h);
    const double zeta = m_gains.dampingRatio;
    const double denominator = h * omega + 2 * zeta;
    const auto rate = btScalar(omega / denominator);    // per unit error
    const auto bias = btScalar(2 * zeta / denominator); // per unit target velocity
    const auto cfm = btScalar(1 / (h * omega * denominator));
    for (int i = 0; i < rowCount(); ++i) info->cfm[i * info->rowskip] = cfm;
    if (m_axes == Axes::SlideAlongX) slideRow(info, rate, bias, impulseBound(m_gains.maxForceN, btScalar(h)));
    else rotationRows(info, rate, bias, impulseBound(m_gains.maxTorqueNm, btScalar(h)));
}

void JointMotorConstraint::rotationRows(btConstraintInfo2* info, btScalar rate, btScalar bias, btScalar bound) const {
    const btMatrix3x3 fa = m_rbA.getCenterOfMassTransform().getBasis() * m_frameInA.getBasis();
    const btMatrix3x3 fb = m_rbB.getCenterOfMassTransform().getBasis() * m_frameInB.getBasis();
    // The world rotation that takes frame B where the target puts it, and the target's velocity in the world.
    const btMatrix3x3 toTarget = fa * btMatrix3x3(m_target) * fb.transpose();
    btQuaternion q;
    toTarget.getRotation(q);
    const btVector3 error = rotationVector(q);
    const btVector3 velocity = fa * m_targetVelocity;
    const RowWriter w{info};
    const btScalar cfm = info->cfm[0];
    if (m_axes == Axes::RotationAboutZ) {
        const btVector3 z = fb.getColumn(2);
        w.angular(0, z);
        w.soft(0, rate * error.dot(z) + bias * velocity.dot(z), rowCfm(cfm, z), bound);
        return;
    }
    if (m_axes == Axes::Swing) {
        // Across the bisector of the shafts, as the joint's twist row lies along it (UniversalConstraint): the
        // twist is the joint's to hold, and a third row would only pull against it.
        btVector3 bisector = fa.getColumn(0) + fb.getColumn(0);
        if (bisector.length2() < btScalar(1e-6)) bisector = fb.getColumn(0);
        bisector.normalize();
        btVector3 across[2];
        btPlaneSpace1(bisector, across[0], across[1]);
        for (int i = 0; i < 2; ++i) {
            w.angular(i, across[i]);
            w.soft(i, rate * error.dot(across[i]) + bias * velocity.dot(across[i]), rowCfm(cfm, across[i]), bound);
        }
        return;
    }
    for (int i = 0; i < 3; ++i) {
        const btVector3 axis(i == 0, i == 1, i == 2);
        w.angular(i, axis);
        w.soft(i, rate * error[i] + bias * velocity[i], rowCfm(cfm, axis), bound);
    }
}

// Bullet takes a row's cfm per unit of its effective mass m = 1/(n·(I_A⁻¹ + I_B⁻¹)·n): the spring is m·ω². With
// the carried inverse inertia W the spring is ω²/(n·W·n), so the cfm is scaled by (n·W·n)/(n·(I_A⁻¹ + I_B⁻¹)·n).
btScalar JointMotorConstraint::rowCfm(btScalar cfm, const btVector3& axis) const {
    if (!m_hasCarried) return cfm;
    const btScalar own =
        axis.dot(m_rbA.getInvInertiaTensorWorld() * axis) + axis.dot(m_rbB.getInvInertiaTensorWorld() * axis);
    const btScalar carried = axis.dot(m_carried * axis);
    if (!(own > 0) || !(carried > 0) || !std::isfinite(double(carried))) return cfm;
    return cfm * (carried / own);
}

void JointMotorConstraint::slideRow(btConstraintInfo2* info, btScalar rate, btScalar bias, btScalar bound) const {
    const btTransform& ta = m_rbA.getCenterOfMassTransform();
    const btTransform& tb = m_rbB.getCenterOfMassTransform();
    const btTransform fa = ta * m_frameInA;
    const btTransform fb = tb * m_frameInB;
    const btVector3 axis = fb.getBasis().getColumn(0);
    const btVector3 at = fb.getOrigin();
    const btScalar offset = (at - fa.getOrigin()).dot(axis);
    // The velocity of B's frame origin relative to the point of A under it, along the axis.
    const int s = 0;
    const btVector3 ra = at - ta.getOrigin(), rb = at - tb.getOrigin();
    const btVector3 angularA = ra.cross(axis), angularB = rb.cross(axis);
    for (int k = 0; k < 3; ++k) {
        info->m_J1linearAxis[s + k] = -axis[k];
        info->m_J2linearAxis[s + k] = axis[k];
        info->m_J1angularAxis[s + k] = -angularA[k];
        info->m_J2angularAxis[s + k] = angularB[k];
    }
    RowWriter{info}.soft(0, rate * (m_targetOffset - offset) + bias * m_targetSpeed, info->cfm[0], bound);
}

} // namespace afb::bullet
