// The props figure: one body per trace-model shape type (box, octahedron, dodecahedron, cylinder, cone,
// bone), each on its own joint, held together by springs.
#include <string>
#include <vector>

#include "AfBuilder.h"
#include "Common.h"
#include "Rig.h"
#include "afb/decl/AfParser.h"
#include "afb/decl/Md5Anim.h"
#include "afb/decl/Md5Mesh.h"

namespace afb::gen {

using namespace afb::decl;
using Eigen::Vector3d;

void writeProps(Output& out) {
    Skeleton sk;
    sk.add("origin", "", {0, 0, 0});
    sk.add("prop_box", "origin", {0, 0, 6});
    sk.add("prop_octahedron", "origin", {0, 20, 6});
    sk.add("prop_dodecahedron", "origin", {0, 40, 6});
    sk.add("prop_cylinder", "origin", {0, 60, 6});
    sk.add("prop_cone", "origin", {0, 80, 12});
    sk.add("prop_bone", "origin", {-6, 100, 4});
    sk.add("prop_bone_tip", "prop_bone", {6, 100, 4});

    Mesh m;
    m.shader = "models/props/props";
    const Vector3d h(6, 6, 6);
    for (const char* j : {"prop_box", "prop_octahedron", "prop_dodecahedron", "prop_cylinder"})
        boxMesh(m, sk, sk.pos(j) - h, sk.pos(j) + h, sk.index(j));
    boxMesh(m, sk, sk.pos("prop_cone") - Vector3d(6, 6, 12), sk.pos("prop_cone") + Vector3d(6, 6, 0),
            sk.index("prop_cone"));
    boxMesh(m, sk, sk.pos("prop_bone") - Vector3d(0, 2, 2), sk.pos("prop_bone_tip") + Vector3d(0, 2, 2),
            sk.index("prop_bone"));
    const std::vector<Mesh> meshes{m};
    out.write("models/md5/props/props.md5mesh",
              writeMd5Mesh(toMd5Mesh(sk, meshes, "afb_gen_content: one prop per shape type")));
    out.write("models/md5/props/props_af_pose.md5anim",
              writeMd5Anim(afPoseAnim(sk, meshes, "afb_gen_content: props af_pose")));

    AfBuilder af("props", sk);
    af.settings("model_props", 30);
    const Vector3d lo(-6, -6, -6), hi(6, 6, 6);
    af.body("box", "origin", shape(ShapeKind::Box, lo, hi), jointV("prop_box"), 5, "origin prop_box");
    af.body("octahedron", "prop_octahedron", shape(ShapeKind::Octahedron, lo, hi), jointV("prop_octahedron"), 5,
            "*prop_octahedron");
    af.body("dodecahedron", "prop_dodecahedron", shape(ShapeKind::Dodecahedron, lo, hi), jointV("prop_dodecahedron"), 5,
            "*prop_dodecahedron");
    af.body("cylinder", "prop_cylinder", shape(ShapeKind::Cylinder, {-5, -5, -6}, {5, 5, 6}, 10),
            jointV("prop_cylinder"), 5, "*prop_cylinder");
    // A cone's apex is at its origin and it extends 12 units down to its base.
    af.body("cone", "prop_cone", shape(ShapeKind::Cone, {-6, -6, 0}, {6, 6, 12}, 12), jointV("prop_cone"), 5,
            "*prop_cone");
    af.body("bone", "prop_bone", boneShape("prop_bone", "prop_bone_tip", 4), boneCenter("prop_bone", "prop_bone_tip"),
            5, "*prop_bone");
    const std::vector<std::pair<std::string, std::string>> links{{"octahedron", "box"},
                                                                 {"dodecahedron", "octahedron"},
                                                                 {"cylinder", "dodecahedron"},
                                                                 {"cone", "cylinder"},
                                                                 {"bone", "cone"}};
    auto jointOf = [](const std::string& body) { return body == "box" ? std::string("prop_box") : "prop_" + body; };
    for (const auto& [b1, b2] : links) {
        const Vector3d p1 = b1 == "bone" ? Vector3d(0, 100, 4) : sk.pos(jointOf(b1));
        const Vector3d p2 = sk.pos(jointOf(b2));
        const double rest = (p2 - p1).norm();
        af.spring(b2 + "_" + b1, b1, b2, b1 == "bone" ? boneCenter("prop_bone", "prop_bone_tip") : jointV(jointOf(b1)),
                  jointV(jointOf(b2)), rest, 0.6 * rest, 1.5 * rest);
    }
    out.write("af/props.af", writeAf(af.decl));
}

} // namespace afb::gen
