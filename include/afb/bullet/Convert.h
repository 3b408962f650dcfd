#pragma once
// Eigen (figure layer, double) to Bullet (btScalar: float or double, per the Bullet build linked).
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

} // namespace afb::bullet
