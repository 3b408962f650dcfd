// Block-tree LDLᵀ (BlockTree.h).
#include "BlockTree.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <utility>

namespace afb::bullet {
namespace {

constexpr int kMaxDim = 24;  // a body is 6, a joint at most 6 rows per constraint (a few constraints per pair)
constexpr int kUnrolled = 6; // blocks up to 6 × 6 get kernels of fixed size (a ragdoll's every block)

// The solve's two steps at one node of dimension d (parent dp; dp = 0 for a root): forward, w = D⁻¹ x_i,
// x_i = w, x_p −= Eᵀ w; backward, x_i −= G x_p. D⁻¹ and G are stored transposed (factor()), so that both products
// run down contiguous columns, a lane per row (each row's sum is still taken in the order of its terms).
// Fixed-size instances are unrolled by the compiler.
template <int D, int P>
void forwardFixed(const double* __restrict inverseT, const double* __restrict e, double* __restrict xi,
                  double* __restrict xp) {
    double w[D] = {};
    for (int q = 0; q < D; ++q) {
        const double x = xi[q];
        for (int r = 0; r < D; ++r) w[r] += inverseT[q * D + r] * x;
    }
    for (int r = 0; r < D; ++r) xi[r] = w[r];
    for (int q = 0; q < D; ++q)
        for (int c = 0; c < P; ++c) xp[c] -= e[q * P + c] * w[q];
}

template <int D, int P>
void backwardFixed(const double* __restrict gT, const double* __restrict xp, double* __restrict xi) {
    double v[D] = {};
    for (int c = 0; c < P; ++c) {
        const double x = xp[c];
        for (int r = 0; r < D; ++r) v[r] += gT[c * D + r] * x;
    }
    for (int r = 0; r < D; ++r) xi[r] -= v[r];
}

void forwardAny(int d, int dp, const double* __restrict inverseT, const double* __restrict e, double* __restrict xi,
                double* __restrict xp) {
    double w[kMaxDim] = {};
    for (int q = 0; q < d; ++q) {
        const double x = xi[q];
        for (int r = 0; r < d; ++r) w[r] += inverseT[q * d + r] * x;
    }
    std::copy(w, w + d, xi);
    for (int q = 0; q < d; ++q)
        for (int c = 0; c < dp; ++c) xp[c] -= e[q * dp + c] * w[q];
}

void backwardAny(int d, int dp, const double* __restrict gT, const double* __restrict xp, double* __restrict xi) {
    double v[kMaxDim] = {};
    for (int c = 0; c < dp; ++c) {
        const double x = xp[c];
        for (int r = 0; r < d; ++r) v[r] += gT[c * d + r] * x;
    }
    for (int r = 0; r < d; ++r) xi[r] -= v[r];
}

using Forward = void (*)(const double*, const double*, double*, double*);
using Backward = void (*)(const double*, const double*, double*);

template <int D, int... P>
constexpr std::array<Forward, sizeof...(P)> forwardRow(std::integer_sequence<int, P...>) {
    return {&forwardFixed<D + 1, P>...};
}
template <int D, int... P>
constexpr std::array<Backward, sizeof...(P)> backwardRow(std::integer_sequence<int, P...>) {
    return {&backwardFixed<D + 1, P>...};
}
template <int... D>
constexpr auto forwardTable(std::integer_sequence<int, D...>) {
    return std::array{forwardRow<D>(std::make_integer_sequence<int, kUnrolled + 1>{})...};
}
template <int... D>
constexpr auto backwardTable(std::integer_sequence<int, D...>) {
    return std::array{backwardRow<D>(std::make_integer_sequence<int, kUnrolled + 1>{})...};
}
// [d − 1][dp]: d in 1…6, dp in 0…6.
constexpr auto kForward = forwardTable(std::make_integer_sequence<int, kUnrolled>{});
constexpr auto kBackward = backwardTable(std::make_integer_sequence<int, kUnrolled>{});

} // namespace

bool BlockTree::reset(std::span<const int> dims, std::span<const int> parent, bool zeroBlocks) {
    const std::size_t n = dims.size();
    // The same layout as last time (a figure's joints from step to step): only the blocks need zeroing.
    if (n == m_dim.size() && parent.size() == n && m_order.size() == n && std::ranges::equal(dims, m_dim) &&
        std::ranges::equal(parent, m_parent)) {
        if (zeroBlocks) std::fill(m_blocks.begin(), m_blocks.end(), 0.0);
        std::fill(m_inverted.begin(), m_inverted.end(), 0);
        return true;
    }
    m_dim.assign(dims.begin(), dims.end());
    m_parent.assign(parent.begin(), parent.end());
    m_offset.assign(n, 0);
    m_diagAt.assign(n, 0);
    m_edgeAt.assign(n, 0);
    m_gainAt.assign(n, 0);
    m_leaf.assign(n, 1);
    m_inverted.assign(n, 0);
    m_order.clear();
    m_steps.clear();
    m_pathOf.clear();
    m_size = 0;
    if (parent.size() != n) return false;
    std::size_t blocks = 0, gains = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const int p = m_parent[i];
        if (m_dim[i] <= 0 || m_dim[i] > kMaxDim || p < -1 || p >= static_cast<int>(n) || p == static_cast<int>(i))
            return false;
        m_offset[i] = m_size;
        m_size += m_dim[i];
        m_diagAt[i] = blocks;
        blocks += static_cast<std::size_t>(m_dim[i] * m_dim[i]);
        m_edgeAt[i] = blocks;
        m_gainAt[i] = gains;
        if (p >= 0) {
            blocks += static_cast<std::size_t>(m_dim[i] * m_dim[static_cast<std::size_t>(p)]);
            gains += static_cast<std::size_t>(m_dim[i] * m_dim[static_cast<std::size_t>(p)]);
        }
    }
    if (zeroBlocks) m_blocks.assign(blocks, 0.0);
    else m_blocks.resize(blocks);
    m_gain.resize(gains); // written whole by factor()
    // Post-order from every root: children before their parent. A node on a cycle is never reached.
    std::vector<std::vector<int>>& children = m_children;
    if (children.size() < n) children.resize(n);
    for (std::size_t i = 0; i < n; ++i) children[i].clear();
    for (std::size_t i = 0; i < n; ++i)
        if (m_parent[i] >= 0) {
            children[static_cast<std::size_t>(m_parent[i])].push_back(static_cast<int>(i));
            m_leaf[static_cast<std::size_t>(m_parent[i])] = 0;
        }
    std::vector<std::pair<int, std::size_t>>& stack = m_stack;
    stack.clear();
    for (std::size_t r = 0; r < n; ++r) {
        if (m_parent[r] >= 0) continue;
        stack.push_back({static_cast<int>(r), 0});
        while (!stack.empty()) {
            auto& [node, next] = stack.back();
            const auto& kids = children[static_cast<std::size_t>(node)];
            if (next < kids.size()) {
                const int child = kids[next++];
                stack.push_back({child, 0});
            } else {
                m_order.push_back(node);
                stack.pop_back();
            }
        }
    }
    if (m_order.size() != n) return false;
    for (const int i : m_order) {
        const std::size_t k = static_cast<std::size_t>(i);
        const int p = m_parent[k];
        const std::size_t q = p < 0 ? 0 : static_cast<std::size_t>(p);
        m_steps.push_back({m_dim[k], p < 0 ? 0 : m_dim[q], m_offset[k], p < 0 ? 0 : m_offset[q], m_diagAt[k],
                           m_edgeAt[k], m_gainAt[k]});
    }
    layPaths();
    return true;
}

void BlockTree::layPaths() {
    // Each node's way to its root in steps: a parent's step comes after its children's.
    const std::size_t n = m_order.size();
    std::vector<int> stepOf(n);
    for (std::size_t k = 0; k < n; ++k) stepOf[static_cast<std::size_t>(m_order[k])] = static_cast<int>(k);
    m_pathOf.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        std::vector<int>& path = m_pathOf[i];
        path.clear();
        for (int j = static_cast<int>(i); j >= 0; j = m_parent[static_cast<std::size_t>(j)])
            path.push_back(stepOf[static_cast<std::size_t>(j)]);
    }
}

namespace {

// The inverse of a symmetric definite (positive or negative) d × d matrix `a`, row-major, by LDLᵀ without
// pivoting (a definite matrix needs none), written transposed (solve()'s layout; the inverse is symmetric, so
// the two layouts hold the same numbers). False when a pivot is zero or not finite. `a` is read only until the inverse
// is written, so the two may be the same block. D > 0: a fixed size (unrolled), D = 0: `n`.
template <int D>
bool invertDefinite(const double* a, int n, double* inverse) {
    const int d = D > 0 ? D : n;
    double l[(D > 0 ? D : kMaxDim) * (D > 0 ? D : kMaxDim)]; // only its strict lower triangle is used
    double diag[D > 0 ? D : kMaxDim];
    for (int j = 0; j < d; ++j) {
        double dj = a[j * d + j];
        for (int k = 0; k < j; ++k) dj -= l[j * d + k] * l[j * d + k] * diag[k];
        if (!(std::abs(dj) > 0) || !std::isfinite(dj)) return false;
        diag[j] = dj;
        for (int i = j + 1; i < d; ++i) {
            double v = a[i * d + j];
            for (int k = 0; k < j; ++k) v -= l[i * d + k] * l[j * d + k] * diag[k];
            l[i * d + j] = v / dj;
        }
    }
    // Column c of the inverse from row c down: L y = e_c (y is zero above row c), y /= D, Lᵀ x = y (row i needs
    // only the rows below it). The inverse is symmetric: the entries above the diagonal are mirrored, a third of
    // the work of solving every column whole.
    for (int c = 0; c < d; ++c) {
        double y[D > 0 ? D : kMaxDim];
        for (int i = c; i < d; ++i) {
            double v = i == c ? 1.0 : 0.0;
            for (int k = c; k < i; ++k) v -= l[i * d + k] * y[k];
            y[i] = v;
        }
        for (int i = c; i < d; ++i) y[i] /= diag[i];
        for (int i = d - 1; i >= c; --i) {
            double v = y[i];
            for (int k = i + 1; k < d; ++k) v -= l[k * d + i] * inverse[c * d + k];
            inverse[c * d + i] = v; // transposed: column c of the inverse is row c here
        }
        for (int i = 0; i < c; ++i) inverse[c * d + i] = inverse[i * d + c];
    }
    for (int k = 0; k < d * d; ++k)
        if (!std::isfinite(inverse[k])) return false;
    return true;
}

// One child's elimination: G = D⁻¹ E (the backward pass's gain, written transposed), and the parent's pivot loses
// Eᵀ G. D⁻¹ comes transposed (invertDefinite). D, P > 0: fixed sizes (unrolled), 0: `dn`, `pn`.
template <int D, int P>
void eliminate(const double* inverseT, const double* e, double* gT, double* parentPivot, int dn, int pn) {
    const int d = D > 0 ? D : dn, dp = P > 0 ? P : pn;
    for (int r = 0; r < d; ++r)
        for (int c = 0; c < dp; ++c) {
            double v = 0;
            for (int q = 0; q < d; ++q) v += inverseT[q * d + r] * e[q * dp + c];
            gT[c * d + r] = v;
        }
    for (int r = 0; r < dp; ++r)
        for (int c = 0; c < dp; ++c) {
            double v = 0;
            for (int q = 0; q < d; ++q) v += e[q * dp + r] * gT[c * d + q];
            parentPivot[r * dp + c] -= v;
        }
}

using Invert = bool (*)(const double*, int, double*);
using Eliminate = void (*)(const double*, const double*, double*, double*, int, int);

template <int... D>
constexpr std::array<Invert, sizeof...(D)> invertTable(std::integer_sequence<int, D...>) {
    return {&invertDefinite<D + 1>...};
}
template <int D, int... P>
constexpr std::array<Eliminate, sizeof...(P)> eliminateRow(std::integer_sequence<int, P...>) {
    return {&eliminate<D + 1, P + 1>...};
}
template <int... D>
constexpr auto eliminateTable(std::integer_sequence<int, D...>) {
    return std::array{eliminateRow<D>(std::make_integer_sequence<int, kUnrolled>{})...};
}
// [d − 1], [d − 1][dp − 1]: d, dp in 1…6.
constexpr auto kInvert = invertTable(std::make_integer_sequence<int, kUnrolled>{});
constexpr auto kEliminate = eliminateTable(std::make_integer_sequence<int, kUnrolled>{});

} // namespace

bool BlockTree::factor() {
    if (m_order.size() != m_dim.size()) return false;
    for (const int i : m_order) {
        const std::size_t k = static_cast<std::size_t>(i);
        const int d = m_dim[k];
        double* pivot = m_blocks.data() + m_diagAt[k];
        if (m_inverted[k]) {
            if (!m_leaf[k]) return false;
        } else {
            const bool inverted = d <= kUnrolled ? kInvert[static_cast<std::size_t>(d - 1)](pivot, d, pivot)
                                                 : invertDefinite<0>(pivot, d, pivot);
            if (!inverted) return false;
        }
        const int p = m_parent[k];
        if (p < 0) continue;
        const int dp = m_dim[static_cast<std::size_t>(p)];
        const double* e = m_blocks.data() + m_edgeAt[k];
        double* g = m_gain.data() + m_gainAt[k];
        double* parentPivot = m_blocks.data() + m_diagAt[static_cast<std::size_t>(p)];
        if (d <= kUnrolled && dp <= kUnrolled)
            kEliminate[static_cast<std::size_t>(d - 1)][static_cast<std::size_t>(dp - 1)](pivot, e, g, parentPivot, d,
                                                                                          dp);
        else eliminate<0, 0>(pivot, e, g, parentPivot, d, dp);
    }
    return true;
}

// Inlined into both solves (out of line, a call per node made `default` 0.7 % dearer).
[[gnu::always_inline]] inline void BlockTree::forwardAt(const Step& s, double* x) const {
    // Forward (L z = b) and diagonal (w = D⁻¹ z) at one node, which hands its part to its parent. A node whose
    // part is still zero hands nothing.
    const int d = s.dim, dp = s.parentDim;
    double* xi = x + s.offset;
    bool zero = true;
    for (int r = 0; r < d && zero; ++r) zero = xi[r] == 0.0;
    if (zero) return;
    double* xp = dp == 0 ? nullptr : x + s.parentOffset;
    const double* inverseT = m_blocks.data() + s.diagAt;
    const double* e = m_blocks.data() + s.edgeAt;
    if (d <= kUnrolled && dp <= kUnrolled)
        kForward[static_cast<std::size_t>(d - 1)][static_cast<std::size_t>(dp)](inverseT, e, xi, xp);
    else forwardAny(d, dp, inverseT, e, xi, xp);
}

[[gnu::always_inline]] inline void BlockTree::backward(double* x) const {
    // Backward (Lᵀ x = w): parents first, x_i −= G_i x_p.
    for (auto it = m_steps.rbegin(); it != m_steps.rend(); ++it) {
        const Step& s = *it;
        const int d = s.dim, dp = s.parentDim;
        if (dp == 0) continue;
        const double* gT = m_gain.data() + s.gainAt;
        const double* xp = x + s.parentOffset;
        double* xi = x + s.offset;
        if (d <= kUnrolled && dp <= kUnrolled)
            kBackward[static_cast<std::size_t>(d - 1)][static_cast<std::size_t>(dp)](gT, xp, xi);
        else backwardAny(d, dp, gT, xp, xi);
    }
}

void BlockTree::solve(double* x) const {
    // Children first; a right-hand side at one body touches only its path to the root.
    for (const Step& s : m_steps) forwardAt(s, x);
    backward(x);
}

void BlockTree::solveFrom(double* x, int a, int b) const {
    // The steps on either path, in elimination order (each path is; their union keeps it). Off the paths every
    // part stays zero, which solve() would find and skip.
    std::vector<int>& walk = m_walk;
    walk.clear();
    static const std::vector<int> kNone;
    const std::vector<int>& pa = a >= 0 ? m_pathOf[static_cast<std::size_t>(a)] : kNone;
    const std::vector<int>& pb = b >= 0 ? m_pathOf[static_cast<std::size_t>(b)] : kNone;
    std::set_union(pa.begin(), pa.end(), pb.begin(), pb.end(), std::back_inserter(walk));
    for (const int k : walk) forwardAt(m_steps[static_cast<std::size_t>(k)], x);
    backward(x);
}

} // namespace afb::bullet
