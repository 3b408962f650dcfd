#include "afb/bullet/Constraints.h"

#include <cmath>

namespace afb::bullet {
namespace {

constexpr btScalar kInfinity = SIMD_INFINITY;

void setAngularRow(btTypedConstraint::btConstraintInfo2* info, int row, const btVector3& axis, btScalar rhs,
                   btScalar lo, btScalar hi) {
    const int s = row * info->rowskip;
    for (int k = 0; k < 3; ++k) {
        info->m_J1angularAxis[s + k] = axis[k];
        info->m_J2angularAxis[s + k] = -axis[k];
    }
    info->m_constraintError[s] = rhs;
    info->m_lowerLimit[s] = lo;
    info->m_upperLimit[s] = hi;
}

btVector3 anyPerpendicular(const btVector3& v) {
    const btVector3 helper = std::abs(v.x()) < btScalar(0.9) ? btVector3(1, 0, 0) : btVector3(0, 1, 0);
    return v.cross(helper).normalized();
}

} // namespace

// --- DirectionLimitConstraint ---------------------------------------------------------------------------------

DirectionLimitConstraint::DirectionLimitConstraint(btRigidBody& a, btRigidBody& b, const btVector3& shaftInA,
                                                   const btMatrix3x3& basisInB, Shape shape, btScalar halfAngle1Rad,
                                                   btScalar halfAngle2Rad)
    : btTypedConstraint(MAX_CONSTRAINT_TYPE, a, b), m_shaftInA(shaftInA.normalized()), m_basisInB(basisInB),
      m_shape(shape), m_half1(halfAngle1Rad), m_half2(halfAngle2Rad) {}

// The excesses here are the same quantities as figure::limitExcessRad's cone and pyramid cases
// (figure/Limits.h: cone angle minus half angle, exact atan2 planar angles minus their half angles), and a
// test holds the two to agree. They are computed again here, not through Limits.h, because each row needs the
// intermediate values (s·f, s·l, s·u, the rotation axis) for its Jacobian, and because the solver works in
// btScalar: routing the angle through Eigen's doubles would change the float build's solution.
int DirectionLimitConstraint::activeRows(Row rows[2]) const {
    const btVector3 s = m_rbA.getCenterOfMassTransform().getBasis() * m_shaftInA;
    const btMatrix3x3 basis = m_rbB.getCenterOfMassTransform().getBasis() * m_basisInB;
    const btVector3 f = basis.getColumn(0), l = basis.getColumn(1), u = basis.getColumn(2);
    int n = 0;
    if (m_shape == Shape::Cone) {
        const btScalar c = btClamped(s.dot(f), btScalar(-1), btScalar(1));
        const btScalar angle = btAcos(c);
        if (angle > m_half1) {
            const btVector3 axis = f.cross(s);
            const btVector3 j = axis.length2() > SIMD_EPSILON ? axis.normalized() : anyPerpendicular(f);
            rows[n++] = {j, angle - m_half1};
        }
        return n;
    }
    // af-format §4.3: planar angles of the shaft in span(f, l) and span(f, u); their rates are derived from
    // d(atan2(y, x))/dt with ds/dt = (ωA − ωB) × s, so the Jacobians are exact, not small-angle.
    const btScalar sf = s.dot(f), sl = s.dot(l), su = s.dot(u);
    const btScalar r1 = sf * sf + sl * sl, r2 = sf * sf + su * su;
    if (r1 > SIMD_EPSILON) {
        const btScalar angle = btAtan2(sl, sf);
        const btVector3 j = u - (su / r1) * (sf * f + sl * l);
        if (angle > m_half1) rows[n++] = {j, angle - m_half1};
        else if (angle < -m_half1) rows[n++] = {-j, -m_half1 - angle};
    }
    if (r2 > SIMD_EPSILON) {
        const btScalar angle = btAtan2(su, sf);
        const btVector3 j = -l + (sl / r2) * (sf * f + su * u);
        if (angle > m_half2) rows[n++] = {j, angle - m_half2};
        else if (angle < -m_half2) rows[n++] = {-j, -m_half2 - angle};
    }
    return n;
}

btScalar DirectionLimitConstraint::violation() const {
    Row rows[2];
    btScalar worst = 0;
    for (int i = 0, n = activeRows(rows); i < n; ++i) worst = btMax(worst, rows[i].excess);
    return worst;
}

void DirectionLimitConstraint::getInfo1(btConstraintInfo1* info) {
    Row rows[2];
    info->m_numConstraintRows = activeRows(rows);
    info->nub = 6 - info->m_numConstraintRows;
}

void DirectionLimitConstraint::getInfo2(btConstraintInfo2* info) {
    Row rows[2];
    const int n = activeRows(rows);
    // Each row's axis is oriented so that a positive impulse reduces the excess: J·v = −(rate of the angle).
    for (int i = 0; i < n; ++i)
        setAngularRow(info, i, -rows[i].axisWorld, kErrorReduction * info->fps * rows[i].excess, 0, kInfinity);
}

// --- JointFrictionConstraint ----------------------------------------------------------------------------------

JointFrictionConstraint::JointFrictionConstraint(btRigidBody& a, btRigidBody& b, const btMatrix3x3& axesInB, int count)
    : btTypedConstraint(MAX_CONSTRAINT_TYPE, a, b), m_axesInB(axesInB), m_count(count) {}

void JointFrictionConstraint::getInfo1(btConstraintInfo1* info) {
    info->m_numConstraintRows = m_maxImpulse > 0 ? m_count : 0;
    info->nub = 6 - info->m_numConstraintRows;
}

void JointFrictionConstraint::getInfo2(btConstraintInfo2* info) {
    if (m_maxImpulse <= 0) return;
    const btMatrix3x3 axes = m_rbB.getCenterOfMassTransform().getBasis() * m_axesInB;
    for (int i = 0; i < m_count; ++i) setAngularRow(info, i, axes.getColumn(i), 0, -m_maxImpulse, m_maxImpulse);
}

// --- SpringConstraint -----------------------------------------------------------------------------------------

SpringConstraint::SpringConstraint(btRigidBody& a, btRigidBody& b, const btVector3& anchorInA, const btVector3& anchorInB,
                                   const Params& params)
    : btTypedConstraint(MAX_CONSTRAINT_TYPE, a, b), m_anchorA(anchorInA), m_anchorB(anchorInB), m_params(params) {}

SpringConstraint::State SpringConstraint::state() const {
    const btTransform& ta = m_rbA.getCenterOfMassTransform();
    const btTransform& tb = m_rbB.getCenterOfMassTransform();
    State st;
    st.ra = ta.getBasis() * m_anchorA;
    st.rb = tb.getBasis() * m_anchorB;
    const btVector3 d = (tb.getOrigin() + st.rb) - (ta.getOrigin() + st.ra);
    st.length = d.length();
    st.n = st.length > SIMD_EPSILON ? d / st.length : btVector3(0, 0, 0);
    return st;
}

btScalar SpringConstraint::length() const { return state().length; }

btScalar SpringConstraint::force() const {
    const State st = state();
    if (st.length <= SIMD_EPSILON) return 0;
    const btVector3 dv = m_rbB.getVelocityInLocalPoint(st.rb) - m_rbA.getVelocityInLocalPoint(st.ra);
    const btScalar damping = m_params.damping * btFabs(dv.dot(st.n)) / st.length;
    const btScalar rest = m_params.restLength;
    if (st.length > rest) {
        const btScalar stretch = st.length - rest;
        return m_params.stretch > 0 ? m_params.stretch * stretch * stretch - damping : 0;
    }
    const btScalar squeeze = rest - st.length;
    return m_params.compress > 0 ? -(m_params.compress * squeeze * squeeze - damping) : 0;
}

void SpringConstraint::getInfo1(btConstraintInfo1* info) {
    const btScalar l = length();
    const bool lengthRow = l < m_params.minLength || (m_params.maxLength > 0 && l > m_params.maxLength);
    info->m_numConstraintRows = (force() != 0 ? 1 : 0) + (lengthRow ? 1 : 0);
    info->nub = 6 - info->m_numConstraintRows;
}

void SpringConstraint::getInfo2(btConstraintInfo2* info) {
    const State st = state();
    if (st.length <= SIMD_EPSILON) return;
    int row = 0;
    // A row along n (J·v = dL/dt for `sign` = +1); `lo`/`hi` bound its impulse.
    auto setRow = [&](btScalar sign, btScalar rhs, btScalar lo, btScalar hi) {
        const btVector3 n = st.n * sign;
        const int s0 = row * info->rowskip;
        const btVector3 ja = -st.ra.cross(n), jb = st.rb.cross(n);
        for (int k = 0; k < 3; ++k) {
            info->m_J1linearAxis[s0 + k] = -n[k];
            info->m_J2linearAxis[s0 + k] = n[k];
            info->m_J1angularAxis[s0 + k] = ja[k];
            info->m_J2angularAxis[s0 + k] = jb[k];
        }
        info->m_constraintError[s0] = rhs;
        info->m_lowerLimit[s0] = lo;
        info->m_upperLimit[s0] = hi;
        ++row;
    };
    // The force as a pinned impulse: an impulse along −J pulls the anchors together, so F·dt goes on −n.
    const btScalar impulse = force() / info->fps;
    if (impulse != 0) setRow(-1, 0, impulse, impulse);
    if (st.length < m_params.minLength)
        setRow(1, info->erp * info->fps * (m_params.minLength - st.length), 0, kInfinity);
    else if (m_params.maxLength > 0 && st.length > m_params.maxLength)
        setRow(-1, info->erp * info->fps * (st.length - m_params.maxLength), 0, kInfinity);
}

} // namespace afb::bullet
