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
/// box–hull pairs, and in front of the box–box algorithm (the speculative one of BoxBoxCollision.h when
/// `speculativeBoxes`, Bullet's otherwise); off, restores Bullet's default from `config` for the first three and
/// leaves box–box as useSpeculativeBoxBoxContacts set it (call that first). The create functions are constant
/// process-lifetime objects: Bullet's algorithm comes from the configuration of the dispatcher creating the pair.
void useSeparatedPairSkip(btCollisionDispatcher& dispatcher, bool on, btCollisionConfiguration& config,
                          bool speculativeBoxes);

} // namespace afb::bullet::detail
