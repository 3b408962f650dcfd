// Exact polyhedral mass properties against the closed forms of docs/format.md §3.2, and the zero-volume rule.
#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>
#include <utility>

#include "afb/figure/MassProperties.h"
#include "afb/figure/Polytope.h"

using afb::figure::computeClipModelMassProperties;
using afb::figure::computeMassProperties;
using afb::figure::MassProperties;
using afb::figure::Polytope;
using Eigen::Matrix3d;
using Eigen::Vector3d;

namespace {

constexpr double kRel = 1e-9;

/// Closed-form expectations: volume, centre of mass and the covariance (second moment per unit volume about
/// the COM; diagonal <x²>, <y²>, <z²>).
struct Expected {
    double volume;
    Vector3d centerOfMass;
    Matrix3d covariance;
};

Matrix3d diagonal(double xx, double yy, double zz) { return Vector3d(xx, yy, zz).asDiagonal(); }

// Checks mass properties at `density` against the closed form; `length` scales the absolute margins used for
// quantities whose expected value is 0.
void checkAgainst(const Polytope& p, const Expected& e, double density, double length) {
    const MassProperties mp = computeMassProperties(p, density);
    CHECK_FALSE(mp.zeroVolumeFallback);
    CHECK(mp.volume == Approx(e.volume).epsilon(kRel));
    CHECK(mp.mass == Approx(density * e.volume).epsilon(kRel));
    for (int a = 0; a < 3; ++a) {
        INFO("COM axis " << a);
        CHECK(mp.centerOfMass[a] == Approx(e.centerOfMass[a]).epsilon(kRel).margin(kRel * length));
    }
    // Expected inertia I = m (tr(C)·1 − C).
    const double mass = density * e.volume;
    const Matrix3d expectedInertia = mass * (e.covariance.trace() * Matrix3d::Identity() - e.covariance);
    const double scale = expectedInertia.diagonal().cwiseAbs().maxCoeff();
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
            INFO("inertia (" << r << ", " << c << ")");
            CHECK(mp.inertia(r, c) == Approx(expectedInertia(r, c)).epsilon(kRel).margin(kRel * scale));
        }
    // The three principal second moments themselves: <x²> = (Iyy + Izz − Ixx) / 2m.
    const Vector3d diag = mp.inertia.diagonal();
    const Vector3d second((diag.y() + diag.z() - diag.x()) / (2 * mp.mass),
                          (diag.x() + diag.z() - diag.y()) / (2 * mp.mass),
                          (diag.x() + diag.y() - diag.z()) / (2 * mp.mass));
    for (int a = 0; a < 3; ++a) {
        INFO("second moment axis " << a);
        CHECK(second[a] == Approx(e.covariance(a, a)).epsilon(kRel));
    }
}

// Off-diagonal inertia terms are ~0 relative to the principal moments (tensor diagonal in the body frame).
void checkDiagonal(const Polytope& p) {
    const MassProperties mp = computeMassProperties(p, 1.0);
    const double scale = mp.inertia.diagonal().cwiseAbs().maxCoeff();
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
            if (r != c) CHECK(std::abs(mp.inertia(r, c)) <= 1e-12 * scale);
}

const std::vector<std::pair<Vector3d, Vector3d>> kBounds = {
    {{-1, -1, -1}, {1, 1, 1}},
    {{-3, -5, -1}, {7, 2, 11}},
    {{10, 20, -30}, {10.5, 26, -2}},
    {{-0.25, 1, 2}, {4, 1.5, 2.75}},
};

const std::vector<double> kDensities = {1.0, 0.2, 7.5};

} // namespace

TEST_CASE("mass: unit tetrahedron, including products of inertia and their sign", "[figure][mass]") {
    Polytope tet;
    tet.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    tet.faces = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    // Covariance about the COM: ∫x² = 1/60 and ∫xy = 1/120 about the origin, shifted by V·(1/4)²: 1/160 and
    // −1/480 per unit volume × 6.
    Matrix3d covariance = Matrix3d::Constant(-1.0 / 480.0) * 6.0;
    covariance.diagonal().setConstant(6.0 / 160.0);
    checkAgainst(tet, {1.0 / 6.0, Vector3d::Constant(0.25), covariance}, 3.0, 1.0);
    const MassProperties mp = computeMassProperties(tet, 1.0);
    CHECK(mp.inertia(0, 1) == Approx(1.0 / 480.0).epsilon(kRel)); // Ixy = −∫xy dV about the COM > 0 here
}

TEST_CASE("mass: box closed form", "[figure][mass]") {
    for (const auto& [min, max] : kBounds)
        for (double density : kDensities) {
            const Vector3d e = max - min;
            const Polytope box = afb::figure::makeBox(min, max);
            checkAgainst(box,
                         {e.prod(), (min + max) / 2,
                          diagonal(e.x() * e.x() / 12, e.y() * e.y() / 12, e.z() * e.z() / 12)},
                         density, e.norm());
            checkDiagonal(box);
        }
}

TEST_CASE("mass: octahedron closed form", "[figure][mass]") {
    for (const auto& [min, max] : kBounds)
        for (double density : kDensities) {
            const Vector3d e = max - min;
            const Vector3d h = e / 2;
            checkAgainst(afb::figure::makeOctahedron(min, max),
                         {e.prod() / 6, (min + max) / 2,
                          diagonal(h.x() * h.x() / 10, h.y() * h.y() / 10, h.z() * h.z() / 10)},
                         density, e.norm());
            checkDiagonal(afb::figure::makeOctahedron(min, max));
        }
}

TEST_CASE("mass: dodecahedron closed form", "[figure][mass]") {
    // docs/format.md §3.2: volume (3√5 − 5)/4 · ex·ey·ez; <x²> = 0.044306·ex², exactly (20 − 3√5)/300 · ex².
    const double sqrt5 = std::sqrt(5.0);
    const double volumeFactor = (3 * sqrt5 - 5) / 4;
    const double secondFactor = (20 - 3 * sqrt5) / 300;
    CHECK(secondFactor == Approx(0.044306).epsilon(1e-5));
    for (const auto& [min, max] : kBounds)
        for (double density : kDensities) {
            const Vector3d e = max - min;
            checkAgainst(afb::figure::makeDodecahedron(min, max),
                         {volumeFactor * e.prod(), (min + max) / 2,
                          diagonal(secondFactor * e.x() * e.x(), secondFactor * e.y() * e.y(),
                                   secondFactor * e.z() * e.z())},
                         density, e.norm());
            checkDiagonal(afb::figure::makeDodecahedron(min, max));
        }
}

TEST_CASE("mass: cylinder (inscribed n-gon prism) closed form", "[figure][mass]") {
    for (const auto& [min, max] : kBounds)
        for (const auto& [requested, n] : {std::pair{3, 3}, {5, 5}, {10, 10}, {12, 10}, {2, 3}}) {
            INFO("requested " << requested);
            const auto build = afb::figure::makeCylinder(min, max, requested);
            REQUIRE(build.effectiveSides == n);
            const Vector3d e = max - min;
            const double hx = e.x() / 2, hy = e.y() / 2;
            const double angle = 2 * std::numbers::pi / n;
            const double k = (2 + std::cos(angle)) / 12;
            checkAgainst(build.polytope,
                         {n / 2.0 * std::sin(angle) * hx * hy * e.z(), (min + max) / 2,
                          diagonal(k * hx * hx, k * hy * hy, e.z() * e.z() / 12)},
                         2.5, e.norm());
            checkDiagonal(build.polytope);
        }
}

TEST_CASE("mass: cone closed form, COM ¾ of the height below the apex", "[figure][mass]") {
    // Decl bounds centred in x/y (the table's case): v1, v2 as written, LoadBody's rewrite in the builder.
    const std::vector<std::pair<Vector3d, Vector3d>> declBounds = {{{-2, -3, 0}, {2, 3, 10}},
                                                                   {{-1, -1, 5}, {1, 1, 6}},
                                                                   {{-7, -0.5, -20}, {7, 0.5, -3}}};
    for (const auto& [v1, v2] : declBounds)
        for (const auto& [requested, n] : {std::pair{3, 3}, {5, 5}, {10, 10}, {15, 15}, {16, 15}}) {
            INFO("requested " << requested);
            const auto build = afb::figure::makeCone(v1, v2, requested);
            REQUIRE(build.effectiveSides == n);
            const double hx = (v2.x() - v1.x()) / 2, hy = (v2.y() - v1.y()) / 2, height = v2.z() - v1.z();
            const double angle = 2 * std::numbers::pi / n;
            const double k = (2 + std::cos(angle)) / 12;
            checkAgainst(build.polytope,
                         {n / 6.0 * std::sin(angle) * hx * hy * height, Vector3d(0, 0, -0.75 * height),
                          diagonal(0.6 * k * hx * hx, 0.6 * k * hy * hy, 3 * height * height / 80)},
                         0.5, (v2 - v1).norm());
            checkDiagonal(build.polytope);
        }
}

TEST_CASE("mass: off-centre cone is sheared toward the apex at x = y = 0", "[figure][mass]") {
    // The engine keeps the apex at (0, 0, 0), so the cone is the centred cone sheared by −z/H·(cx, cy): its
    // COM is ¾ of the way from the apex to the base centre and its tensor gains products of inertia.
    const Vector3d v1(1, 2, -4), v2(5, 3, 7);
    const double cx = 3, cy = 2.5, hx = 2, hy = 0.5, height = 11;
    for (int n : {3, 5, 10}) {
        const auto build = afb::figure::makeCone(v1, v2, n);
        const double angle = 2 * std::numbers::pi / n;
        const double k = (2 + std::cos(angle)) / 12;
        const double zz = 3 * height * height / 80;
        Matrix3d covariance;
        covariance << 0.6 * k * hx * hx + cx * cx * zz / (height * height), cx * cy * zz / (height * height),
            -cx * zz / height, //
            cx * cy * zz / (height * height), 0.6 * k * hy * hy + cy * cy * zz / (height * height),
            -cy * zz / height, //
            -cx * zz / height, -cy * zz / height, zz;
        checkAgainst(build.polytope,
                     {n / 6.0 * std::sin(angle) * hx * hy * height, Vector3d(0.75 * cx, 0.75 * cy, -0.75 * height),
                      covariance},
                     1.0, (v2 - v1).norm());
    }
}

TEST_CASE("mass: bone closed form, COM at the body origin", "[figure][mass]") {
    for (const auto& [length, width] : {std::pair{10.0, 2.0}, std::pair{3.0, 5.0}, std::pair{0.7, 0.1}})
        for (double density : kDensities) {
            const double w2 = width * width;
            checkAgainst(afb::figure::makeBone(length, width),
                         {w2 * length / 8, Vector3d::Zero(), diagonal(w2 / 40, 3 * w2 / 160, length * length / 40)},
                         density, length + width);
            checkDiagonal(afb::figure::makeBone(length, width));
        }
}

TEST_CASE("mass: translation moves only the COM / rotation turns the tensor", "[figure][mass]") {
    const Vector3d min(-3, -5, -1), max(7, 2, 11), shift(100, -250, 37.5);
    const MassProperties base = computeMassProperties(afb::figure::makeBox(min, max), 2.0);
    const MassProperties moved = computeMassProperties(afb::figure::makeBox(min + shift, max + shift), 2.0);
    CHECK(moved.volume == Approx(base.volume).epsilon(kRel));
    CHECK(moved.mass == Approx(base.mass).epsilon(kRel));
    CHECK((moved.centerOfMass - (base.centerOfMass + shift)).norm() <= kRel * shift.norm());
    CHECK((moved.inertia - base.inertia).norm() <= kRel * base.inertia.norm());

    const Matrix3d rotation = Eigen::AngleAxisd(0.7, Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
    Polytope turned = afb::figure::makeDodecahedron(min, max);
    const MassProperties unturned = computeMassProperties(turned, 1.0);
    for (auto& v : turned.vertices) v = rotation * v;
    const MassProperties rotated = computeMassProperties(turned, 1.0);
    CHECK(rotated.volume == Approx(unturned.volume).epsilon(kRel));
    CHECK((rotated.centerOfMass - rotation * unturned.centerOfMass).norm() <= kRel * (max - min).norm());
    CHECK((rotated.inertia - rotation * unturned.inertia * rotation.transpose()).norm() <=
          kRel * unturned.inertia.norm());
}

TEST_CASE("mass: inverted bounds give negative volume and mass, as in the engine", "[figure][mass]") {
    const MassProperties mp = computeMassProperties(afb::figure::makeBox({1, 0, 0}, {0, 2, 3}), 1.0);
    CHECK(mp.volume == Approx(-6.0).epsilon(kRel));
    CHECK(mp.mass < 0);
    CHECK_FALSE(computeClipModelMassProperties(afb::figure::makeBox({1, 0, 0}, {0, 2, 3}), 1.0).zeroVolumeFallback);
}

TEST_CASE("mass: zero-volume rule (idClipModel cache)", "[figure][mass]") {
    SECTION("a 2-sided cone has exactly zero volume") {
        const auto cone = afb::figure::makeCone({-1, -2, 0}, {3, 2, 9}, 2);
        REQUIRE(cone.effectiveSides == 2);
        const MassProperties exact = computeMassProperties(cone.polytope, 4.0);
        CHECK(exact.volume == 0.0);
        CHECK(exact.mass == 0.0);
        CHECK(exact.inertia == Matrix3d::Zero());
        CHECK_FALSE(exact.zeroVolumeFallback);

        const MassProperties clip = computeClipModelMassProperties(cone.polytope, 4.0);
        CHECK(clip.zeroVolumeFallback);
        CHECK(clip.volume == 0.0);
        CHECK(clip.mass == 4.0); // = density, not 0
        CHECK(clip.centerOfMass == Vector3d::Zero());
        CHECK(clip.inertia == 4.0 * Matrix3d::Identity());
    }
    SECTION("flat boxes and bones are exactly zero too") {
        for (const Polytope& flat :
             {afb::figure::makeBox({1, 2, 3}, {1, 5, 7}), afb::figure::makeBox({-1, 2, 3}, {4, 5, 3}),
              afb::figure::makeBone(5.0, 0.0), afb::figure::makeBone(0.0, 2.0),
              afb::figure::makeCylinder({-1, 2, 3}, {1, 2, 7}, 5).polytope}) {
            const MassProperties clip = computeClipModelMassProperties(flat, 1.0);
            CHECK(clip.volume == 0.0);
            CHECK(clip.zeroVolumeFallback);
            CHECK(clip.mass == 1.0);
            CHECK(clip.inertia == Matrix3d::Identity());
        }
    }
    SECTION("non-degenerate shapes are untouched") {
        const Polytope box = afb::figure::makeBox({-1, -2, -3}, {4, 5, 6});
        const MassProperties exact = computeMassProperties(box, 3.0);
        const MassProperties clip = computeClipModelMassProperties(box, 3.0);
        CHECK_FALSE(clip.zeroVolumeFallback);
        CHECK(clip.mass == exact.mass);
        CHECK(clip.centerOfMass == exact.centerOfMass);
        CHECK(clip.inertia == exact.inertia);
    }
}
