// Trace-model shapes (docs/format.md §3.1). Vertex layouts follow the engine's so indices can be compared; the
// face loops are our own, each counter-clockwise seen from outside.
#include "afb/figure/Polytope.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

namespace afb::figure {

namespace {

// The engine's trace-model limits (TraceModel.h), which bound the side counts.
constexpr int kMaxVerts = 32;
constexpr int kMaxEdges = 32;
constexpr int kMaxPolys = 16;

// Circumradius-1 dodecahedron constants: a = 1/√3, b = √((3 − √5)/6), c = √((3 + √5)/6). The spec quotes them
// to 10 digits (0.5773502692, 0.3568220898, 0.9341723590); the full values keep the pentagons exactly planar.
constexpr double kDodA = 0.57735026918962576451;
constexpr double kDodB = 0.35682208977308993194;
constexpr double kDodC = 0.93417235896271569645;

// Unit-dodecahedron vertices in the engine's order (docs/format.md §3.1).
constexpr std::array<std::array<double, 3>, 20> kDodVertices = {{
    {kDodA, kDodA, kDodA},  {kDodA, kDodA, -kDodA},  {kDodA, -kDodA, kDodA},  {kDodA, -kDodA, -kDodA},
    {-kDodA, kDodA, kDodA}, {-kDodA, kDodA, -kDodA}, {-kDodA, -kDodA, kDodA}, {-kDodA, -kDodA, -kDodA},
    {kDodB, kDodC, 0},      {-kDodB, kDodC, 0},      {kDodB, -kDodC, 0},      {-kDodB, -kDodC, 0},
    {kDodC, 0, kDodB},      {kDodC, 0, -kDodB},      {-kDodC, 0, kDodB},      {-kDodC, 0, -kDodB},
    {0, kDodB, kDodC},      {0, -kDodB, kDodC},      {0, kDodB, -kDodC},      {0, -kDodB, -kDodC},
}};

// The 12 pentagons of that vertex list, counter-clockwise seen from outside (derived from the convex hull of
// the vertices; tests check orientation, planarity and convexity).
constexpr std::array<std::array<int, 5>, 12> kDodFaces = {{
    {0, 8, 9, 4, 16},
    {0, 12, 13, 1, 8},
    {0, 16, 17, 2, 12},
    {1, 13, 3, 19, 18},
    {1, 18, 5, 9, 8},
    {2, 10, 3, 13, 12},
    {2, 17, 6, 11, 10},
    {3, 10, 11, 7, 19},
    {4, 9, 5, 15, 14},
    {4, 14, 6, 17, 16},
    {5, 18, 19, 7, 15},
    {6, 14, 15, 7, 11},
}};

Eigen::Vector3d boundsCentre(const Eigen::Vector3d& min, const Eigen::Vector3d& max) { return (min + max) * 0.5; }

// Ring vertex i of n on the ellipse with half-axes (hx, hy) around `centre` at height z; θi = 2πi/n, as the
// engine computes it, so vertex 0 lies on +X.
Eigen::Vector3d ringVertex(const Eigen::Vector3d& centre, const Eigen::Vector3d& half, int i, int n, double z) {
    const double angle = 2.0 * std::numbers::pi * i / n;
    return {std::cos(angle) * half.x() + centre.x(), std::sin(angle) * half.y() + centre.y(), z};
}

// The cap loop of a ring of n vertices starting at `first`, seen from below (outward normal −Z).
std::vector<int> lowerCap(int first, int n) {
    std::vector<int> loop;
    for (int i = n - 1; i >= 0; --i) loop.push_back(first + i);
    return loop;
}

ShapeBuild withSides(Polytope polytope, int requested, int effective) {
    return {std::move(polytope), requested, effective, requested != effective};
}

} // namespace

int Polytope::edgeCount() const {
    std::size_t uses = 0;
    for (const auto& face : faces) uses += face.size();
    return static_cast<int>(uses / 2);
}

std::optional<Eigen::Vector3d> faceNormal(std::span<const Eigen::Vector3d> vertices, std::span<const int> face) {
    if (face.size() < 3) return std::nullopt;
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    for (std::size_t k = 0; k < face.size(); ++k) {
        const Eigen::Vector3d& p = vertices[static_cast<std::size_t>(face[k])];
        const Eigen::Vector3d& q = vertices[static_cast<std::size_t>(face[(k + 1) % face.size()])];
        n += p.cross(q);
    }
    if (!(n.norm() > 0.0)) return std::nullopt;
    return n.normalized();
}

std::vector<FacePlane> facePlanes(std::span<const Eigen::Vector3d> vertices, std::span<const std::vector<int>> faces) {
    std::vector<FacePlane> planes;
    for (const std::vector<int>& face : faces) {
        const std::optional<Eigen::Vector3d> n = faceNormal(vertices, face);
        if (!n) continue;
        Eigen::Vector3d centre = Eigen::Vector3d::Zero();
        for (int v : face) centre += vertices[static_cast<std::size_t>(v)];
        centre /= static_cast<double>(face.size());
        planes.push_back({*n, n->dot(centre)});
    }
    return planes;
}

double inRadius(std::span<const FacePlane> planes) {
    double r = std::numeric_limits<double>::infinity();
    for (const FacePlane& plane : planes) r = std::min(r, plane.offset);
    return r;
}

int effectiveCylinderSides(int requested) {
    // docs/format.md §3.1: the engine's checks in order (written without the products, which could overflow).
    int n = requested < 3 ? 3 : requested;
    if (n > kMaxVerts / 2) n = kMaxVerts / 2; // 2n ≤ MAX_TRACEMODEL_VERTS
    if (n > kMaxEdges / 3) n = kMaxEdges / 3; // 3n ≤ MAX_TRACEMODEL_EDGES
    if (n > kMaxPolys - 2) n = kMaxPolys - 2; // n + 2 ≤ MAX_TRACEMODEL_POLYS
    return n;
}

int effectiveConeSides(int requested) {
    // docs/format.md §3.1: n < 2 → 3, so a 2-sided (zero-volume) cone is accepted.
    int n = requested < 2 ? 3 : requested;
    if (n > kMaxVerts - 1) n = kMaxVerts - 1; // n + 1 ≤ MAX_TRACEMODEL_VERTS
    if (n > kMaxEdges / 2) n = kMaxEdges / 2; // 2n ≤ MAX_TRACEMODEL_EDGES
    if (n > kMaxPolys - 1) n = kMaxPolys - 1; // n + 1 ≤ MAX_TRACEMODEL_POLYS
    return n;
}

Polytope makeBox(const Eigen::Vector3d& min, const Eigen::Vector3d& max) {
    Polytope box;
    for (int i = 0; i < 8; ++i) {
        // Bit pattern: the low two bits walk the square (−−, +−, ++, −+), bit 2 picks the z face.
        const bool xMax = ((i ^ (i >> 1)) & 1) != 0;
        const bool yMax = ((i >> 1) & 1) != 0;
        const bool zMax = ((i >> 2) & 1) != 0;
        box.vertices.emplace_back(xMax ? max.x() : min.x(), yMax ? max.y() : min.y(), zMax ? max.z() : min.z());
    }
    box.faces = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
    return box;
}

Polytope makeOctahedron(const Eigen::Vector3d& min, const Eigen::Vector3d& max) {
    const Eigen::Vector3d c = boundsCentre(min, max);
    const Eigen::Vector3d h = max - c;
    Polytope oct;
    oct.vertices = {c + Eigen::Vector3d(h.x(), 0, 0), c - Eigen::Vector3d(h.x(), 0, 0),
                    c + Eigen::Vector3d(0, h.y(), 0), c - Eigen::Vector3d(0, h.y(), 0),
                    c + Eigen::Vector3d(0, 0, h.z()), c - Eigen::Vector3d(0, 0, h.z())};
    // One triangle per octant (sx, sy, sz); (X, Y, Z) is counter-clockwise from outside when the octant has
    // an even number of negative signs, (X, Z, Y) otherwise.
    for (int octant = 0; octant < 8; ++octant) {
        const int x = (octant & 1) ? 1 : 0;
        const int y = (octant & 2) ? 3 : 2;
        const int z = (octant & 4) ? 5 : 4;
        const bool even = ((octant & 1) ^ ((octant >> 1) & 1) ^ ((octant >> 2) & 1)) == 0;
        oct.faces.push_back(even ? std::vector<int>{x, y, z} : std::vector<int>{x, z, y});
    }
    return oct;
}

Polytope makeDodecahedron(const Eigen::Vector3d& min, const Eigen::Vector3d& max) {
    // docs/format.md §3.1: per-axis scale extent·0.5/c puts the ±c vertices on the bounds.
    const Eigen::Vector3d scale = (max - min) * (0.5 / kDodC);
    const Eigen::Vector3d centre = boundsCentre(min, max);
    Polytope dod;
    for (const auto& v : kDodVertices)
        dod.vertices.emplace_back(centre.x() + v[0] * scale.x(), centre.y() + v[1] * scale.y(),
                                  centre.z() + v[2] * scale.z());
    for (const auto& f : kDodFaces) dod.faces.emplace_back(f.begin(), f.end());
    return dod;
}

ShapeBuild makeCylinder(const Eigen::Vector3d& min, const Eigen::Vector3d& max, int numSides) {
    const int n = effectiveCylinderSides(numSides);
    const Eigen::Vector3d centre = boundsCentre(min, max);
    const Eigen::Vector3d half = max - centre;
    Polytope cyl;
    cyl.vertices.resize(static_cast<std::size_t>(2 * n));
    for (int i = 0; i < n; ++i) {
        cyl.vertices[i] = ringVertex(centre, half, i, n, centre.z() - half.z());
        cyl.vertices[n + i] = ringVertex(centre, half, i, n, centre.z() + half.z());
    }
    for (int i = 0; i < n; ++i) {
        const int next = (i + 1) % n;
        cyl.faces.push_back({i, next, n + next, n + i});
    }
    cyl.faces.push_back(lowerCap(0, n));
    std::vector<int> top;
    for (int i = 0; i < n; ++i) top.push_back(n + i);
    cyl.faces.push_back(std::move(top));
    return withSides(std::move(cyl), numSides, n);
}

ShapeBuild makeCone(const Eigen::Vector3d& v1, const Eigen::Vector3d& v2, int numSides) {
    const int n = effectiveConeSides(numSides);
    // docs/format.md §3.1: LoadBody rewrites the z bounds to [v1.z − v2.z, 0] before SetupCone, which puts the
    // apex at z = 0 and hard-codes its x and y to 0.
    const Eigen::Vector3d min(v1.x(), v1.y(), v1.z() - v2.z());
    const Eigen::Vector3d max(v2.x(), v2.y(), 0.0);
    const Eigen::Vector3d centre = boundsCentre(min, max);
    const Eigen::Vector3d half = max - centre;
    Polytope cone;
    cone.vertices.resize(static_cast<std::size_t>(n + 1));
    for (int i = 0; i < n; ++i) cone.vertices[i] = ringVertex(centre, half, i, n, min.z());
    cone.vertices[n] = Eigen::Vector3d::Zero();
    for (int i = 0; i < n; ++i) cone.faces.push_back({i, (i + 1) % n, n});
    cone.faces.push_back(lowerCap(0, n));
    return withSides(std::move(cone), numSides, n);
}

Polytope makeBone(double length, double width) {
    const double halfLength = length * 0.5;
    Polytope bone;
    bone.vertices = {{0, 0, -halfLength},
                     {0, -width * 0.5, 0},
                     {width * 0.5, width * 0.25, 0},
                     {-width * 0.5, width * 0.25, 0},
                     {0, 0, halfLength}};
    // The equator 1 → 2 → 3 runs counter-clockwise seen from +Z: upper pyramid with apex 4, lower with apex
    // 0.
    bone.faces = {{1, 2, 4}, {2, 3, 4}, {3, 1, 4}, {2, 1, 0}, {3, 2, 0}, {1, 3, 0}};
    return bone;
}

Eigen::Matrix3d boneFrame(const Eigen::Vector3d& v1, const Eigen::Vector3d& v2) {
    const Eigen::Vector3d diff = v2 - v1;
    const double length = diff.norm();
    if (length == 0.0) return Eigen::Matrix3d::Identity();
    const Eigen::Vector3d d = diff / length;
    // docs/format.md §0 NormalVectors: left = (−y, x, 0)/√(x² + y²), or (1, 0, 0) when x² + y² is exactly 0.
    const double lenSqrXY = d.x() * d.x() + d.y() * d.y();
    const Eigen::Vector3d left =
        lenSqrXY == 0.0 ? Eigen::Vector3d(1, 0, 0) : Eigen::Vector3d(-d.y(), d.x(), 0) / std::sqrt(lenSqrXY);
    // docs/format.md §3.1: Doom's axis rows (left, d × left, d) are our columns.
    Eigen::Matrix3d frame;
    frame.col(0) = left;
    frame.col(1) = d.cross(left);
    frame.col(2) = d;
    return frame;
}

} // namespace afb::figure
