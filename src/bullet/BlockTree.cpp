// Block-tree LDLᵀ (BlockTree.h).
#include "BlockTree.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

namespace afb::bullet {
namespace {

constexpr int kMaxDim = 24;  // a body is 6, a joint at most 6 rows per constraint (a few constraints per pair)
constexpr int kUnrolled = 6; // blocks up to 6 × 6 get kernels of fixed size (a ragdoll's every block)

// The solve's two steps at one node of dimension d (parent dp; dp = 0 for a root): forward, w = D⁻¹ x_i,
// x_i = w, x_p −= Eᵀ w; backward, x_i −= G x_p. Fixed-size instances are unrolled by the compiler.
template <int D, int P>
void forwardFixed(const double* inverse, const double* e, double* xi, double* xp) {
    double w[D];
    for (int r = 0; r < D; ++r) {
        double v = 0;
        for (int q = 0; q < D; ++q) v += inverse[r * D + q] * xi[q];
        w[r] = v;
    }
    for (int r = 0; r < D; ++r) xi[r] = w[r];
    for (int q = 0; q < D; ++q)
        for (int c = 0; c < P; ++c) xp[c] -= e[q * P + c] * w[q];
}

template <int D, int P>
void backwardFixed(const double* g, const double* xp, double* xi) {
    for (int r = 0; r < D; ++r) {
        double v = 0;
        for (int c = 0; c < P; ++c) v += g[r * P + c] * xp[c];
        xi[r] -= v;
    }
}

void forwardAny(int d, int dp, const double* inverse, const double* e, double* xi, double* xp) {
    double w[kMaxDim];
    for (int r = 0; r < d; ++r) {
        double v = 0;
        for (int q = 0; q < d; ++q) v += inverse[r * d + q] * xi[q];
        w[r] = v;
    }
    std::copy(w, w + d, xi);
    for (int q = 0; q < d; ++q)
        for (int c = 0; c < dp; ++c) xp[c] -= e[q * dp + c] * w[q];
}

void backwardAny(int d, int dp, const double* g, const double* xp, double* xi) {
    for (int r = 0; r < d; ++r) {
        double v = 0;
        for (int c = 0; c < dp; ++c) v += g[r * dp + c] * xp[c];
        xi[r] -= v;
    }
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

bool BlockTree::reset(std::span<const int> dims, std::span<const int> parent) {
    const std::size_t n = dims.size();
    m_dim.assign(dims.begin(), dims.end());
    m_parent.assign(parent.begin(), parent.end());
    m_offset.assign(n, 0);
    m_diagAt.assign(n, 0);
    m_edgeAt.assign(n, 0);
    m_gainAt.assign(n, 0);
    m_order.clear();
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
    m_blocks.assign(blocks, 0.0);
    m_gain.assign(gains, 0.0);
    // Post-order from every root: children before their parent. A node on a cycle is never reached.
    std::vector<std::vector<int>> children(n);
    for (std::size_t i = 0; i < n; ++i)
        if (m_parent[i] >= 0) children[static_cast<std::size_t>(m_parent[i])].push_back(static_cast<int>(i));
    std::vector<std::pair<int, std::size_t>> stack;
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
    return m_order.size() == n;
}

namespace {

// The inverse of a symmetric definite (positive or negative) d × d matrix `a`, row-major, by LDLᵀ without
// pivoting (a definite matrix needs none). False when a pivot is zero or not finite.
bool invertDefinite(const double* a, int d, double* inverse) {
    double l[kMaxDim * kMaxDim] = {};
    double diag[kMaxDim];
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
    // Column c of the inverse: L y = e_c, y /= D, Lᵀ x = y.
    for (int c = 0; c < d; ++c) {
        double y[kMaxDim];
        for (int i = 0; i < d; ++i) {
            double v = i == c ? 1.0 : 0.0;
            for (int k = 0; k < i; ++k) v -= l[i * d + k] * y[k];
            y[i] = v;
        }
        for (int i = 0; i < d; ++i) y[i] /= diag[i];
        for (int i = d - 1; i >= 0; --i) {
            double v = y[i];
            for (int k = i + 1; k < d; ++k) v -= l[k * d + i] * inverse[k * d + c];
            inverse[i * d + c] = v;
        }
    }
    for (int k = 0; k < d * d; ++k)
        if (!std::isfinite(inverse[k])) return false;
    return true;
}

} // namespace

bool BlockTree::factor() {
    if (m_order.size() != m_dim.size()) return false;
    double inverse[kMaxDim * kMaxDim];
    for (const int i : m_order) {
        const std::size_t k = static_cast<std::size_t>(i);
        const int d = m_dim[k];
        double* pivot = m_blocks.data() + m_diagAt[k];
        if (!invertDefinite(pivot, d, inverse)) return false;
        std::copy(inverse, inverse + d * d, pivot);
        const int p = m_parent[k];
        if (p < 0) continue;
        const int dp = m_dim[static_cast<std::size_t>(p)];
        const double* e = m_blocks.data() + m_edgeAt[k];
        double* g = m_gain.data() + m_gainAt[k];
        // G = D⁻¹ E (the backward pass's gain); the parent's pivot loses Eᵀ G.
        for (int r = 0; r < d; ++r)
            for (int c = 0; c < dp; ++c) {
                double v = 0;
                for (int q = 0; q < d; ++q) v += pivot[r * d + q] * e[q * dp + c];
                g[r * dp + c] = v;
            }
        double* parentPivot = m_blocks.data() + m_diagAt[static_cast<std::size_t>(p)];
        for (int r = 0; r < dp; ++r)
            for (int c = 0; c < dp; ++c) {
                double v = 0;
                for (int q = 0; q < d; ++q) v += e[q * dp + r] * g[q * dp + c];
                parentPivot[r * dp + c] -= v;
            }
    }
    return true;
}

void BlockTree::solve(double* x) const {
    // Forward (L z = b) and diagonal (w = D⁻¹ z): children first, each hands its part to its parent. A node
    // whose part is still zero hands nothing (a right-hand side at one body touches only its path to the root).
    for (const int i : m_order) {
        const std::size_t k = static_cast<std::size_t>(i);
        const int d = m_dim[k];
        double* xi = x + m_offset[k];
        bool zero = true;
        for (int r = 0; r < d && zero; ++r) zero = xi[r] == 0.0;
        if (zero) continue;
        const int p = m_parent[k];
        const int dp = p < 0 ? 0 : m_dim[static_cast<std::size_t>(p)];
        double* xp = p < 0 ? nullptr : x + m_offset[static_cast<std::size_t>(p)];
        const double* inverse = m_blocks.data() + m_diagAt[k];
        const double* e = m_blocks.data() + m_edgeAt[k];
        if (d <= kUnrolled && dp <= kUnrolled)
            kForward[static_cast<std::size_t>(d - 1)][static_cast<std::size_t>(dp)](inverse, e, xi, xp);
        else forwardAny(d, dp, inverse, e, xi, xp);
    }
    // Backward (Lᵀ x = w): parents first, x_i −= G_i x_p.
    for (auto it = m_order.rbegin(); it != m_order.rend(); ++it) {
        const std::size_t k = static_cast<std::size_t>(*it);
        const int p = m_parent[k];
        if (p < 0) continue;
        const int d = m_dim[k], dp = m_dim[static_cast<std::size_t>(p)];
        const double* g = m_gain.data() + m_gainAt[k];
        const double* xp = x + m_offset[static_cast<std::size_t>(p)];
        double* xi = x + m_offset[k];
        if (d <= kUnrolled && dp <= kUnrolled)
            kBackward[static_cast<std::size_t>(d - 1)][static_cast<std::size_t>(dp)](g, xp, xi);
        else backwardAny(d, dp, g, xp, xi);
    }
}

} // namespace afb::bullet
