#pragma once
// Plain Bullet's version of a figure, the reference every chart shows (`afb chart`, docs/methods.md): the same
// bodies as bullet::Ragdoll, joined by Bullet's own constraints as a plain Bullet user would join them, with none
// of afbullet's policies. Built from the same figure::Figure and RagdollAsset; measured through the same probes
// (detail/Probes.h), so a drop reports it exactly as it reports the adapter. Tools library only: the economy
// benchmark and the stress matrix use it too.
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <btBulletDynamicsCommon.h>

#include "afb/bullet/Method.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/bullet/RagdollAsset.h"
#include "afb/detail/Probes.h"

namespace afb::sim {

/// The name of the plain-Bullet reference method ("raw"): a drop or a chart with a method of this name builds
/// RawRagdolls instead of bullet::Ragdolls.
inline constexpr std::string_view kRawMethodName = "raw";

/// The raw method: Bullet's own world defaults as knobs (10 iterations, one step per frame, split impulse, ERP
/// 0.2, warm starting 0.85, one contact point per plane touch), no per-joint iterations, Bullet's default limit
/// bias 0.3, no continuous collision, and none of afbullet's techniques (position pass, speculative contacts and
/// limits). Its Bullet knobs may be varied like any method's ("raw with 4 substeps"); its afbullet-only knobs
/// must stay off (rawMethodError).
bullet::Method rawMethod();
/// True when `method` selects the plain-Bullet reference (its name is kRawMethodName).
bool isRaw(const bullet::Method& method);
/// An error message when `method` is raw but asks for a technique plain Bullet does not have (position
/// iterations, speculative contacts or limits); empty otherwise.
std::string rawMethodError(const bullet::Method& method);
/// Every method name a tool accepts: the presets (bullet::methodPresetNames) and "raw".
std::vector<std::string_view> methodNames();
/// The preset or raw method called `name`, or nullopt.
std::optional<bullet::Method> methodByName(std::string_view name);

/// A figure in a caller's world as plain Bullet builds it:
///  - bodies: one btRigidBody per figure body with the asset's shapes and the figure's mass, principal inertia,
///    body frame, contact friction, restitution and damping, and the same collision filtering (groups, masks,
///    the figure's self-collision pairs; jointed bodies never collide) — identical to bullet::Ragdoll's;
///  - constraints (docs/format.md §4 as a plain Bullet user maps it): fixed → btFixedConstraint; ball-and-socket →
///    btPoint2PointConstraint, or with a limit btConeTwistConstraint with free twist (a cone: both swing spans
///    the half angle; a pyramid: an elliptical cone with the two half angles as spans, its corners cut);
///    universal → btConeTwistConstraint with twist locked, its swing cone the limit's (frame B's X is the cone
///    axis or the pyramid's f, frame A's X the shaft, so twist is locked about the limit's axis rather than the
///    shafts) or free (±π) without a limit; hinge → btHingeConstraint with its range as btHinge's own limit;
///    slider → btSliderConstraint; spring → nothing (Bullet has no spring between two anchors);
///  - policies: the method's jointIterations as Bullet's per-constraint override (raw: none), its limitErp as the
///    limits' bias factor (raw: Bullet's 0.3), its CCD policy (raw: off); no joint friction (docs/format.md §4.8),
///    Bullet's product rule for contact friction, and Bullet's own deactivation (default thresholds) instead of the
///    figure's rest rules. Nothing runs on its bodies but Bullet.
/// atRest() is the figure's own rest rules (docs/format.md §6.1) applied as a measurement only, so that settle times
/// compare. Not copyable; one world, one thread.
class RawRagdoll {
  public:
    /// Spawns into `world` (a plain world, or a sim::Scene's): `options.entityTransform`, collision group and
    /// mask, `method` (as above), `startAtRest` (bodies asleep until touched), `comeToRest` (off: Bullet never
    /// deactivates the bodies and atRest() stays false). engineContactFriction is ignored.
    RawRagdoll(std::shared_ptr<const bullet::RagdollAsset> asset, btDynamicsWorld& world,
               const bullet::SpawnOptions& options = {});
    ~RawRagdoll();
    RawRagdoll(const RawRagdoll&) = delete;
    RawRagdoll& operator=(const RawRagdoll&) = delete;

    const figure::Figure& figure() const { return m_asset->figure(); }
    const std::shared_ptr<const bullet::RagdollAsset>& asset() const { return m_asset; }
    const btTransform& spawnTransform() const { return m_spawn; }

    /// Number of rigid bodies (one per figure body, same order).
    int bodyCount() const { return static_cast<int>(m_bodies.size()); }
    /// Rigid body of figure body `i`; its transform is the body frame (centre of mass, principal axes).
    btRigidBody& body(int i) { return *m_bodies[static_cast<std::size_t>(i)]; }
    const btRigidBody& body(int i) const { return *m_bodies[static_cast<std::size_t>(i)]; }
    /// The collision object of body `i` (as bullet::Ragdoll::collisionObject).
    const btCollisionObject& collisionObject(int i) const { return body(i); }
    /// The Bullet constraint of figure constraint `i`, or nullptr for a spring.
    const btTypedConstraint* constraint(int i) const { return m_main[static_cast<std::size_t>(i)]; }

    /// The constraint frame of figure constraint `i` as attached to body1 and to body2 (or the world), world
    /// space now (the figure's frames, as bullet::Ragdoll::constraintFramesWorld).
    std::pair<btTransform, btTransform> constraintFramesWorld(int i) const;
    /// How far figure constraint `i` is from holding now (bullet::jointErrorOf, as bullet::Ragdoll reports it).
    bullet::JointError jointError(int i) const;

    /// World transforms of every body (body frames), metres.
    std::vector<figure::Transform> bodyTransforms() const;
    /// World transforms and velocities of every body.
    std::vector<figure::BodyState> bodyStates() const;
    /// Sets every body's velocities (one per body, in body order) and activates the bodies; false and nothing
    /// changed when the count is not bodyCount() (as bullet::Ragdoll::setBodyVelocities).
    [[nodiscard]] bool setBodyVelocities(std::span<const bullet::BodyVelocity> velocities);
    /// Applies `impulse` (N·s, world) at `worldPoint` to body `body` and activates it; with ImpulseRule::Always
    /// whatever its size, else only at or above bullet::Ragdoll's wake threshold. False for a body out of range.
    bool applyBodyImpulse(int body, const btVector3& impulse, const btVector3& worldPoint,
                          bullet::ImpulseRule rule = bullet::ImpulseRule::EngineThreshold);
    /// Bodies Bullet is simulating now (not deactivated).
    int awakeBodyCount() const;
    /// True once the figure's rest rules (docs/format.md §6.1) have said the figure is at rest (latched: plain Bullet
    /// does not act on it). Always false when spawned with comeToRest off.
    bool atRest() const;

  private:
    class Observer;
    void addBodies(const bullet::SpawnOptions& options, const bullet::Method& method);
    void addConstraints(const bullet::Method& method);
    void filterPairs();

    std::shared_ptr<const bullet::RagdollAsset> m_asset;
    btDynamicsWorld& m_world;
    btTransform m_spawn;
    std::vector<std::unique_ptr<btRigidBody>> m_bodies;
    std::vector<btRigidBody*> m_bodyList; ///< m_bodies as the probes take them (bullet::BodyList)
    std::vector<std::unique_ptr<btTypedConstraint>> m_constraints; ///< in the order added to the world
    std::vector<btTypedConstraint*> m_main;                        ///< per figure constraint (nullptr: spring)
    std::vector<std::pair<btTransform, btTransform>> m_frames;     ///< per figure constraint: in body1, in body2
    std::unique_ptr<Observer> m_observer;
};

} // namespace afb::sim
