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
    return m_axes == Axes::Rotation ? 3 : 1;
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
        w.soft(0, rate * error.dot(z) + bias * velocity.dot(z), cfm, bound);
        return;
    }
    for (int i = 0; i < 3; ++i) {
        const btVector3 axis(i == 0, i == 1, i == 2);
        w.angular(i, axis);
        w.soft(i, rate * error[i] + bias * velocity[i], cfm, bound);
    }
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
