// A block LDLᵀ factorisation of a symmetric matrix whose block graph is a tree (or a forest): Baraff's linear-time
// elimination ("Linear-time dynamics using Lagrange multipliers", SIGGRAPH 1996). Internal to the bullet layer:
// the direct joint solve (RagdollSolver) builds one per ragdoll from its bodies and joints.
#pragma once

#include <span>
#include <utility>
#include <vector>

namespace afb::bullet {

/// H x = b for a symmetric H made of square diagonal blocks H_ii (node i of dimension d_i) and one off-diagonal
/// block H_{i,p(i)} (d_i × d_{p(i)}, and its transpose) per tree edge, factored once and solved in O(Σ d_i²)
/// without fill-in. Every pivot D_i = H_ii − Σ_children H_{c,i}ᵀ D_c⁻¹ H_{c,i} must be invertible; the bodies and
/// joints of a ragdoll give positive-definite body pivots and negative-definite joint pivots when the tree is
/// rooted at a body or at the one joint that holds the figure to the world.
class BlockTree {
  public:
    /// Lays out nodes of the given dimensions and parents (−1: a root); blocks are zeroed, unless `zeroBlocks` is
    /// false (a caller that writes every entry of every block). False (and unusable) when `parent` has a cycle or
    /// an out-of-range index.
    bool reset(std::span<const int> dims, std::span<const int> parent, bool zeroBlocks = true);

    int nodes() const { return static_cast<int>(m_dim.size()); }
    int dim(int i) const { return m_dim[static_cast<std::size_t>(i)]; }
    int parent(int i) const { return m_parent[static_cast<std::size_t>(i)]; }
    /// Offset of node i's entries in the vectors solve() takes, and their total size.
    int offset(int i) const { return m_offset[static_cast<std::size_t>(i)]; }
    int size() const { return m_size; }

    /// H_ii, row-major d_i × d_i; H_{i,p(i)}, row-major d_i × d_p. Filled by the caller before factor().
    double* diag(int i) { return m_blocks.data() + m_diagAt[static_cast<std::size_t>(i)]; }
    double* toParent(int i) { return m_blocks.data() + m_edgeAt[static_cast<std::size_t>(i)]; }

    /// Whether node i has no children: its pivot is its own block H_ii.
    bool leaf(int i) const { return m_leaf[static_cast<std::size_t>(i)] != 0; }
    /// Marks diag(i) as holding H_ii⁻¹ already (written by the caller, transposed as factor() leaves a pivot's
    /// inverse), for a leaf whose inverse is known (a body's M⁻¹): factor() then skips inverting it. Cleared by
    /// reset(); factor() fails when the node is not a leaf.
    void setInverted(int i) { m_inverted[static_cast<std::size_t>(i)] = 1; }

    /// Factors in place (the diagonal blocks become the pivots' inverses, stored transposed for solve()). False
    /// when a pivot is singular or not finite (every pivot must be definite, of either sign: no pivoting is done).
    bool factor();
    /// Solves H x = b in place (x holds b on entry, laid out by offset()).
    void solve(double* x) const;
    /// solve() for a b that is zero outside nodes `a` and `b` (−1: none; a column of one row at one or two
    /// bodies): the forward half walks only their paths to the root, the rest of which it would find zero, and
    /// does the same arithmetic there as solve(), so the result is solve()'s to the bit.
    void solveFrom(double* x, int a, int b) const;

  private:
    // What solve() needs of a node, in m_order (parentDim 0: a root).
    struct Step {
        int dim, parentDim, offset, parentOffset;
        std::size_t diagAt, edgeAt, gainAt;
    };
    void layPaths(); // m_pathOf, from m_order and m_parent (reset())
    void forwardAt(const Step& s, double* x) const;
    void backward(double* x) const;
    std::vector<Step> m_steps;
    std::vector<std::vector<int>> m_pathOf; // per node: the steps from it to its root, in elimination order
    mutable std::vector<int> m_walk;        // solveFrom's scratch
    std::vector<int> m_dim, m_parent, m_offset, m_order; // m_order: every node after its children
    std::vector<std::size_t> m_diagAt, m_edgeAt, m_gainAt;
    std::vector<char> m_leaf, m_inverted;
    std::vector<double> m_blocks, m_gain;             // m_gain: (D_i⁻¹ H_{i,p(i)})ᵀ per edge, after factor()
    std::vector<std::vector<int>> m_children;         // reset()'s scratch, kept for its capacity
    std::vector<std::pair<int, std::size_t>> m_stack; // (node, next child)
    int m_size = 0;
};

} // namespace afb::bullet
