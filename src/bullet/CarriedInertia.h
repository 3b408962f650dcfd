// The inertia a joint motor carries (docs/motors.md, "Strength"): internal to the rigid backend's motors.
#pragma once

#include <span>
#include <utility>
#include <vector>

#include <Eigen/Dense>
#include <btBulletDynamicsCommon.h>

namespace afb::bullet::detail {

/// For each joint of a figure whose rigid bodies form a tree, the inverse inertia that the joint's relative
/// rotation meets when every other joint holds: each side of the joint (the bodies beyond it and the rest) as one
/// rigid composite about the joint's pivot, W = Σ I_side⁻¹ over the sides free to turn. A side is held (left out)
/// when one of its bodies does not move under forces (a keyframed or static body: inverse mass 0) or is jointed to
/// the world; when both sides are held, the parts of both that do move count instead (the pelvis between two
/// keyframed legs carries the upper body). A joint on a loop of the figure, or with nothing that moves on either
/// side, has none (its motor keeps the inertia of its two bodies).
class CarriedInertia {
  public:
    /// One joint: its two rigid bodies (b = −1: the world).
    struct Joint {
        int a = -1, b = -1;
    };
    /// Lays out the tree over `rigids` bodies from rigid 0 (every joint a connection, motor or not; a figure in
    /// several parts is a forest, each part rooted at its first rigid).
    void reset(int rigids, std::span<const Joint> joints);
    /// W of joint `j` about world point `pivot` with the bodies as they are now, 1/(kg·m²), world axes; false
    /// (and `w` unset) when the joint has none. update() must have run since the bodies last moved.
    bool inverseInertia(int j, const btVector3& pivot, btMatrix3x3& w) const;
    /// The bodies' masses, centres of mass and inertia now, summed over every subtree of the tree.
    void update(std::span<btRigidBody* const> bodies);

  private:
    // A sum of bodies: the mass, first and second moments of those that move about the reference point (rigid 0's
    // centre of mass at update()), and how many are held.
    struct Sum {
        double mass = 0;
        Eigen::Vector3d first = Eigen::Vector3d::Zero();
        Eigen::Matrix3d second = Eigen::Matrix3d::Zero(); ///< Σ I_b + m_b (|x|² 1 − x xᵀ)
        int held = 0;
        Sum& operator+=(const Sum& o);
        Sum operator-(const Sum& o) const;
        Eigen::Matrix3d about(const Eigen::Vector3d& x) const; ///< the inertia about point x
    };
    std::vector<Joint> m_joints;    ///< as reset() took them
    std::vector<int> m_order;       ///< rigids in breadth-first order from rigid 0
    std::vector<int> m_parent;      ///< per rigid, its parent in the tree (−1: a root)
    std::vector<int> m_root;        ///< per rigid, the root of its part of the figure (its connected bodies)
    std::vector<int> m_child;       ///< per joint, the rigid whose subtree is its far side (−1: none)
    std::vector<int> m_worldJoints; ///< per rigid, how many joints hold it to the world
    std::vector<Sum> m_subtree;     ///< per rigid, its own body and everything below it in the tree
    Eigen::Vector3d m_reference = Eigen::Vector3d::Zero();
};

} // namespace afb::bullet::detail
