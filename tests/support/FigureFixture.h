#pragma once
// Builds figures for tests: md5 values of a skeleton from a joint list (text only through the md5 writers),
// an .af decl from inline text, and the Figure.
#include <optional>
#include <string>
#include <vector>

#include "afb/decl/AfParser.h"
#include "afb/decl/Md5Anim.h"
#include "afb/decl/Md5Mesh.h"
#include "afb/figure/Figure.h"

namespace afb::test {

/// One joint of a test skeleton: model-space position, identity orientation.
struct TestJoint {
    std::string name;
    int parent;
    double x, y, z;
};

/// An md5mesh of a skeleton with identity orientations and one triangle weighted to the last joint.
inline decl::Md5Mesh md5Mesh(const std::vector<TestJoint>& joints) {
    decl::Md5Mesh mesh;
    for (const TestJoint& j : joints) mesh.joints.push_back({j.name, j.parent, {j.x, j.y, j.z}, {0, 0, 0}});
    const int last = static_cast<int>(joints.size()) - 1;
    decl::Md5SubMesh sub;
    sub.shader = "x";
    sub.verts = {{0, 0, 0, 1}, {0, 0, 1, 1}, {0, 0, 2, 1}};
    sub.tris = {{{0, 1, 2}}};
    sub.weights = {{last, 1, {0, 0, 0}}, {last, 1, {1, 0, 0}}, {last, 1, {0, 1, 0}}};
    mesh.meshes.push_back(sub);
    return mesh;
}

/// A one-frame af_pose md5anim equal to the mesh's bind pose (identity orientations).
inline decl::Md5Anim md5Anim(const std::vector<TestJoint>& joints) {
    decl::Md5Anim anim;
    anim.frameRate = 24;
    for (const TestJoint& j : joints) {
        anim.hierarchy.push_back({j.name, j.parent, 0, 0});
        decl::Vec3 p{j.x, j.y, j.z};
        if (j.parent >= 0) {
            const TestJoint& parent = joints[static_cast<std::size_t>(j.parent)];
            p = {j.x - parent.x, j.y - parent.y, j.z - parent.z};
        }
        anim.baseframe.push_back({p, {0, 0, 0}});
    }
    anim.bounds = {{{-1, -1, -1}, {1, 1, 1}}};
    anim.frames = {{}};
    return anim;
}

/// md5mesh text of md5Mesh(joints), for tests that need a file.
inline std::string md5MeshText(const std::vector<TestJoint>& joints) { return decl::writeMd5Mesh(md5Mesh(joints)); }

/// md5anim text of md5Anim(joints), for tests that need a file.
inline std::string md5AnimText(const std::vector<TestJoint>& joints) { return decl::writeMd5Anim(md5Anim(joints)); }

/// Everything a test needs to keep alive around a built figure.
struct BuiltFigure {
    std::optional<figure::Figure> figure;
    text::Diagnostics diagnostics; ///< parse errors and figure findings
};

/// Parses `afText` (its first decl) and builds it on the skeleton `joints`.
inline BuiltFigure buildTestFigure(const std::string& afText, const std::vector<TestJoint>& joints,
                                   figure::UnitSystem units = {}) {
    BuiltFigure out;
    const auto af = decl::parseAf(afText, "test.af", out.diagnostics);
    if (!af || af->decls.empty()) return out;
    const auto skeleton =
        figure::Skeleton::build(md5Mesh(joints), md5Anim(joints), Eigen::Vector3d::Zero(), out.diagnostics, "test");
    if (!skeleton) return out;
    out.figure = figure::buildFigure({&af->decls[0], &*skeleton, units}, out.diagnostics);
    return out;
}

/// The one-arm pendulum the method and multibody tests drive into their limits: `top`, an 8-unit cube fixed to
/// the world at (0, 0, 104), and `arm`, a 20-unit box along +X from the anchor (0, 0, 100), joined by `constraint`
/// (an .af constraint block between "arm" and "top"), `armSettings` added to the arm's body block (e.g. its friction).
/// Skeleton origin, top, arm with identity orientations.
inline BuiltFigure buildArmFigure(const std::string& constraint, const std::string& armSettings = "") {
    const std::vector<TestJoint> joints = {{"origin", -1, 0, 0, 0}, {"top", 0, 0, 0, 104}, {"arm", 1, 0, 0, 100}};
    return buildTestFigure("articulatedFigure t {\n settings { selfCollision 0 }\n"
                           " body \"top\" { joint \"origin\" model box( ( -4, -4, -4 ), ( 4, 4, 4 ) ) origin ( 0, 0, "
                           "104 ) density 0.1 }\n"
                           " body \"arm\" { joint \"arm\" model box( ( 0, -1, -1 ), ( 20, 1, 1 ) ) origin ( 0, 0, "
                           "100 ) density 0.2 " +
                               armSettings +
                               " }\n"
                               " fixed \"mount\" { body1 \"top\" body2 \"world\" }\n " +
                               constraint + "\n}\n",
                           joints);
}

/// A 0.5 kg plate (`foot`, 20 × 20 × 2 units) under a 50 kg block (`block`, 20 × 20 × 20 units) joined by a
/// `fixed` constraint, the plate's centre 2 units above the entity's origin: the direct solve's landing tests.
inline BuiltFigure buildPlateUnderBlockFigure() {
    const std::vector<TestJoint> joints = {{"origin", -1, 0, 0, 2}, {"top", 0, 0, 0, 4}};
    return buildTestFigure(
        "articulatedFigure pair {\n settings { selfCollision 0 }\n"
        " body \"foot\" { joint \"origin\" model box( ( -10, -10, -1 ), ( 10, 10, 1 ) ) origin ( 0, 0, 2 ) density "
        "0.000625 containedJoints \"origin\" }\n"
        " body \"block\" { joint \"top\" model box( ( -10, -10, 0 ), ( 10, 10, 20 ) ) origin ( 0, 0, 3 ) density "
        "0.0062 containedJoints \"top\" }\n"
        " fixed \"ankle\" { body1 \"block\" body2 \"foot\" }\n}\n",
        joints);
}

} // namespace afb::test
