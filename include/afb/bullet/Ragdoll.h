#pragma once
// A live ragdoll: a RagdollAsset's bodies and constraints in the caller's btDynamicsWorld.
#include <memory>
#include <span>
#include <vector>

#include <btBulletDynamicsCommon.h>

#include "afb/bullet/RagdollAsset.h"
#include "afb/figure/Placement.h"

namespace afb::bullet {

/// Where and how a ragdoll enters a world.
struct SpawnOptions {
    /// Entity transform: model space (X forward, Y left, Z up, metres) to world.
    btTransform entityTransform = btTransform::getIdentity();
    /// Bullet collision group of every body (the caller's choice).
    int collisionGroup = btBroadphaseProxy::DefaultFilter;
    /// Bullet collision mask of every body; bodies attached to the world by a collision-disabling constraint
    /// also drop btBroadphaseProxy::StaticFilter (the engine lets them pass through world geometry, §6.2).
    int collisionMask = btBroadphaseProxy::AllFilter;
    /// Solver iterations for the figure's joints and limits (btTypedConstraint's per-constraint override), or 0
    /// for the world's count. Contacts keep the world's count. 20 holds loaded limits to within 1° at 60 Hz where
    /// the common 10 leaves 1–2° (measured in tests/bullet/test_constraints.cpp).
    int constraintIterations = 20;
    /// Spawn at rest until touched (entityDef `"nodrop" "1"`, or the seed page's `"sleep" "1"`).
    bool startAtRest = false;
    /// Apply the figure's rest rules (§6.1) and put it to sleep when they say so (the engine's comeToRest).
    /// Off: the ragdoll never rests by itself (putToRest still works).
    bool comeToRest = true;
    /// Continuous collision for bodies that move more than their inner radius in one step (Bullet's CCD).
    bool continuousCollision = true;
    /// The engine's contact friction (§4.8): min of the two bodies' values between ragdoll bodies, the ragdoll
    /// body's own value against anything else, instead of Bullet's product. Needs Bullet's one global contact
    /// callback: see installEngineContactFriction(); without it this flag has no effect.
    bool engineContactFriction = true;
};

/// Installs Bullet's global contact-added callback (gContactAddedCallback) with the engine's friction combination
/// for ragdoll bodies spawned with `engineContactFriction`; other objects are left as Bullet combines them.
/// Bullet has one such callback per process: returns false (and installs nothing) when another one is set.
/// Idempotent; call it once at start-up if you want the engine's contact friction.
bool installEngineContactFriction();

/// A figure's bodies and constraints added to a caller-owned world; the destructor removes them again. Shapes
/// are the asset's, shared with every other ragdoll of it. Not copyable; one world, one thread.
class Ragdoll {
  public:
    Ragdoll(std::shared_ptr<const RagdollAsset> asset, btDynamicsWorld& world, const SpawnOptions& options = {});
    ~Ragdoll();
    Ragdoll(const Ragdoll&) = delete;
    Ragdoll& operator=(const Ragdoll&) = delete;

    /// The built figure this ragdoll simulates.
    const figure::Figure& figure() const { return m_asset->figure(); }
    /// The shared asset.
    const std::shared_ptr<const RagdollAsset>& asset() const { return m_asset; }
    /// The world the ragdoll lives in.
    btDynamicsWorld& world() const { return m_world; }
    /// The entity transform it was spawned with (model space to world).
    const btTransform& spawnTransform() const { return m_spawn; }

    /// Number of rigid bodies (one per figure body, same order).
    int bodyCount() const { return static_cast<int>(m_bodies.size()); }
    /// Rigid body of figure body `i`; its transform is the body frame (centre of mass, principal axes).
    btRigidBody& body(int i) const { return *m_bodies[static_cast<std::size_t>(i)]; }
    /// The main Bullet constraint of figure constraint `i`.
    btTypedConstraint* constraint(int i) const { return m_main[static_cast<std::size_t>(i)]; }
    /// Every Bullet constraint the ragdoll added (main constraints, limits, friction, spring lengths).
    int bulletConstraintCount() const { return static_cast<int>(m_constraints.size()); }

    /// The constraint frame of figure constraint `i` as attached to body1 and to body2 (or the world), in world
    /// space now; at spawn the two coincide.
    std::pair<btTransform, btTransform> constraintFramesWorld(int i) const;

    /// World transforms of every body (body frames: centre of mass, principal axes), metres.
    std::vector<figure::Transform> bodyTransforms() const;
    /// Places every body (one state per body) and sets its velocities, e.g. from an animation
    /// (figure::bodiesFromJoints, figure::inheritVelocities); wakes the ragdoll.
    void setBodyStates(std::span<const figure::BodyState> states);

    /// Applies `impulse` (N·s, world) at `worldPoint` to the body containing md5 joint `joint` (containedJoints,
    /// §5.3) and wakes the ragdoll. As in the engine, an impulse below the wake threshold (500 engine units,
    /// 500·metresPerUnit N·s) or on a joint no body contains is ignored: returns false.
    bool applyImpulse(int joint, const btVector3& impulse, const btVector3& worldPoint);
    /// The wake threshold of applyImpulse, N·s.
    double impulseThresholdNs() const { return 500.0 * figure().units.metresPerUnit; }

    /// True while the figure is at rest by its own rules (§6.1); its bodies are then asleep in Bullet.
    bool atRest() const;
    /// Seconds simulated since the ragdoll last woke (the engine's activateTime).
    double activeSeconds() const;
    /// Puts the figure to rest now: zero velocities, bodies asleep.
    void putToRest();
    /// Wakes the figure and restarts its rest timers.
    void wake();

  private:
    class Action;
    void addBodies(const SpawnOptions& options);
    void addConstraints(int iterations);
    void filterPairs();
    btRigidBody& other(int body2) const;
    btTransform frameOfBody2(const figure::FigureConstraint& c) const;

    std::shared_ptr<const RagdollAsset> m_asset;
    btDynamicsWorld& m_world;
    btTransform m_spawn;
    std::vector<std::unique_ptr<btRigidBody>> m_bodies;
    std::vector<std::unique_ptr<btTypedConstraint>> m_constraints; ///< in the order added to the world
    std::vector<btTypedConstraint*> m_main;                       ///< per figure constraint
    std::vector<std::unique_ptr<btJointFeedback>> m_feedback;
    std::unique_ptr<Action> m_action;
};

} // namespace afb::bullet
