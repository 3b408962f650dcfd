#pragma once
// The reduced-coordinate backend of bullet::Ragdoll (Method::backend = Backend::Multibody): the figure as
// btMultiBody trees in a btMultiBodyDynamicsWorld. Internal: bullet::Ragdoll owns one and forwards its
// interface to it, so nothing above the bullet layer sees which backend runs.
#include <memory>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include <btBulletDynamicsCommon.h>

#include "MultibodyJoints.h"
#include "afb/bullet/Method.h"
#include "afb/bullet/RagdollAsset.h"
#include "afb/detail/Probes.h"

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
/// spherical link whose twist a row holds). Loops, world attachments and springs are btMultiBodyConstraints. What
/// each joint type becomes is MultibodyJoints.h's; which joints are edges, bases and loops is figure::freedomOf's.
/// Files: Multibody.cpp (the instance, its per-substep action and its state), MultibodyTree.cpp (trees, links,
/// colliders, joint coordinates), MultibodyConstraints.cpp (loops, limits, friction, springs, guards),
/// MultibodySweeps.cpp (position sweeps), MultibodyRows.h (the rows themselves).
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
    /// The role of each of the ragdoll's btMultiBodyConstraints that adds rows, in the order the ragdoll holds them:
    /// per figure constraint its friction rows, a loop's own constraint, its limit; then every twist row (the energy
    /// guards, which add no rows, left out).
    std::vector<RowRole> rowRoles() const;

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
    /// A tree edge: the link that carries the child, and how its coordinates follow from its two bodies' poses
    /// (setBodyStates).
    struct Joint {
        LinkKind kind{};
        bool twistRow = false;         ///< a spherical link whose twist a row holds (a universal joint)
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
    /// A btMultiBodyConstraint of the ragdoll's, and the role of its rows (none: an energy guard, which adds none).
    struct Owned {
        std::unique_ptr<btMultiBodyConstraint> constraint;
        std::optional<RowRole> role;
    };

    // MultibodyTree.cpp
    /// The multibody parts of every figure constraint (MultibodyJoints.h), at the frames m_frames holds.
    std::vector<MultibodyJointParts> jointParts() const;
    /// The parts (trees) and where each body sits in them, tree edges breadth first from each part's base.
    void layoutTrees(std::span<const MultibodyJointParts> joints);
    /// Tree edge `ci` from body `parent` to body `child`.
    Joint treeJoint(int ci, int parent, int child, const MultibodyJointParts& parts) const;
    /// The part's btMultiBody, its links set up, into the world.
    void buildTree(Part& part, const SpawnOptions& options);
    void addColliders(const SpawnOptions& options);
    /// The figure body of collision object `o` if it is one of this ragdoll's, else −1.
    int bodyOfCollider(const btCollisionObject* o) const;
    /// Joint `j`'s coordinates and their rates from its two bodies' states.
    static void setJointCoordinates(btMultiBody& mb, const Joint& j, const figure::BodyState& parent,
                                    const figure::BodyState& child);

    // MultibodyConstraints.cpp
    btMultiBodyConstraint* add(std::unique_ptr<btMultiBodyConstraint> constraint, std::optional<RowRole> role);
    void addConstraints(const Method& method, std::span<const MultibodyJointParts> joints);
    /// A loop or a world attachment `c` with its frames: a constraint on the anchors (and on the frames when the
    /// joint holds every rotation), solved like a rigid body's joint, so it can separate again; not in the world yet.
    std::unique_ptr<btMultiBodyConstraint> makeLoop(const figure::FigureConstraint& c,
                                                    const std::pair<btTransform, btTransform>& frames);
    /// Figure constraint `c`'s limit on the links of its tree.
    void addLimit(const figure::FigureConstraint& c, const MultibodyLimit::Kind& limit, const LimitRowPolicy& policy);
    /// The twist rows of the tree edges whose link leaves the twist free (universal joints, §4.4), parent side first.
    void addTwistRows(const LimitRowPolicy& policy);
    /// docs/format.md §4.8 joint friction rows on figure constraint `ci` if it has friction (`loop`: its constraint
    /// when it is not a tree edge, whose applied impulses are the reaction; else the reaction of the child's subtree).
    void addFriction(int ci, const MultibodyJointParts& parts, btMultiBodyConstraint* loop);
    /// The figure bodies of the subtree that tree edge `c` carries (its child's and below), or none if `c` is not one.
    std::optional<std::vector<int>> subtreeOf(const figure::FigureConstraint& c) const;
    /// §4.7: the spring between the two bodies' anchors (frames' origins, body frames; world for the world).
    void addSpring(const figure::FigureConstraint& c, const btTransform& fa, const btTransform& fb);
    /// Each friction row's bound for the coming step from its joint's reaction in the step just solved.
    void updateFrictionBounds(btScalar dt);
    /// This substep's contact impulse on each body (m_contactImpulse).
    void gatherContactImpulses();

    // MultibodySweeps.cpp
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

    // Multibody.cpp
    void refreshTransforms(btMultiBody& body);
    void meanDamping();
    void dampVelocities(btScalar dt);
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
    std::vector<Owned> m_constraints; ///< limits, twists, loops, world joints, friction, springs, guards
    std::vector<std::pair<btTransform, btTransform>> m_frames; ///< per figure constraint (Ragdoll's meaning)
    std::vector<std::pair<int, int>>
        m_colliding; ///< figure::selfCollisionPairs (Method::exemptOverlapping: less the overlapping)
    std::vector<btVector3> m_angularVelocity; ///< per figure body, at the end of the last substep (limit margins)
    btScalar m_linearDamping = 0, m_angularDamping = 0;
    std::vector<bool> m_treeEdge;              ///< per figure constraint: a tree joint (a link), not a loop
    std::vector<EnergyGuard*> m_guards;        ///< per part, its energy guard (owned by m_constraints)
    std::vector<MultibodyLimit*> m_swept;      ///< limit and twist rows, for the sweeps (owned by m_constraints)
    int m_positionIterations = 0;              ///< sweeps of correctPositions
    std::vector<SweepContact> m_sweepContacts; ///< this substep's, for correctPositions
    std::vector<btScalar> m_sweepJac, m_sweepJacB, m_sweepMove;
    /// A joint's friction rows and where its reaction force is read.
    struct Friction {
        MultibodyFriction* rows = nullptr;     ///< owned by m_constraints
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
