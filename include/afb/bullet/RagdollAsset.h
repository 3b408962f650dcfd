#pragma once
// The Bullet half of a Figure that every live Ragdoll shares: collision shapes, built once.
#include <memory>
#include <utility>
#include <vector>

#include <btBulletDynamicsCommon.h>

#include "afb/figure/Figure.h"

namespace afb::bullet {

/// Largest collision margin used, metres. Margins never make a body fatter than its polytope: a hull is shrunk
/// by its margin first (each face plane moved inward), so shrunk hull ⊕ margin sphere lies inside the polytope,
/// touching every face; btBoxShape keeps its margin inside its half extents by construction. The margin is
/// min(kMaxMarginM, 0.2 × the smallest distance from the centre of mass to a face).
inline constexpr double kMaxMarginM = 0.01;

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
    /// tests them for contact. Computed once per figure (issue 12).
    const std::vector<std::pair<int, int>>& prunedPairs() const { return m_prunedPairs; }

  private:
    explicit RagdollAsset(figure::Figure figure) : m_figure(std::move(figure)) {}
    figure::Figure m_figure;
    std::vector<std::unique_ptr<btCollisionShape>> m_shapes;
    std::vector<double> m_margins;
    std::vector<double> m_innerRadii;
    std::vector<std::pair<int, int>> m_contactPairs;
    std::vector<std::pair<int, int>> m_prunedPairs;
};

} // namespace afb::bullet
