// The buggy: a box chassis and four wheels, each on a hub that slides vertically against a spring.
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

void writeBuggy(Output& out) {
    Skeleton sk;
    sk.add("origin", "", {0, 0, 0});
    sk.add("chassis", "origin", {0, 0, 18});
    struct Wheel {
        std::string id;
        double x, y;
    };
    const std::vector<Wheel> wheels{{"fl", 14, 16}, {"fr", 14, -16}, {"rl", -14, 16}, {"rr", -14, -16}};
    for (const Wheel& w : wheels) {
        sk.add("hub_" + w.id, "chassis", {w.x, w.y, 8});
        sk.add("wheel_" + w.id, "hub_" + w.id, {w.x, w.y, 8});
    }

    Mesh m;
    m.shader = "models/props/buggy";
    boxMesh(m, sk, {-20, -12, 14}, {20, 12, 22}, sk.index("chassis"));
    for (const Wheel& w : wheels) {
        const double sy = w.y > 0 ? 1 : -1;
        tube(m, sk, {w.x, w.y - sy * 2, 8}, {w.x, w.y + sy * 2, 8}, linear(8, 8, 8, 8),
             {sk.index("wheel_" + w.id), -1, 2, 10, true, true});
        boxMesh(m, sk, {w.x - 1, w.y - sy * 4 - 1, 7}, {w.x + 1, w.y - sy * 4 + 1, 19}, sk.index("hub_" + w.id));
    }
    const std::vector<Mesh> meshes{m};
    out.write("models/md5/props/buggy/buggy.md5mesh",
              writeMd5Mesh(toMd5Mesh(sk, meshes, "afb_gen_content: a sprung buggy")));
    out.write("models/md5/props/buggy/af_pose.md5anim",
              writeMd5Anim(afPoseAnim(sk, meshes, "afb_gen_content: buggy af_pose")));

    AfBuilder af("buggy", sk);
    af.settings("model_buggy", 80);
    af.body("chassis", "origin", shape(ShapeKind::Box, {-20, -12, -4}, {20, 12, 4}), jointV("chassis"), 40,
            "origin chassis");
    for (const Wheel& w : wheels) {
        AfBody& hub = af.body("hub_" + w.id, "hub_" + w.id, shape(ShapeKind::Box, {-1.5, -1.5, -1.5}, {1.5, 1.5, 1.5}),
                              jointV("hub_" + w.id), 5, "hub_" + w.id);
        hub.mod = "both"; // the hub slides: its joint takes its position from the body, not from the chassis
        AfBody& wheel =
            af.body("wheel_" + w.id, "wheel_" + w.id, shape(ShapeKind::Cylinder, {-8, -8, -2}, {8, 8, 2}, 10),
                    jointV("wheel_" + w.id), 6, "*wheel_" + w.id);
        wheel.angles = lit(0, 0, 90); // the cylinder's axis (local Z) turned onto the axle (-Y)
        wheel.friction = BodyFriction{0.01, 0.01, 1};
    }
    for (const Wheel& w : wheels) {
        AfConstraint& slider = af.constraint(ConstraintType::Slider, "suspension_" + w.id, "hub_" + w.id, "chassis");
        slider.axis = lit(0, 0, 1);
        af.spring("spring_" + w.id, "hub_" + w.id, "chassis", jointV("hub_" + w.id), lit(w.x, w.y, 20), 12, 6, 16);
        AfConstraint& axle = af.constraint(ConstraintType::Hinge, "axle_" + w.id, "wheel_" + w.id, "hub_" + w.id);
        axle.anchor = jointV("wheel_" + w.id);
        axle.axis = lit(0, 1, 0);
        axle.friction = 0.05;
    }
    out.write("af/buggy.af", writeAf(af.decl));
}

} // namespace afb::gen
