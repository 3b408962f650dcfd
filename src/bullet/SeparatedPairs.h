#pragma once
// Convex pairs that are plainly apart skip the narrow phase. Bullet runs GJK on every pair whose bounding boxes
// overlap, every step, although most such pairs of a ragdoll (thigh beside thigh, arm beside chest) stay
// centimetres apart for seconds. This algorithm first tries one separating axis, the line between the two
// bodies' centres: when the gap along it, measured from the shapes' support points (margins included), is wider
// than the farthest a contact could be reported at, Bullet's algorithm would add no point, so it is not run. The
// result is the same contacts, bit for bit; otherwise Bullet's convex–convex algorithm runs as before
// (docs/performance.md, separated pairs).
#include <btBulletCollisionCommon.h>

namespace afb::bullet::detail {

/// Installs the separating-axis test in front of Bullet's convex–convex algorithm for hull–hull, hull–box and
/// box–hull pairs, or restores Bullet's default from `config`. The create function is a stateless process-lifetime
/// object: Bullet's algorithm behind it comes from the configuration of the dispatcher that creates the pair.
void useSeparatedPairSkip(btCollisionDispatcher& dispatcher, bool on, btCollisionConfiguration& config);

} // namespace afb::bullet::detail
