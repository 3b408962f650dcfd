#pragma once
// The conversions of afb/bullet/Convert.h, and the two rotations the Bullet builders (bullet::Ragdoll,
// sim::RawRagdoll) set up constraint frames with.
#include <btBulletDynamicsCommon.h>

#include "afb/bullet/Convert.h"

namespace afb::bullet {

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
