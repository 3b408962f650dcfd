#pragma once
// Conversions between the library's value types (Eigen, double: figure::Transform, figure::BodyState) and Bullet's
// (btScalar: float or double, per the Bullet build linked), for code that passes one to the other.
#include <btBulletDynamicsCommon.h>

#include "afb/figure/Transform.h"

namespace afb::bullet {

/// A vector in Bullet's precision (rounded to float for float Bullet).
inline btVector3 toBt(const Eigen::Vector3d& v) {
    return {static_cast<btScalar>(v.x()), static_cast<btScalar>(v.y()), static_cast<btScalar>(v.z())};
}
/// A 3×3 matrix (a rotation, say) in Bullet's precision.
inline btMatrix3x3 toBt(const Eigen::Matrix3d& m) {
    return {static_cast<btScalar>(m(0, 0)), static_cast<btScalar>(m(0, 1)), static_cast<btScalar>(m(0, 2)),
            static_cast<btScalar>(m(1, 0)), static_cast<btScalar>(m(1, 1)), static_cast<btScalar>(m(1, 2)),
            static_cast<btScalar>(m(2, 0)), static_cast<btScalar>(m(2, 1)), static_cast<btScalar>(m(2, 2))};
}
/// A rigid transform (rotation and position, metres) as a btTransform.
inline btTransform toBt(const figure::Transform& t) { return btTransform(toBt(t.rotation), toBt(t.position)); }

/// A Bullet vector in double precision (exact).
inline Eigen::Vector3d toEigen(const btVector3& v) { return {v.x(), v.y(), v.z()}; }
/// A Bullet matrix in double precision (exact).
inline Eigen::Matrix3d toEigen(const btMatrix3x3& m) {
    Eigen::Matrix3d r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r(i, j) = m[i][j];
    return r;
}
/// A btTransform as the library's rigid transform (exact).
inline figure::Transform toEigen(const btTransform& t) { return {toEigen(t.getBasis()), toEigen(t.getOrigin())}; }

} // namespace afb::bullet
