#pragma once
// The marker by which the engine's contact friction callback recognises ragdoll bodies (internal).
#include <btBulletDynamicsCommon.h>

namespace afb::bullet {

/// btCollisionObject user index 2 of a ragdoll body that wants the engine's contact friction ("AFBF").
inline constexpr int kEngineFrictionMarker = 0x41464246;
/// The same for a body whose world keeps speculative contacts ("AFBS"): its contacts at a positive distance
/// get no restitution (they are not touching yet).
inline constexpr int kSpeculativeFrictionMarker = 0x41464253;

} // namespace afb::bullet
