// The position pass: per joint, limits first, then locked axes, then the anchor (so a sweep ends with the
// anchors closed), then the contacts. Each projection moves the two bodies by the mass-weighted split of the
// correction (the effective mass of the constraint's rows, as a velocity row would use it), so the centre of
// mass and the momentum of an isolated pair are unchanged. References: Müller et al., "Position Based
// Dynamics" (2007) and Jolt's position steps for the nonlinear Gauss–Seidel scheme; Cline & Pai,
// "Post-Stabilization for Rigid Body Simulation with Contact and Constraints" (2003) for leaving velocities be.
#include "PositionPass.h"

#include <algorithm>

#include "afb/bullet/Constraints.h"
#include "afb/bullet/Convert.h"
#include "afb/bullet/Ragdoll.h"

namespace afb::bullet::detail {
namespace {

// Contacts: correct only what is deeper than the slop, and that a fraction at a time, so that resting contacts
// are not pushed apart and re-made every substep (which would feed jitter into the velocity solve).
constexpr btScalar kContactSlopM = btScalar(0.002);
constexpr btScalar kContactFraction = btScalar(0.5);

// One body as the pass sees it: immovable (world, static geometry, a game's own body) or a ragdoll body.
struct Side {
    btRigidBody* body = nullptr;
    btScalar invMass = 0;
    btMatrix3x3 invInertia{0, 0, 0, 0, 0, 0, 0, 0, 0};
};

Side sideOf(btRigidBody* body) {
    Side s;
    if (body == nullptr || body->getInvMass() == 0) return s;
    s.body = body;
    s.invMass = body->getInvMass();
    s.invInertia = body->getInvInertiaTensorWorld();
    return s;
}

btMatrix3x3 skew(const btVector3& r) { return {0, -r.z(), r.y(), r.z(), 0, -r.x(), -r.y(), r.x(), 0}; }

// Moves a body by `dx` and turns it by the rotation vector `dtheta` (first order, renormalised).
void move(Side& s, const btVector3& dx, const btVector3& dtheta) {
    if (s.body == nullptr) return;
    btTransform t = s.body->getCenterOfMassTransform();
    t.getOrigin() += dx;
    btQuaternion q = t.getRotation();
    const btQuaternion dq(dtheta.x(), dtheta.y(), dtheta.z(), 0);
    q += (dq * q) * btScalar(0.5);
    q.normalize();
    t.setRotation(q);
    s.body->setCenterOfMassTransform(t); // also updates the world inverse inertia
    s.invInertia = s.body->getInvInertiaTensorWorld();
}

// Inverse effective mass of a point fixed in a body at offset r: Δ(point) = K·P for an impulse P at the point.
btMatrix3x3 pointInvMass(const Side& s, const btVector3& r) {
    const btMatrix3x3 rx = skew(r);
    return btMatrix3x3::getIdentity() * s.invMass - rx * s.invInertia * rx;
}

// Applies the positional impulse P at rA on A and −P at rB on B.
void applyLinear(Side& a, Side& b, const btVector3& p, const btVector3& ra, const btVector3& rb) {
    move(a, p * a.invMass, a.invInertia * ra.cross(p));
    move(b, -p * b.invMass, -(b.invInertia * rb.cross(p)));
}

// Applies the angular positional impulse L: A turns by IA⁻¹L, B by −IB⁻¹L.
void applyAngular(Side& a, Side& b, const btVector3& l) {
    move(a, btVector3(0, 0, 0), a.invInertia * l);
    move(b, btVector3(0, 0, 0), -(b.invInertia * l));
}

// Solves the 2×2 system [n1 n2]ᵀ K [n1 n2] λ = rhs and returns [n1 n2] λ (zero when singular).
btVector3 solveTwoRows(const btMatrix3x3& k, const btVector3& n1, const btVector3& n2, btScalar r1, btScalar r2) {
    const btScalar k11 = n1.dot(k * n1), k12 = n1.dot(k * n2), k22 = n2.dot(k * n2);
    const btScalar det = k11 * k22 - k12 * k12;
    if (det <= SIMD_EPSILON * (k11 * k22 + SIMD_EPSILON)) return {0, 0, 0};
    const btScalar l1 = (k22 * r1 - k12 * r2) / det, l2 = (k11 * r2 - k12 * r1) / det;
    return n1 * l1 + n2 * l2;
}

// The rotation vector that turns unit `from` onto unit `to`.
btVector3 turnOnto(const btVector3& from, const btVector3& to) {
    const btVector3 c = from.cross(to);
    const btScalar s = c.length();
    if (s < SIMD_EPSILON) return {0, 0, 0};
    return c * (btAtan2(s, from.dot(to)) / s);
}

// Anchor: the two anchor copies meet (sliders: only across the axis).
void projectAnchor(Side& a, Side& b, const btTransform& fa, const btTransform& fb, bool slider) {
    const btVector3 ra = fa.getOrigin() - (a.body ? a.body->getCenterOfMassPosition() : fa.getOrigin());
    const btVector3 rb = fb.getOrigin() - (b.body ? b.body->getCenterOfMassPosition() : fb.getOrigin());
    const btVector3 c = fb.getOrigin() - fa.getOrigin();
    const btMatrix3x3 k = pointInvMass(a, ra) + pointInvMass(b, rb);
    btVector3 p;
    if (slider) {
        const btVector3 axis = fb.getBasis().getColumn(0);
        btVector3 n1, n2;
        btPlaneSpace1(axis, n1, n2);
        p = solveTwoRows(k, n1, n2, c.dot(n1), c.dot(n2));
    } else {
        if (btFabs(k.determinant()) < SIMD_EPSILON) return;
        p = k.inverse() * c;
    }
    applyLinear(a, b, p, ra, rb);
}

// Full orientation lock (fixed, slider): frame A's rotation onto frame B's.
void projectOrientation(Side& a, Side& b, const btMatrix3x3& frameA, const btMatrix3x3& frameB) {
    btQuaternion q;
    (frameB * frameA.transpose()).getRotation(q);
    if (q.w() < 0) q = -q;
    const btScalar angle = q.getAngle();
    if (angle < SIMD_EPSILON) return;
    const btVector3 delta = q.getAxis() * angle;
    const btMatrix3x3 k = a.invInertia + b.invInertia;
    if (btFabs(k.determinant()) < SIMD_EPSILON) return;
    applyAngular(a, b, k.inverse() * delta);
}

// Hinge axes: frame A's Z onto frame B's Z, leaving the rotation about the axis free.
void projectHingeAxis(Side& a, Side& b, const btMatrix3x3& frameA, const btMatrix3x3& frameB) {
    const btVector3 za = frameA.getColumn(2), zb = frameB.getColumn(2);
    const btVector3 delta = turnOnto(za, zb);
    if (delta.isZero()) return;
    btVector3 n1, n2;
    btPlaneSpace1(zb, n1, n2);
    applyAngular(a, b, solveTwoRows(a.invInertia + b.invInertia, n1, n2, delta.dot(n1), delta.dot(n2)));
}

// One limit row past its limit: turn the bodies back by the excess.
void projectLimitRow(Side& a, Side& b, const LimitRow& row) {
    if (row.excess <= 0) return;
    const btScalar w = row.axisWorld.dot((a.invInertia + b.invInertia) * row.axisWorld);
    if (w < SIMD_EPSILON) return;
    applyAngular(a, b, row.axisWorld * (-row.excess / w));
}

void projectLimit(Side& a, Side& b, const figure::FigureConstraint& c, const btTransform& fa, const btTransform& fb,
                  const btMatrix3x3& body2Basis) {
    LimitRow rows[2];
    int n = 0;
    const btMatrix3x3 body1Basis = a.body ? a.body->getCenterOfMassTransform().getBasis() : btMatrix3x3::getIdentity();
    if (const auto* h = std::get_if<figure::HingeRange>(&c.limit)) {
        n = hingeRangeRow(fa.getBasis(), fb.getBasis(), static_cast<btScalar>(h->lowerRad),
                          static_cast<btScalar>(h->upperRad), 0, rows[0]);
    } else if (const auto* cone = std::get_if<figure::ConeLimit>(&c.limit)) {
        btVector3 y, z;
        const btVector3 axis = (body2Basis * toBt(cone->axisInBody2)).normalized();
        btPlaneSpace1(axis, y, z);
        btMatrix3x3 basis;
        basis.setValue(axis.x(), y.x(), z.x(), axis.y(), y.y(), z.y(), axis.z(), y.z(), z.z());
        n = directionLimitRows(body1Basis * toBt(cone->shaftInBody1), basis, LimitShape::Cone,
                               static_cast<btScalar>(cone->halfAngleRad), 0, 0, rows);
    } else if (const auto* p = std::get_if<figure::PyramidLimit>(&c.limit)) {
        n = directionLimitRows(body1Basis * toBt(p->shaftInBody1), body2Basis * toBt(p->basisInBody2),
                               LimitShape::Pyramid, static_cast<btScalar>(p->halfAngle1Rad),
                               static_cast<btScalar>(p->halfAngle2Rad), 0, rows);
    }
    for (int i = 0; i < n; ++i) projectLimitRow(a, b, rows[i]);
}

void projectContact(Side& a, Side& b, const btManifoldPoint& cp) {
    const btTransform ta = a.body ? a.body->getCenterOfMassTransform() : btTransform::getIdentity();
    const btTransform tb = b.body ? b.body->getCenterOfMassTransform() : btTransform::getIdentity();
    // Immovable sides keep the world points Bullet found; movable ones carry theirs along.
    const btVector3 pa = a.body ? a.body->getWorldTransform() * cp.m_localPointA : cp.m_positionWorldOnA;
    const btVector3 pb = b.body ? b.body->getWorldTransform() * cp.m_localPointB : cp.m_positionWorldOnB;
    const btVector3& n = cp.m_normalWorldOnB;
    const btScalar depth = -(pa - pb).dot(n) - kContactSlopM;
    if (depth <= 0) return;
    const btVector3 ra = pa - ta.getOrigin(), rb = pb - tb.getOrigin();
    const btVector3 ran = ra.cross(n), rbn = rb.cross(n);
    const btScalar w = a.invMass + b.invMass + ran.dot(a.invInertia * ran) + rbn.dot(b.invInertia * rbn);
    if (w < SIMD_EPSILON) return;
    applyLinear(a, b, n * (kContactFraction * depth / w), ra, rb);
}

} // namespace

void positionSweep(Ragdoll& r, std::span<btPersistentManifold* const> manifolds, const MovableTest& movable) {
    const figure::Figure& f = r.figure();
    for (int i = 0; i < static_cast<int>(f.constraints.size()); ++i) {
        const figure::FigureConstraint& c = f.constraints[static_cast<std::size_t>(i)];
        if (c.type == figure::JointType::Spring) continue;
        Side a = sideOf(&r.body(c.body1));
        Side b = c.body2 >= 0 ? sideOf(&r.body(c.body2)) : Side{};
        if (a.body == nullptr && b.body == nullptr) continue;
        auto frames = [&] { return r.constraintFramesWorld(i); };
        const btMatrix3x3 body2Basis =
            c.body2 >= 0 ? r.body(c.body2).getCenterOfMassTransform().getBasis() : r.spawnTransform().getBasis();
        if (!std::holds_alternative<std::monostate>(c.limit)) {
            const auto [fa, fb] = frames();
            projectLimit(a, b, c, fa, fb, body2Basis);
        }
        if (c.type == figure::JointType::Fixed || c.type == figure::JointType::Slider) {
            const auto [fa, fb] = frames();
            projectOrientation(a, b, fa.getBasis(), fb.getBasis());
        } else if (c.type == figure::JointType::Hinge) {
            const auto [fa, fb] = frames();
            projectHingeAxis(a, b, fa.getBasis(), fb.getBasis());
        }
        const auto [fa, fb] = frames();
        projectAnchor(a, b, fa, fb, c.type == figure::JointType::Slider);
    }
    for (btPersistentManifold* m : manifolds) {
        auto* oa = const_cast<btCollisionObject*>(m->getBody0());
        auto* ob = const_cast<btCollisionObject*>(m->getBody1());
        Side a = movable.movable(oa) ? sideOf(btRigidBody::upcast(oa)) : Side{};
        Side b = movable.movable(ob) ? sideOf(btRigidBody::upcast(ob)) : Side{};
        if (a.body == nullptr && b.body == nullptr) continue;
        for (int k = 0; k < m->getNumContacts(); ++k) projectContact(a, b, m->getContactPoint(k));
    }
}

} // namespace afb::bullet::detail
