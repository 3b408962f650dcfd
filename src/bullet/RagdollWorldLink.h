#pragma once
// What a Ragdoll and the RagdollWorld that spawned it may reach of each other's private state, and nothing more.
// Neither class befriends the other; both befriend this one, whose static members forward to the few private
// members the other side needs:
//   the ragdoll tells its world that it leaves (its destructor), that its explosion guard restored it, that a level
//   of detail replaces its Bullet objects, and that a collision object of its (a sunk ragdoll's box) is destroyed;
//   the world makes a ragdoll its member (RagdollWorld::spawn), runs sinking (the calm-substep count, sink(),
//   and which box stands for a sunk ragdoll) and moves its keyframed bodies (before a step and after each substep).
#include "afb/bullet/Ragdoll.h"
#include "afb/bullet/RagdollWorld.h"

namespace afb::bullet::detail {

class RagdollWorldLink {
  public:
    // Ragdoll → its world.

    /// The ragdoll is being destroyed: the world forgets it.
    static void detach(RagdollWorld& world, Ragdoll& ragdoll) { world.detach(ragdoll); }
    /// The ragdoll's explosion guard restored it: its warm-started joint impulses are stale.
    static void restartWarmStarting(RagdollWorld& world, Ragdoll& ragdoll) { world.restartWarmStarting(ragdoll); }
    /// The ragdoll is about to replace its Bullet bodies and constraints (Ragdoll::setLod).
    static void detachBodies(RagdollWorld& world, Ragdoll& ragdoll) { world.detachBodies(ragdoll); }
    /// The ragdoll has replaced them.
    static void attachBodies(RagdollWorld& world, Ragdoll& ragdoll) { world.attachBodies(ragdoll); }
    /// A collision object of the ragdoll's left the world and is being destroyed.
    static void forget(RagdollWorld& world, const btCollisionObject* object) { world.forget(object); }

    // The world → a ragdoll it spawned.

    /// Makes `ragdoll` (just constructed in `world`'s Bullet world) a member of `world`.
    static void join(Ragdoll& ragdoll, RagdollWorld& world) { ragdoll.m_manager = &world; }
    /// Substeps in a row the frozen ragdoll had nothing active near it.
    static int& calmSubsteps(Ragdoll& ragdoll) { return ragdoll.m_calmSubsteps; }
    /// Takes the frozen ragdoll out of the world behind one box (Ragdoll::sunk).
    static void sink(Ragdoll& ragdoll) { ragdoll.sink(); }
    /// The box that stands for the ragdoll while it is sunk, or null.
    static const btCollisionObject* sunkBox(const Ragdoll& ragdoll) { return ragdoll.m_restProxy.get(); }
    /// A step of `seconds` begins: the keyframed bodies take the velocity that reaches their targets by its end.
    static void beginKeyframeStep(Ragdoll& ragdoll, double seconds) { ragdoll.beginKeyframeStep(seconds); }
    /// A step begins: the motors take the inertia each joint carries in the pose the step starts from.
    static void beginMotorStep(Ragdoll& ragdoll) { ragdoll.beginMotorStep(); }
    /// A substep of `dt` integrated the simulated bodies: the keyframed ones move too.
    static void advanceKeyframes(Ragdoll& ragdoll, btScalar dt) { ragdoll.advanceKeyframes(dt); }
};

} // namespace afb::bullet::detail
