#pragma once
// Contacts between a polytope (convex hull or box) and a static plane from every vertex within the manifold's reach,
// instead of Bullet's single supporting vertex (plus perturbed copies of it). A tilted body then has contact
// points on the far side of its tipping edge before it rolls onto them, so a speculative contact can stop the
// roll (docs/methods.md, speculative contacts).
#include <btBulletCollisionCommon.h>

namespace afb::bullet::detail {

/// Installs the polytope–plane algorithm into a dispatcher (both orders), or restores Bullet's default from `config`.
/// The create functions are process-lifetime objects, so a dispatcher never holds a dangling one.
void useVertexHullPlaneContacts(btCollisionDispatcher& dispatcher, bool on, btCollisionConfiguration& config);

} // namespace afb::bullet::detail
