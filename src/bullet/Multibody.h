#pragma once
// The reduced-coordinate backend of bullet::Ragdoll (Method::backend = Backend::Multibody): the figure as
// btMultiBody trees in a btMultiBodyDynamicsWorld. Internal: bullet::Ragdoll owns one and forwards its
// interface to it, so nothing above the bullet layer sees which backend runs.
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include <btBulletDynamicsCommon.h>

#include "afb/bullet/Method.h"
#include "afb/bullet/RagdollAsset.h"
#include "afb/detail/Probes.h"

class btMultiBody;
class btMultiBodyConstraint;
class btMultiBodyDynamicsWorld;
class btMultiBodyLinkCollider;

namespace afb::bullet {
struct SpawnOptions;
}

namespace afb::bullet::detail {

/// The message of the error a multibody ragdoll spawned into a plain btDiscreteDynamicsWorld throws
/// (std::invalid_argument).
inline constexpr const char* kNeedsMultiBodyWorld =
    "afbullet: the multibody backend needs a btMultiBodyDynamicsWorld (with a btMultiBodyConstraintSolver); this "
    "world is a plain btDynamicsWorld: create a btMultiBodyDynamicsWorld, or use the rigid backend";

/// A figure as btMultiBody trees: one per connected part of its constraint graph, a body fixed to the world as a
/// fixed base, else the part's first body as the floating base and one link per tree edge (a universal joint: a
/// spherical link whose twist a row holds). Loops, world attachments and springs are btMultiBodyConstraints.
class MultibodyRagdoll {
  public:
    /// Throws std::invalid_argument (kNeedsMultiBodyWorld) unless `world` is a btMultiBodyDynamicsWorld.
    MultibodyRagdoll(std::shared_ptr<const RagdollAsset> asset, btDynamicsWorld& world, const SpawnOptions& options);
    ~MultibodyRagdoll();
    MultibodyRagdoll(const MultibodyRagdoll&) = delete;
    MultibodyRagdoll& operator=(const MultibodyRagdoll&) = delete;

    int bodyCount() const { return static_cast<int>(m_bodies.size()); }
    /// The collision object of figure body `i` (a btMultiBodyLinkCollider).
    btCollisionObject& collider(int i);
    const btCollisionObject& collider(int i) const;
    /// The multibody trees, the figure's origin body's first.
    int partCount() const { return static_cast<int>(m_parts.size()); }
    btMultiBody& part(int k) { return *m_parts[static_cast<std::size_t>(k)].body; }
    /// Links of figure body `i`'s tree (−1: the base) and its part.
    int linkOf(int i) const { return m_bodies[static_cast<std::size_t>(i)].link; }
    int partOf(int i) const { return m_bodies[static_cast<std::size_t>(i)].part; }

    /// Body frames (centre of mass, principal axes) and velocities now, in figure body order.
    std::vector<BodySample> samples() const;
    std::vector<btTransform> transforms() const;
    /// As Ragdoll's (see there).
    std::pair<btTransform, btTransform> constraintFramesWorld(int i) const;
    const std::pair<btTransform, btTransform>& constraintFramesLocal(int i) const {
        return m_frames[static_cast<std::size_t>(i)];
    }
    JointError jointError(int i) const;
    int awakeBodyCount() const;
    /// Places the trees as near the states as their joints allow (the base exactly, every joint coordinate from
    /// its two bodies' relative pose and velocity) and wakes the ragdoll.
    void setBodyStates(std::span<const figure::BodyState> states);
    /// An impulse (N·s, world) at a world point of body `i`: the generalised velocity change M⁻¹·Jᵀ·p.
    void applyImpulse(int i, const btVector3& impulse, const btVector3& worldPoint);

    bool atRest() const;
    double activeSeconds() const;
    void putToRest();
    void wake();

  private:
    class Action;
    class LinkCollider;
    /// Where figure body i lives.
    struct BodyRef {
        int part = 0;
        int link = -1; ///< −1: the part's base
    };
    /// How a link's joint coordinates follow from its two bodies' poses (setBodyStates).
    struct Joint {
        enum class Kind { Fixed, Revolute, Prismatic, Spherical, Universal } kind = Kind::Fixed;
        int child = -1, parent = -1;   ///< figure bodies
        int link = -1;                 ///< the child's link
        btMatrix3x3 zeroParentToChild; ///< rotation parent frame → child frame at zero coordinates
        btVector3 axisInChild;         ///< revolute / prismatic axis, child frame
        btVector3 parentToPivot;       ///< pivot from the parent's centre of mass, parent frame
        btVector3 pivotToChild;        ///< child's centre of mass from the pivot, child frame
        btMatrix3x3 frameInParent,
            frameInChild; ///< the constraint frame's rotation in each body (universal: X = shaft 1)
    };
    struct Part {
        std::unique_ptr<btMultiBody> body;
        int root = 0;              ///< figure body of the base
        bool fixedBase = false;    ///< fixed to the world (the figure fixes that body there)
        std::vector<Joint> joints; ///< in link order (parents first)
    };

    void build(const SpawnOptions& options);
    void addColliders(const SpawnOptions& options);
    void addConstraints(const Method& method);
    /// docs/format.md §4.8 joint friction rows on figure constraint `ci` if it has friction (`loop`: its constraint
    /// when it is not a tree edge, whose applied impulses are the reaction; else the reaction of the child's subtree).
    void addFriction(int ci, btMultiBodyConstraint* loop);
    /// §4.7: the spring between the two bodies' anchors (frames' origins, body frames; world for the world).
    void addSpring(const figure::FigureConstraint& c, const btTransform& fa, const btTransform& fb);
    /// Each friction row's bound for the coming step from its joint's reaction in the step just solved.
    void updateFrictionBounds(btScalar dt);
    void refreshTransforms(btMultiBody& body);
    void dampVelocities(btScalar dt);
    /// A contact of the ragdoll's bodies for the position sweeps: the figure bodies on each side (−1: not ours).
    struct SweepContact {
        btPersistentManifold* manifold;
        int bodyA, bodyB;
    };
    /// Method::positionIterations sweeps on positions (velocities untouched) after each substep: every limit and
    /// twist row, then every contact of the ragdoll's bodies, so what the velocity rows left past a limit is
    /// closed before the step ends without pushing a limb into the ground.
    void correctPositions();
    /// Moves the contact's tree(s) by M⁻¹Jᵀ to close part of its depth past the slop; false if nothing to do.
    bool correctContact(const SweepContact& c, const btManifoldPoint& cp, btAlignedObjectArray<btScalar>& r,
                        btAlignedObjectArray<btVector3>& v, btAlignedObjectArray<btMatrix3x3>& m,
                        btAlignedObjectArray<btQuaternion>& q, btAlignedObjectArray<btVector3>& o);
    /// Every body's velocity on its collider (btCollisionObject's interpolation velocities, which Bullet leaves
    /// unused for a link collider), where the collision algorithms and the speculative reach read a body's motion
    /// (as a btRigidBody's velocity for the rigid backend).
    void publishVelocities(std::span<const BodySample> samples);
    /// The trees' motion now as the energy guards' reference (after each step and any outside velocity change).
    void recordMotion();

    std::shared_ptr<const RagdollAsset> m_asset;
    btMultiBodyDynamicsWorld& m_world;
    btTransform m_spawn;
    std::vector<Part> m_parts;
    std::vector<BodyRef> m_bodies;
    std::vector<std::unique_ptr<btMultiBodyLinkCollider>> m_colliders; ///< per figure body
    std::vector<std::unique_ptr<btMultiBodyConstraint>> m_constraints; ///< limits, loops, world joints, springs
    std::vector<std::pair<btTransform, btTransform>> m_frames;         ///< per figure constraint (Ragdoll's meaning)
    std::vector<std::pair<int, int>>
        m_colliding; ///< figure::selfCollisionPairs (Method::exemptOverlapping: less the overlapping)
    std::vector<btVector3> m_angularVelocity; ///< per figure body, at the end of the last substep (limit margins)
    btScalar m_linearDamping = 0, m_angularDamping = 0;
    std::vector<bool> m_treeEdge;                 ///< per figure constraint: a tree joint (a link), not a loop
    std::vector<btMultiBodyConstraint*> m_guards; ///< per part, its energy guard (owned by m_constraints)
    std::vector<btMultiBodyConstraint*> m_limits; ///< limit and twist rows (owned by m_constraints)
    int m_positionIterations = 0;                 ///< sweeps of correctPositions
    std::vector<SweepContact> m_sweepContacts;    ///< this substep's, for correctPositions
    std::vector<btScalar> m_sweepJac, m_sweepJacB, m_sweepMove;
    /// A joint's friction rows and where its reaction force is read.
    struct Friction {
        btMultiBodyConstraint* rows = nullptr; ///< a JointFriction (owned by m_constraints)
        std::vector<int> subtree;              ///< a tree joint: the figure bodies its child carries
        btMultiBodyConstraint* loop = nullptr; ///< a loop or world joint's constraint
        btScalar coefficientTimesLever = 0;    ///< friction × metres per unit (§4.8 in SI)
    };
    std::vector<Friction> m_frictions;
    std::vector<btVector3> m_linearVelocity; ///< per figure body, as last published (joint reactions)
    std::vector<btVector3> m_contactImpulse; ///< per figure body, this substep's (joint reactions)
    std::unique_ptr<Action> m_action;
};

} // namespace afb::bullet::detail
