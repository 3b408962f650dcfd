#pragma once
// The Bullet half of a Figure that every live Ragdoll shares: collision shapes, built once.
#include <atomic>
#include <cstddef>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include <btBulletDynamicsCommon.h>

#include "afb/figure/Figure.h"
#include "afb/figure/Lod.h"

namespace afb::bullet {

/// Largest collision margin used, metres. Margins never make a body fatter than its polytope: a hull is shrunk
/// by its margin first (each face plane moved inward), so shrunk hull ⊕ margin sphere lies inside the polytope,
/// touching every face; btBoxShape keeps its margin inside its half extents by construction. The margin is
/// min(kMaxMarginM, 0.2 × the smallest distance from the centre of mass to a face).
inline constexpr double kMaxMarginM = 0.01;

/// How a ragdoll's figure bodies become Bullet rigid bodies: one each, or with the bodies joined by `fixed`
/// constraints merged into one (Method::mergeFixed). Computed once per figure, shared by every instance.
struct RigidLayout {
    /// One Bullet rigid body.
    struct Rigid {
        std::vector<int> bodies; ///< the figure bodies it carries, ascending
        /// The heaviest of them (lowest index on ties): its friction, damping and restitution are the rigid's.
        int representative = 0;
        double massKg = 0;                                     ///< the sum of its bodies' masses, kg
        Eigen::Vector3d inertiaKgM2 = Eigen::Vector3d::Zero(); ///< principal moments (figure::combineRigidParts)
        /// The rigid's frame (centre of mass, principal axes), model space, at the load pose; for a level of detail
        /// (RagdollAsset::layoutAt, Ragdoll::setLod), world space at the switch.
        figure::Transform loadPose;
        btCollisionShape* shape = nullptr; ///< the body's own shape, or a btCompoundShape of its bodies' (the asset's)
        /// Radius of its continuous-collision sphere: the smallest inner radius of its bodies, metres.
        double innerRadius = 0;
        /// Bullet's bounding sphere radius of the shape (btCollisionShape::getBoundingSphere), metres.
        double boundingRadius = 0;
    };
    std::vector<Rigid> rigids;                  ///< the Bullet rigid bodies, ordered by their first figure body
    std::vector<int> rigidOf;                   ///< per figure body: index into rigids
    std::vector<figure::Transform> bodyInRigid; ///< per figure body: its body frame in its rigid's frame
    std::vector<btTransform> bodyInRigidBt;     ///< the same in Bullet's precision
    /// Rigid pairs (i < j, ascending) that test contact: those with a figure pair in RagdollAsset::contactPairs.
    std::vector<std::pair<int, int>> contactPairs;
    /// The same less the figure pairs in RagdollAsset::overlappingPairs (Method::exemptOverlapping): a rigid pair
    /// stays when one of its figure pairs is not overlapping.
    std::vector<std::pair<int, int>> contactPairsApart;
    /// The rigid pairs (i < j, ascending) that never collide: those not in contactPairs, and those joined by a
    /// constraint that disables collision between its bodies (as Bullet's constraint references would have them).
    std::vector<std::pair<int, int>> ignoredPairs;
    /// The same with contactPairsApart in place of contactPairs (Method::exemptOverlapping).
    std::vector<std::pair<int, int>> ignoredPairsApart;
    /// Whether figure constraint `i` joins two bodies of one rigid (then it has no Bullet constraint).
    std::vector<bool> internal;
};

/// A figure plus its Bullet collision shapes. Immutable once made; share it between any number of ragdolls
/// (one per Bullet precision: this type is compiled against the linked Bullet's btScalar).
class RagdollAsset {
  public:
    /// Builds the shapes of every body of `figure`.
    static std::shared_ptr<const RagdollAsset> create(figure::Figure figure);

    RagdollAsset(const RagdollAsset&) = delete;
    RagdollAsset& operator=(const RagdollAsset&) = delete;

    /// The figure the shapes belong to.
    const figure::Figure& figure() const { return m_figure; }
    /// Collision shape of body `body`, in the body frame (centre of mass, principal axes).
    btCollisionShape* shape(int body) const { return m_shapes[static_cast<std::size_t>(body)].get(); }
    /// The margin the shape of body `body` uses, metres.
    double margin(int body) const { return m_margins[static_cast<std::size_t>(body)]; }
    /// Distance from the centre of mass of body `body` to its nearest face, metres (its inscribed radius about
    /// the centre of mass): the radius of its continuous-collision sphere.
    double innerRadius(int body) const { return m_innerRadii[static_cast<std::size_t>(body)]; }
    /// Self-collision pairs (i < j, ascending) a ragdoll tests for contact: figure::selfCollisionPairs less the
    /// prunedPairs().
    const std::vector<std::pair<int, int>>& contactPairs() const { return m_contactPairs; }
    /// Self-collision pairs the figure's joints keep apart (ascending): along every joint path between the two
    /// bodies, within the joints' limits widened by 10° each, they stay more than 2 cm apart, so a ragdoll never
    /// tests them for contact. Computed once per figure.
    const std::vector<std::pair<int, int>>& prunedPairs() const { return m_prunedPairs; }
    /// The contactPairs() whose bodies overlap by more than figure::kTouchToleranceM at the load pose (ascending).
    /// Their contact fights the joints from the first step, and when the limits do not let them separate it never
    /// ends (the AF guide's warning; `afb inspect` reports each); under Method::exemptOverlapping (every preset
    /// but legacy) they do not collide, as Jolt's RagdollSettings::DisableParentChildCollisions does for pairs
    /// overlapping in the pose it is given, and as `afb gen` does for the figures it writes.
    const std::vector<std::pair<int, int>>& overlappingPairs() const { return m_overlappingPairs; }
    /// The figure's bodies as Bullet rigid bodies: one each, or (`mergeFixed`) with bodies joined by `fixed`
    /// constraints between two bodies merged into one compound.
    const RigidLayout& layout(bool mergeFixed) const { return mergeFixed ? m_merged : m_separate; }
    /// A level of detail's layout (Ragdoll::setLod): one rigid per group of `level`, each a compound of its bodies'
    /// shapes placed as `poses` (every body's frame, in one frame: the rigids' frames come out in it) places them,
    /// with the exact combined mass properties at those poses. Compound shapes it makes are appended to `compounds`
    /// (the caller owns them; they must outlive the layout). `level` must be a partition of the figure's bodies.
    RigidLayout layoutAt(const figure::LodLevel& level, std::span<const figure::Transform> poses,
                         std::vector<std::unique_ptr<btCollisionShape>>& compounds) const;

  private:
    // Ragdoll sizes each instance's arena from what earlier instances took.
    friend class Ragdoll;
    // Bytes and objects one instance's Bullet objects took (the most of any instance so far; 0 before the
    // first): Ragdoll sizes its arena from it. Thread-safe.
    std::pair<std::size_t, std::size_t> instanceArenaHint() const {
        return {m_arenaBytes.load(std::memory_order_relaxed), m_arenaObjects.load(std::memory_order_relaxed)};
    }
    // Records what one instance's Bullet objects took, raising instanceArenaHint. Thread-safe.
    void noteInstanceArena(std::size_t bytes, std::size_t objects) const {
        for (std::size_t seen = m_arenaBytes.load(std::memory_order_relaxed);
             bytes > seen && !m_arenaBytes.compare_exchange_weak(seen, bytes, std::memory_order_relaxed);) {
        }
        for (std::size_t seen = m_arenaObjects.load(std::memory_order_relaxed);
             objects > seen && !m_arenaObjects.compare_exchange_weak(seen, objects, std::memory_order_relaxed);) {
        }
    }

    explicit RagdollAsset(figure::Figure figure) : m_figure(std::move(figure)) {}
    figure::Figure m_figure;
    std::vector<std::unique_ptr<btCollisionShape>> m_shapes;
    std::vector<double> m_margins;
    std::vector<double> m_innerRadii;
    std::vector<std::pair<int, int>> m_contactPairs;
    std::vector<std::pair<int, int>> m_prunedPairs;
    std::vector<std::pair<int, int>> m_overlappingPairs;
    std::vector<std::unique_ptr<btCollisionShape>> m_compounds; ///< of m_merged's rigids of several bodies
    RigidLayout m_separate;
    RigidLayout m_merged;
    mutable std::atomic<std::size_t> m_arenaBytes{0}, m_arenaObjects{0}; ///< see instanceArenaHint
    void buildLayout(RigidLayout& layout, bool mergeFixed);
    void fillLayout(RigidLayout& layout, const std::vector<std::vector<int>>& groups,
                    std::span<const figure::Transform> poses,
                    std::vector<std::unique_ptr<btCollisionShape>>& compounds) const;
};

} // namespace afb::bullet
