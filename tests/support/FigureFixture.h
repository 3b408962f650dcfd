#pragma once
// Builds figures from inline text for tests: an md5 skeleton from a joint list, an .af decl, and the Figure.
#include <optional>
#include <sstream>
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

/// md5mesh text of a skeleton with identity orientations and one triangle weighted to the last joint.
inline std::string md5MeshText(const std::vector<TestJoint>& joints) {
    std::ostringstream s;
    s << "MD5Version 10\ncommandline \"\"\nnumJoints " << joints.size() << "\nnumMeshes 1\njoints {\n";
    for (const TestJoint& j : joints)
        s << "\"" << j.name << "\" " << j.parent << " ( " << j.x << " " << j.y << " " << j.z << " ) ( 0 0 0 )\n";
    s << "}\nmesh {\nshader \"x\"\nnumverts 3\nvert 0 ( 0 0 ) 0 1\nvert 1 ( 0 0 ) 1 1\nvert 2 ( 0 0 ) 2 1\n"
      << "numtris 1\ntri 0 0 1 2\nnumweights 3\n";
    const std::size_t last = joints.size() - 1;
    s << "weight 0 " << last << " 1 ( 0 0 0 )\nweight 1 " << last << " 1 ( 1 0 0 )\nweight 2 " << last
      << " 1 ( 0 1 0 )\n}\n";
    return s.str();
}

/// A one-frame af_pose md5anim equal to the mesh's bind pose (identity orientations).
inline std::string md5AnimText(const std::vector<TestJoint>& joints) {
    std::ostringstream s;
    s << "MD5Version 10\ncommandline \"\"\nnumFrames 1\nnumJoints " << joints.size()
      << "\nframeRate 24\nnumAnimatedComponents 0\nhierarchy {\n";
    for (const TestJoint& j : joints) s << "\"" << j.name << "\" " << j.parent << " 0 0\n";
    s << "}\nbounds {\n( -1 -1 -1 ) ( 1 1 1 )\n}\nbaseframe {\n";
    for (const TestJoint& j : joints) {
        double px = j.x, py = j.y, pz = j.z;
        if (j.parent >= 0) {
            const TestJoint& p = joints[static_cast<std::size_t>(j.parent)];
            px -= p.x;
            py -= p.y;
            pz -= p.z;
        }
        s << "( " << px << " " << py << " " << pz << " ) ( 0 0 0 )\n";
    }
    s << "}\nframe 0 {\n}\n";
    return s.str();
}

/// Everything a test needs to keep alive around a built figure.
struct BuiltFigure {
    std::optional<figure::Figure> figure;
    text::Diagnostics diagnostics; ///< parse errors and figure findings
};

/// Parses `afText` (its first decl) and builds it on the skeleton `joints`.
inline BuiltFigure buildTestFigure(const std::string& afText, const std::vector<TestJoint>& joints,
                                   figure::UnitSystem units = {}) {
    BuiltFigure out;
    const auto mesh = decl::parseMd5Mesh(md5MeshText(joints), "test.md5mesh", out.diagnostics);
    const auto anim = decl::parseMd5Anim(md5AnimText(joints), "test.md5anim", out.diagnostics);
    const auto af = decl::parseAf(afText, "test.af", out.diagnostics);
    if (!mesh || !anim || !af || af->decls.empty()) return out;
    const auto skeleton = figure::Skeleton::build(*mesh, *anim, Eigen::Vector3d::Zero(), out.diagnostics, "test");
    if (!skeleton) return out;
    out.figure = figure::buildFigure({&af->decls[0], &*skeleton, units}, out.diagnostics);
    return out;
}

} // namespace afb::test
