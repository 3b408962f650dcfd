// ArticulatedTree (src/bullet/ArticulatedTree.h), the joint-space form of the exact joint solve, against a dense
// solve of the same equations by Eigen: random trees (fixed seed) of bodies with random masses, inertias and
// places, held by ball, universal-like (one axis locked) and hinge-like (two locked) joints whose rows are built
// as a solver builds them (anchor rows along arbitrary directions, either body as the row's side A), some with soft
// angular rows (motors) on top, free or hung from the world; and the layouts it must refuse.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Dense>

#include "bullet/ArticulatedTree.h"

using afb::bullet::ArticulatedTree;
using Vec3 = Eigen::Vector3d;
using Vec6 = ArticulatedTree::Vec6;

namespace {

struct Figure {
    std::vector<ArticulatedTree::Body> bodies;
    std::vector<Vec3> centre;
    std::vector<ArticulatedTree::Row> rows;
};

Vec3 randomVec(std::mt19937& rng, double scale) {
    std::uniform_real_distribution<double> u(-scale, scale);
    return {u(rng), u(rng), u(rng)};
}

// The rows of a joint between `parent` (−1: the world) and `child` at `anchor`, locking `locked` rotation axes, and
// `soft` soft angular rows along arbitrary axes (a motor).
void addJoint(Figure& fig, int parent, int child, const Vec3& anchor, int locked, std::mt19937& rng, int soft = 0) {
    const Vec3 rc = anchor - fig.centre[static_cast<std::size_t>(child)];
    const Vec3 rp = parent >= 0 ? Vec3(anchor - fig.centre[static_cast<std::size_t>(parent)]) : Vec3::Zero();
    std::bernoulli_distribution coin(0.5);
    auto add = [&](const Vec6& jc, const Vec6& jp) {
        ArticulatedTree::Row r;
        if (coin(rng)) r = {child, parent, jc, jp};
        else r = {parent, child, jp, jc};
        fig.rows.push_back(r);
    };
    for (int i = 0; i < 3; ++i) { // anchor rows along arbitrary, independent directions
        Vec3 n = randomVec(rng, 1.0) + 2.0 * Vec3::Unit(i);
        if (coin(rng)) n = -n;
        Vec6 jc, jp;
        jc << n, rc.cross(n);
        jp << -n, -rp.cross(n);
        add(jc, jp);
    }
    for (int i = 0; i < locked; ++i) {
        const Vec3 u = randomVec(rng, 1.0) + 2.0 * Vec3::Unit(i);
        Vec6 jc, jp;
        jc << Vec3::Zero(), u;
        jp << Vec3::Zero(), -u;
        add(jc, jp);
    }
    for (int i = 0; i < soft; ++i) {
        const Vec3 u = randomVec(rng, 1.0);
        Vec6 jc, jp;
        jc << Vec3::Zero(), u;
        jp << Vec3::Zero(), -u;
        add(jc, jp);
        fig.rows.back().cfm = std::uniform_real_distribution<double>(0.01, 2.0)(rng);
    }
}

// `motors`: each joint gets 0 to 3 soft rows.
Figure randomFigure(int n, bool hung, std::mt19937& rng, bool motors = false) {
    Figure fig;
    std::uniform_real_distribution<double> mass(0.5, 70.0), axis(0.01, 2.0);
    for (int i = 0; i < n; ++i) {
        const Eigen::Matrix3d rot =
            Eigen::Quaterniond(
                Eigen::Vector4d(randomVec(rng, 1).x(), randomVec(rng, 1).y(), randomVec(rng, 1).z(), 1.0).normalized())
                .toRotationMatrix();
        const Vec3 diag(axis(rng), axis(rng), axis(rng));
        fig.bodies.push_back({mass(rng), rot * diag.asDiagonal() * rot.transpose()});
        fig.centre.push_back(randomVec(rng, 1.0));
    }
    std::uniform_int_distribution<int> locks(0, 2), softRows(0, 3);
    auto soft = [&] { return motors ? softRows(rng) : 0; };
    if (hung) addJoint(fig, -1, 0, randomVec(rng, 1.0), locks(rng), rng, soft());
    for (int i = 1; i < n; ++i) {
        const int parent = std::uniform_int_distribution<int>(0, i - 1)(rng);
        addJoint(fig, parent, i, randomVec(rng, 1.0), locks(rng), rng, soft());
    }
    return fig;
}

// [[M, −Jᵀ], [J, C]] [Δv; λ] = [f; e], densely (C: the rows' compliances).
Eigen::VectorXd denseSolve(const Figure& fig, const Eigen::VectorXd& f, const Eigen::VectorXd& e) {
    const int n = static_cast<int>(fig.bodies.size()), k = static_cast<int>(fig.rows.size());
    Eigen::MatrixXd h = Eigen::MatrixXd::Zero(6 * n + k, 6 * n + k);
    for (int i = 0; i < n; ++i) {
        h.block<3, 3>(6 * i, 6 * i) = fig.bodies[static_cast<std::size_t>(i)].mass * Eigen::Matrix3d::Identity();
        h.block<3, 3>(6 * i + 3, 6 * i + 3) = fig.bodies[static_cast<std::size_t>(i)].inertia;
    }
    for (int r = 0; r < k; ++r) {
        const ArticulatedTree::Row& row = fig.rows[static_cast<std::size_t>(r)];
        for (const auto& [body, j] : {std::pair{row.a, row.ja}, std::pair{row.b, row.jb}}) {
            if (body < 0) continue;
            h.block<6, 1>(6 * body, 6 * n + r) = -j;
            h.block<1, 6>(6 * n + r, 6 * body) = j.transpose();
        }
        h(6 * n + r, 6 * n + r) = row.cfm;
    }
    Eigen::VectorXd rhs(6 * n + k);
    rhs << f, e;
    return h.fullPivLu().solve(rhs);
}

// The tree of `fig`, built and factored.
ArticulatedTree factored(const Figure& fig) {
    ArticulatedTree tree;
    REQUIRE(tree.build(fig.bodies, fig.rows));
    REQUIRE(tree.factor());
    return tree;
}

// M⁻¹ f per body: the velocity changes that impulses `f` give the bodies on their own (what project() then holds to
// the joints: M Δv = f + Jᵀλ).
std::vector<double> freeMotion(const Figure& fig, const Eigen::VectorXd& f) {
    std::vector<double> dv(static_cast<std::size_t>(f.size()));
    for (std::size_t i = 0; i < fig.bodies.size(); ++i) {
        const auto& body = fig.bodies[i];
        const Eigen::Index at = 6 * static_cast<Eigen::Index>(i);
        Eigen::Map<Vec3>(dv.data() + at) = f.segment<3>(at) / body.mass;
        Eigen::Map<Vec3>(dv.data() + at + 3) = body.inertia.inverse() * f.segment<3>(at + 3);
    }
    return dv;
}

// A rod of mass m and length len along x, its centre at len/2, hung from the world by a hinge about z at its end
// (three anchor rows, x and y locked); with softCfm > 0, a soft row about z with that compliance too.
Figure hingedRod(double m, double len, double softCfm) {
    Figure fig;
    fig.bodies.push_back({m, Eigen::Vector3d(1e-3, m * len * len / 12, m * len * len / 12).asDiagonal()});
    fig.centre.push_back(Vec3(len / 2, 0, 0));
    const Vec3 rc(-len / 2, 0, 0);
    for (int i = 0; i < 3; ++i) {
        Vec6 j;
        j << Vec3::Unit(i), rc.cross(Vec3::Unit(i));
        fig.rows.push_back({0, -1, j, Vec6::Zero()});
    }
    for (int i = 0; i < (softCfm > 0 ? 3 : 2); ++i) {
        Vec6 j;
        j << Vec3::Zero(), Vec3::Unit(i);
        fig.rows.push_back({-1, 0, Vec6::Zero(), j, i == 2 ? softCfm : 0.0});
    }
    return fig;
}

} // namespace

TEST_CASE("articulated tree: projection and the joints' impulses from momentum give the dense solve's velocities "
          "and impulses",
          "[bullet][direct]") {
    // setTargets(e), project(M⁻¹f), jointImpulses(f, ·): M Δv = f + Jᵀλ, J Δv = e; set once, the targets serve
    // every projection.
    std::mt19937 rng(20261129);
    for (int trial = 0; trial < 60; ++trial) {
        const int n = 1 + trial % 15;
        const Figure fig = randomFigure(n, trial % 3 == 0, rng);
        ArticulatedTree tree = factored(fig);
        const int k = static_cast<int>(fig.rows.size());
        Eigen::VectorXd e(k);
        for (int i = 0; i < k; ++i) e[i] = trial % 5 == 4 ? 0.0 : std::uniform_real_distribution<double>(-1, 1)(rng);
        tree.setTargets(std::span<const double>(e.data(), static_cast<std::size_t>(k)));
        for (int round = 0; round < 2; ++round) {
            Eigen::VectorXd f(6 * n);
            for (int i = 0; i < 6 * n; ++i) f[i] = std::uniform_real_distribution<double>(-5, 5)(rng);
            std::vector<double> dv = freeMotion(fig, f), lambda(static_cast<std::size_t>(k));
            tree.project(dv);
            tree.jointImpulses(std::span<const double>(f.data(), static_cast<std::size_t>(6 * n)), dv, lambda);
            const Eigen::VectorXd ref = denseSolve(fig, f, e);
            const double scale = ref.cwiseAbs().maxCoeff();
            INFO("trial " << trial << " round " << round << ", " << n << " bodies, " << k << " rows");
            for (int i = 0; i < 6 * n; ++i)
                CHECK(dv[static_cast<std::size_t>(i)] == Approx(ref[i]).margin(1e-9 * scale));
            for (int r = 0; r < k; ++r)
                CHECK(lambda[static_cast<std::size_t>(r)] == Approx(ref[6 * n + r]).margin(1e-9 * scale));
            // The rows meet their targets.
            for (int r = 0; r < k; ++r) {
                const ArticulatedTree::Row& row = fig.rows[static_cast<std::size_t>(r)];
                double v = 0;
                for (const auto& [body, j] : {std::pair{row.a, row.ja}, std::pair{row.b, row.jb}})
                    if (body >= 0) v += j.dot(Eigen::Map<const Vec6>(dv.data() + 6 * body));
                CHECK(v == Approx(e[r]).margin(1e-9 * std::max(1.0, scale)));
            }
        }
    }
}

TEST_CASE("articulated tree: a body hung from the world by a hinge turns about the hinge alone", "[bullet][direct]") {
    // A rod of 2 kg, 1 m long along x, hinged about z at its end: an impulse of 1 N·s along y at its centre
    // turns it about the hinge with ω = J·p / (I_end) where I_end = m·L²/3, and moves its centre at ω·L/2.
    const double m = 2.0, len = 1.0;
    const Figure fig = hingedRod(m, len, 0);
    const ArticulatedTree tree = factored(fig);
    Eigen::VectorXd f(6);
    f << 0, 1, 0, 0, 0, 0;
    std::vector<double> dv = freeMotion(fig, f), lambda(5);
    tree.project(dv);
    tree.jointImpulses(std::span<const double>(f.data(), 6), dv, lambda);
    const double omega = (len / 2) * 1.0 / (m * len * len / 3);
    CHECK(dv[5] == Approx(omega));
    CHECK(dv[1] == Approx(omega * len / 2));
    for (const int i : {0, 2, 3, 4}) CHECK(dv[static_cast<std::size_t>(i)] == Approx(0).margin(1e-12));
    // The hinge pushes back along y with what the impulse does not spend on the rod's motion.
    CHECK(lambda[1] == Approx(m * omega * len / 2 - 1.0));
}

TEST_CASE("articulated tree: refuses what is not a tree of point joints", "[bullet][direct]") {
    std::mt19937 rng(7);
    SECTION("a loop") {
        Figure fig = randomFigure(3, false, rng);
        addJoint(fig, 1, 2, randomVec(rng, 1.0), 0, rng);
        ArticulatedTree tree;
        CHECK_FALSE(tree.build(fig.bodies, fig.rows));
    }
    SECTION("two joints to the world") {
        Figure fig = randomFigure(3, true, rng);
        addJoint(fig, -1, 2, randomVec(rng, 1.0), 0, rng);
        ArticulatedTree tree;
        CHECK_FALSE(tree.build(fig.bodies, fig.rows));
    }
    SECTION("a joint of two anchor rows") {
        Figure fig = randomFigure(2, false, rng);
        fig.rows.erase(fig.rows.begin());
        ArticulatedTree tree;
        CHECK_FALSE(tree.build(fig.bodies, fig.rows));
    }
    SECTION("anchor rows whose lever arms disagree") {
        Figure fig = randomFigure(2, false, rng);
        fig.rows[1].ja.tail<3>() += Vec3(0.1, 0, 0);
        ArticulatedTree tree;
        CHECK_FALSE(tree.build(fig.bodies, fig.rows));
    }
    SECTION("bodies no joint reaches") {
        Figure fig = randomFigure(3, false, rng);
        fig.bodies.push_back(fig.bodies.back());
        ArticulatedTree tree;
        CHECK_FALSE(tree.build(fig.bodies, fig.rows));
    }
}

TEST_CASE("articulated tree: the column of a row on one or two bodies is their impulses' projection",
          "[bullet][direct]") {
    std::mt19937 rng(42);
    for (int trial = 0; trial < 30; ++trial) {
        const int n = 2 + trial % 12;
        const Figure fig = randomFigure(n, trial % 4 == 0, rng);
        ArticulatedTree tree = factored(fig);
        const int k = static_cast<int>(fig.rows.size());
        tree.setTargets(std::vector<double>(static_cast<std::size_t>(k), 0.0));
        INFO("trial " << trial << ", " << n << " bodies");
        // A row between bodies a and b (b −1 on every third trial: a contact with the ground).
        const int a = std::uniform_int_distribution<int>(0, n - 1)(rng);
        const int b = trial % 3 == 0 ? -1 : std::uniform_int_distribution<int>(0, n - 1)(rng);
        const Vec6 fa = (Vec6() << randomVec(rng, 1), randomVec(rng, 1)).finished();
        const Vec6 fb = (Vec6() << randomVec(rng, 1), randomVec(rng, 1)).finished();
        Eigen::VectorXd f = Eigen::VectorXd::Zero(6 * n);
        f.segment<6>(6 * a) += fa;
        if (b >= 0) f.segment<6>(6 * b) += fb;
        std::vector<double> dv = freeMotion(fig, f), column(static_cast<std::size_t>(6 * n));
        tree.project(dv);
        tree.solveImpulse(a, fa, b, fb, column);
        for (int i = 0; i < 6 * n; ++i)
            CHECK(column[static_cast<std::size_t>(i)] == Approx(dv[static_cast<std::size_t>(i)]).margin(1e-12));
    }
}

TEST_CASE("articulated tree: soft rows (motors) give the dense solve of J dv + C lambda = e, from any impulse they "
          "took before",
          "[bullet][direct]") {
    // A soft row's impulse so far is already in the bodies' momentum: starting from M⁻¹(f + J_sᵀ λ0) with λ0 as the
    // soft rows' impulses, one projection reaches the dense solution of f alone, its soft impulses included, and a
    // second changes nothing. A row's column (solveImpulse) is the projection of its impulses with no targets.
    std::mt19937 rng(1129);
    for (int trial = 0; trial < 60; ++trial) {
        const int n = 1 + trial % 12;
        const Figure fig = randomFigure(n, trial % 3 == 0, rng, true);
        ArticulatedTree tree = factored(fig);
        const int k = static_cast<int>(fig.rows.size());
        INFO("trial " << trial << ", " << n << " bodies, " << k << " rows");
        Eigen::VectorXd e(k);
        for (int i = 0; i < k; ++i) e[i] = std::uniform_real_distribution<double>(-1, 1)(rng);
        tree.setTargets(std::span<const double>(e.data(), static_cast<std::size_t>(k)));
        Eigen::VectorXd f(6 * n);
        for (int i = 0; i < 6 * n; ++i) f[i] = std::uniform_real_distribution<double>(-5, 5)(rng);
        std::vector<double> lambda(static_cast<std::size_t>(k), 0.0);
        Eigen::VectorXd taken = f;
        for (int r = 0; r < k; ++r) {
            const ArticulatedTree::Row& row = fig.rows[static_cast<std::size_t>(r)];
            if (!(row.cfm > 0)) continue;
            lambda[static_cast<std::size_t>(r)] = std::uniform_real_distribution<double>(-3, 3)(rng);
            for (const auto& [body, j] : {std::pair{row.a, row.ja}, std::pair{row.b, row.jb}})
                if (body >= 0) taken.segment<6>(6 * body) += j * lambda[static_cast<std::size_t>(r)];
        }
        std::vector<double> dv = freeMotion(fig, taken);
        tree.project(dv, lambda);
        const Eigen::VectorXd ref = denseSolve(fig, f, e);
        const double scale = std::max(1.0, ref.cwiseAbs().maxCoeff());
        for (int i = 0; i < 6 * n; ++i) CHECK(dv[static_cast<std::size_t>(i)] == Approx(ref[i]).margin(1e-9 * scale));
        const std::vector<double> once = dv;
        tree.project(dv, lambda);
        for (int i = 0; i < 6 * n; ++i)
            CHECK(dv[static_cast<std::size_t>(i)] == Approx(once[static_cast<std::size_t>(i)]).margin(1e-9 * scale));
        tree.jointImpulses(std::span<const double>(f.data(), static_cast<std::size_t>(6 * n)), dv, lambda);
        for (int r = 0; r < k; ++r)
            CHECK(lambda[static_cast<std::size_t>(r)] == Approx(ref[6 * n + r]).margin(1e-8 * scale));

        const int a = std::uniform_int_distribution<int>(0, n - 1)(rng);
        const Vec6 fa = (Vec6() << randomVec(rng, 1), randomVec(rng, 1)).finished();
        Eigen::VectorXd single = Eigen::VectorXd::Zero(6 * n);
        single.segment<6>(6 * a) = fa;
        const Eigen::VectorXd column = denseSolve(fig, single, Eigen::VectorXd::Zero(k));
        std::vector<double> got(static_cast<std::size_t>(6 * n));
        tree.solveImpulse(a, fa, -1, Vec6::Zero(), got);
        for (int i = 0; i < 6 * n; ++i)
            CHECK(got[static_cast<std::size_t>(i)] ==
                  Approx(column[i]).margin(1e-9 * std::max(1.0, column.cwiseAbs().maxCoeff())));
    }
}

TEST_CASE("articulated tree: a soft row about a hinge is an implicit damper on its turn", "[bullet][direct]") {
    // A rod of 2 kg, 1 m, hinged about z at its end, with a soft row about z asking a turn rate e: from rest,
    // ω (I_end) = λ and ω + γλ = e give ω = e / (1 + γ I_end), the closed form of an implicit damper.
    const double m = 2.0, len = 1.0, gamma = 0.5, rate = 3.0;
    const double iEnd = m * len * len / 3;
    const Figure fig = hingedRod(m, len, gamma);
    ArticulatedTree tree = factored(fig);
    std::vector<double> e{0, 0, 0, 0, 0, rate}, lambda(6, 0.0), dv(6, 0.0);
    tree.setTargets(e);
    tree.project(dv, lambda);
    const double omega = rate / (1 + gamma * iEnd);
    CHECK(dv[5] == Approx(omega));
    CHECK(dv[1] == Approx(omega * len / 2));
    CHECK(lambda[5] == Approx(iEnd * omega));
}
