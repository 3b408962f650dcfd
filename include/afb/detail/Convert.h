#pragma once
// Eigen (figure layer, double) to Bullet (btScalar: float or double, per the Bullet build linked), and the two
// rotations the Bullet builders (bullet::Ragdoll, sim::RawRagdoll) set up constraint frames with.
#include <btBulletDynamicsCommon.h>

#include "afb/figure/Transform.h"

namespace afb::bullet {

inline btVector3 toBt(const Eigen::Vector3d& v) {
    return {static_cast<btScalar>(v.x()), static_cast<btScalar>(v.y()), static_cast<btScalar>(v.z())};
}
inline btMatrix3x3 toBt(const Eigen::Matrix3d& m) {
    return {static_cast<btScalar>(m(0, 0)), static_cast<btScalar>(m(0, 1)), static_cast<btScalar>(m(0, 2)),
            static_cast<btScalar>(m(1, 0)), static_cast<btScalar>(m(1, 1)), static_cast<btScalar>(m(1, 2)),
            static_cast<btScalar>(m(2, 0)), static_cast<btScalar>(m(2, 1)), static_cast<btScalar>(m(2, 2))};
}
inline btTransform toBt(const figure::Transform& t) { return btTransform(toBt(t.rotation), toBt(t.position)); }

inline Eigen::Vector3d toEigen(const btVector3& v) { return {v.x(), v.y(), v.z()}; }
inline Eigen::Matrix3d toEigen(const btMatrix3x3& m) {
    Eigen::Matrix3d r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r(i, j) = m[i][j];
    return r;
}
inline figure::Transform toEigen(const btTransform& t) { return {toEigen(t.getBasis()), toEigen(t.getOrigin())}; }

/// The rotation taking unit vector `from` to unit vector `to` along the shortest arc.
inline btMatrix3x3 shortestArc(btVector3 from, btVector3 to) {
    return btMatrix3x3(shortestArcQuatNormalize2(from, to));
}

/// A rotation whose first column is `x` (unit); the other two columns are Bullet's btPlaneSpace1 of it.
inline btMatrix3x3 basisWithX(const btVector3& x) {
    btVector3 y, z;
    btPlaneSpace1(x, y, z);
    btMatrix3x3 m;
    m.setValue(x.x(), y.x(), z.x(), x.y(), y.y(), z.y(), x.z(), y.z(), z.z());
    return m;
}

} // namespace afb::bullet
