#pragma once
// The world-level half of a Method, installed into a caller-owned btDiscreteDynamicsWorld for as long as this
// guard lives: solver settings, the engine's contact friction and the position pass over every ragdoll that
// was spawned through it (RagdollWorld::spawn). Create it before the ragdolls and destroy it after them.
#include <memory>
#include <utility>
#include <vector>

#include <btBulletDynamicsCommon.h>

#include "afb/bullet/Method.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/bullet/RagdollAsset.h"

namespace afb::bullet {

namespace detail {
class RagdollWorldLink;
} // namespace detail

/// The engine's friction combination (docs/format.md §4.8) through Bullet's one process-wide contact-added callback:
/// ragdoll bodies spawned with SpawnOptions::engineContactFriction then combine friction as the engine does.
///
/// The callback is written once per process, by the first install() (every RagdollWorld and every guard calls it),
/// and never removed: Bullet calls it only for objects flagged CF_CUSTOM_MATERIAL_CALLBACK, and it changes only the
/// contacts of ragdoll bodies. Every world reads that global in its collision detection, so the one write must not
/// overlap another thread's step of a world made before it: a game that steps Bullet worlds on several threads calls
/// install() (or makes its first RagdollWorld) before those threads start. Worlds made and stepped after it never
/// write it again. If the game installed a callback of its own first, it is left alone: active() is false and
/// Bullet's product rule stays in force.
class EngineContactFriction {
  public:
    /// Installs the callback (see install()).
    EngineContactFriction();
    EngineContactFriction(const EngineContactFriction&) = delete;
    EngineContactFriction& operator=(const EngineContactFriction&) = delete;
    /// True when the engine's rule is in force.
    bool active() const { return m_active; }
    /// Writes Bullet's contact-added callback unless one is already set; the first call writes it, later calls (on
    /// any thread) only wait for the first to finish. Returns whether the engine's rule is in force.
    static bool install();
    /// True when the engine's rule is in force now (what a ragdoll reports).
    static bool installed();

  private:
    bool m_active = false;
};

/// `method` as a world with (`ragdollSolver`) or without a RagdollSolver runs it (RagdollWorld::method).
Method methodInForce(const Method& method, bool ragdollSolver);

/// A caller's world with a Method's world-level knobs (substeps, iterations, split impulse, ERPs, warm starting,
/// position iterations) and the engine's contact friction, and the place ragdolls are spawned: spawn() adds one,
/// destroying what it returned removes it. Not copyable; one world, one thread.
///
/// Lifetimes nest: the btDiscreteDynamicsWorld outlives the RagdollWorld, which outlives every Ragdoll it spawned.
/// Declare the RagdollWorld before the ragdolls (or clear the container that holds them before destroying it).
class RagdollWorld {
  public:
    /// Installs `method`'s world-level knobs into `world` (applyWorldKnobs) and the engine's contact friction;
    /// `world` must outlive this object and every ragdoll spawned through it.
    RagdollWorld(btDiscreteDynamicsWorld& world, const Method& method);
    /// Takes the position pass and the solver's contact cap out of the world; its solver settings stay. Destroy
    /// the ragdolls spawned through it first.
    ~RagdollWorld();
    RagdollWorld(const RagdollWorld&) = delete;
    RagdollWorld& operator=(const RagdollWorld&) = delete;

    /// Spawns a ragdoll of `asset` into the world: its bodies and constraints join it now, built with the
    /// per-ragdoll knobs of `options.method` (the world-level ones are this world's method()), and it gets the
    /// position pass, the contact handling and frozen rest of this world. The caller owns the ragdoll: destroying
    /// it (`ragdoll.reset()`, or the end of its scope or container) removes it from the world, between steps (not
    /// from inside one, as from ExplosionGuard::onTrip). It must not outlive this RagdollWorld. Throws
    /// std::invalid_argument when `options.method` is the multibody backend and the world is not a
    /// btMultiBodyDynamicsWorld (makeWorld makes one that is), and then adds nothing.
    [[nodiscard]] std::unique_ptr<Ragdoll> spawn(std::shared_ptr<const RagdollAsset> asset,
                                                 const SpawnOptions& options = {});

    /// The caller's world this one manages.
    btDiscreteDynamicsWorld& world() { return m_world; }
    /// The caller's world this one manages.
    const btDiscreteDynamicsWorld& world() const { return m_world; }
    /// The method whose world-level knobs are in force: the one given, except in a world whose constraint solver
    /// is not a RagdollSolver, where the direct joint solve cannot run: its world-level knobs then fall back to the
    /// iterative default's (direct-joints off, position-tree 0, friction-directions 1), because the tree position
    /// step over Bullet's iterative joints pushes limbs into the ground (docs/methods.md). `methodInForce` gives
    /// the same without a world.
    const Method& method() const { return m_method; }

    /// Steps one frame of `dtSeconds` as the method's substeps (stepSimulation with a fixed substep), or more while
    /// a ragdoll and another object's dynamic body close fast (Method::impactSubsteps), after the explosion guard
    /// of every ragdoll checked what the game wrote since the last frame (Ragdoll::checkGuard).
    void step(double dtSeconds);
    /// The substeps the last step() took.
    int lastSubsteps() const { return m_lastSubsteps; }

    /// Whether the engine's contact friction is in force (another contact callback may own Bullet's hook).
    bool engineContactFriction() const { return m_friction.active(); }

    /// Sinking (off by default; sim::Scene turns it on): a frozen ragdoll with no active object near it for half a
    /// second leaves the world behind one static, contact-free box (Ragdoll::sunk), so 1000 resting ragdolls are
    /// 1000 objects in Bullet's per-step loops, not 15,000. Its bodies come back (frozen) when an active object's
    /// bounding box meets the box, and on an impulse, setBodyStates or wake(). While sunk, the world's queries
    /// (ray tests, contact tests) see the box, whose user pointer is the Ragdoll, not its bodies: a game that
    /// ray-tests resting ragdolls calls Ragdoll::surface() on a hit box first, or leaves sinking off.
    void setSinking(bool on) { m_sinking = on; }
    /// Whether sinking is on (setSinking).
    bool sinking() const { return m_sinking; }

    /// The ragdoll spawned through this world that `object` belongs to (one of its bodies, or the box of a sunk
    /// ragdoll), or null: what a ray or contact test hit (then Ragdoll::figureBodyOf for the body).
    Ragdoll* ragdollOf(const btCollisionObject* object) const;

  private:
    // What a ragdoll tells the world it was spawned through (its destructor, a guard's restore, a level of detail's
    // new Bullet objects, a sunk ragdoll's box destroyed): src/bullet/RagdollWorldLink.h, the one way in.
    friend class detail::RagdollWorldLink;
    // A ragdoll joins the world (spawn).
    void attach(Ragdoll& ragdoll);
    // Unregisters a ragdoll (its destructor).
    void detach(Ragdoll& ragdoll);
    // Forgets the ragdoll's warm-started joint impulses (its explosion guard restored it).
    void restartWarmStarting(Ragdoll& ragdoll);
    // Forget the ragdoll's Bullet bodies and constraints before it replaces them, and learn the new ones after
    // (Ragdoll::setLod); it keeps its place.
    void detachBodies(Ragdoll& ragdoll);
    // Learns the ragdoll's new Bullet bodies and constraints (the second half of detachBodies).
    void attachBodies(Ragdoll& ragdoll);
    // A collision object of the ragdoll's (a sunk ragdoll's box) leaves the world and is destroyed.
    void forget(const btCollisionObject* object) { m_goneObjects.push_back(object); }

    class PositionAction;
    class MergedBodies;
    void addOwners(Ragdoll& ragdoll, int index);
    void trackJoints(Ragdoll& ragdoll);
    void untrackJoints(Ragdoll& ragdoll); ///< what trackJoints tracked, no longer
    void markSpeculative(Ragdoll& ragdoll);

    btDiscreteDynamicsWorld& m_world;
    Method m_method;
    EngineContactFriction m_friction;
    std::vector<Ragdoll*> m_ragdolls; ///< in spawn order
    bool m_sinking = false;           ///< see setSinking
    /// A ragdoll body: which ragdoll owns it and its bounding radius (for the speculative reach), fixed at spawn.
    struct BodyOwner {
        const btCollisionObject* body;
        int ragdoll; ///< index into m_ragdolls
        btScalar boundingRadius;
    };
    /// The ragdoll bodies of the world by address: open addressing with linear probing, at most half taken. Asked
    /// for every contact pair and manifold each step, so a lookup is one or two probes.
    class OwnerTable {
      public:
        const BodyOwner* find(const btCollisionObject* body) const;
        void insert(const BodyOwner& owner); ///< a body already present keeps its entry
        /// Removes ragdoll `index`'s bodies (appended to `gone`); later ragdolls' indices go down by one when
        /// `renumber`.
        void removeRagdoll(int index, bool renumber, std::vector<const btCollisionObject*>& gone);

      private:
        std::size_t slotOf(const btCollisionObject* body) const;
        void rehash();
        std::vector<BodyOwner> m_slots; ///< body null: empty; the size a power of two
        std::size_t m_count = 0;        ///< live entries
        std::size_t m_removed = 0;      ///< slots of removed entries (kept until the next rehash)
        int m_shift = 64;               ///< 64 − log2(slots)
    };
    OwnerTable m_owners;
    const BodyOwner* ownerOf(const btCollisionObject* body) const { return m_owners.find(body); }
    /// How far a ragdoll body's surface can move in `dt` seconds (0 for other objects), metres.
    btScalar reachOf(const btCollisionObject* body, btScalar dt) const;
    /// The contact breaking threshold of a manifold between `a` and `b` for a substep of `dt` (speculative contacts).
    btScalar breakingThreshold(const btCollisionObject* a, const btCollisionObject* b, btScalar dt) const;
    /// The substeps of a frame of `dtSeconds`: the method's, or more for a fast impact (Method::impactSubsteps).
    int substepsFor(double dtSeconds) const;
    int m_lastSubsteps = 1;
    /// Ragdoll collision objects destroyed since the last step. Bullet keeps the last step's speculative (CCD)
    /// manifolds until the next step begins, and they may still name them: substepsFor skips those manifolds
    /// without reading the objects.
    std::vector<const btCollisionObject*> m_goneObjects;
    std::unique_ptr<PositionAction> m_action;
    std::unique_ptr<MergedBodies> m_mergedBodies; ///< contacts of merged bodies (Method::mergeFixed), child by child
};

/// A dynamics world and its solver, as makeWorld makes them (destroy the world first).
struct WorldParts {
    std::unique_ptr<btConstraintSolver> solver;     ///< the world's constraint solver (a RagdollSolver or Bullet's)
    std::unique_ptr<btDiscreteDynamicsWorld> world; ///< the dynamics world, using `solver`
};

/// The world a method's backend needs, on the caller's collision parts: for Backend::Multibody a
/// btMultiBodyDynamicsWorld with Bullet's btMultiBodyConstraintSolver (rigid-body ragdolls and the game's rigid
/// bodies work in it too, with Bullet's solver), otherwise a btDiscreteDynamicsWorld with a RagdollSolver.
WorldParts makeWorld(const Method& method, btDispatcher& dispatcher, btBroadphaseInterface& broadphase,
                     btCollisionConfiguration& configuration);

/// Sets a world's solver to a method's world-level knobs (what RagdollWorld does at construction). With
/// Method::directJoints it also makes the world solve one island at a time (btContactSolverInfo's
/// m_minimumSolverBatchSize = 1), so that no island's result depends on which others were batched with it; a later
/// call with another method leaves that setting as it is.
void applyWorldKnobs(btDynamicsWorld& world, const Method& method);

} // namespace afb::bullet
