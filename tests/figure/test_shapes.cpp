// Trace-model shape construction (docs/format.md §3.1): vertex layouts, counts, side clamps, orientation, the bone
// frame.
#include <catch2/catch.hpp>

#include <climits>
#include <cmath>
#include <map>
#include <numbers>
#include <utility>

#include "afb/figure/Polytope.h"

using afb::figure::Polytope;
using Eigen::Vector3d;

namespace {

struct Counts {
    int vertices, edges, faces;
};

void checkCounts(const Polytope& p, Counts expected) {
    CHECK(p.vertexCount() == expected.vertices);
    CHECK(p.edgeCount() == expected.edges);
    CHECK(p.faceCount() == expected.faces);
}

Vector3d vertexMean(const Polytope& p) {
    Vector3d sum = Vector3d::Zero();
    for (const auto& v : p.vertices) sum += v;
    return sum / static_cast<double>(p.vertices.size());
}

double diameter(const Polytope& p) {
    double d = 0;
    for (const auto& a : p.vertices)
        for (const auto& b : p.vertices) d = std::max(d, (a - b).norm());
    return d;
}

// Newell's normal of a face loop: length = twice the area, direction by the right-hand rule.
Vector3d newellNormal(const Polytope& p, const std::vector<int>& face) {
    Vector3d n = Vector3d::Zero();
    for (std::size_t i = 0; i < face.size(); ++i) {
        const Vector3d& a = p.vertices[face[i]];
        const Vector3d& b = p.vertices[face[(i + 1) % face.size()]];
        n += a.cross(b);
    }
    return n;
}

// A non-degenerate convex polytope with consistently outward faces: every face planar, its normal pointing
// away from the interior, every vertex behind every face plane, every directed edge used once and its reverse
// once (closed 2-manifold), Euler characteristic 2.
void checkConvexClosedOutward(const Polytope& p) {
    const double tol = 1e-12 * diameter(p);
    const Vector3d inside = vertexMean(p);
    std::map<std::pair<int, int>, int> directedEdges;
    for (const auto& face : p.faces) {
        REQUIRE(face.size() >= 3);
        const Vector3d normal = newellNormal(p, face).normalized();
        Vector3d faceCentre = Vector3d::Zero();
        for (int i : face) faceCentre += p.vertices[i];
        faceCentre /= static_cast<double>(face.size());
        const double offset = normal.dot(faceCentre);
        for (int i : face) CHECK(std::abs(normal.dot(p.vertices[i]) - offset) <= tol); // planar
        CHECK(normal.dot(faceCentre - inside) > 0);                                    // outward
        for (const auto& v : p.vertices) CHECK(normal.dot(v) - offset <= tol);         // convex
        for (std::size_t i = 0; i < face.size(); ++i) ++directedEdges[{face[i], face[(i + 1) % face.size()]}];
    }
    for (const auto& [edge, uses] : directedEdges) {
        CHECK(uses == 1);
        const auto reverse = directedEdges.find({edge.second, edge.first});
        CHECK((reverse != directedEdges.end() && reverse->second == 1));
    }
    CHECK(static_cast<int>(directedEdges.size()) == 2 * p.edgeCount());
    CHECK(p.vertexCount() - p.edgeCount() + p.faceCount() == 2);
}

const std::vector<std::pair<Vector3d, Vector3d>> kBounds = {
    {{-1, -1, -1}, {1, 1, 1}},
    {{-3, -5, -1}, {7, 2, 11}},
    {{10, 20, -30}, {10.5, 26, -2}},
    {{-0.25, 1, 2}, {4, 1.5, 2.75}},
};

} // namespace

TEST_CASE("box: 8 corners, 12 edges, 6 outward faces", "[figure][shapes]") {
    for (const auto& [min, max] : kBounds) {
        const Polytope box = afb::figure::makeBox(min, max);
        checkCounts(box, {8, 12, 6});
        checkConvexClosedOutward(box);
        CHECK(box.vertices[0] == min);
        CHECK(box.vertices[6] == max);
        for (const auto& v : box.vertices)
            for (int a = 0; a < 3; ++a) CHECK((v[a] == min[a] || v[a] == max[a]));
    }
}

TEST_CASE("octahedron: axis tips of the bounds", "[figure][shapes]") {
    for (const auto& [min, max] : kBounds) {
        const Polytope oct = afb::figure::makeOctahedron(min, max);
        checkCounts(oct, {6, 12, 8});
        checkConvexClosedOutward(oct);
        const Vector3d c = (min + max) / 2;
        CHECK(oct.vertices[0].x() == Approx(max.x()));
        CHECK(oct.vertices[1].x() == Approx(min.x()));
        CHECK(oct.vertices[2].y() == Approx(max.y()));
        CHECK(oct.vertices[3].y() == Approx(min.y()));
        CHECK(oct.vertices[4].z() == Approx(max.z()));
        CHECK(oct.vertices[5].z() == Approx(min.z()));
        CHECK(oct.vertices[0].y() == c.y());
        CHECK(oct.vertices[4].x() == c.x());
    }
}

TEST_CASE("dodecahedron: 20/30/12, planar pentagons, ±c vertices touch the bounds", "[figure][shapes]") {
    for (const auto& [min, max] : kBounds) {
        const Polytope dod = afb::figure::makeDodecahedron(min, max);
        checkCounts(dod, {20, 30, 12});
        checkConvexClosedOutward(dod);
        for (const auto& face : dod.faces) CHECK(face.size() == 5);
        const double tol = 1e-12 * (max - min).norm();
        // docs/format.md §3.1 vertex order: 8–11 = (±b, ±c, 0), 12–15 = (±c, 0, ±b), 16–19 = (0, ±b, ±c).
        CHECK(dod.vertices[12].x() == Approx(max.x()).margin(tol));
        CHECK(dod.vertices[13].x() == Approx(max.x()).margin(tol));
        CHECK(dod.vertices[14].x() == Approx(min.x()).margin(tol));
        CHECK(dod.vertices[15].x() == Approx(min.x()).margin(tol));
        CHECK(dod.vertices[8].y() == Approx(max.y()).margin(tol));
        CHECK(dod.vertices[9].y() == Approx(max.y()).margin(tol));
        CHECK(dod.vertices[10].y() == Approx(min.y()).margin(tol));
        CHECK(dod.vertices[11].y() == Approx(min.y()).margin(tol));
        CHECK(dod.vertices[16].z() == Approx(max.z()).margin(tol));
        CHECK(dod.vertices[17].z() == Approx(max.z()).margin(tol));
        CHECK(dod.vertices[18].z() == Approx(min.z()).margin(tol));
        CHECK(dod.vertices[19].z() == Approx(min.z()).margin(tol));
        for (const auto& v : dod.vertices)
            for (int a = 0; a < 3; ++a) {
                CHECK(v[a] >= min[a] - tol);
                CHECK(v[a] <= max[a] + tol);
            }
        // The spec's 10-digit constants: vertex 0 is centre + a·extent·0.5/c.
        const Vector3d c = (min + max) / 2;
        CHECK(dod.vertices[0].x() - c.x() == Approx(0.5773502692 * (max.x() - min.x()) * 0.5 / 0.9341723590));
        CHECK(dod.vertices[8].x() - c.x() == Approx(0.3568220898 * (max.x() - min.x()) * 0.5 / 0.9341723590));
    }
}

TEST_CASE("side clamps follow the engine's order", "[figure][shapes]") {
    using afb::figure::effectiveConeSides;
    using afb::figure::effectiveCylinderSides;
    const std::vector<std::pair<int, int>> cylinder = {{INT_MIN, 3}, {-5, 3},   {0, 3},       {1, 3},   {2, 3},
                                                       {3, 3},       {7, 7},    {10, 10},     {11, 10}, {12, 10},
                                                       {16, 10},     {100, 10}, {INT_MAX, 10}};
    for (const auto& [requested, effective] : cylinder) {
        INFO("cylinder " << requested);
        CHECK(effectiveCylinderSides(requested) == effective);
    }
    const std::vector<std::pair<int, int>> cone = {{INT_MIN, 3}, {-1, 3},  {0, 3},   {1, 3},   {2, 2},   {3, 3},
                                                   {14, 14},     {15, 15}, {16, 15}, {31, 15}, {32, 15}, {INT_MAX, 15}};
    for (const auto& [requested, effective] : cone) {
        INFO("cone " << requested);
        CHECK(effectiveConeSides(requested) == effective);
    }
}

TEST_CASE("cylinder: 2n/3n/n+2 prism, first vertex on +X", "[figure][shapes]") {
    for (const auto& [min, max] : kBounds)
        for (int n : {3, 4, 5, 7, 10}) {
            INFO("n = " << n);
            const auto build = afb::figure::makeCylinder(min, max, n);
            CHECK(build.effectiveSides == n);
            CHECK(build.requestedSides == n);
            CHECK_FALSE(build.clamped);
            const Polytope& cyl = build.polytope;
            checkCounts(cyl, {2 * n, 3 * n, n + 2});
            checkConvexClosedOutward(cyl);
            const Vector3d c = (min + max) / 2;
            CHECK(cyl.vertices[0] == Vector3d(max.x(), c.y(), min.z()));
            CHECK(cyl.vertices[n] == Vector3d(max.x(), c.y(), max.z()));
            const double angle = 2 * std::numbers::pi / n;
            CHECK(cyl.vertices[1].x() == Approx(c.x() + std::cos(angle) * (max.x() - c.x())));
            CHECK(cyl.vertices[1].y() == Approx(c.y() + std::sin(angle) * (max.y() - c.y())));
        }
}

TEST_CASE("cylinder: clamped counts are reported", "[figure][shapes]") {
    const Vector3d min(-1, -2, -3), max(1, 2, 3);
    const auto twelve = afb::figure::makeCylinder(min, max, 12);
    CHECK(twelve.requestedSides == 12);
    CHECK(twelve.effectiveSides == 10);
    CHECK(twelve.clamped);
    checkCounts(twelve.polytope, {20, 30, 12});
    checkConvexClosedOutward(twelve.polytope);
    const auto two = afb::figure::makeCylinder(min, max, 2);
    CHECK(two.effectiveSides == 3);
    CHECK(two.clamped);
    checkCounts(two.polytope, {6, 9, 5});
}

TEST_CASE("cone: apex at the local origin, base at −H around the bounds' x/y centre", "[figure][shapes]") {
    // Decl bounds as written; LoadBody's z rewrite is the builder's job.
    const std::vector<std::pair<Vector3d, Vector3d>> declBounds = {
        {{-2, -3, 0}, {2, 3, 10}},
        {{-1, -1, 5}, {1, 1, 6}},
        {{1, 2, -4}, {5, 3, 7}}, // off-centre x/y: the apex still sits at x = y = 0
    };
    for (const auto& [v1, v2] : declBounds)
        for (int n : {3, 5, 10, 15}) {
            INFO("n = " << n);
            const auto build = afb::figure::makeCone(v1, v2, n);
            CHECK(build.effectiveSides == n);
            CHECK_FALSE(build.clamped);
            const Polytope& cone = build.polytope;
            checkCounts(cone, {n + 1, 2 * n, n + 1});
            checkConvexClosedOutward(cone);
            CHECK(cone.vertices[n] == Vector3d::Zero());
            const double height = v2.z() - v1.z();
            const double cx = (v1.x() + v2.x()) / 2, cy = (v1.y() + v2.y()) / 2;
            Vector3d baseCentre = Vector3d::Zero();
            for (int i = 0; i < n; ++i) {
                CHECK(cone.vertices[i].z() == -height);
                baseCentre += cone.vertices[i];
            }
            baseCentre /= n;
            CHECK(baseCentre.x() == Approx(cx).margin(1e-12));
            CHECK(baseCentre.y() == Approx(cy).margin(1e-12));
            CHECK(cone.vertices[0] == Vector3d(v2.x(), cy, -height));
        }
}

TEST_CASE("cone: clamps, and the accepted 2-sided cone", "[figure][shapes]") {
    const Vector3d v1(-1, -1, 0), v2(1, 1, 4);
    const auto sixteen = afb::figure::makeCone(v1, v2, 16);
    CHECK(sixteen.effectiveSides == 15);
    CHECK(sixteen.clamped);
    checkCounts(sixteen.polytope, {16, 30, 16});
    checkConvexClosedOutward(sixteen.polytope);

    const auto two = afb::figure::makeCone(v1, v2, 2);
    CHECK(two.effectiveSides == 2);
    CHECK_FALSE(two.clamped);
    checkCounts(two.polytope, {3, 4, 3}); // a flat triangle seen from both sides plus a 2-vertex "base"

    for (int n : {1, 0, -7}) {
        const auto raised = afb::figure::makeCone(v1, v2, n);
        CHECK(raised.effectiveSides == 3);
        CHECK(raised.clamped);
        checkCounts(raised.polytope, {4, 6, 4});
    }
}

TEST_CASE("bone: two triangular pyramids on an isosceles equator, centred on the origin", "[figure][shapes]") {
    for (const auto& [length, width] : {std::pair{10.0, 2.0}, std::pair{3.0, 5.0}, std::pair{0.7, 0.1}}) {
        const Polytope bone = afb::figure::makeBone(length, width);
        checkCounts(bone, {5, 9, 6});
        checkConvexClosedOutward(bone);
        CHECK(bone.vertices[0] == Vector3d(0, 0, -length / 2));
        CHECK(bone.vertices[1] == Vector3d(0, -width / 2, 0));
        CHECK(bone.vertices[2] == Vector3d(width / 2, width / 4, 0));
        CHECK(bone.vertices[3] == Vector3d(-width / 2, width / 4, 0));
        CHECK(bone.vertices[4] == Vector3d(0, 0, length / 2));
    }
}

TEST_CASE("bone frame: columns are the body axes, right-handed, Z along the bone", "[figure][shapes]") {
    using afb::figure::boneFrame;
    SECTION("exactly vertical bones take left = +X") {
        CHECK(boneFrame({1, 2, 3}, {1, 2, 8}) == Eigen::Matrix3d::Identity());
        Eigen::Matrix3d down;
        down << 1, 0, 0, 0, -1, 0, 0, 0, -1;
        CHECK(boneFrame({1, 2, 3}, {1, 2, -8}) == down);
        CHECK(down.determinant() == 1.0);
    }
    SECTION("the zero test is exact: a bone a hair off vertical turns left to ±Y") {
        const Eigen::Matrix3d frame = boneFrame({0, 0, 0}, {1e-9, 0, 1});
        CHECK(frame.col(0).isApprox(Vector3d(0, 1, 0), 1e-12));
    }
    SECTION("along +X") {
        const Eigen::Matrix3d frame = boneFrame({0, 0, 0}, {4, 0, 0});
        CHECK(frame.col(0).isApprox(Vector3d(0, 1, 0)));
        CHECK(frame.col(1).isApprox(Vector3d(0, 0, 1)));
        CHECK(frame.col(2).isApprox(Vector3d(1, 0, 0)));
    }
    SECTION("general directions") {
        const std::vector<std::pair<Vector3d, Vector3d>> bones = {{{0, 0, 0}, {1, 2, 3}},
                                                                  {{5, -1, 2}, {-3, 4, -6}},
                                                                  {{0, 0, 0}, {0, -1, 0}},
                                                                  {{1, 1, 1}, {1.5, 1, -9}}};
        for (const auto& [v1, v2] : bones) {
            const Eigen::Matrix3d frame = boneFrame(v1, v2);
            const Vector3d d = (v2 - v1).normalized();
            CHECK(frame.col(2).isApprox(d, 1e-14));
            CHECK(frame.col(0).isApprox(Vector3d(-d.y(), d.x(), 0).normalized(), 1e-14));
            CHECK(frame.col(1).isApprox(d.cross(frame.col(0)), 1e-14));
            CHECK((frame.transpose() * frame).isApprox(Eigen::Matrix3d::Identity(), 1e-14));
            CHECK(frame.determinant() == Approx(1.0).epsilon(1e-14));
            CHECK(frame.col(0).cross(frame.col(1)).isApprox(frame.col(2), 1e-14));
            // The bone's +Z tip, placed at bonecenter(v1, v2), lands on v2.
            const double length = (v2 - v1).norm();
            const Polytope bone = afb::figure::makeBone(length, 1.0);
            const Vector3d tip = frame * bone.vertices[4] + (v1 + v2) / 2;
            CHECK((tip - v2).norm() <= 1e-12 * length);
        }
    }
    SECTION("a zero-length bone gets the identity") {
        CHECK(boneFrame({1, 2, 3}, {1, 2, 3}) == Eigen::Matrix3d::Identity());
    }
}

TEST_CASE("face normals, face planes and the in-radius about the origin", "[figure][shapes]") {
    using afb::figure::FacePlane;
    // A box from (−1, −2, −3) to (3, 2, 3): the origin is 1 from the −X face, 2 from ±Y, 3 from the rest.
    const Polytope box = afb::figure::makeBox({-1, -2, -3}, {3, 2, 3});
    const std::vector<FacePlane> planes = afb::figure::facePlanes(box.vertices, box.faces);
    REQUIRE(planes.size() == 6);
    std::map<std::pair<int, int>, double> offsetByAxis; // (axis, sign) → offset
    for (const FacePlane& p : planes) {
        int axis = 0;
        p.normal.cwiseAbs().maxCoeff(&axis);
        CHECK(std::abs(p.normal[axis]) == Approx(1.0).margin(1e-15));
        offsetByAxis[{axis, p.normal[axis] > 0 ? 1 : -1}] = p.offset;
        for (int v : box.faces[static_cast<std::size_t>(&p - planes.data())])
            CHECK(p.normal.dot(box.vertices[static_cast<std::size_t>(v)]) == Approx(p.offset).margin(1e-12));
    }
    CHECK(offsetByAxis.at({0, -1}) == Approx(1));
    CHECK(offsetByAxis.at({0, 1}) == Approx(3));
    CHECK(offsetByAxis.at({1, -1}) == Approx(2));
    CHECK(offsetByAxis.at({1, 1}) == Approx(2));
    CHECK(offsetByAxis.at({2, -1}) == Approx(3));
    CHECK(offsetByAxis.at({2, 1}) == Approx(3));
    CHECK(afb::figure::inRadius(planes) == Approx(1));

    // Every face of every shape points outward: its normal agrees with centroid − (an interior point).
    const Polytope dodecahedron = afb::figure::makeDodecahedron({-1, -2, -3}, {2, 2, 1});
    for (const std::vector<int>& face : dodecahedron.faces) {
        const auto n = afb::figure::faceNormal(dodecahedron.vertices, face);
        REQUIRE(n);
        CHECK(n->norm() == Approx(1.0));
        CHECK(n->dot(dodecahedron.vertices[static_cast<std::size_t>(face[0])] - vertexMean(dodecahedron)) > 0);
    }

    // Degenerate faces have no normal and no plane; no plane at all means an unbounded in-radius.
    const std::vector<Vector3d> points = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
    CHECK_FALSE(afb::figure::faceNormal(points, std::vector<int>{0, 1}));
    CHECK_FALSE(afb::figure::faceNormal(points, std::vector<int>{0, 1, 2})); // collinear: zero area
    CHECK(afb::figure::facePlanes(points, std::vector<std::vector<int>>{{0, 1, 2}}).empty());
    CHECK(std::isinf(afb::figure::inRadius({})));
}
