#pragma once
// The engine's trace-model shapes as exact convex polytopes (docs/format.md §3.1), in body-local coordinates.
// Lengths are in whatever unit the caller passes (Doom units when built from a decl; the figure layer scales
// afterwards). No Doom row-matrix math leaks out: `boneFrame` returns a standard column rotation.
#include <optional>
#include <span>
#include <vector>

#include <Eigen/Geometry>

namespace afb::figure {

/// A closed convex polyhedron given by its vertices and its faces.
struct Polytope {
    /// Vertex positions, body-local, in the caller's length unit.
    std::vector<Eigen::Vector3d> vertices;
    /// One vertex-index loop per face, counter-clockwise seen from outside (outward normal by the right-hand
    /// rule). Degenerate shapes (a 2-sided cone) may have 2-vertex faces.
    std::vector<std::vector<int>> faces;

    /// Number of vertices (the engine's `numVerts`).
    int vertexCount() const { return static_cast<int>(vertices.size()); }
    /// Number of faces (the engine's `numPolys`).
    int faceCount() const { return static_cast<int>(faces.size()); }
    /// Number of edges (the engine's `numEdges`): every edge bounds exactly two faces, so half the number of
    /// face-vertex uses.
    int edgeCount() const;
};

/// The outward unit normal of one face loop over `vertices` (counter-clockwise seen from outside): the sum of
/// the cross products of consecutive vertices (Newell's method, exact for planar loops), normalized. nullopt
/// for a degenerate face (fewer than 3 vertices, or zero area).
std::optional<Eigen::Vector3d> faceNormal(std::span<const Eigen::Vector3d> vertices, std::span<const int> face);

/// A face's plane: points p on it have normal · p = offset, points inside the polytope normal · p ≤ offset.
struct FacePlane {
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ(); ///< outward, unit
    double offset = 0; ///< signed distance of the plane from the origin along `normal`, in the vertices' unit
};

/// The plane of every non-degenerate face (see faceNormal), through the face's vertex centroid, in face
/// order.
std::vector<FacePlane> facePlanes(std::span<const Eigen::Vector3d> vertices, std::span<const std::vector<int>> faces);

/// The distance from the origin to the nearest of `planes` (for a body's polytope: the radius of the largest
/// sphere about its centre of mass that fits inside); negative when the origin is outside, +infinity for
/// none.
double inRadius(std::span<const FacePlane> planes);

/// A cylinder or cone build: the polytope plus what the engine's side clamps did to the requested count.
struct ShapeBuild {
    Polytope polytope;      ///< the shape, body-local
    int requestedSides = 0; ///< `numSides` as the decl gave it
    int effectiveSides = 0; ///< sides actually built after the engine's clamps (docs/format.md §3.1)
    /// True when effectiveSides != requestedSides (raised to the minimum or cut to the maximum); the engine
    /// changes the count silently or with only a console print (docs/format.md §8 item 15).
    bool clamped = false;
};

/// Side count the engine builds for `cylinder(…, requested)`: < 3 → 3, then 2n ≤ 32, 3n ≤ 32, n + 2 ≤ 16,
/// in that order, so the result is in [3, 10] (docs/format.md §3.1).
int effectiveCylinderSides(int requested);
/// Side count the engine builds for `cone(…, requested)`: < 2 → 3 (2 stays 2), then n + 1 ≤ 32, 2n ≤ 32,
/// n + 1 ≤ 16, in that order, so the result is 2 or in [3, 15] (docs/format.md §3.1).
int effectiveConeSides(int requested);

/// `box(min, max)`: the 8 corners (docs/format.md §3.1). Vertices 0–3 are the min-z face counter-clockwise from
/// (min.x, min.y) seen from +Z, vertices 4–7 the same at max z. Inverted bounds give inward faces (negative
/// volume), as in the engine.
Polytope makeBox(const Eigen::Vector3d& min, const Eigen::Vector3d& max);

/// `octahedron(min, max)`: centre ± half-extent along each axis, vertices in the order +X, −X, +Y, −Y, +Z, −Z
/// (docs/format.md §3.1).
Polytope makeOctahedron(const Eigen::Vector3d& min, const Eigen::Vector3d& max);

/// `dodecahedron(min, max)`: the circumradius-1 regular dodecahedron (±a,±a,±a), (±b,±c,0), (±c,0,±b),
/// (0,±b,±c), scaled per axis by extent·0.5/c and centred on the bounds centre, so the ±c vertices touch the
/// bounds (docs/format.md §3.1). Vertex order as the engine's.
Polytope makeDodecahedron(const Eigen::Vector3d& min, const Eigen::Vector3d& max);

/// `cylinder(min, max, numSides)`: an n-sided prism along Z inscribed in the ellipse with the bounds' x/y
/// half-extents, vertex i at centre + (cos θi·hx, sin θi·hy, −hz) and vertex n + i the same at +hz, with
/// θi = 2πi/n (vertex 0 lies on +X) (docs/format.md §3.1).
ShapeBuild makeCylinder(const Eigen::Vector3d& min, const Eigen::Vector3d& max, int numSides);

/// `cone(v1, v2, numSides)` with v1/v2 AS THE DECL GAVE THEM: this applies LoadBody's z rewrite itself
/// (bounds z become [v1.z − v2.z, 0]). Apex at body-local (0, 0, 0) whatever the bounds' x/y centre (the
/// engine hard-codes apex x = y = 0); base n-gon at z = −(v2.z − v1.z), vertex i = (cx + cos θi·hx, cy + sin
/// θi·hy), θi = 2πi/n; the apex is the last vertex (index n). The cone points along +Z (docs/format.md §3.1).
ShapeBuild makeCone(const Eigen::Vector3d& v1, const Eigen::Vector3d& v2, int numSides);

/// `bone(v1, v2, width)` in its own body frame, centred on the body origin: vertices (0,0,−L/2), (0,−w/2,0),
/// (+w/2,+w/4,0), (−w/2,+w/4,0), (0,0,+L/2) and 6 triangles (docs/format.md §3.1). `length` = |v2 − v1|.
Polytope makeBone(double length, double width);

/// The bone body's orientation in model space as a standard rotation: columns are the body's local X, Y, Z
/// axes. Z = d = (v2 − v1)/|v2 − v1|, X = `left` of NormalVectors(d) (exact zero test: (1,0,0) when
/// d.x² + d.y² == 0), Y = d × left (docs/format.md §3.1, §0; Doom's axis rows are these columns).
/// Returns the identity when v1 == v2 (the engine's result there is NaN; the figure layer reports it).
Eigen::Matrix3d boneFrame(const Eigen::Vector3d& v1, const Eigen::Vector3d& v2);

} // namespace afb::figure
