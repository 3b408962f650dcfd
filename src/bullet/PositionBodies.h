#pragma once
// The position pass's view of bodies (PositionPass.cpp, PositionTree.h): a working copy of each body's pose and
// inverse mass, moved by positional impulses and written back to Bullet once, at the end of the pass.
#include <utility>

#include <btBulletDynamicsCommon.h>

namespace afb::bullet::detail::position {

// Errors below these are left alone (and a sweep that finds none ends the pass): a tenth of a millimetre and
// a hundredth of a degree, well below what any metric reports, so a figure at rest or in free fall costs the
// pass almost nothing.
inline constexpr btScalar kAnchorToleranceM = btScalar(1e-4);
inline constexpr btScalar kAngleToleranceRad = btScalar(2e-4);

// One body as the pass sees it: immovable (world, static geometry, another figure's or a game's body) or a body
// of this ragdoll, whose pose the pass works on locally and writes back once, at the end of the pass. A keyframed
// body of this ragdoll (inverse mass 0) is immovable at its pose.
struct Side {
    btRigidBody* body = nullptr; ///< null: immovable
    bool placed = false;         ///< a body of this ragdoll, movable or not: its joints' frames move with x and q
    btVector3 x{0, 0, 0};        ///< centre of mass, world
    btQuaternion q = btQuaternion::getIdentity();
    btMatrix3x3 r = btMatrix3x3::getIdentity(); ///< rotation of q
    btVector3 invInertiaLocal{0, 0, 0};
    btScalar invMass = 0;
    btMatrix3x3 invInertia{0, 0, 0, 0, 0, 0, 0, 0, 0}; ///< world
    bool moved = false;
    unsigned version = 0;  ///< how many times the pass has moved it (a check it passed holds until this changes)
    btVector3 x0{0, 0, 0}; ///< the pose the pass started from
    btQuaternion q0 = btQuaternion::getIdentity();

    btTransform transform() const { return btTransform(r, x); }
    void updateRotation() {
        r.setRotation(q);
        invInertia = r.scaled(invInertiaLocal) * r.transpose();
    }
};

inline Side sideOf(btRigidBody* body) {
    Side s;
    if (body == nullptr) return s;
    s.placed = true;
    const btTransform& t = body->getCenterOfMassTransform();
    s.x = t.getOrigin();
    t.getBasis().getRotation(s.q);
    s.x0 = s.x;
    s.q0 = s.q;
    if (body->getInvMass() != 0) {
        s.body = body;
        s.invMass = body->getInvMass();
        s.invInertiaLocal = body->getInvInertiaDiagLocal();
    }
    s.updateRotation();
    return s;
}

// Scales a body's inverse mass and inertia (the pass's own copy; Bullet's body is untouched).
inline void scaleMass(Side& s, btScalar inverseFactor) {
    s.invMass *= inverseFactor;
    s.invInertiaLocal *= inverseFactor;
    s.updateRotation();
}

inline btMatrix3x3 skew(const btVector3& r) { return {0, -r.z(), r.y(), r.z(), 0, -r.x(), -r.y(), r.x(), 0}; }

// Moves a body by `dx` and turns it by the rotation vector `dtheta` (first order, renormalised).
inline void move(Side& s, const btVector3& dx, const btVector3& dtheta) {
    if (s.body == nullptr) return;
    s.x += dx;
    const btQuaternion dq(dtheta.x(), dtheta.y(), dtheta.z(), 0);
    s.q += (dq * s.q) * btScalar(0.5);
    s.q.normalize();
    s.updateRotation();
    s.moved = true;
    ++s.version;
}

// Inverse effective mass of a point fixed in a body at offset r: Δ(point) = K·P for an impulse P at the point.
inline btMatrix3x3 pointInvMass(const Side& s, const btVector3& r) {
    if (s.body == nullptr) return {0, 0, 0, 0, 0, 0, 0, 0, 0};
    const btMatrix3x3 rx = skew(r);
    return btMatrix3x3::getIdentity() * s.invMass - rx * s.invInertia * rx;
}

// Applies the positional impulse P at rA on A and −P at rB on B.
inline void applyLinear(Side& a, Side& b, const btVector3& p, const btVector3& ra, const btVector3& rb) {
    move(a, p * a.invMass, a.invInertia * ra.cross(p));
    move(b, -p * b.invMass, -(b.invInertia * rb.cross(p)));
}

// Applies the angular positional impulse L: A turns by IA⁻¹L, B by −IB⁻¹L.
inline void applyAngular(Side& a, Side& b, const btVector3& l) {
    move(a, btVector3(0, 0, 0), a.invInertia * l);
    move(b, btVector3(0, 0, 0), -(b.invInertia * l));
}

// Solves the 2×2 system [n1 n2]ᵀ K [n1 n2] λ = rhs and returns [n1 n2] λ (zero when singular).
inline btVector3 solveTwoRows(const btMatrix3x3& k, const btVector3& n1, const btVector3& n2, btScalar r1,
                              btScalar r2) {
    const btScalar k11 = n1.dot(k * n1), k12 = n1.dot(k * n2), k22 = n2.dot(k * n2);
    const btScalar det = k11 * k22 - k12 * k12;
    if (det <= SIMD_EPSILON * (k11 * k22 + SIMD_EPSILON)) return {0, 0, 0};
    const btScalar l1 = (k22 * r1 - k12 * r2) / det, l2 = (k11 * r2 - k12 * r1) / det;
    return n1 * l1 + n2 * l2;
}

// The rotation vector that turns unit `from` onto unit `to`.
inline btVector3 turnOnto(const btVector3& from, const btVector3& to) {
    const btVector3 c = from.cross(to);
    const btScalar s = c.length();
    if (s < SIMD_EPSILON) return {0, 0, 0};
    return c * (btAtan2(s, from.dot(to)) / s);
}

// A constraint's two frames in the world, from the pass's working poses.
struct Frames {
    btTransform a, b;
};
inline Frames framesOf(const Side& a, const Side& b, const std::pair<btTransform, btTransform>& local) {
    return {a.transform() * local.first, b.placed ? b.transform() * local.second : local.second};
}

} // namespace afb::bullet::detail::position
