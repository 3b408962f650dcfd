// The exact joint solve of one ragdoll in joint space: the system BlockTree solves, M Δv = f + Jᵀλ and J Δv = e
// (no compliance), for a tree of bodies held by point joints whose rotation is free about some axes and locked about
// the others (ball, universal, hinge). Each joint's free motions are eliminated from the leaves to the root
// (Featherstone's articulated-body recursion, in impulse form): every body carries the inertia of the subtree
// below it as its joint lets that subtree move, so no body needs a 6×6 inverse but the root and every solve works
// on the joints' free motions (1 to 3 per joint) rather than on their rows (3 to 5). A joint may also carry soft
// angular rows (motors: J Δv + cfm·λ = e), which act on its free motions as an implicit spring and damper. Internal
// to the bullet layer.
#pragma once

#include <span>
#include <vector>

#include <Eigen/Dense>

namespace afb::bullet {

class ArticulatedTree {
  public:
    using Vec6 = Eigen::Matrix<double, 6, 1>; ///< linear then angular, as a solver row stores them
    using Mat6 = Eigen::Matrix<double, 6, 6>;

    /// A body: its mass and its inertia tensor in the world (about its centre of mass).
    struct Body {
        double mass = 0;
        Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
    };
    /// A joint row: its Jacobian at body `a` and at body `b` (linear, angular); −1 for a side that is not one of
    /// the bodies (the world, or a body held still for this solve).
    struct Row {
        int a = -1, b = -1;
        Vec6 ja = Vec6::Zero(), jb = Vec6::Zero();
        double cfm = 0; ///< compliance, velocity per unit impulse: above 0, a soft row (J Δv + cfm·λ = e)
    };

    /// Takes the bodies and the rows. False, and unusable, unless the rows of each body pair are one point joint
    /// (three rows whose linear parts span space and whose angular parts are the anchor's lever arms on both sides)
    /// plus at most two rows locking rotation (angular only, opposite on the two sides) and at most three soft rows
    /// of the same shape (a motor), and the pairs join the bodies into one tree held to the world by at most one
    /// joint. The caller then keeps the general solve.
    bool build(std::span<const Body> bodies, std::span<const Row> rows);
    /// The articulated inertias of the bodies' current masses and rows. False when one is not positive definite.
    bool factor();
    /// Fixes the rows' targets `e` (one per row, in build()'s order) for project(): each joint's particular motion
    /// and the impulse it passes to its parent are taken once, not at every projection.
    void setTargets(std::span<const double> e);
    /// The velocity changes `dv` (6 per body) replaced by the nearest, in the mass metric, that meet setTargets'
    /// targets: M dv′ = M dv + Jᵀλ and J dv′ = e. No row's velocity is read: an iteration that restores the joints
    /// costs one pass up and one down. (For impulses f, project M⁻¹f: M dv′ = f + Jᵀλ.) With soft rows, `lambda`
    /// (one per row) holds their accumulated impulses, already in M dv: each soft row then meets
    /// J dv′ + cfm·(λ + Δλ) = e and its entry becomes λ + Δλ. The other entries are neither read nor written.
    void project(std::span<double> dv, std::span<double> lambda = {}) const;

    /// M Δv = f + Jᵀλ, J Δv + C λ = 0 for impulses `fa` on body a and `fb` on body b (−1: none), without the joints'
    /// impulses: a row's column through the figure. Only the paths from a and b to the root carry the impulses up.
    void solveImpulse(int a, const Vec6& fa, int b, const Vec6& fb, std::span<double> dv) const;
    /// The joint rows' impulses λ from the bodies' velocity changes `dv` and every other impulse `f` they took (6 per
    /// body each), by each body's momentum: M dv = f + Jᵀλ. The soft rows' entries are read (project()'s), the others
    /// written.
    void jointImpulses(std::span<const double> f, std::span<const double> dv, std::span<double> lambda) const;

    int bodies() const { return static_cast<int>(m_mass.size()); }

  private:
    // One joint, stored at its child body, in order from the root (a parent before its children).
    struct Joint {
        int parent = -1, child = -1;                        // parent −1: the world
        int free = 0;                                       // free rotations (3 − locked)
        int pairRows[8] = {-1, -1, -1, -1, -1, -1, -1, -1}; // the rows of the body pair, in their order
        int pairCount = 0;
        int rows[5] = {-1, -1, -1, -1, -1}; // the three anchor rows, then the locked ones
        int locked = 0;
        // Soft rows (a motor): their rows, axes at the child (u, the child side's angular Jacobian) and compliances;
        // setTargets(): their targets and Σ u uᵀ c / cfm over them (c the particular motion's turn).
        int soft[3] = {-1, -1, -1};
        int softCount = 0;
        Eigen::Matrix3d softAxis;
        double softCfm[3] = {0, 0, 0};
        double softTarget[3] = {0, 0, 0};
        Eigen::Vector3d softBias = Eigen::Vector3d::Zero();
        Eigen::Vector3d rc, d;         // the child's lever arm to its anchor; the shift from parent to child
        Eigen::Matrix3d nInv;          // inverse of the anchor rows' directions (columns) at the child
        Eigen::Matrix<double, 3, 2> u; // locked axes at the child
        Eigen::Matrix2d uGram;         // (UᵀU)⁻¹ of the locked axes
        Eigen::Matrix<double, 6, 3> s; // the free motions of the child (first `free` columns)
        // factor(): the inertia the joint passes to the parent (before the shift), and the solves' kernels.
        Mat6 passed;
        struct Kernels {     // laid out for the solves' loops, which sum scaled columns (each entry in its order)
            double kp[6][3]; // (D⁻¹ Sᵀ)ᵀ
            double k[6][3];  // (D⁻¹ (I S)ᵀ)ᵀ
            double is[3][6]; // (I S)ᵀ: column i of I S
            double s[3][6];  // Sᵀ: free motion i
        } kernels{};
    };
    template <int F>
    bool factorJoint(Joint& j);
    template <int F, bool Soft>
    void upJoint(const Joint& j, const Vec6* passedOffset, const Eigen::Vector3d* yOffset) const;
    template <int F>
    void downJoint(const Joint& j, const double* w, double* out) const;
    // `offsets`: per body, the particular motion of its joint and (`passedOffsets`) the impulse that passes on;
    // `yOffsets`: per body, its soft rows' part of the free motions; null: no targets.
    template <bool Soft = false>
    void up(const Joint& j, const std::vector<Vec6>* passedOffsets,
            const std::vector<Eigen::Vector3d>* yOffsets = nullptr) const;
    // Per joint with soft rows, before a projection: their part of the free motions, D⁻¹ Sᵀ Σ u (e − cfm·λ)/cfm
    // less the particular motion's (m_softY); after it, their impulses.
    void softOffsets(std::span<const double> lambda) const;
    void softImpulses(std::span<const double> dv, std::span<double> lambda) const;
    void down(std::span<double> dv, const std::vector<Vec6>* offsets) const;
    bool orient(std::span<const Row> rows);
    bool shapeJoint(Joint& j, std::span<const Row> rows);
    Vec6 particular(const Joint& j, std::span<const double> e) const;
    void impulses(const Joint& j, const Vec6& g, std::span<double> lambda) const;

    std::vector<int> m_key; // the layout build() last oriented: the bodies' count, then each row's two bodies
    bool m_valid = false;
    std::vector<double> m_mass;
    std::vector<Eigen::Matrix3d> m_inertia;
    std::vector<Joint> m_joints;                // root first
    std::vector<int> m_jointOf;                 // per body: its joint (−1: the free root)
    int m_root = -1;                            // the free root body (−1: the tree hangs from the world)
    std::vector<Mat6> m_ia;                     // factor(): articulated inertias
    Mat6 m_rootInverse;                         // factor(): the free root's articulated inertia, inverted
    mutable std::vector<Vec6> m_p, m_pt;        // the solves' scratch: bias impulses, their part through the joint
    std::vector<Vec6> m_target, m_targetPassed; // setTargets(): particular motions, and what they pass on
    bool m_hasTargets = false;
    int m_softRows = 0;                           // build(): rows with a compliance
    mutable std::vector<Eigen::Vector3d> m_softY; // softOffsets(), per body
    mutable std::vector<Eigen::Vector3d> m_y;     // D⁻¹ Sᵀ p per joint
    mutable std::vector<char> m_onPath;           // solveImpulse()'s bodies on a path to the root
};

} // namespace afb::bullet
