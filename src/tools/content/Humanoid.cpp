// The humanoid: a 30-joint skeleton, a skinned body and head made of tubes, its 15-body ragdoll, a walk cycle and an
// idle (breathing and a slow sway over the feet).
#include <algorithm>
#include <cmath>
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
using Eigen::Quaterniond;
using Eigen::Vector3d;

namespace {

Skeleton humanoidSkeleton() {
    Skeleton s;
    const double c = std::cos(45 * kDeg), sn = std::sin(45 * kDeg);
    s.add("origin", "", {0, 0, 0});
    s.add("pelvis", "origin", {0, 0, 38});
    s.add("spine", "pelvis", {0, 0, 43});
    s.add("chest", "spine", {0, 0, 50});
    s.add("neck", "chest", {0, 0, 59});
    s.add("head", "neck", {0, 0, 62.5});
    s.add("head_end", "head", {0, 0, 71});
    s.add("jaw", "head", {1.5, 0, 61.5});
    for (const char* side : {"l", "r"}) {
        const std::string p = side;
        const double sy = p == "l" ? 1 : -1;
        const Vector3d d(0, sy * c, -sn); // the arm hangs 45 degrees below horizontal
        const Vector3d shoulder(0, sy * 7.5, 57);
        s.add(p + "_clavicle", "chest", {0, sy * 2, 57});
        s.add(p + "_upperarm", p + "_clavicle", shoulder);
        s.add(p + "_forearm", p + "_upperarm", shoulder + 11 * d);
        s.add(p + "_hand", p + "_forearm", shoulder + 21 * d);
        s.add(p + "_finger1", p + "_hand", shoulder + 24.5 * d);
        s.add(p + "_finger2", p + "_finger1", shoulder + 26.5 * d);
        s.add(p + "_thumb", p + "_hand", shoulder + 22.5 * d + Vector3d(1.2, 0, 0));
    }
    for (const char* side : {"l", "r"}) {
        const std::string p = side;
        const double sy = p == "l" ? 1 : -1;
        s.add(p + "_thigh", "pelvis", {0, sy * 4, 37});
        s.add(p + "_shin", p + "_thigh", {0, sy * 5, 20});
        s.add(p + "_foot", p + "_shin", {0, sy * 6, 3});
        s.add(p + "_toe", p + "_foot", {5, sy * 6, 1});
    }
    return s;
}

std::vector<Mesh> humanoidMeshes(const Skeleton& sk) {
    Mesh body;
    body.name = "body";
    body.shader = "models/humanoid/body";
    Mesh head;
    head.name = "head";
    head.shader = "models/humanoid/head";
    const int N = 12;
    auto J = [&](const std::string& n) { return sk.index(n); };
    auto P = [&](const std::string& n) { return sk.pos(n); };
    // Torso: hips, abdomen, chest (elliptic: deeper across Y than across X).
    tube(body, sk, {0, 0, 32}, {0, 0, 43}, linear(4.8, 7.2, 4.4, 6.4), {J("pelvis"), -1, 6, N, true, false});
    tube(body, sk, {0, 0, 43}, {0, 0, 50}, linear(4.4, 6.4, 5.2, 7.6), {J("spine"), J("pelvis"), 5, N, false, false});
    tube(body, sk, {0, 0, 50}, {0, 0, 59}, linear(5.2, 7.6, 3.6, 6.6), {J("chest"), J("spine"), 6, N, false, true});
    tube(body, sk, {0, 0, 58}, {0, 0, 62.5}, linear(2.1, 2.1, 2.0, 2.0), {J("neck"), J("chest"), 3, N, false, false});
    // Head: a bulging tube with caps, plus the jaw.
    tube(head, sk, {0.5, 0, 60.8}, {0.5, 0, 71},
         [](double t) {
             const double k = std::pow(std::sin(kPi * (0.1 + 0.8 * t)), 0.6);
             return Eigen::Vector2d(4.2 * k, 3.6 * k);
         },
         {J("head"), J("neck"), 8, N, true, true});
    tube(head, sk, P("jaw"), P("jaw") + Vector3d(2.6, 0, -1.2), linear(1.6, 2.2, 1.0, 1.4),
         {J("jaw"), -1, 3, N, true, true});
    for (const char* side : {"l", "r"}) {
        const std::string p = side;
        tube(body, sk, P(p + "_upperarm"), P(p + "_forearm"), linear(2.2, 2.2, 1.7, 1.7),
             {J(p + "_upperarm"), J(p + "_clavicle"), 7, N, true, false});
        tube(body, sk, P(p + "_forearm"), P(p + "_hand"), linear(1.7, 1.7, 1.3, 1.3),
             {J(p + "_forearm"), J(p + "_upperarm"), 6, N, false, false});
        tube(body, sk, P(p + "_hand"), P(p + "_finger1"), linear(1.3, 0.8, 1.6, 0.6),
             {J(p + "_hand"), J(p + "_forearm"), 3, N, false, true});
        tube(body, sk, P(p + "_finger1"), P(p + "_finger2"), linear(0.5, 0.5, 0.45, 0.45),
             {J(p + "_finger1"), -1, 3, N, true, false});
        const Vector3d tip = P(p + "_finger2") + (P(p + "_finger2") - P(p + "_finger1"));
        tube(body, sk, P(p + "_finger2"), tip, linear(0.45, 0.45, 0.35, 0.35),
             {J(p + "_finger2"), J(p + "_finger1"), 3, N, false, true});
        const Vector3d thumbTip = P(p + "_thumb") + Vector3d(1.6, 0, -0.6);
        tube(body, sk, P(p + "_thumb"), thumbTip, linear(0.45, 0.45, 0.35, 0.35),
             {J(p + "_thumb"), -1, 3, N, true, true});
        tube(body, sk, P(p + "_thigh"), P(p + "_shin"), linear(3.3, 3.3, 2.3, 2.3),
             {J(p + "_thigh"), J("pelvis"), 8, N, false, false});
        tube(body, sk, P(p + "_shin"), P(p + "_foot"), linear(2.3, 2.3, 1.5, 1.5),
             {J(p + "_shin"), J(p + "_thigh"), 8, N, false, true});
        const Vector3d heel = P(p + "_foot") + Vector3d(-2, 0, -1.5);
        tube(body, sk, heel, P(p + "_toe"), linear(1.5, 1.8, 1.1, 1.8), {J(p + "_foot"), -1, 5, N, true, false});
        tube(body, sk, P(p + "_toe"), P(p + "_toe") + Vector3d(3, 0, -0.2), linear(1.1, 1.8, 0.7, 1.5),
             {J(p + "_toe"), J(p + "_foot"), 3, N, false, true});
    }
    return {body, head};
}

// The humanoid's bodies: pelvis, torso and head, then each arm, then each leg.
void humanoidBodies(AfBuilder& af) {
    af.body("pelvis", "origin", shape(ShapeKind::Box, {-4.5, -6.5, -4}, {4.5, 6.5, 4}), lit(0, 0, 38), 10,
            "*origin -*spine -*l_thigh -*r_thigh")
        .friction = BodyFriction{0.01, 0.01, 0.8};
    af.body("torso", "spine", shape(ShapeKind::Box, {-4, -6.5, -7.5}, {4, 6.5, 7.5}), boneCenter("spine", "neck"), 14,
            "*spine -*neck -*l_upperarm -*r_upperarm")
        .friction = BodyFriction{0.01, 0.01, 0.8};
    af.body("head", "neck", shape(ShapeKind::Dodecahedron, {-4, -3.8, -1.5}, {4.5, 3.8, 8.5}), jointV("head"), 5,
            "*neck")
        .friction = BodyFriction{0.02, 0.02, 0.6};
    for (const char* side : {"l", "r"}) {
        const std::string p = side;
        const bool left = p == "l";
        af.body(p + "_upperarm", p + "_upperarm", boneShape(p + "_upperarm", p + "_forearm", 4),
                boneCenter(p + "_upperarm", p + "_forearm"), 3.5, "*" + p + "_upperarm -*" + p + "_forearm");
        af.body(p + "_forearm", p + "_forearm", boneShape(p + "_forearm", p + "_hand", 3.5),
                boneCenter(p + "_forearm", p + "_hand"), 2.5, "*" + p + "_forearm -*" + p + "_hand");
        // The hand box runs along the arm: roll turns its local Y onto the arm direction.
        AfBody& hand = af.body(p + "_hand", p + "_hand",
                               left ? shape(ShapeKind::Box, {-1, 0.5, -2}, {1, 5.5, 2})
                                    : shape(ShapeKind::Box, {-1, -5.5, -2}, {1, -0.5, 2}),
                               jointV(p + "_hand"), 1.5, "*" + p + "_hand", false);
        hand.angles = lit(0, 0, left ? -45 : 45);
        hand.friction = BodyFriction{0.02, 0.02, 0.9};
    }
    for (const char* side : {"l", "r"}) {
        const std::string p = side;
        af.body(p + "_thigh", p + "_thigh", boneShape(p + "_thigh", p + "_shin", 5.5),
                boneCenter(p + "_thigh", p + "_shin"), 9, "*" + p + "_thigh -*" + p + "_shin");
        AfBody& shin = af.body(p + "_shin", p + "_shin", boneShape(p + "_shin", p + "_foot", 4.5),
                               boneCenter(p + "_shin", p + "_foot"), 5, "*" + p + "_shin -*" + p + "_foot");
        shin.inertiaScale = std::array<double, 9>{1, 0, 0, 0, 1, 0, 0, 0, 2}; // more spin inertia: a steadier bone
        af.body(p + "_foot", p + "_foot", shape(ShapeKind::Box, {-2.5, -1.8, -3}, {8, 1.8, 1}), jointV(p + "_foot"), 2,
                "*" + p + "_foot")
            .friction = BodyFriction{0.01, 0.01, 1};
    }
}

// The humanoid's joints: waist and neck, then each arm's shoulder, elbow and wrist, then each leg's hip, knee and
// ankle.
void humanoidConstraints(AfBuilder& af) {
    const double s45 = rnd(std::sin(45 * kDeg), 6);
    {
        AfConstraint& c = af.constraint(ConstraintType::Universal, "waist", "torso", "pelvis");
        c.anchor = jointV("spine");
        c.shafts = std::array<AfVector, 2>{lit(0, 0, 1), lit(0, 0, -1)};
        c.friction = 0.5;
        c.limit = PyramidLimit{lit(0, 0, 1), 60, 50, 0, std::nullopt};
    }
    {
        AfConstraint& c = af.constraint(ConstraintType::BallAndSocket, "neck", "head", "torso");
        c.anchor = jointV("neck");
        c.friction = 0.3;
        c.limit = ConeLimit{lit(0, 0, 1), 90, lit(0, 0, 1)};
    }
    for (const char* side : {"l", "r"}) {
        const std::string p = side;
        const double sy = p == "l" ? 1 : -1;
        {
            AfConstraint& c = af.constraint(ConstraintType::Universal, p + "_shoulder", p + "_upperarm", "torso");
            c.anchor = jointV(p + "_upperarm");
            c.shafts = std::array<AfVector, 2>{boneDir(p + "_upperarm", p + "_forearm"),
                                               boneDir(p + "_upperarm", p + "_forearm", true)};
            c.friction = 0.4;
            c.limit = ConeLimit{lit(0.2, sy * 1, -1.5), 160, std::nullopt};
        }
        {
            // Elbow: axis d × X (unit), so positive angles bring the hand forward; range [-5, 140] degrees.
            AfConstraint& c = af.constraint(ConstraintType::Hinge, p + "_elbow", p + "_forearm", p + "_upperarm");
            c.anchor = jointV(p + "_forearm");
            c.axis = lit(0, -s45, -sy * s45);
            c.friction = 0.4;
            c.limit = HingeLimit{-67.5, 145, 0};
        }
        af.constraint(ConstraintType::Fixed, p + "_wrist", p + "_hand", p + "_forearm");
    }
    for (const char* side : {"l", "r"}) {
        const std::string p = side;
        const double sy = p == "l" ? 1 : -1;
        {
            AfConstraint& c = af.constraint(ConstraintType::Universal, p + "_hip", p + "_thigh", "pelvis");
            c.anchor = jointV(p + "_thigh");
            c.shafts =
                std::array<AfVector, 2>{boneDir(p + "_thigh", p + "_shin"), boneDir(p + "_thigh", p + "_shin", true)};
            c.friction = 0.5;
            c.limit = ConeLimit{lit(0.5, sy * 0.15, -1), 110, std::nullopt};
        }
        {
            // Knee: about +Y positive angles swing the shin backwards; range [-5, 140] degrees (off-centre).
            AfConstraint& c = af.constraint(ConstraintType::Hinge, p + "_knee", p + "_shin", p + "_thigh");
            c.anchor = jointV(p + "_shin");
            c.axis = lit(0, 1, 0);
            c.friction = 0.5;
            c.limit = HingeLimit{0, 145, 67.5};
        }
        {
            AfConstraint& c = af.constraint(ConstraintType::BallAndSocket, p + "_ankle", p + "_foot", p + "_shin");
            c.anchor = jointV(p + "_foot");
            c.friction = 0.5;
            c.limit = PyramidLimit{lit(1, 0, 0), 30, 70, 0, lit(1, 0, 0)};
        }
    }
}

std::string humanoidAf(const Skeleton& sk) {
    AfBuilder af("humanoid", sk);
    af.settings("model_humanoid", 70);
    humanoidBodies(af);
    humanoidConstraints(af);
    return writeAf(af.decl);
}

// The turn that takes bone `from`→`to` of the bind pose to where `turn` points it, by the shortest arc: a swing
// without twist about the bone, which is what a universal joint (the humanoid's shoulders and hips) lets a limb do.
Quaterniond swingOf(const Skeleton& sk, const std::string& from, const std::string& to, const Quaterniond& turn) {
    const Vector3d rest = (sk.pos(to) - sk.pos(from)).normalized();
    return Quaterniond::FromTwoVectors(rest, turn * rest);
}

std::string humanoidWalk(const Skeleton& sk, const std::vector<Mesh>& meshes) {
    const int numFrames = 25; // 24 distinct frames plus the first again, so the cycle loops (1 s at 24 fps)
    std::vector<int> animated(sk.joints.size(), 0);
    const int TZ = 4, QALL = 8 | 16 | 32, QY = 16;
    animated[static_cast<std::size_t>(sk.index("pelvis"))] = TZ;
    for (const char* side : {"l", "r"}) {
        const std::string p = side;
        animated[static_cast<std::size_t>(sk.index(p + "_upperarm"))] = QALL;
        animated[static_cast<std::size_t>(sk.index(p + "_thigh"))] = QALL;
        animated[static_cast<std::size_t>(sk.index(p + "_shin"))] = QY;
        animated[static_cast<std::size_t>(sk.index(p + "_foot"))] = QY;
    }
    auto aa = [](double deg, const Vector3d& axis) { return Quaterniond(Eigen::AngleAxisd(deg * kDeg, axis)); };
    std::vector<Pose> frames;
    for (int f = 0; f < numFrames; ++f) {
        const double phase = 2 * kPi * (f % 24) / 24.0;
        Pose pose = bindPose(sk);
        pose.t[static_cast<std::size_t>(sk.index("pelvis"))].z() = 38 - 0.8 + 0.8 * std::cos(2 * phase);
        for (const char* side : {"l", "r"}) {
            const std::string p = side;
            const double sy = p == "l" ? 1 : -1;
            const double ph = p == "l" ? phase : phase + kPi;
            const double s45 = std::sin(45 * kDeg);
            // Negative angles about +Y swing a limb forward (-Z towards +X).
            const double thigh = -25 * std::sin(ph);
            const double knee = 5 + 45 * std::pow(std::max(0.0, std::cos(ph)), 2);
            pose.q[static_cast<std::size_t>(sk.index(p + "_thigh"))] =
                swingOf(sk, p + "_thigh", p + "_shin", aa(thigh, Vector3d::UnitY()));
            pose.q[static_cast<std::size_t>(sk.index(p + "_shin"))] = aa(knee, Vector3d::UnitY());
            pose.q[static_cast<std::size_t>(sk.index(p + "_foot"))] = aa(-0.6 * (thigh + knee), Vector3d::UnitY());
            // Arms: lowered from the 45-degree rest to about 80 degrees, swinging against the legs; shoulders and
            // hips are universal joints, so each limb swings without twist (swingOf).
            pose.q[static_cast<std::size_t>(sk.index(p + "_upperarm"))] =
                swingOf(sk, p + "_upperarm", p + "_forearm",
                        aa(20 * std::sin(ph), Vector3d::UnitY()) * aa(-sy * 35, Vector3d::UnitX()));
            pose.q[static_cast<std::size_t>(sk.index(p + "_forearm"))] = aa(20, Vector3d(0, -s45, -sy * s45));
        }
        frames.push_back(pose);
    }
    return writeMd5Anim(toMd5Anim(sk, meshes, frames, animated, 24, "afb_gen_content: humanoid walk cycle"));
}

// The idle: 4 s (96 distinct frames plus the first again, at 24 fps) of standing. The whole figure sways over its
// feet, turning about the model origin on the ground between them (the root joint's rotation: its translation is
// dropped by the loader), once sideways and twice back and forth per cycle; the feet turn back to stay flat and the
// spine leans a little against the sway. It breathes twice per cycle: the spine and the head nod, the arms hanging
// from the shoulders lift and the elbows bend a little with it. Every term is a whole number of periods of the cycle,
// so the last frame is the first again, and every joint stays well inside the .af's limits.
std::string humanoidIdle(const Skeleton& sk, const std::vector<Mesh>& meshes) {
    const int cycle = 96, numFrames = cycle + 1;
    std::vector<int> animated(sk.joints.size(), 0);
    const int QALL = 8 | 16 | 32; // a product of turns about X and Y has a Z component too
    auto at = [&](const std::string& joint) { return static_cast<std::size_t>(sk.index(joint)); };
    animated[at("origin")] = QALL;
    animated[at("spine")] = QALL;
    animated[at("neck")] = QALL;
    for (const char* side : {"l", "r"}) {
        const std::string p = side;
        animated[at(p + "_upperarm")] = QALL;
        animated[at(p + "_forearm")] = QALL;
        animated[at(p + "_thigh")] = QALL;
        animated[at(p + "_shin")] = QALL;
        animated[at(p + "_foot")] = QALL;
    }
    auto aa = [](double deg, const Vector3d& axis) { return Quaterniond(Eigen::AngleAxisd(deg * kDeg, axis)); };
    std::vector<Pose> frames;
    for (int f = 0; f < numFrames; ++f) {
        const double phase = 2 * kPi * (f % cycle) / cycle;
        const double breath = std::sin(2 * phase); // > 0: breathing in
        const double sway = std::sin(phase);       // > 0: the weight over the left foot (+Y)
        Pose pose = bindPose(sk);
        // About +X a positive angle tips the top towards −Y (right); about +Y it tips it towards +X (forward).
        const Quaterniond root =
            aa(-2.0 * sway, Vector3d::UnitX()) * aa(-0.8 * std::sin(2 * phase + 1), Vector3d::UnitY());
        pose.q[at("origin")] = root;
        pose.q[at("spine")] = aa(0.8 * sway, Vector3d::UnitX()) * aa(1.5 * breath, Vector3d::UnitY());
        pose.q[at("neck")] = aa(-1.2 * breath, Vector3d::UnitY()) * aa(4 * std::sin(phase + 0.5), Vector3d::UnitZ());
        for (const char* side : {"l", "r"}) {
            const std::string p = side;
            const double sy = p == "l" ? 1 : -1;
            // The leg the weight leaves bends its knee a little; the foot turns back flat on the ground.
            const double knee = 4 + 3 * (1 - sy * sway);
            // Shoulders and hips are universal joints: limbs swing without twist (swingOf).
            const Quaterniond thigh = swingOf(sk, p + "_thigh", p + "_shin",
                                              aa(-0.5 * knee, Vector3d::UnitY()) * aa(0.5 * sy, Vector3d::UnitX()));
            const Quaterniond shin = aa(knee, Vector3d::UnitY());
            pose.q[at(p + "_thigh")] = thigh;
            pose.q[at(p + "_shin")] = shin;
            pose.q[at(p + "_foot")] = (root * thigh * shin).inverse();
            const double s45 = std::sin(45 * kDeg);
            const Quaterniond lower = aa(-sy * (38 - 2 * breath), Vector3d::UnitX());
            pose.q[at(p + "_upperarm")] =
                swingOf(sk, p + "_upperarm", p + "_forearm", aa(-3 * breath - 4, Vector3d::UnitY()) * lower);
            pose.q[at(p + "_forearm")] = aa(12 + 3 * breath, Vector3d(0, -s45, -sy * s45));
        }
        frames.push_back(pose);
    }
    return writeMd5Anim(
        toMd5Anim(sk, meshes, frames, animated, 24, "afb_gen_content: humanoid idle (breathing, sway)"));
}

} // namespace

void writeHumanoid(Output& out) {
    const Skeleton sk = humanoidSkeleton();
    const std::vector<Mesh> meshes = humanoidMeshes(sk);
    out.write("models/md5/humanoid/humanoid.md5mesh",
              writeMd5Mesh(toMd5Mesh(sk, meshes, "afb_gen_content: humanoid (procedural tubes), MIT licensed")));
    out.write("models/md5/humanoid/af_pose.md5anim",
              writeMd5Anim(
                  afPoseAnim(sk, meshes, "afb_gen_content: humanoid af_pose (arms 45 degrees down, legs apart)")));
    out.write("models/md5/humanoid/walk.md5anim", humanoidWalk(sk, meshes));
    out.write("models/md5/humanoid/idle.md5anim", humanoidIdle(sk, meshes));
    out.write("af/humanoid.af", humanoidAf(sk));
}

} // namespace afb::gen
