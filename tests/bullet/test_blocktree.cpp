// BlockTree (src/bullet/BlockTree.h), the block LDLᵀ behind the direct joint solve, against a dense solve of the
// same matrix by Eigen: random trees (fixed seed) whose blocks have a ragdoll's signs (positive-definite body
// blocks, negative-definite joint blocks, a body–joint coupling per edge), node sizes from 1 to 9 so that both the
// fixed-size kernels (≤ 6) and the general path run, sparse right-hand sides (the zero-skip in the forward pass),
// and the inputs it must refuse.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Dense>

#include "bullet/BlockTree.h"

using afb::bullet::BlockTree;

namespace {

// A random symmetric definite d × d block: A Aᵀ + d·I, negated when `negative`.
Eigen::MatrixXd definite(int d, bool negative, std::mt19937& rng) {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Eigen::MatrixXd a(d, d);
    for (int r = 0; r < d; ++r)
        for (int c = 0; c < d; ++c) a(r, c) = u(rng);
    Eigen::MatrixXd m = a * a.transpose() + d * Eigen::MatrixXd::Identity(d, d);
    return negative ? Eigen::MatrixXd(-m) : m;
}

struct Case {
    std::vector<int> dims, parent;
    Eigen::MatrixXd dense;
};

// Nodes alternate body (positive) and joint (negative) by depth, as in a ragdoll rooted at a body.
Case randomTree(int nodes, std::mt19937& rng) {
    Case c;
    std::uniform_int_distribution<int> size(1, 9);
    std::vector<int> depth;
    for (int i = 0; i < nodes; ++i) {
        c.dims.push_back(size(rng));
        const int p = i == 0 ? -1 : std::uniform_int_distribution<int>(0, i - 1)(rng);
        c.parent.push_back(p);
        depth.push_back(p < 0 ? 0 : depth[static_cast<std::size_t>(p)] + 1);
    }
    std::vector<int> offset;
    int n = 0;
    for (int d : c.dims) {
        offset.push_back(n);
        n += d;
    }
    c.dense = Eigen::MatrixXd::Zero(n, n);
    std::uniform_real_distribution<double> u(-0.5, 0.5);
    for (int i = 0; i < nodes; ++i) {
        const auto k = static_cast<std::size_t>(i);
        c.dense.block(offset[k], offset[k], c.dims[k], c.dims[k]) = definite(c.dims[k], depth[k] % 2 == 1, rng);
        const int p = c.parent[k];
        if (p < 0) continue;
        const auto q = static_cast<std::size_t>(p);
        Eigen::MatrixXd e(c.dims[k], c.dims[q]);
        for (int r = 0; r < e.rows(); ++r)
            for (int col = 0; col < e.cols(); ++col) e(r, col) = u(rng);
        c.dense.block(offset[k], offset[q], c.dims[k], c.dims[q]) = e;
        c.dense.block(offset[q], offset[k], c.dims[q], c.dims[k]) = e.transpose();
    }
    return c;
}

// Writes every entry of every block of `c` into a tree laid out for it.
void fill(BlockTree& tree, const Case& c) {
    for (int i = 0; i < tree.nodes(); ++i) {
        const int d = tree.dim(i);
        double* diag = tree.diag(i);
        for (int r = 0; r < d; ++r)
            for (int col = 0; col < d; ++col) diag[r * d + col] = c.dense(tree.offset(i) + r, tree.offset(i) + col);
        const int p = tree.parent(i);
        if (p < 0) continue;
        const int dp = tree.dim(p);
        double* edge = tree.toParent(i);
        for (int r = 0; r < d; ++r)
            for (int col = 0; col < dp; ++col) edge[r * dp + col] = c.dense(tree.offset(i) + r, tree.offset(p) + col);
    }
}

bool load(BlockTree& tree, const Case& c) {
    if (!tree.reset(c.dims, c.parent)) return false;
    fill(tree, c);
    return true;
}

} // namespace

TEST_CASE("block tree: solves match a dense solve on random ragdoll-signed trees", "[bullet][blocktree]") {
    std::mt19937 rng(20261123);
    for (int trial = 0; trial < 40; ++trial) {
        const int nodes = 1 + trial % 25;
        const Case c = randomTree(nodes, rng);
        BlockTree tree;
        REQUIRE(load(tree, c));
        REQUIRE(tree.size() == c.dense.rows());
        REQUIRE(tree.factor());
        const Eigen::PartialPivLU<Eigen::MatrixXd> lu(c.dense);
        std::uniform_real_distribution<double> u(-1.0, 1.0);
        for (int rhs = 0; rhs < 3; ++rhs) {
            // rhs 0: dense; 1: one node's entries only; 2: one entry.
            Eigen::VectorXd b = Eigen::VectorXd::Zero(c.dense.rows());
            const int node = std::uniform_int_distribution<int>(0, nodes - 1)(rng);
            for (int k = 0; k < b.size(); ++k) {
                const bool inNode = k >= tree.offset(node) && k < tree.offset(node) + tree.dim(node);
                if (rhs == 0 || (rhs == 1 && inNode) || (rhs == 2 && k == tree.offset(node))) b[k] = u(rng);
            }
            Eigen::VectorXd x = b;
            tree.solve(x.data());
            const Eigen::VectorXd expected = lu.solve(b);
            INFO("trial " << trial << ", " << nodes << " nodes, size " << b.size() << ", rhs " << rhs);
            CHECK((c.dense * x - b).norm() <= 1e-10 * (1.0 + b.norm()));
            CHECK((x - expected).norm() <= 1e-9 * (1.0 + expected.norm()));
        }
    }
}

TEST_CASE("block tree: a solve from one or two nodes equals the full solve to the bit", "[bullet][blocktree]") {
    // solveFrom walks only the two nodes' paths to the root in its forward half; off them the full solve finds
    // zeros and skips. Both must give the same numbers, bit for bit (a direct solve's column, at one body or two),
    // in a forest too (the second node in the other tree).
    std::mt19937 rng(20261129);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int trial = 0; trial < 30; ++trial) {
        const int nodes = 2 + trial % 20;
        const Case c = randomTree(nodes, rng);
        BlockTree tree;
        REQUIRE(load(tree, c));
        REQUIRE(tree.factor());
        std::uniform_int_distribution<int> pick(0, nodes - 1);
        for (int rhs = 0; rhs < 4; ++rhs) {
            const int a = pick(rng), b = rhs == 0 ? -1 : rhs == 1 ? a : pick(rng);
            Eigen::VectorXd x = Eigen::VectorXd::Zero(c.dense.rows());
            for (int node : {a, b}) {
                if (node < 0) continue;
                for (int k = 0; k < tree.dim(node); ++k) x[tree.offset(node) + k] += u(rng);
            }
            const Eigen::VectorXd b0 = x;
            Eigen::VectorXd full = x;
            tree.solve(full.data());
            tree.solveFrom(x.data(), a, b);
            INFO("trial " << trial << ", nodes " << a << " and " << b);
            for (Eigen::Index k = 0; k < x.size(); ++k) REQUIRE(x[k] == full[k]);
            CHECK((c.dense * x - b0).norm() <= 1e-10 * (1.0 + b0.norm()));
        }
    }
}

TEST_CASE("block tree: a forest solves each tree on its own", "[bullet][blocktree]") {
    std::mt19937 rng(7);
    Case a = randomTree(6, rng), b = randomTree(4, rng);
    Case c;
    c.dims = a.dims;
    c.parent = a.parent;
    for (std::size_t i = 0; i < b.dims.size(); ++i) {
        c.dims.push_back(b.dims[i]);
        c.parent.push_back(b.parent[i] < 0 ? -1 : b.parent[i] + static_cast<int>(a.dims.size()));
    }
    const auto na = a.dense.rows(), nb = b.dense.rows();
    c.dense = Eigen::MatrixXd::Zero(na + nb, na + nb);
    c.dense.topLeftCorner(na, na) = a.dense;
    c.dense.bottomRightCorner(nb, nb) = b.dense;
    BlockTree tree;
    REQUIRE(load(tree, c));
    REQUIRE(tree.factor());
    Eigen::VectorXd rhs = Eigen::VectorXd::LinSpaced(na + nb, -1.0, 1.0);
    Eigen::VectorXd x = rhs;
    tree.solve(x.data());
    CHECK((c.dense * x - rhs).norm() <= 1e-10);
}

TEST_CASE("block tree: refuses cycles, bad sizes and singular pivots", "[bullet][blocktree]") {
    BlockTree tree;
    const std::vector<int> three{3, 3, 3};
    CHECK_FALSE(tree.reset(three, std::vector<int>{1, 2, 0})); // a cycle, no root
    CHECK_FALSE(tree.factor());
    CHECK_FALSE(tree.reset(three, std::vector<int>{-1, 0, 2})); // its own parent
    CHECK_FALSE(tree.reset(three, std::vector<int>{-1, 0, 5})); // out of range
    CHECK_FALSE(tree.reset(three, std::vector<int>{-1, 0}));    // sizes disagree
    CHECK_FALSE(tree.reset(std::vector<int>{3, 0}, std::vector<int>{-1, 0}));
    CHECK_FALSE(tree.reset(std::vector<int>{3, 25}, std::vector<int>{-1, 0}));

    // A zero pivot: the child's block is singular.
    REQUIRE(tree.reset(std::vector<int>{2, 2}, std::vector<int>{-1, 0}));
    double* d0 = tree.diag(0);
    d0[0] = d0[3] = 1.0;
    double* d1 = tree.diag(1);
    d1[0] = 1.0; // d1[3] stays 0: rank 1
    CHECK_FALSE(tree.factor());

    // A Schur complement that vanishes: H = [1 1; 1 1] as two 1 × 1 nodes.
    REQUIRE(tree.reset(std::vector<int>{1, 1}, std::vector<int>{-1, 0}));
    tree.diag(0)[0] = 1.0;
    tree.diag(1)[0] = 1.0;
    tree.toParent(1)[0] = 1.0;
    CHECK_FALSE(tree.factor());
}

TEST_CASE("block tree: a reset to the same layout zeroes the blocks and solves as a fresh tree",
          "[bullet][blocktree]") {
    std::mt19937 rng(11);
    const Case first = randomTree(12, rng);
    Case second = first; // the same layout, other values (the blocks' signs kept)
    second.dense *= 1.5;
    const Case other = randomTree(5, rng);
    std::vector<double> b(static_cast<std::size_t>(first.dense.rows()));
    for (std::size_t k = 0; k < b.size(); ++k) b[k] = std::sin(double(k));
    BlockTree fresh;
    REQUIRE(load(fresh, second));
    REQUIRE(fresh.factor());
    std::vector<double> expected = b;
    fresh.solve(expected.data());

    BlockTree reused;
    for (const Case* before : {&first, &other}) { // the same layout last time, or another one
        REQUIRE(load(reused, *before));
        REQUIRE(reused.factor());
        REQUIRE(reused.reset(second.dims, second.parent));
        for (int i = 0; i < reused.nodes(); ++i) {
            const int d = reused.dim(i), p = reused.parent(i);
            for (int k = 0; k < d * d; ++k) CHECK(reused.diag(i)[k] == 0.0);
            for (int k = 0; p >= 0 && k < d * reused.dim(p); ++k) CHECK(reused.toParent(i)[k] == 0.0);
        }
        REQUIRE(load(reused, second));
        REQUIRE(reused.factor());
        std::vector<double> x = b;
        reused.solve(x.data());
        CHECK(x == expected); // bit for bit
    }
}

TEST_CASE("block tree: leaves given their inverse solve as leaves given their block", "[bullet][blocktree]") {
    // A body without child joints has its own block as its pivot: the caller may hand in its inverse (a body's M⁻¹
    // as Bullet keeps it) and factor() takes it as is. Any node with children refuses one.
    std::mt19937 rng(29);
    for (int trial = 0; trial < 10; ++trial) {
        const Case c = randomTree(4 + trial, rng);
        BlockTree plain, given;
        REQUIRE(load(plain, c));
        REQUIRE(plain.factor());
        REQUIRE(load(given, c));
        int leaves = 0;
        for (int i = 0; i < given.nodes(); ++i) {
            bool hasChild = false;
            for (int k = 0; k < given.nodes(); ++k) hasChild = hasChild || given.parent(k) == i;
            CHECK(given.leaf(i) == !hasChild);
            if (!given.leaf(i)) continue;
            const int d = given.dim(i), at = given.offset(i);
            const Eigen::MatrixXd inverse = c.dense.block(at, at, d, d).inverse();
            for (int r = 0; r < d; ++r)
                for (int col = 0; col < d; ++col) given.diag(i)[r * d + col] = inverse(col, r); // transposed
            given.setInverted(i);
            ++leaves;
        }
        REQUIRE(leaves > 0);
        REQUIRE(given.factor());
        Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(c.dense.rows(), -2.0, 3.0);
        Eigen::VectorXd x = b, y = b;
        plain.solve(x.data());
        given.solve(y.data());
        INFO("trial " << trial);
        CHECK((c.dense * y - b).norm() <= 1e-10 * (1.0 + b.norm()));
        CHECK((x - y).norm() <= 1e-9 * (1.0 + x.norm()));
    }
    BlockTree tree;
    REQUIRE(tree.reset(std::vector<int>{1, 1}, std::vector<int>{-1, 0}));
    tree.diag(0)[0] = 1.0;
    tree.diag(1)[0] = -1.0;
    tree.toParent(1)[0] = 0.5;
    CHECK_FALSE(tree.leaf(0));
    tree.setInverted(0); // the root has a child: its pivot is not its block
    CHECK_FALSE(tree.factor());
}

TEST_CASE("block tree: a pivot's inverse is symmetric to the bit", "[bullet][blocktree]") {
    // One node of each size: its inverse (the root's pivot, read back after factor()) is computed once per pair of
    // entries, so it is exactly symmetric, and it inverts the block.
    std::mt19937 rng(5);
    for (int d = 1; d <= 9; ++d) {
        const Eigen::MatrixXd m = definite(d, d % 2 == 0, rng);
        BlockTree tree;
        REQUIRE(tree.reset(std::vector<int>{d}, std::vector<int>{-1}));
        for (int r = 0; r < d; ++r)
            for (int c = 0; c < d; ++c) tree.diag(0)[r * d + c] = m(r, c);
        REQUIRE(tree.factor());
        Eigen::MatrixXd inverse(d, d);
        for (int r = 0; r < d; ++r)
            for (int c = 0; c < d; ++c) inverse(r, c) = tree.diag(0)[r * d + c];
        INFO("size " << d);
        CHECK(inverse == inverse.transpose());
        CHECK((m * inverse - Eigen::MatrixXd::Identity(d, d)).norm() <= 1e-12 * d);
    }
}

TEST_CASE("block tree: a reset that keeps the blocks solves as a fresh tree once every entry is written",
          "[bullet][blocktree]") {
    // reset(..., false) skips zeroing for a caller that writes every block (the direct solve, the position tree).
    std::mt19937 rng(13);
    const Case first = randomTree(9, rng);
    Case second = first;
    second.dense *= 0.75;
    std::vector<double> b(static_cast<std::size_t>(first.dense.rows()), 0.5);
    BlockTree fresh;
    REQUIRE(load(fresh, second));
    REQUIRE(fresh.factor());
    std::vector<double> expected = b;
    fresh.solve(expected.data());
    BlockTree reused;
    REQUIRE(load(reused, first));
    REQUIRE(reused.factor());
    REQUIRE(reused.reset(second.dims, second.parent, false));
    fill(reused, second);
    REQUIRE(reused.factor());
    std::vector<double> x = b;
    reused.solve(x.data());
    CHECK(x == expected);
}
