#pragma once
// The sequential-impulse row update (one constraint row, two bodies) in SSE, rounded bit for bit as Bullet's scalar
// reference rounds (btSequentialImpulseConstraintSolver's gResolveSingleConstraintRow*_scalar_reference and
// btSolverBody::internalApplyImpulse, Bullet 3.24). Debian's Bullet is built without BT_USE_SSE on Linux, so its
// solver runs the scalar reference; this is the same arithmetic, operation for operation, with the x, y and z of a
// product or a sum taken in one instruction (IEEE single precision per lane, as the scalar code's): a dot product
// still sums (x + y) + z and every vector product keeps Bullet's association. Only the w lane of the bodies'
// vectors is left as it was (Bullet's scalar code never writes it).
//
// RagdollSolver runs its iterations on these (docs/performance.md); tests/bullet/test_row_kernels.cpp compares them
// with Bullet's own scalar functions on random rows.
#include <BulletDynamics/ConstraintSolver/btSolverBody.h>
#include <BulletDynamics/ConstraintSolver/btSolverConstraint.h>

#if defined(__SSE2__) && !defined(BT_USE_DOUBLE_PRECISION)
#include <emmintrin.h>
#include <xmmintrin.h>
#define AFB_SIMD_ROWS 1
#else
#define AFB_SIMD_ROWS 0
#endif

namespace afb::bullet::detail {

/// Which of a body's two velocity pairs a row moves: the velocity solve's (Bullet's delta velocities) or the split
/// impulse's (push and turn velocities).
enum class RowTarget { Velocity, Push };

/// A body's linear and angular velocity of that pair.
template <RowTarget T, class Body>
auto& linearOf(Body& body) {
    if constexpr (T == RowTarget::Velocity) return body.m_deltaLinearVelocity;
    else return body.m_pushVelocity;
}
template <RowTarget T, class Body>
auto& angularOf(Body& body) {
    if constexpr (T == RowTarget::Velocity) return body.m_deltaAngularVelocity;
    else return body.m_turnVelocity;
}

#if AFB_SIMD_ROWS

inline __m128 loadVector(const btVector3& v) { return _mm_loadu_ps(v.m_floats); } // 8-aligned in Debian's build

/// v.x, v.y, v.z += d.x, d.y, d.z; v.w unchanged (d's w lane is cleared first).
inline void addXyz(btVector3& v, __m128 d) {
    const __m128 xyz = _mm_castsi128_ps(_mm_set_epi32(0, -1, -1, -1));
    _mm_storeu_ps(v.m_floats, _mm_add_ps(loadVector(v), _mm_and_ps(d, xyz)));
}

/// body.internalApplyImpulse(normal * body.internalGetInvMass(), angular, impulse) (or internalApplyPushImpulse):
/// linear += ((normal ∘ invMass) · impulse) ∘ linearFactor, angular += angular ∘ (angularFactor · impulse).
template <RowTarget T>
inline void applyRowImpulse(btSolverBody& body, const btVector3& normal, const btVector3& angular, btScalar impulse) {
    if (body.m_originalBody == nullptr) return;
    const __m128 s = _mm_set1_ps(impulse);
    const __m128 linear = _mm_mul_ps(_mm_mul_ps(_mm_mul_ps(loadVector(normal), loadVector(body.m_invMass)), s),
                                     loadVector(body.m_linearFactor));
    const __m128 turn = _mm_mul_ps(loadVector(angular), _mm_mul_ps(loadVector(body.m_angularFactor), s));
    addXyz(linearOf<T>(body), linear);
    addXyz(angularOf<T>(body), turn);
}

/// The row's four dot products in lanes 0–3: n₁ · v_A, (r₁ × n) · ω_A, n₂ · v_B, (r₂ × n) · ω_B over the bodies'
/// delta (or push) velocities, each summed as btVector3::dot sums, (x + y) + z (the four products transposed so
/// that each lane sums its own).
template <RowTarget T>
inline __m128 rowDots(const btSolverBody& a, const btSolverBody& b, const btSolverConstraint& c) {
    const btVector3 &va = linearOf<T>(a), &wa = angularOf<T>(a), &vb = linearOf<T>(b), &wb = angularOf<T>(b);
    __m128 x = _mm_mul_ps(loadVector(c.m_contactNormal1), loadVector(va));
    __m128 y = _mm_mul_ps(loadVector(c.m_relpos1CrossNormal), loadVector(wa));
    __m128 z = _mm_mul_ps(loadVector(c.m_contactNormal2), loadVector(vb));
    __m128 w = _mm_mul_ps(loadVector(c.m_relpos2CrossNormal), loadVector(wb));
    _MM_TRANSPOSE4_PS(x, y, z, w); // x: the four products' x components, y: their y, z: their z
    return _mm_add_ps(_mm_add_ps(x, y), z);
}

/// J v of the row per side, as Bullet's row update sums it: side A = n₁ · v_A + (r₁ × n) · ω_A, side B likewise.
template <RowTarget T>
inline void rowVelocities(const btSolverBody& a, const btSolverBody& b, const btSolverConstraint& c, btScalar& sideA,
                          btScalar& sideB) {
    const __m128 dots = rowDots<T>(a, b, c);
    const __m128 sides = _mm_add_ps(dots, _mm_shuffle_ps(dots, dots, _MM_SHUFFLE(2, 3, 0, 1)));
    sideA = _mm_cvtss_f32(sides);
    sideB = _mm_cvtss_f32(_mm_movehl_ps(sides, sides));
}

/// J v of the row summed left to right, as `n₁·v_A + (r₁×n)·ω_A + n₂·v_B + (r₂×n)·ω_B` sums in btScalar.
template <RowTarget T>
inline btScalar rowVelocitySum(const btSolverBody& a, const btSolverBody& b, const btSolverConstraint& c) {
    const __m128 dots = rowDots<T>(a, b, c);
    __m128 sum = _mm_add_ss(dots, _mm_shuffle_ps(dots, dots, _MM_SHUFFLE(1, 1, 1, 1)));
    sum = _mm_add_ss(sum, _mm_movehl_ps(dots, dots));
    return _mm_cvtss_f32(_mm_add_ss(sum, _mm_shuffle_ps(dots, dots, _MM_SHUFFLE(3, 3, 3, 3))));
}

#else // a double-precision or non-SSE build: Bullet's own vector arithmetic (the same roundings by definition)

template <RowTarget T>
inline void applyRowImpulse(btSolverBody& body, const btVector3& normal, const btVector3& angular, btScalar impulse) {
    if constexpr (T == RowTarget::Velocity) body.internalApplyImpulse(normal * body.m_invMass, angular, impulse);
    else body.internalApplyPushImpulse(normal * body.m_invMass, angular, impulse);
}

template <RowTarget T>
inline void rowVelocities(const btSolverBody& a, const btSolverBody& b, const btSolverConstraint& c, btScalar& sideA,
                          btScalar& sideB) {
    const btVector3 &va = linearOf<T>(a), &wa = angularOf<T>(a), &vb = linearOf<T>(b), &wb = angularOf<T>(b);
    sideA = c.m_contactNormal1.dot(va) + c.m_relpos1CrossNormal.dot(wa);
    sideB = c.m_contactNormal2.dot(vb) + c.m_relpos2CrossNormal.dot(wb);
}

template <RowTarget T>
inline btScalar rowVelocitySum(const btSolverBody& a, const btSolverBody& b, const btSolverConstraint& c) {
    const btVector3 &va = linearOf<T>(a), &wa = angularOf<T>(a), &vb = linearOf<T>(b), &wb = angularOf<T>(b);
    return c.m_contactNormal1.dot(va) + c.m_relpos1CrossNormal.dot(wa) + c.m_contactNormal2.dot(vb) +
           c.m_relpos2CrossNormal.dot(wb);
}

#endif

/// One row update as Bullet's scalar reference does it: bounded on both sides (`Upper`, the generic row) or below
/// only (contacts); on the velocities or, for split impulse, the push velocities (a row with no penetration to
/// recover is skipped then, as Bullet skips it). Returns what Bullet's returns, the solver's residual term: the
/// impulse change divided by the row's jacDiagABInv (a velocity), in double precision rounded to btScalar.
template <bool Upper, RowTarget T>
inline btScalar resolveRow(btSolverBody& a, btSolverBody& b, const btSolverConstraint& c) {
    btScalar deltaImpulse = 0;
    if (T == RowTarget::Velocity || c.m_rhsPenetration != 0) {
        btScalar& applied = T == RowTarget::Velocity ? c.m_appliedImpulse : c.m_appliedPushImpulse;
        const btScalar rhs = T == RowTarget::Velocity ? c.m_rhs : c.m_rhsPenetration;
        deltaImpulse = rhs - applied * c.m_cfm;
        btScalar sideA = 0, sideB = 0;
        rowVelocities<T>(a, b, c, sideA, sideB);
        deltaImpulse -= sideA * c.m_jacDiagABInv;
        deltaImpulse -= sideB * c.m_jacDiagABInv;
        const btScalar sum = applied + deltaImpulse;
        if (sum < c.m_lowerLimit) {
            deltaImpulse = c.m_lowerLimit - applied;
            applied = c.m_lowerLimit;
        } else if (Upper && sum > c.m_upperLimit) {
            deltaImpulse = c.m_upperLimit - applied;
            applied = c.m_upperLimit;
        } else {
            applied = sum;
        }
        applyRowImpulse<T>(a, c.m_contactNormal1, c.m_angularComponentA, deltaImpulse);
        applyRowImpulse<T>(b, c.m_contactNormal2, c.m_angularComponentB, deltaImpulse);
    }
    return static_cast<btScalar>(double(deltaImpulse) * (1. / double(c.m_jacDiagABInv)));
}

// As btSingleConstraintRowSolver functions (btSequentialImpulseConstraintSolver's function pointers; the row's
// impulses are `mutable` in btSolverConstraint).
inline btScalar resolveRowGeneric(btSolverBody& a, btSolverBody& b, const btSolverConstraint& c) {
    return resolveRow<true, RowTarget::Velocity>(a, b, c);
}
inline btScalar resolveRowLowerLimit(btSolverBody& a, btSolverBody& b, const btSolverConstraint& c) {
    return resolveRow<false, RowTarget::Velocity>(a, b, c);
}
inline btScalar resolveRowSplitPenetration(btSolverBody& a, btSolverBody& b, const btSolverConstraint& c) {
    return resolveRow<false, RowTarget::Push>(a, b, c);
}

} // namespace afb::bullet::detail
