#include "afb/detail/Constraints.h"

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

// --- limit rows ---------------------------------------------------------------------------------------------

// The excesses here are the same quantities as figure::limitExcessRad's cone, pyramid and hinge cases
// (figure/Limits.h), and a test holds the two to agree. They are computed again here, not through Limits.h,
// because each row needs the intermediate values (s·f, s·l, s·u, the rotation axis) for its Jacobian, and
// because the solver works in btScalar: routing the angle through Eigen's doubles would change the float
// build's solution.

int directionLimitRows(const btVector3& s, const btMatrix3x3& basis, LimitShape shape, btScalar half1, btScalar half2,
                       btScalar margin, LimitRow rows[2]) {
    const btVector3 f = basis.getColumn(0), l = basis.getColumn(1), u = basis.getColumn(2);
    int n = 0;
    if (shape == LimitShape::Cone) {
        const btScalar angle = btAcos(btClamped(s.dot(f), btScalar(-1), btScalar(1)));
        if (angle - half1 > -margin) {
            const btVector3 axis = f.cross(s);
            const btVector3 j = axis.length2() > SIMD_EPSILON ? axis.normalized() : anyPerpendicular(f);
            rows[n++] = {j, angle - half1};
        }
        return n;
    }
    // docs/format.md §4.3: planar angles of the shaft in span(f, l) and span(f, u); their rates are derived from
    // d(atan2(y, x))/dt with ds/dt = (ωA − ωB) × s, so the Jacobians are exact, not small-angle.
    const btScalar sf = s.dot(f), sl = s.dot(l), su = s.dot(u);
    const btScalar r1 = sf * sf + sl * sl, r2 = sf * sf + su * su;
    if (r1 > SIMD_EPSILON) {
        const btScalar angle = btAtan2(sl, sf);
        const btVector3 j = u - (su / r1) * (sf * f + sl * l);
        if (angle - half1 > -margin) rows[n++] = {j, angle - half1};
        else if (-half1 - angle > -margin) rows[n++] = {-j, -half1 - angle};
    }
    if (r2 > SIMD_EPSILON) {
        const btScalar angle = btAtan2(su, sf);
        const btVector3 j = -l + (sl / r2) * (sf * f + su * u);
        if (angle - half2 > -margin) rows[n++] = {j, angle - half2};
        else if (-half2 - angle > -margin) rows[n++] = {-j, -half2 - angle};
    }
    return n;
}

int hingeRangeRow(const btMatrix3x3& frameA, const btMatrix3x3& frameB, btScalar lower, btScalar upper, btScalar margin,
                  LimitRow& row) {
    // φ: rotation of frame A relative to frame B about B's Z; dφ/dt = (ωA − ωB)·z.
    const btMatrix3x3 rel = frameB.transpose() * frameA;
    const btScalar phi = btAtan2(rel[1][0], rel[0][0]);
    const btScalar centre = btScalar(0.5) * (lower + upper), half = btScalar(0.5) * (upper - lower);
    const btScalar d = btNormalizeAngle(phi - centre);
    const btVector3 z = frameB.getColumn(2);
    if (d - half > -margin && d >= 0) {
        row = {z, d - half};
        return 1;
    }
    if (-half - d > -margin && d < 0) {
        row = {-z, -half - d};
        return 1;
    }
    return 0;
}

namespace {

// The speculative margin of a limit: the angle the joint can turn in about two steps at its current rate.
btScalar speculativeMargin(const btRigidBody& a, const btRigidBody& b, btScalar step) {
    return (a.getAngularVelocity() - b.getAngularVelocity()).length() * step * 2 + btScalar(0.01);
}

// A limit row: past the limit, Baumgarte recovery of errorReduction per step; before it (speculative), the
// joint may close at most the remaining gap in this step.
void setLimitRow(btTypedConstraint::btConstraintInfo2* info, int i, const LimitRow& r, const LimitRowPolicy& p) {
    const btScalar rhs = r.excess > 0 ? p.errorReduction * info->fps * r.excess : info->fps * r.excess;
    // The axis is oriented so that a positive impulse reduces the excess: J·v = −(rate of the excess).
    setAngularRow(info, i, -r.axisWorld, rhs, 0, kInfinity);
}

} // namespace

// --- DirectionLimitConstraint ---------------------------------------------------------------------------------

DirectionLimitConstraint::DirectionLimitConstraint(btRigidBody& a, btRigidBody& b, const btVector3& shaftInA,
                                                   const btMatrix3x3& basisInB, Shape shape, btScalar halfAngle1Rad,
                                                   btScalar halfAngle2Rad, LimitRowPolicy policy)
    : btTypedConstraint(MAX_CONSTRAINT_TYPE, a, b), m_shaftInA(shaftInA.normalized()), m_basisInB(basisInB),
      m_shape(shape), m_half1(halfAngle1Rad), m_half2(halfAngle2Rad), m_policy(policy) {}

int DirectionLimitConstraint::rows(LimitRow out[2], btScalar margin) const {
    return directionLimitRows(m_rbA.getCenterOfMassTransform().getBasis() * m_shaftInA,
                              m_rbB.getCenterOfMassTransform().getBasis() * m_basisInB, m_shape, m_half1, m_half2,
                              margin, out);
}

btScalar DirectionLimitConstraint::violation() const {
    LimitRow r[2];
    btScalar worst = 0;
    for (int i = 0, n = rows(r, 0); i < n; ++i) worst = btMax(worst, r[i].excess);
    return worst;
}

void DirectionLimitConstraint::getInfo1(btConstraintInfo1* info) {
    LimitRow r[2];
    m_margin = m_policy.speculative ? speculativeMargin(m_rbA, m_rbB, m_lastStep) : 0;
    info->m_numConstraintRows = rows(r, m_margin);
    info->nub = 6 - info->m_numConstraintRows;
}

void DirectionLimitConstraint::getInfo2(btConstraintInfo2* info) {
    LimitRow r[2];
    m_lastStep = btScalar(1) / info->fps;
    for (int i = 0, n = rows(r, m_margin); i < n; ++i) setLimitRow(info, i, r[i], m_policy);
}

// --- HingeRangeConstraint -------------------------------------------------------------------------------------

HingeRangeConstraint::HingeRangeConstraint(btRigidBody& a, btRigidBody& b, const btTransform& frameInA,
                                           const btTransform& frameInB, btScalar lowerRad, btScalar upperRad,
                                           LimitRowPolicy policy)
    : btTypedConstraint(MAX_CONSTRAINT_TYPE, a, b), m_frameInA(frameInA.getBasis()), m_frameInB(frameInB.getBasis()),
      m_lower(lowerRad), m_upper(upperRad), m_policy(policy) {}

int HingeRangeConstraint::row(LimitRow& out, btScalar margin) const {
    return hingeRangeRow(m_rbA.getCenterOfMassTransform().getBasis() * m_frameInA,
                         m_rbB.getCenterOfMassTransform().getBasis() * m_frameInB, m_lower, m_upper, margin, out);
}

void HingeRangeConstraint::getInfo1(btConstraintInfo1* info) {
    LimitRow r;
    m_margin = m_policy.speculative ? speculativeMargin(m_rbA, m_rbB, m_lastStep) : 0;
    info->m_numConstraintRows = row(r, m_margin);
    info->nub = 6 - info->m_numConstraintRows;
}

void HingeRangeConstraint::getInfo2(btConstraintInfo2* info) {
    LimitRow r;
    m_lastStep = btScalar(1) / info->fps;
    if (row(r, m_margin) == 1) setLimitRow(info, 0, r, m_policy);
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

// --- UniversalConstraint --------------------------------------------------------------------------------------

UniversalConstraint::UniversalConstraint(btRigidBody& a, btRigidBody& b, const btTransform& frameInA,
                                         const btTransform& frameInB)
    : btTypedConstraint(MAX_CONSTRAINT_TYPE, a, b), m_frameInA(frameInA), m_frameInB(frameInB) {}

void UniversalConstraint::getInfo1(btConstraintInfo1* info) {
    info->m_numConstraintRows = 4;
    info->nub = 4; // all unbounded
}

namespace {

// The twist of frame `a` against frame `b` (world bases, X the shafts) about the bisector of their X axes, both
// turned halfway through the swing onto it; `bisector` receives that axis (b's X when the shafts are opposed, where
// the twist is taken as 0).
btScalar universalTwist(const btMatrix3x3& a, const btMatrix3x3& b, btVector3& bisector) {
    const btVector3 xa = a.getColumn(0), xb = b.getColumn(0);
    bisector = xa + xb;
    if (bisector.length2() < btScalar(1e-6)) {
        bisector = xb;
        return 0;
    }
    bisector.normalize();
    const btVector3 ya = quatRotate(shortestArcQuat(xa, bisector), a.getColumn(1));
    const btVector3 yb = quatRotate(shortestArcQuat(xb, bisector), b.getColumn(1));
    return btAtan2(bisector.dot(yb.cross(ya)), yb.dot(ya));
}

} // namespace

btScalar UniversalConstraint::twist() const {
    btVector3 bisector;
    return universalTwist(m_rbA.getCenterOfMassTransform().getBasis() * m_frameInA.getBasis(),
                          m_rbB.getCenterOfMassTransform().getBasis() * m_frameInB.getBasis(), bisector);
}

void UniversalConstraint::getInfo2(btConstraintInfo2* info) {
    const btTransform& ta = m_rbA.getCenterOfMassTransform();
    const btTransform& tb = m_rbB.getCenterOfMassTransform();
    const btVector3 ra = ta.getBasis() * m_frameInA.getOrigin(), rb = tb.getBasis() * m_frameInB.getOrigin();
    const btScalar k = info->fps * info->erp;
    const btVector3 gap = (tb.getOrigin() + rb) - (ta.getOrigin() + ra);
    for (int i = 0; i < 3; ++i) {
        const int s = i * info->rowskip;
        btVector3 e(0, 0, 0);
        e[i] = 1;
        const btVector3 angA = ra.cross(e), angB = -rb.cross(e);
        for (int q = 0; q < 3; ++q) {
            info->m_J1linearAxis[s + q] = e[q];
            info->m_J1angularAxis[s + q] = angA[q];
            if (info->m_J2linearAxis) info->m_J2linearAxis[s + q] = -e[q];
            info->m_J2angularAxis[s + q] = angB[q];
        }
        info->m_constraintError[s] = k * gap[i];
    }
    // One pass over the frames gives the row's axis and its error.
    btVector3 n;
    const btScalar twist =
        universalTwist(ta.getBasis() * m_frameInA.getBasis(), tb.getBasis() * m_frameInB.getBasis(), n);
    setAngularRow(info, 3, n, -k * twist, -SIMD_INFINITY, SIMD_INFINITY);
}

// --- SpringConstraint -----------------------------------------------------------------------------------------

SpringConstraint::Params SpringConstraint::Params::of(const figure::SpringParams& spring) {
    Params p;
    p.stretch = static_cast<btScalar>(spring.stretchNPerM2);
    p.compress = static_cast<btScalar>(spring.compressNPerM2);
    p.damping = static_cast<btScalar>(spring.dampingNs);
    p.restLength = static_cast<btScalar>(spring.restLengthM);
    p.minLength = static_cast<btScalar>(spring.minLengthM);
    p.maxLength = static_cast<btScalar>(spring.maxLengthM);
    return p;
}

SpringConstraint::SpringConstraint(btRigidBody& a, btRigidBody& b, const btVector3& anchorInA,
                                   const btVector3& anchorInB, const Params& params)
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

SpringConstraint::Terms SpringConstraint::terms(const State& st) const {
    Terms t;
    if (st.length <= SIMD_EPSILON) return t;
    const btVector3 dv = m_rbB.getVelocityInLocalPoint(st.rb) - m_rbA.getVelocityInLocalPoint(st.ra);
    t.speed = btFabs(dv.dot(st.n));
    t.damping = m_params.damping * t.speed / st.length;
    const btScalar rest = m_params.restLength;
    t.deviation = btFabs(st.length - rest);
    const btScalar k = st.length > rest ? m_params.stretch : m_params.compress;
    if (k > 0) {
        t.sign = st.length > rest ? 1 : -1;
        t.spring = k * t.deviation * t.deviation;
    }
    return t;
}

btScalar SpringConstraint::force() const {
    const Terms t = terms(state());
    return t.sign * (t.spring - t.damping);
}

btScalar SpringConstraint::impulse(btScalar dt) const {
    const State st = state();
    const Terms t = terms(st);
    if (t.sign == 0) return 0;
    // The row's effective mass: the mass the two anchors present to an impulse along n.
    auto angular = [&](const btRigidBody& body, const btVector3& r) {
        const btVector3 arm = r.cross(st.n);
        return arm.dot(body.getInvInertiaTensorWorld() * arm);
    };
    const btScalar inverseMass =
        m_rbA.getInvMass() + m_rbB.getInvMass() + angular(m_rbA, st.ra) + angular(m_rbB, st.rb);
    if (!(inverseMass > 0)) return t.sign * (t.spring - t.damping) * dt;
    const btScalar mass = 1 / inverseMass;
    const btScalar spring = btMin(t.spring * dt, mass * t.deviation / dt);
    const btScalar damping = btMin(t.damping * dt, mass * t.speed);
    return t.sign * (spring - damping);
}

void SpringConstraint::getInfo1(btConstraintInfo1* info) {
    const btScalar l = length();
    const bool lengthRow = l < m_params.minLength || (m_params.maxLength > 0 && l > m_params.maxLength);
    // The force row exists whenever the active side has a stiffness, so getInfo2 fills exactly these rows.
    info->m_numConstraintRows = (terms(state()).sign != 0 ? 1 : 0) + (lengthRow ? 1 : 0);
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
    if (terms(st).sign != 0) {
        const btScalar pull = impulse(1 / info->fps);
        setRow(-1, 0, pull, pull);
    }
    if (st.length < m_params.minLength)
        setRow(1, info->erp * info->fps * (m_params.minLength - st.length), 0, kInfinity);
    else if (m_params.maxLength > 0 && st.length > m_params.maxLength)
        setRow(-1, info->erp * info->fps * (st.length - m_params.maxLength), 0, kInfinity);
}

std::unique_ptr<btSliderConstraint> makeSlider(btRigidBody& a, btRigidBody& b, const btTransform& frameInA,
                                               const btTransform& frameInB) {
    auto s = std::make_unique<btSliderConstraint>(a, b, frameInA, frameInB, false);
    s->setLowerLinLimit(1); // lower > upper: free along the axis
    s->setUpperLinLimit(-1);
    s->setLowerAngLimit(0); // no rotation
    s->setUpperAngLimit(0);
    return s;
}

} // namespace afb::bullet
