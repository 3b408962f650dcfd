#pragma once
// A live ragdoll: a RagdollAsset's bodies and constraints in the caller's btDynamicsWorld.
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <btBulletDynamicsCommon.h>

#include "afb/bullet/Method.h"
#include "afb/bullet/Motor.h"
#include "afb/bullet/RagdollAsset.h"
#include "afb/detail/Probes.h"
#include "afb/figure/Load.h"
#include "afb/figure/Placement.h"

namespace afb::bullet {

class RagdollWorld;
namespace detail {
class CarriedInertia;
class MultibodyRagdoll;
class ObjectArena;
class RagdollWorldLink;
} // namespace detail

/// Restitution of every AF body (docs/format.md §3.4: the engine's fixed value; it applies it above 2 units/s only).
inline constexpr double kBodyRestitution = 0.4;

class Ragdoll;
class JointMotorConstraint;
struct JointParts;

/// What the rows of one of a ragdoll's Bullet constraints do (Ragdoll::bulletConstraintRole).
enum class RowRole {
    Joint,    ///< keep the joint together: anchors and locked axes (equalities)
    Limit,    ///< a limit of its own: cone, pyramid or hinge range (one-sided)
    Friction, ///< joint friction, bounded by the joint's reaction (docs/format.md §4.8)
    Spring,   ///< a spring's length (docs/format.md §4.7)
    Motor,    ///< a joint motor toward a target pose (Ragdoll::setMotorGains; soft rows)
};

/// What tripped a ragdoll's explosion guard.
struct GuardTrip {
    /// The bound that was crossed.
    enum class Cause {
        NonFinite,   ///< a body's pose or velocity became NaN or infinite
        Speed,       ///< a body moved faster than ExplosionGuard::maxSpeedMps
        AnchorError, ///< a constraint's anchors came further apart than ExplosionGuard::maxAnchorErrorM
    };
    Cause cause = Cause::NonFinite; ///< the bound that was crossed
    int body = -1;                  ///< the body (Speed, NonFinite), or −1
    int constraint = -1;            ///< the figure constraint (AnchorError), or −1
    double value = 0;               ///< the speed (m/s) or the anchor error (m) that tripped it; 0 for NonFinite
    double activeSeconds = 0;       ///< Ragdoll::activeSeconds() when it tripped
};
/// "non-finite", "speed", "anchor-error".
std::string_view toString(GuardTrip::Cause cause);

/// The explosion guard: after every substep, a ragdoll whose state is non-finite or beyond these bounds is put back
/// to its state after the last good substep and frozen (zero velocities, asleep, at rest until touched or woken;
/// its contacts and warm-started impulses dropped), so a NaN never reaches the solver again and never another
/// body of the world. Costs a pass over the bodies per substep (docs/stability.md).
struct ExplosionGuard {
    bool enabled = true;        ///< run the guard after every substep (and in checkGuard)
    double maxSpeedMps = 100.0; ///< a body faster than this trips the guard (≤ 0: speed not checked)
    /// A constraint whose anchors are further apart than this trips it (≤ 0: not checked). A metre is a joint
    /// torn open beyond any doubt; ragdolls recover from gaps of decimetres.
    double maxAnchorErrorM = 1.0;
    /// Called after the ragdoll was restored and frozen (from inside the world's step or RagdollWorld::step: do not
    /// remove the ragdoll here; note it and remove it after the step).
    std::function<void(Ragdoll&, const GuardTrip&)> onTrip;
};

/// Velocity clamps (opt-in): after every substep, a body's linear and angular speeds are scaled down to these
/// bounds (0: no bound). A clamp caps what one bad solve can throw a body to; it also caps honest motion, so set it
/// above anything the game needs (docs/stability.md).
struct VelocityClamp {
    double maxLinearMps = 0;    ///< largest speed of a body's centre of mass, m/s (0: no bound)
    double maxAngularRadps = 0; ///< largest spin of a body, rad/s (0: no bound)
};

/// A body's velocities: of its centre of mass (m/s) and its spin (rad/s), world.
struct BodyVelocity {
    btVector3 linearMps{0, 0, 0};    ///< velocity of the centre of mass, m/s, world
    btVector3 angularRadps{0, 0, 0}; ///< angular velocity, rad/s, world
};

/// How a figure body moves (Ragdoll::setBodyMode; docs/motors.md, "Keyframed bodies and partial ragdolls").
enum class BodyMode {
    Simulated, ///< moved by the solver, limp or powered by its joints' motors (the default)
    Keyframed, ///< follows the game's targets (Ragdoll::setKeyframeTargets); pushes, is never pushed back
};

/// Which impulses Ragdoll::applyBodyImpulse applies.
enum class ImpulseRule {
    EngineThreshold, ///< as the engine: below the wake threshold (Ragdoll::impulseThresholdNs) nothing happens
    Always,          ///< every impulse, however small
};

/// Where and how a ragdoll enters a world.
struct SpawnOptions {
    /// Entity transform: model space (X forward, Y left, Z up, metres) to world.
    btTransform entityTransform = btTransform::getIdentity();
    /// Bullet collision group of every body (the caller's choice).
    int collisionGroup = btBroadphaseProxy::DefaultFilter;
    /// Bullet collision mask of every body; bodies attached to the world by a collision-disabling constraint
    /// also drop btBroadphaseProxy::StaticFilter (the engine lets them pass through world geometry; docs/format.md
    /// §6.2).
    int collisionMask = btBroadphaseProxy::AllFilter;
    /// How the ragdoll is simulated. Its per-ragdoll knobs (joint iterations, limit rows, continuous collision)
    /// apply here; its world-level knobs (substeps, solver, position pass) are the world's: see RagdollWorld.
    Method method = {};
    /// Spawn at rest until touched (entityDef `"nodrop" "1"`, or the id modding page's `"sleep" "1"`).
    bool startAtRest = false;
    /// Apply the figure's rest rules (docs/format.md §6.1) and put it to sleep when they say so (the engine's
    /// comeToRest). Off: the ragdoll never rests by itself (putToRest still works).
    bool comeToRest = true;
    /// The engine's contact friction (docs/format.md §4.8): min of the two bodies' values between ragdoll bodies, the
    /// ragdoll body's own value against anything else, instead of Bullet's product. Bullet has one process-wide contact
    /// callback for it: it is in force while an EngineContactFriction guard (every RagdollWorld holds one) lives;
    /// Ragdoll::engineContactFriction() says whether it is.
    bool engineContactFriction = true;
    /// The explosion guard (on by default).
    ExplosionGuard guard = {};
    /// Velocity clamps (off by default).
    VelocityClamp velocityClamp = {};
};

/// Spawn options that carry what the loaded entity asks for: its "nodrop"/"sleep" flag as startAtRest, and
/// `method`. Set the entity transform and collision filter on the result.
inline SpawnOptions spawnOptionsFor(const figure::LoadedFigure& loaded, const Method& method = {}) {
    SpawnOptions options;
    options.method = method;
    options.startAtRest = loaded.startAtRest;
    return options;
}

/// A figure's bodies and constraints added to a caller-owned world; the destructor removes them again. Shapes
/// are the asset's, shared with every other ragdoll of it. Not copyable; one world, one thread.
///
/// A game spawns ragdolls through its RagdollWorld (RagdollWorld::spawn, which returns a std::unique_ptr<Ragdoll>)
/// and removes one by destroying it; it must not outlive that RagdollWorld. The constructor spawns into a plain
/// btDynamicsWorld instead, without the world-level half of the method.
///
/// The backend is the method's (SpawnOptions::method.backend), chosen here once: Backend::Rigid builds one
/// btRigidBody per body and btTypedConstraints; Backend::Multibody builds btMultiBody trees (reduced coordinates:
/// tree joints cannot separate) and needs a btMultiBodyDynamicsWorld (with a btMultiBodyConstraintSolver): spawned
/// into any other world it throws std::invalid_argument.
///
/// Everything answers the same way for both backends except the accessors of the rigid backend's Bullet objects
/// (body(), rigidBody(), constraint(), bulletConstraint(), bulletConstraintIsLimit()): on a multibody ragdoll they
/// throw std::logic_error, since its bodies are links of btMultiBody trees. Code that serves both reads and sets
/// bodies through bodyState(), bodyStates(), setBodyStates(), setBodyVelocities(), collisionObject() and
/// applyBodyImpulse().
class Ragdoll {
  public:
    /// Spawns into a plain world: the method's per-ragdoll knobs apply, the world keeps its own settings and
    /// there is no position pass, no frozen rest. `world` must outlive the ragdoll. Into a world a RagdollWorld
    /// manages, spawn with RagdollWorld::spawn.
    Ragdoll(std::shared_ptr<const RagdollAsset> asset, btDynamicsWorld& world, const SpawnOptions& options = {});
    /// Removes the ragdoll's bodies and constraints from its world (and from its RagdollWorld's bookkeeping).
    ~Ragdoll();
    Ragdoll(const Ragdoll&) = delete;
    Ragdoll& operator=(const Ragdoll&) = delete;

    /// The built figure this ragdoll simulates.
    const figure::Figure& figure() const { return m_asset->figure(); }
    /// The shared asset.
    const std::shared_ptr<const RagdollAsset>& asset() const { return m_asset; }
    /// The world the ragdoll lives in.
    btDynamicsWorld& world() { return m_world; }
    /// The world the ragdoll lives in.
    const btDynamicsWorld& world() const { return m_world; }
    /// The method it was spawned with.
    const Method& method() const { return m_method; }
    /// Whether the engine's contact friction is in force for its bodies (SpawnOptions::engineContactFriction and
    /// a live EngineContactFriction guard).
    bool engineContactFriction() const;
    /// The entity transform it was spawned with (model space to world).
    const btTransform& spawnTransform() const { return m_spawn; }

    /// The backend it was built with (the method's).
    Backend backend() const { return m_method.backend; }
    /// Number of bodies (one per figure body, same order), for either backend.
    int bodyCount() const;
    /// The collision object of figure body `i` (a btRigidBody, or a btMultiBodyLinkCollider); its world
    /// transform is the body frame (centre of mass, principal axes).
    btCollisionObject& collisionObject(int i);
    /// The collision object of figure body `i` (see the non-const overload).
    const btCollisionObject& collisionObject(int i) const;
    /// Rigid body of figure body `i`; its transform is the body frame (centre of mass, principal axes), unless the
    /// body was merged with others (Method::mergeFixed, setLod): then it is their compound, whose frame is the
    /// union's (bodyInRigid(i) places the body in it). Rigid backend only: throws std::logic_error on a multibody
    /// ragdoll (bodyState() and collisionObject() serve both).
    btRigidBody& body(int i);
    /// Rigid body of figure body `i` (see the non-const overload); rigid backend only.
    const btRigidBody& body(int i) const;
    /// The Bullet rigid bodies (rigid backend): one per figure body, or fewer with Method::mergeFixed or setLod;
    /// 0 for a multibody ragdoll.
    int rigidBodyCount() const { return static_cast<int>(m_bodies.size()); }
    /// Rigid body `k` of rigidBodyCount(); throws std::logic_error on a multibody ragdoll.
    btRigidBody& rigidBody(int k);
    /// Rigid body `k` of rigidBodyCount(); throws std::logic_error on a multibody ragdoll.
    const btRigidBody& rigidBody(int k) const;
    /// The rigid body (index for rigidBody) carrying figure body `i`.
    int rigidIndexOf(int i) const { return m_layout->rigidOf[static_cast<std::size_t>(i)]; }
    /// Figure body `i`'s frame in its rigid body's frame (identity unless merged).
    const btTransform& bodyInRigid(int i) const { return m_layout->bodyInRigidBt[static_cast<std::size_t>(i)]; }
    /// How the figure's bodies map to rigid bodies (the asset's for this ragdoll's method, or its level of detail's).
    const RigidLayout& layout() const { return *m_layout; }

    /// Switches to a level of detail (figure::lodFromNames, figure::automaticLod; docs/performance.md): each group of
    /// `level` becomes one rigid body, a compound of its bodies' shapes as they are placed now, with their exact
    /// combined mass properties at this pose, so nothing moves: the joints inside a group hold their current
    /// relative pose (and their current error) until setFullDetail(). Each rigid body gets its bodies' total
    /// momentum and angular momentum about its centre of mass; a body's own state is the rigid's velocity field.
    /// Call between steps. Rest, freezing, the explosion guard's saved state and joint warm starting carry over
    /// (the rebuilt joints start warm starting afresh). Rigid backend only. Returns an error message and changes
    /// nothing when `level` is not a partition of the figure's bodies or the backend is the multibody one; else an
    /// empty string.
    std::string setLod(const figure::LodLevel& level);
    /// Back to one rigid body per body (or per group of Method::mergeFixed), each at its figure body's current pose
    /// with its velocity as the level of detail moved it. No-op at full detail.
    void setFullDetail();
    /// Whether a level of detail is in force.
    bool lodActive() const { return m_lodLayout != nullptr; }
    /// The main Bullet constraint of figure constraint `i` (null for a fixed constraint inside a merged body).
    /// Rigid backend only: throws std::logic_error on a multibody ragdoll.
    btTypedConstraint* constraint(int i);
    /// The main Bullet constraint of figure constraint `i` (see the non-const overload); rigid backend only.
    const btTypedConstraint* constraint(int i) const;
    /// Every Bullet constraint the ragdoll added (main constraints, limits, friction, spring lengths); 0 for a
    /// multibody ragdoll.
    int bulletConstraintCount() const { return static_cast<int>(m_constraints.size()); }
    /// What the rows of Bullet constraint `k` do; throws std::logic_error on a multibody ragdoll.
    RowRole bulletConstraintRole(int k) const;
    /// Whether Bullet constraint `k` is a limit of its own (DirectionLimitConstraint, HingeRangeConstraint), i.e.
    /// its role is RowRole::Limit; throws std::logic_error on a multibody ragdoll.
    bool bulletConstraintIsLimit(int k) const { return bulletConstraintRole(k) == RowRole::Limit; }
    /// Bullet constraint `k` of those, in the order they were added to the world; throws std::logic_error on a
    /// multibody ragdoll.
    btTypedConstraint& bulletConstraint(int k);
    /// Bullet constraint `k` (see the non-const overload); throws std::logic_error on a multibody ragdoll.
    const btTypedConstraint& bulletConstraint(int k) const;

    /// The constraint frame of figure constraint `i` as attached to body1 and to body2 (or the world), in world
    /// space now; at spawn the two coincide.
    std::pair<btTransform, btTransform> constraintFramesWorld(int i) const;
    /// The constraint frame of figure constraint `i` in body1's frame, and in body2's frame (or in the world
    /// for a world constraint), in Bullet's precision; fixed at spawn.
    const std::pair<btTransform, btTransform>& constraintFramesLocal(int i) const {
        return m_frames[static_cast<std::size_t>(i)];
    }
    /// The same frames in the frames of the two rigid bodies (rigidIndexOf(body1), rigidIndexOf(body2)), as the
    /// Bullet constraints hold them; equal to constraintFramesLocal unless a body was merged.
    const std::pair<btTransform, btTransform>& rigidFramesLocal(int i) const {
        return m_rigidFrames[static_cast<std::size_t>(i)];
    }

    /// How far a figure constraint is from holding (the probes' type).
    using JointError = bullet::JointError;
    /// How far figure constraint `i` is from holding now (what accuracy metrics read, for any backend).
    JointError jointError(int i) const;

    /// World transforms of every body (body frames: centre of mass, principal axes), metres.
    std::vector<figure::Transform> bodyTransforms() const;
    /// World transforms and velocities of every body.
    std::vector<figure::BodyState> bodyStates() const;
    /// World transform and velocities of figure body `i` (its frame: centre of mass, principal axes), either backend.
    figure::BodyState bodyState(int i) const;
    /// Figure bodies Bullet is simulating now (not asleep; a merged rigid counts each body it carries).
    int awakeBodyCount() const;
    /// Places every body (one state per body, in body order) and sets its velocities, e.g. from an animation
    /// (figure::bodiesFromJoints, figure::inheritVelocities); wakes the ragdoll. Returns false and changes
    /// nothing when the number of states is not bodyCount(). A non-finite state reaches the explosion guard of a
    /// rigid ragdoll (it trips before the next step); a multibody ragdoll refuses it (false).
    [[nodiscard]] bool setBodyStates(std::span<const figure::BodyState> states);
    /// Sets every body's velocities (one per body, in body order: m/s of its centre of mass and rad/s, world) and
    /// keeps the poses; wakes the ragdoll. A rigid body that carries merged bodies takes its representative body's
    /// motion; a multibody ragdoll takes the joint velocities that carry it (as setBodyStates). Returns false and
    /// changes nothing when the number of velocities is not bodyCount() (or, multibody, one is not finite).
    [[nodiscard]] bool setBodyVelocities(std::span<const BodyVelocity> velocities);

    /// Applies `impulse` (N·s, world) at `worldPoint` to the body containing md5 joint `joint` (containedJoints;
    /// docs/format.md §5.3) and wakes the ragdoll. As in the engine, an impulse below the wake threshold (500 engine
    /// units, 500·metresPerUnit N·s) or on a joint no body contains is ignored: returns false.
    bool applyImpulse(int joint, const btVector3& impulse, const btVector3& worldPoint);
    /// The same on figure body `body` (figureBodyOf a ray hit, say); false for a body out of range. With
    /// ImpulseRule::Always the wake threshold does not apply (a scripted push of any size).
    bool applyBodyImpulse(int body, const btVector3& impulse, const btVector3& worldPoint,
                          ImpulseRule rule = ImpulseRule::EngineThreshold);
    /// Which figure body a ray or contact test hit: `object` one of this ragdoll's collision objects, `worldPoint`
    /// the hit point. A rigid body that carries several merged bodies (Method::mergeFixed, setLod) answers with the
    /// one whose surface is nearest the point. −1 when `object` is not this ragdoll's (a sunk ragdoll's box is not a
    /// body: surface() it first; RagdollWorld::ragdollOf finds the ragdoll of either).
    int figureBodyOf(const btCollisionObject& object, const btVector3& worldPoint) const;
    /// The wake threshold of applyImpulse, N·s.
    double impulseThresholdNs() const { return 500.0 * figure().units.metresPerUnit; }

    /// Sets the gains of every joint motor (afb/bullet/Motor.h, docs/motors.md): one motor per figure constraint
    /// whose joint has free axes (ball-and-socket and universal: its whole relative rotation; hinge: its angle;
    /// slider: its offset; none for fixed joints, springs and joints inside a merged body). A frequency of 0
    /// switches them off: the ragdoll then moves exactly as a limp one. The motors' first setting adds them to the
    /// world; until driveToPose they hold the figure's load pose. Rigid backend spawned through a RagdollWorld
    /// only (the motor's soft rows need its solver): returns false and changes nothing otherwise.
    [[nodiscard]] bool setMotorGains(const MotorGains& gains);
    /// Sets the gains of the motor of figure constraint `constraint` (per-joint strength; a frequency of 0 lets that
    /// joint go limp). Gains and targets are kept for a joint a level of detail merges, and apply again at full
    /// detail. False, changing nothing, where setMotorGains(gains) would refuse, for an index out of range, or for a
    /// fixed joint or a spring.
    [[nodiscard]] bool setMotorGains(int constraint, const MotorGains& gains);
    /// Sets every motor from a profile: `profile.all`, then each named joint's gains. False, changing nothing, where
    /// setMotorGains(gains) would refuse, or when a name is no joint of the figure with a motor (a fixed joint, a
    /// spring or a misspelling).
    [[nodiscard]] bool setMotorGains(const MotorProfile& profile);
    /// The gains of figure constraint `constraint`'s motor (frequency 0 until set, and for a fixed joint or spring).
    MotorGains motorGains(int constraint) const;
    /// Whether figure constraint `constraint` has a motor in the current layout (see setMotorGains).
    bool hasMotor(int constraint) const;
    /// Sets every motor's target from a pose: one state per body (body order, world body frames and velocities, as
    /// bodyStates() gives them, e.g. figure::bodiesFromJoints of an animation frame). Each motor drives its joint
    /// toward the rotation (hinge: angle; slider: offset) of body2 relative to body1 that the pose gives, and toward
    /// their relative velocity; only relative motion counts, so the pose's placement in the world does not matter
    /// (unless a constraint ties a body to the world). Does not wake a ragdoll at rest. Returns false and changes
    /// nothing when the number of states is not bodyCount() or a state is not finite.
    [[nodiscard]] bool driveToPose(std::span<const figure::BodyState> target);
    /// Scales every motor at once (the figure's muscle tone): the stiffness, damping and bounds of the gains set by
    /// setMotorGains times `strength` in [0, 1] (scaledGains). 1, the default, is the gains as set; 0 lets the whole
    /// figure go limp, exactly as gains of 0 do. motorGains() still answers the gains as set. Stops a regain under
    /// way. False, changing nothing, for a strength outside [0, 1] or where setMotorGains would refuse.
    [[nodiscard]] bool setMotorStrength(double strength);
    /// The motors' strength now (1 unless setMotorStrength or a hit lowered it).
    double motorStrength() const { return m_motorStrength; }
    /// A hit: applyBodyImpulse(body, impulse, worldPoint, ImpulseRule::Always) (it wakes the ragdoll), and, when the
    /// ragdoll has motors, their strength drops to `reaction.strength` (or stays lower) and regains linearly to 1
    /// over `reaction.regainSeconds` of simulated time (docs/motors.md). A limp ragdoll, or one on the multibody
    /// backend, takes the impulse alone. False, changing nothing, for a body out of range, a non-finite impulse or
    /// point, or a reaction outside its ranges.
    [[nodiscard]] bool hit(int body, const btVector3& impulse, const btVector3& worldPoint,
                           const HitReaction& reaction = {});

    /// Sets figure body `body`'s mode (docs/motors.md, "Keyframed bodies and partial ragdolls"). Keyframed, the body
    /// is moved by the velocity that takes it to its target over each RagdollWorld::step: contacts and its joints
    /// act on its neighbours, nothing acts on it. It holds its current pose until setKeyframeTargets gives it
    /// another. Back to Simulated, it keeps its pose and the velocity of its last keyframed step. A rigid body that
    /// carries several figure bodies (Method::mergeFixed, setLod) is keyframed while any of them is, and follows
    /// the target of the first of them in body order. Rigid backend spawned through a RagdollWorld only: false,
    /// changing nothing, otherwise or for a body out of range.
    [[nodiscard]] bool setBodyMode(int body, BodyMode mode);
    /// The mode figure body `body` was given (Simulated for a body out of range).
    BodyMode bodyMode(int body) const;
    /// Whether rigid body `k` (rigidBodyCount) is keyframed: one of the figure bodies it carries is.
    bool rigidKeyframed(int k) const { return keyframeSource(static_cast<std::size_t>(k)) >= 0; }
    /// Sets the keyframe targets: one state per body (body order, world body frames, as bodyStates() gives them,
    /// e.g. figure::bodyStatesFromAnimation of the next frame); the keyframed bodies reach theirs at the end of
    /// the next RagdollWorld::step, moving at the constant velocity that takes them there (the states' velocities
    /// are not used). The next step wakes a ragdoll at rest whose keyframed bodies have a target away from their
    /// pose. False, changing nothing, where setBodyMode would refuse, when the number of states is not
    /// bodyCount() or a state is not finite.
    [[nodiscard]] bool setKeyframeTargets(std::span<const figure::BodyState> targets);

    /// True while the figure is at rest by its own rules (docs/format.md §6.1). Spawned through a RagdollWorld, its
    /// bodies are then frozen (frozen()); in a plain world they are asleep in Bullet.
    bool atRest() const;
    /// True while the ragdoll rests frozen (only when spawned through a RagdollWorld): its constraints are out of
    /// the world and its bodies are static objects of the StaticFilter group that test no pairs against static
    /// objects, so it costs the world (almost) nothing per step. A contact with an active body (the RagdollWorld
    /// checks every substep), an impulse above the threshold, setBodyStates or wake() restore it exactly.
    bool frozen() const { return m_frozen; }
    /// True while a frozen ragdoll with nothing active near it is out of the world: its bodies are replaced by one
    /// static, contact-free box round them (Bullet's per-object loops then see one object, not one per body). An
    /// active object's bounding box meeting the box puts the bodies back, frozen, where frozen()'s contact rule
    /// decides; the RagdollWorld sinks it again when nothing active is near.
    bool sunk() const { return m_restProxy != nullptr; }
    /// Brings a sunk ragdoll's bodies back into the world, still frozen (for a game about to ray-test it; see
    /// RagdollWorld::setSinking). No-op when not sunk.
    void surface();
    /// The deepest contact of the ragdoll's bodies at the moment it froze (penetration in metres, 0 for none, and
    /// the two objects): a frozen ragdoll has no contacts in the world, but it still rests that deep.
    struct FrozenContact {
        double depthM = 0;                    ///< penetration depth, metres; 0 for no contact
        const btCollisionObject* a = nullptr; ///< one object of that contact (null for none)
        const btCollisionObject* b = nullptr; ///< the other object of that contact (null for none)
    };
    /// The deepest contact at the moment the ragdoll froze (see FrozenContact).
    const FrozenContact& frozenContact() const { return m_frozenContact; }
    /// Seconds simulated since the ragdoll last woke (the engine's activateTime).
    double activeSeconds() const;
    /// Puts the figure to rest now: zero velocities, bodies asleep.
    void putToRest();
    /// Wakes the figure and restarts its rest timers.
    void wake();
    /// Runs the explosion guard's test now (if enabled) and, when it trips, restores, freezes and reports as after a
    /// substep. RagdollWorld::step calls it before each frame, so a state the game wrote between steps (a NaN
    /// through setBodyStates or a body's velocity) is caught before Bullet's collision detection or solver reads
    /// it. Returns true when it tripped.
    bool checkGuard();
    /// Puts the ragdoll back to its state after the last substep the guard passed (or its spawn, or the last
    /// setBodyStates) and freezes it there, as the guard does when it trips (without calling onTrip).
    void freeze();
    /// How many times the explosion guard has restored and frozen the ragdoll.
    int guardTrips() const;
    /// The last trip of the guard, if any.
    const std::optional<GuardTrip>& lastGuardTrip() const;

  private:
    // The origins of constraintFramesWorld(i), without the frames' rotations (the explosion guard's per-step test).
    std::pair<btVector3, btVector3> anchorsWorld(int i) const;
    class Action;
    void addBodies();
    void relayout(const figure::LodLevel* level); ///< see setLod; null: full detail
    void placeRigids(std::span<const BodySample> bodies);
    /// Puts `b` at `t` with velocities `v`, `w` (and Bullet's interpolation state with them).
    static void placeRigid(btRigidBody& b, const btTransform& t, const btVector3& v, const btVector3& w);
    void removeBulletObjects(); ///< constraints and bodies out of the world and destroyed (the layout stays)
    void rememberGoodState();   ///< the explosion guard's saved state := now
    void addConstraints();
    void addJoint(const figure::FigureConstraint& c, const JointParts& parts);
    void filterPairs();
    void addMotors(); ///< motors of every joint that has one, with their gains and targets (m_motorGains)
    bool motorsAllowed() const;
    bool drivable(int constraint) const;          ///< the joint type has free axes (its gains and target are kept)
    void applyMotorGains(std::size_t constraint); ///< m_motorGains to its motor, in or out of the world
    void regainStrength(double dt);               ///< a substep of a hit's regain (Action)
    void beginMotorStep(); ///< before a RagdollWorld::step: each motor's carried inertia (CarriedInertia) now
    void freezeBodies();   ///< rest as static bodies (RagdollWorld's frozen rest)
    void thawBodies();
    // What the RagdollWorld that spawned it reaches (spawn, sinking): src/bullet/RagdollWorldLink.h, the one way in.
    friend class detail::RagdollWorldLink;
    void sink(); ///< frozen → out of the world behind one box (sunk())
    // Keyframed bodies (src/bullet/RagdollKeyframes.cpp).
    bool keyframesAllowed() const { return !m_multibody && m_manager != nullptr; }
    int keyframeSource(std::size_t rigid) const; ///< the figure body whose target a rigid follows, or −1
    void applyRigidMode(std::size_t rigid);      ///< kinematic or dynamic, as its bodies' modes say
    void beginKeyframeStep(double stepSeconds);  ///< before a RagdollWorld::step: each rigid's velocity to its target
    void advanceKeyframes(btScalar dt);          ///< after each substep's integration: the keyframed rigids move

    void requireRigid(const char* accessor) const; ///< throws std::logic_error for a multibody ragdoll
    btRigidBody& other(int body2) const;
    btTransform frameOfBody2(const figure::FigureConstraint& c) const;
    bool merged() const { return m_layout->rigids.size() != m_layout->rigidOf.size(); }
    std::vector<btTransform> figureBodyTransforms() const; ///< every figure body's frame, world
    void figureBodySamples(std::vector<BodySample>& out) const;

    std::shared_ptr<const RagdollAsset> m_asset;
    const RigidLayout* m_layout = nullptr; ///< the asset's, for m_method.mergeFixed
    btDynamicsWorld& m_world;
    RagdollWorld* m_manager = nullptr; ///< the RagdollWorld it was spawned through, if any
    Method m_method;
    bool m_engineFriction = false;
    btTransform m_spawn;
    std::unique_ptr<detail::ObjectArena> m_arena;  ///< owns the bodies, constraints and feedback below
    std::vector<btRigidBody*> m_bodies;            ///< one per rigid of m_layout
    std::vector<btTypedConstraint*> m_constraints; ///< in the order added to the world
    std::vector<RowRole> m_roles;                  ///< per Bullet constraint, what its rows do
    int m_group = 0;                               ///< collision group of every body
    int m_spawnMask = 0;                           ///< SpawnOptions::collisionMask
    std::vector<int> m_masks;                      ///< collision mask of each rigid body
    bool m_frozen = false;                         ///< see frozen()
    FrozenContact m_frozenContact;
    std::unique_ptr<btBoxShape> m_restProxyShape;   ///< see sunk()
    std::unique_ptr<btCollisionObject> m_restProxy; ///< see sunk()
    int m_calmSubsteps = 0; ///< frozen, not sunk: substeps in a row with nothing active near (RagdollWorld)
    std::vector<btTypedConstraint*> m_main;
    std::vector<std::pair<btTransform, btTransform>> m_frames; ///< per figure constraint, see constraintFramesLocal
    std::vector<std::pair<btTransform, btTransform>> m_rigidFrames; ///< see rigidFramesLocal
    std::vector<btJointFeedback*> m_feedback;
    std::unique_ptr<Action> m_action;
    std::unique_ptr<RigidLayout> m_lodLayout;                      ///< the level of detail in force, or null
    std::vector<std::unique_ptr<btCollisionShape>> m_lodCompounds; ///< its compound shapes
    std::unique_ptr<detail::MultibodyRagdoll> m_multibody;         ///< the multibody backend, or null for the rigid one
    /// A joint motor's target: frame B's rotation in frame A and B's angular velocity relative to A in frame A
    /// (sliders: the offset along the axis and its rate).
    struct MotorTarget {
        btQuaternion rotation = btQuaternion::getIdentity();
        btVector3 angularVelocity{0, 0, 0};
        btScalar offset = 0;
        btScalar speed = 0;
    };
    std::vector<MotorGains> m_motorGains;              ///< per figure constraint; empty until motors are first set
    std::vector<MotorTarget> m_motorTargets;           ///< per figure constraint
    std::vector<JointMotorConstraint*> m_motors;       ///< per figure constraint, null where none (owned by m_arena)
    std::unique_ptr<detail::CarriedInertia> m_carried; ///< the tree of the rigids, for the motors' inertia
    double m_motorStrength = 1;                        ///< setMotorStrength, lowered by a hit
    double m_regainPerSecond = 0; ///< the strength's rise per simulated second after a hit (0: none)
    /// Keyframed bodies: each figure body's mode and target, and the step that moves the keyframed rigids.
    struct Keyframes {
        std::vector<BodyMode> modes;            ///< per figure body; empty while every body is simulated
        std::vector<figure::BodyState> targets; ///< per figure body, world
        std::vector<btVector3> linear, angular; ///< per rigid: the velocity that reaches its target, m/s and rad/s
        int keyframed = 0;                      ///< how many figure bodies are keyframed
        double stepSeconds = 0;                 ///< the step under way (RagdollWorld::step), s
        double elapsedSeconds = 0;              ///< of it, simulated so far, s
        bool moving = false;                    ///< a keyframed rigid moves in the step under way
    };
    Keyframes m_keyframes;
};

} // namespace afb::bullet
