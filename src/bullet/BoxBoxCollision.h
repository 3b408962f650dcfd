#pragma once
// Box–box contacts that keep speculative points. Bullet's box–box algorithm (btBoxBoxDetector) reports contacts
// only while the boxes overlap: it ignores the manifold's contact breaking threshold, so two boxes approaching
// each other never get the speculative contact that stops a hull before it touches (RagdollWorld widens every
// ragdoll manifold's threshold to the distance its bodies can close in a substep). This algorithm runs Bullet's
// detector while the boxes overlap (its up-to-four clipped points, as before) and, while they are apart, adds
// GJK's closest points within the manifold's reach, as Bullet's convex–convex algorithm does for hulls
// (docs/methods.md, speculative contacts).
#include <btBulletCollisionCommon.h>

namespace afb::bullet::detail {

/// Installs the box–box algorithm into a dispatcher, or restores Bullet's default from `config`. The create
/// function is a process-lifetime object, so a dispatcher never holds a dangling one.
void useSpeculativeBoxBoxContacts(btCollisionDispatcher& dispatcher, bool on, btCollisionConfiguration& config);
/// The box–box algorithm's create function (a process-lifetime object).
btCollisionAlgorithmCreateFunc& speculativeBoxBoxCreateFunc();

} // namespace afb::bullet::detail
