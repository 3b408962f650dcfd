// The lamp: a shade hanging from a hook in the world on three links (ball-and-socket and universal joints).
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

void writeLamp(Output& out) {
    Skeleton sk;
    sk.add("origin", "", {0, 0, 0});
    sk.add("link1", "origin", {0, 0, 100});
    sk.add("link2", "link1", {0, 0, 92});
    sk.add("link3", "link2", {0, 0, 84});
    sk.add("shade", "link3", {0, 0, 76});
    sk.add("bulb", "shade", {0, 0, 70});

    Mesh m;
    m.shader = "models/props/lamp";
    const int N = 10;
    tube(m, sk, sk.pos("link1"), sk.pos("link2"), linear(0.6, 0.6, 0.6, 0.6),
         {sk.index("link1"), -1, 2, N, true, false});
    tube(m, sk, sk.pos("link2"), sk.pos("link3"), linear(0.6, 0.6, 0.6, 0.6),
         {sk.index("link2"), sk.index("link1"), 3, N, false, false});
    tube(m, sk, sk.pos("link3"), sk.pos("shade"), linear(0.6, 0.6, 0.6, 0.6),
         {sk.index("link3"), sk.index("link2"), 3, N, false, false});
    tube(m, sk, sk.pos("shade"), sk.pos("shade") - Vector3d(0, 0, 8), linear(2.5, 2.5, 8, 8),
         {sk.index("shade"), -1, 4, N, true, false});
    tube(m, sk, sk.pos("bulb") + Vector3d(0, 0, 3), sk.pos("bulb") - Vector3d(0, 0, 1), linear(1.5, 1.5, 1.2, 1.2),
         {sk.index("bulb"), -1, 3, N, true, true});
    const std::vector<Mesh> meshes{m};
    out.write("models/md5/props/lamp/lamp.md5mesh",
              writeMd5Mesh(toMd5Mesh(sk, meshes, "afb_gen_content: a hanging lamp")));
    out.write("models/md5/props/lamp/af_pose.md5anim",
              writeMd5Anim(afPoseAnim(sk, meshes, "afb_gen_content: lamp af_pose")));

    AfBuilder af("lamp", sk);
    af.settings("model_lamp", 8);
    af.body("link1", "origin", boneShape("link1", "link2", 2.5), boneCenter("link1", "link2"), 1.5, "*origin -*link2");
    af.body("link2", "link2", boneShape("link2", "link3", 2.5), boneCenter("link2", "link3"), 1.5, "*link2 -*link3");
    af.body("link3", "link3", boneShape("link3", "shade", 2.5), boneCenter("link3", "shade"), 1.5, "*link3 -*shade");
    af.body("shade", "shade", shape(ShapeKind::Cylinder, {-8, -8, -8}, {8, 8, 0}, 10), jointV("shade"), 4, "*shade");
    {
        AfConstraint& c = af.constraint(ConstraintType::BallAndSocket, "hook", "link1", "world");
        c.anchor = jointV("link1");
        c.friction = 0.1;
    }
    {
        AfConstraint& c = af.constraint(ConstraintType::BallAndSocket, "link1_link2", "link2", "link1");
        c.anchor = jointV("link2");
        c.friction = 0.1;
        c.limit = ConeLimit{lit(0, 0, -1), 90, lit(0, 0, -1)};
    }
    {
        AfConstraint& c = af.constraint(ConstraintType::Universal, "link2_link3", "link3", "link2");
        c.anchor = jointV("link3");
        c.shafts = std::array<AfVector, 2>{lit(0, 0, -1), lit(0, 0, 1)};
        c.friction = 0.1;
        c.limit = ConeLimit{lit(0, 0, -1), 90, std::nullopt};
    }
    {
        AfConstraint& c = af.constraint(ConstraintType::Universal, "link3_shade", "shade", "link3");
        c.anchor = jointV("shade");
        c.shafts = std::array<AfVector, 2>{lit(0, 0, -1), lit(0, 0, 1)};
        c.friction = 0.2;
        c.limit = ConeLimit{lit(0, 0, -1), 60, std::nullopt};
    }
    out.write("af/lamp.af", writeAf(af.decl));
}

} // namespace afb::gen
