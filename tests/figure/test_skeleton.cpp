// figure::Skeleton and the md5 pose functions (docs/format.md §0, §2.1, §2.4, §5.1, §5.3, §7.3, §7.4, §8 items 19,
// 21, 22). Expected values are worked out by hand from the spec, not from the code under test.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <numbers>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "TestSupport.h"
#include "afb/decl/Md5Anim.h"
#include "afb/decl/Md5Mesh.h"
#include "afb/figure/Skeleton.h"

using namespace afb;
using Eigen::Matrix3d;
using Eigen::Vector3d;
using figure::Skeleton;
using figure::Transform;

namespace {

constexpr double kPi = std::numbers::pi;
const double kS45 = std::sqrt(0.5); // sin 45° = cos 45°

decl::Md5Mesh mesh(const std::string& joints, int numJoints) {
    const std::string src = "MD5Version 10\ncommandline \"\"\nnumJoints " + std::to_string(numJoints) +
                            "\nnumMeshes 0\njoints {\n" + joints + "}\n";
    text::Diagnostics d;
    auto m = decl::parseMd5Mesh(src, "test.md5mesh", d);
    INFO(d.str());
    REQUIRE(m);
    return *m;
}

// `hierarchy` and `baseframe` hold one line per joint; `frames` one brace body per frame.
decl::Md5Anim anim(const std::string& hierarchy, const std::string& baseframe, const std::vector<std::string>& frames,
                   int numJoints, int numComponents, int frameRate = 24) {
    std::string src = "MD5Version 10\ncommandline \"\"\nnumFrames " + std::to_string(frames.size()) + "\nnumJoints " +
                      std::to_string(numJoints) + "\nframeRate " + std::to_string(frameRate) +
                      "\nnumAnimatedComponents " + std::to_string(numComponents) + "\nhierarchy {\n" + hierarchy +
                      "}\nbounds {\n";
    for (std::size_t k = 0; k < frames.size(); ++k) src += "( 0 0 0 ) ( 0 0 0 )\n";
    src += "}\nbaseframe {\n" + baseframe + "}\n";
    for (std::size_t k = 0; k < frames.size(); ++k) src += "frame " + std::to_string(k) + " {\n" + frames[k] + "\n}\n";
    text::Diagnostics d;
    auto a = decl::parseMd5Anim(src, "test.md5anim", d);
    INFO(d.str());
    REQUIRE(a);
    return *a;
}

// A five-joint skeleton. Hips is turned +90° about Z (X → Y). By docs/format.md §0/§7.3 the file stores the
// conjugate: the standard quaternion (w = cos 45°, z = sin 45°) is written as components (0, 0, −sin 45°).
// Head adds +90° about its local X (Y → Z), written (−sin 45°, 0, 0) in the anim; its model-space rotation
// Rz(90°)·Rx(90°) is the 120° turn about (1,1,1) (X → Y, Y → Z, Z → X), the standard quaternion (½; ½, ½, ½),
// written (−½, −½, −½). "HIPS" repeats "Hips" ignoring case.
const std::string kJoints = "\"origin\" -1 ( 0 0 0 ) ( 0 0 0 )\n"
                            "\"Hips\" 0 ( 0 0 10 ) ( 0 0 -0.70710678118654752 )\n"
                            "\"Spine\" 1 ( 0 5 10 ) ( 0 0 -0.70710678118654752 )\n"
                            "\"Head\" 2 ( 0 7 10 ) ( -0.5 -0.5 -0.5 )\n"
                            "\"HIPS\" 0 ( 3 0 0 ) ( 0 0 0 )\n";
const std::string kHierarchy = "\"origin\" -1 0 0\n\"Hips\" 0 0 0\n\"Spine\" 1 0 0\n\"Head\" 2 0 0\n\"HIPS\" 0 0 0\n";
// The same pose, parent-relative: Spine is 5 along Hips' X, Head 2 along Spine's X.
const std::string kBaseframe = "( 0 0 0 ) ( 0 0 0 )\n"
                               "( 0 0 10 ) ( 0 0 -0.70710678118654752 )\n"
                               "( 5 0 0 ) ( 0 0 0 )\n"
                               "( 2 0 0 ) ( -0.70710678118654752 0 0 )\n"
                               "( 3 0 0 ) ( 0 0 0 )\n";

Skeleton build(const decl::Md5Mesh& m, const decl::Md5Anim& a, const Vector3d& offset = Vector3d::Zero(),
               figure::RootTranslation rule = figure::RootTranslation::ReplacedByOffset) {
    text::Diagnostics d;
    auto s = Skeleton::build(m, a, offset, d, "test", rule);
    INFO(d.str());
    REQUIRE(s);
    REQUIRE_FALSE(d.hasErrors());
    return *s;
}

bool near(const Vector3d& a, const Vector3d& b, double tol) { return (a - b).cwiseAbs().maxCoeff() <= tol; }
bool near(const Matrix3d& a, const Matrix3d& b, double tol) { return (a - b).cwiseAbs().maxCoeff() <= tol; }
bool near(const Transform& a, const Transform& b, double tol) {
    return near(a.rotation, b.rotation, tol) && near(a.position, b.position, tol);
}
Matrix3d rotZ(double deg) { return Eigen::AngleAxisd(deg * kPi / 180, Vector3d::UnitZ()).toRotationMatrix(); }

bool isRotation(const Matrix3d& r, double tol) {
    return near(Matrix3d(r.transpose() * r), Matrix3d::Identity(), tol) && std::abs(r.determinant() - 1) <= tol;
}

std::size_t countContaining(const text::Diagnostics& d, text::Severity severity, const std::string& needle) {
    return static_cast<std::size_t>(std::count_if(d.items().begin(), d.items().end(), [&](const text::Diagnostic& x) {
        return x.severity == severity && x.message.find(needle) != std::string::npos;
    }));
}

} // namespace

static_assert(std::is_copy_constructible_v<Skeleton> && std::is_copy_assignable_v<Skeleton>);

TEST_CASE("md5 quaternions are conjugated into standard rotations", "[figure][skeleton]") {
    const Skeleton s = build(mesh(kJoints, 5), anim(kHierarchy, kBaseframe, {""}, 5, 0));
    REQUIRE(s.jointCount() == 5);
    const auto& bind = s.bindPose();
    // Hips: written (0, 0, −sin 45°) is +90° about Z in column math: its local X axis points along model +Y.
    CHECK(near(bind[1].rotation, rotZ(90), 1e-12));
    CHECK(near(Vector3d(bind[1].rotation * Vector3d::UnitX()), Vector3d(0, 1, 0), 1e-12));
    // Head: X → Y, Y → Z, Z → X.
    Matrix3d head;
    head << 0, 0, 1, //
        1, 0, 0,     //
        0, 1, 0;
    CHECK(near(bind[3].rotation, head, 1e-12));
    CHECK(near(bind[3].position, Vector3d(0, 7, 10), 0));
    // w is always +sqrt(|1 − x² − y² − z²|): the written components alone fix the rotation.
    CHECK(near(figure::rotationFromMd5(0, 0, -kS45), rotZ(90), 1e-12));
    CHECK(near(figure::rotationFromMd5(0, 0, kS45), rotZ(-90), 1e-12));
}

TEST_CASE("a baseframe equal to the bind pose gives load pose == bind pose", "[figure][skeleton]") {
    const Skeleton s = build(mesh(kJoints, 5), anim(kHierarchy, kBaseframe, {""}, 5, 0));
    for (int i = 0; i < s.jointCount(); ++i) {
        INFO("joint " << i);
        CHECK(near(s.loadPose()[static_cast<std::size_t>(i)], s.bindPose()[static_cast<std::size_t>(i)], 1e-9));
    }
    // Hand FK of the anim: Spine = Hips + Rz(90°)·(5,0,0) = (0,5,10); Head = Spine + Rz(90°)·(2,0,0) =
    // (0,7,10).
    CHECK(near(s.loadPose()[2].position, Vector3d(0, 5, 10), 1e-12));
    CHECK(near(s.loadPose()[3].position, Vector3d(0, 7, 10), 1e-12));
    // Runtime FK starts from the same pose here (docs/format.md §5.1 step 3).
    const auto runtime = figure::toModelSpace(s.afPoseLocal(), s.parents());
    for (std::size_t i = 0; i < runtime.size(); ++i) CHECK(near(runtime[i], s.loadPose()[i], 1e-12));
    CHECK(s.names() == std::vector<std::string>{"origin", "Hips", "Spine", "Head", "HIPS"});
    CHECK(s.parents() == std::vector<int>{-1, 0, 1, 2, 0});
}

TEST_CASE("the load pose is frame 0 blended frameRate/1000 toward frame 1", "[figure][skeleton]") {
    // Hips animates Qz (flags 32, component 0): 90° in frame 0, 0° in frame 1. Spine animates Tx (flags 1,
    // component 1): 5 in frame 0, 15 in frame 1.
    const std::string hierarchy =
        "\"origin\" -1 0 0\n\"Hips\" 0 32 0\n\"Spine\" 1 1 1\n\"Head\" 2 0 0\n\"HIPS\" 0 0 0\n";
    for (int rate : {24, 60}) {
        INFO("frameRate " << rate);
        const decl::Md5Anim a = anim(hierarchy, kBaseframe, {"-0.70710678118654752 5", "0 15"}, 5, 2, rate);
        text::Diagnostics d;
        const auto s = Skeleton::build(mesh(kJoints, 5), a, Vector3d::Zero(), d, "test");
        REQUIRE(s);
        const double w = rate / 1000.0; // t = 1 ms
        const double hipsDeg = 90 * (1 - w);
        CHECK(near(s->loadPose()[1].rotation, rotZ(hipsDeg), 1e-9));
        const Vector3d spine = Vector3d(0, 0, 10) + rotZ(hipsDeg) * Vector3d(5 + 10 * w, 0, 0);
        CHECK(near(s->loadPose()[2].position, spine, 1e-9));
        // The runtime pose is the baseframe (docs/format.md §8 item 19), which differs: build says so.
        CHECK(near(s->afPoseLocal()[1].rotation, rotZ(90), 1e-12));
        CHECK(countContaining(d, text::Severity::Warning, "baseframe") == 1);
    }
}

TEST_CASE("animPoseLocal follows the engine's frame time math", "[figure][skeleton]") {
    const std::string hierarchy =
        "\"origin\" -1 0 0\n\"Hips\" 0 32 0\n\"Spine\" 1 1 1\n\"Head\" 2 0 0\n\"HIPS\" 0 0 0\n";
    const decl::Md5Anim a =
        anim(hierarchy, kBaseframe, {"-0.70710678118654752 5", "0 15", "0.70710678118654752 25"}, 5, 2, 10);
    const auto at = [&](double t) { return figure::animPoseLocal(a, t); };
    // t <= 0: frame 0.
    CHECK(near(at(-1)[1].rotation, rotZ(90), 1e-12));
    CHECK(at(0)[2].position.x() == 5);
    // Halfway between frames 0 and 1 (frame time 0.5 at 10 fps): slerp 90° → 0° gives 45°, lerp 5 → 15
    // gives 10.
    CHECK(near(at(0.05)[1].rotation, rotZ(45), 1e-12));
    CHECK(at(0.05)[2].position.x() == Approx(10).margin(1e-12));
    // A quarter into frames 1 → 2: 0° → −90° gives −22.5°; 15 → 25 gives 17.5.
    CHECK(near(at(0.125)[1].rotation, rotZ(-22.5), 1e-12));
    CHECK(at(0.125)[2].position.x() == Approx(17.5).margin(1e-12));
    // From the last frame's time on (2 frames × 0.1 s), it holds the last frame: no looping.
    CHECK(near(at(0.2)[1].rotation, rotZ(-90), 1e-12));
    CHECK(near(at(5.0)[1].rotation, rotZ(-90), 1e-12));
    CHECK(at(5.0)[2].position.x() == 25);
    // animFrameLocal reads one frame; out-of-range indices clamp.
    CHECK(figure::animFrameLocal(a, 1)[2].position.x() == 15);
    CHECK(figure::animFrameLocal(a, 99)[2].position.x() == 25);
    CHECK(figure::animFrameLocal(a, -3)[2].position.x() == 5);
    // Unanimated joints keep their baseframe values.
    CHECK(figure::animFrameLocal(a, 2)[3].position == Vector3d(2, 0, 0));
}

TEST_CASE("slerp takes the shorter arc", "[figure][skeleton]") {
    // Frame 0: +170° about Z (written z = −sin 85°); frame 1: −170° (written z = +sin 85°). The short way
    // passes through 180°, not 0°.
    const std::string hierarchy =
        "\"origin\" -1 0 0\n\"Hips\" 0 32 0\n\"Spine\" 1 0 0\n\"Head\" 2 0 0\n\"HIPS\" 0 0 0\n";
    const double z = std::sin(85 * kPi / 180);
    std::ostringstream f0, f1;
    f0 << std::setprecision(17) << -z;
    f1 << std::setprecision(17) << z;
    const decl::Md5Anim a = anim(hierarchy, kBaseframe, {f0.str(), f1.str()}, 5, 1, 10);
    CHECK(near(figure::animPoseLocal(a, 0.05)[1].rotation, rotZ(180), 1e-9));
}

TEST_CASE("root translation: zeroed by the loader, then the model offset", "[figure][skeleton]") {
    // The anim's root sits at (7, 8, 9); only Tx is animated, written 11 in the single frame.
    const std::string hierarchy =
        "\"origin\" -1 1 0\n\"Hips\" 0 0 0\n\"Spine\" 1 0 0\n\"Head\" 2 0 0\n\"HIPS\" 0 0 0\n";
    const std::string baseframe = "( 7 8 9 ) ( 0 0 0 )\n" + kBaseframe.substr(kBaseframe.find('\n') + 1);
    const decl::Md5Anim a = anim(hierarchy, baseframe, {"11"}, 5, 1);
    // Loader: animated root components minus the baseframe value (11 − 7 = 4), the rest 0.
    CHECK(figure::animFrameLocal(a, 0)[0].position == Vector3d(4, 0, 0));
    const Vector3d offset(1, 2, 3);
    const Skeleton actor = build(mesh(kJoints, 5), a, offset);
    CHECK(actor.modelOffset() == offset);
    CHECK(near(actor.loadPose()[0].position, offset, 0));
    CHECK(near(actor.loadPose()[1].position, Vector3d(1, 2, 13), 1e-12));
    CHECK(near(actor.loadPose()[3].position, Vector3d(1, 9, 13), 1e-12));
    const Skeleton entity = build(mesh(kJoints, 5), a, offset, figure::RootTranslation::OffsetAdded);
    CHECK(near(entity.loadPose()[0].position, Vector3d(5, 2, 3), 0));
    // Runtime FK: baseframe root translation zeroed, plus the offset, under either rule (docs/format.md §5.1).
    CHECK(actor.afPoseLocal()[0].position == offset);
    CHECK(entity.afPoseLocal()[0].position == offset);
    CHECK(actor.afPoseLocal()[1].position == Vector3d(0, 0, 10));
    // The bind pose is the mesh as written: no offset.
    CHECK(actor.bindPose()[0].position == Vector3d::Zero());
}

TEST_CASE("joint lookup, first child and descendants", "[figure][skeleton]") {
    text::Diagnostics d;
    const auto s =
        Skeleton::build(mesh(kJoints, 5), anim(kHierarchy, kBaseframe, {""}, 5, 0), Vector3d::Zero(), d, "dup.def");
    REQUIRE(s);
    // Case-insensitive, first match wins: "HIPS" (joint 4) is shadowed by "Hips" (docs/format.md §8 item 22).
    CHECK(s->findJoint("hips") == 1);
    CHECK(s->findJoint("HIPS") == 1);
    CHECK(s->findJoint("HEAD") == 3);
    CHECK(s->findJoint("Origin") == 0);
    CHECK_FALSE(s->findJoint("neck"));
    CHECK_FALSE(s->findJoint(""));
    REQUIRE(countContaining(d, text::Severity::Warning, "same name") == 1);
    CHECK(d.items().front().where.file == "dup.def");
    CHECK(d.warningCount() == 1);

    // idAnimator::GetFirstChild: first joint in list order with that parent; a leaf gives itself; -1 gives 0.
    CHECK(s->firstChild(0) == 1);
    CHECK(s->firstChild(1) == 2);
    CHECK(s->firstChild(3) == 3);
    CHECK(s->firstChild(4) == 4);
    CHECK(s->firstChild(-1) == 0);

    // `*name`: scan forward until a joint whose parent index is lower than the joint's (docs/format.md §5.3).
    CHECK(s->jointAndDescendants(0) == std::vector<int>{0, 1, 2, 3, 4});
    CHECK(s->jointAndDescendants(1) == std::vector<int>{1, 2, 3});
    CHECK(s->jointAndDescendants(2) == std::vector<int>{2, 3});
    CHECK(s->jointAndDescendants(4) == std::vector<int>{4});
}

TEST_CASE("descendants scan follows the engine on non-depth-first order", "[figure][skeleton]") {
    // Joint 3 is a child of joint 1 but comes after joint 2 (a child of the root): the scan from joint 1
    // stops at joint 2, as the engine's does, and misses joint 3.
    const std::string joints = "\"r\" -1 ( 0 0 0 ) ( 0 0 0 )\n\"a\" 0 ( 1 0 0 ) ( 0 0 0 )\n"
                               "\"b\" 0 ( 2 0 0 ) ( 0 0 0 )\n\"c\" 1 ( 3 0 0 ) ( 0 0 0 )\n";
    const std::string hierarchy = "\"r\" -1 0 0\n\"a\" 0 0 0\n\"b\" 0 0 0\n\"c\" 1 0 0\n";
    const std::string baseframe =
        "( 0 0 0 ) ( 0 0 0 )\n( 1 0 0 ) ( 0 0 0 )\n( 2 0 0 ) ( 0 0 0 )\n( 2 0 0 ) ( 0 0 0 )\n";
    const Skeleton s = build(mesh(joints, 4), anim(hierarchy, baseframe, {""}, 4, 0));
    CHECK(s.jointAndDescendants(1) == std::vector<int>{1});
    CHECK(s.jointAndDescendants(0) == std::vector<int>{0, 1, 2, 3});
    CHECK(s.firstChild(0) == 1);
    CHECK(near(s.loadPose()[3].position, Vector3d(3, 0, 0), 0));
}

TEST_CASE("build reports errors instead of asserting", "[figure][skeleton]") {
    const decl::Md5Mesh m = mesh(kJoints, 5);
    // A hierarchy that differs from the mesh's is reported where it differs (the af_pose's joint line, or the
    // mesh's joint count); what the files cannot locate, at the entity's decl.
    const auto fails = [&](const decl::Md5Anim& a, const std::string& needle, const std::string& file = "zombie.def") {
        text::Diagnostics d;
        const auto s = Skeleton::build(m, a, Vector3d::Zero(), d, "zombie.def");
        CHECK_FALSE(s);
        REQUIRE(d.errorCount() == 1);
        INFO(d.str());
        CHECK(d.items().front().message.find(needle) != std::string::npos);
        CHECK(d.items().front().where.file == file);
    };
    SECTION("joint names are compared case-sensitively against the mesh") {
        std::string h = kHierarchy;
        h.replace(h.find("\"Spine\""), 7, "\"spine\"");
        fails(anim(h, kBaseframe, {""}, 5, 0), "hierarchy", "test.md5anim");
    }
    SECTION("parent indices must match") {
        std::string h = kHierarchy;
        h.replace(h.find("\"Head\" 2"), 8, "\"Head\" 1");
        fails(anim(h, kBaseframe, {""}, 5, 0), "parent", "test.md5anim");
    }
    SECTION("joint counts must match") {
        fails(anim("\"origin\" -1 0 0\n", "( 0 0 0 ) ( 0 0 0 )\n", {""}, 1, 0), "joints", "test.md5mesh");
    }
    SECTION("an anim value without frames") {
        decl::Md5Anim a = anim(kHierarchy, kBaseframe, {""}, 5, 0);
        a.frames.clear();
        fails(a, "no frames");
    }
    SECTION("a hand-built anim with a short frame") {
        const std::string h = "\"origin\" -1 0 0\n\"Hips\" 0 32 0\n\"Spine\" 1 0 0\n\"Head\" 2 0 0\n\"HIPS\" 0 0 0\n";
        decl::Md5Anim a = anim(h, kBaseframe, {"0"}, 5, 1);
        a.frames[0].clear();
        fails(a, "values");
    }
    SECTION("a mesh without joints") {
        text::Diagnostics d;
        CHECK_FALSE(
            Skeleton::build(decl::Md5Mesh{}, anim(kHierarchy, kBaseframe, {""}, 5, 0), Vector3d::Zero(), d, "x"));
        CHECK(d.hasErrors());
    }
}

TEST_CASE("toModelSpace concatenates parents first", "[figure][skeleton]") {
    const std::vector<Transform> local = {{rotZ(90), Vector3d(1, 0, 0)},
                                          {Matrix3d::Identity(), Vector3d(2, 0, 0)},
                                          {rotZ(90), Vector3d(0, 3, 0)}};
    const auto model = figure::toModelSpace(local, {-1, 0, 1});
    CHECK(near(model[1].position, Vector3d(1, 2, 0), 1e-12));
    CHECK(near(model[2].position, Vector3d(-2, 2, 0), 1e-12)); // (1,2,0) + Rz(90)·(0,3,0)
    CHECK(near(model[2].rotation, rotZ(180), 1e-12));
    // A parent that does not precede its child is treated as a root rather than read out of order.
    const auto odd = figure::toModelSpace(local, {-1, 2});
    CHECK(odd[1].position == Vector3d(2, 0, 0));
    CHECK(odd[2].position == Vector3d(0, 3, 0));
}

// ---------------------------------------------------------------------------------------------------------------
// Real files. The zsec exporter (Blender idTech Tools) writes each frame's `bounds` as the box around the
// joint positions; that is an independent, exporter-side FK of the same data, so it checks the quaternion
// sign and the hierarchy concatenation end to end (the unconjugated convention misses by 25-55 units on these
// files).

namespace {

struct ZsecSet {
    const char* folder;
    const char* mesh;
    std::vector<const char*> anims;
    int joints;
};

const std::vector<ZsecSet> kZsec = {
    {"zsec_pistol", "zsecpistol.md5mesh", {}, 61},
    {"zsec_shotgun", "zsecshotgun.md5mesh", {"stand.md5anim", "walk.md5anim"}, 59},
    {"zsec_machinegun",
     "zsecmachinegun.md5mesh",
     {"machinegun_stand.md5anim", "machinegun_walk.md5anim", "machinegun_run.md5anim"},
     57},
};

double jointBoundsError(const std::vector<Transform>& pose, const decl::Md5Bounds& b) {
    Vector3d lo = Vector3d::Constant(1e300), hi = Vector3d::Constant(-1e300);
    for (const Transform& t : pose) {
        lo = lo.cwiseMin(t.position);
        hi = hi.cwiseMax(t.position);
    }
    return std::max((lo - Vector3d(b.min.x, b.min.y, b.min.z)).cwiseAbs().maxCoeff(),
                    (hi - Vector3d(b.max.x, b.max.y, b.max.z)).cwiseAbs().maxCoeff());
}

} // namespace

TEST_CASE("corpus: zsec skeletons build and match their exporter's bounds", "[figure][skeleton][corpus]") {
    AFB_REQUIRE_CORPUS(corpus);
    const auto dir = corpus / "doom3-kroom3/base/models/md5/monsters/zombies";
    for (const ZsecSet& set : kZsec) {
        INFO(set.folder);
        text::Diagnostics d;
        const auto m = decl::loadMd5Mesh(dir / set.folder / set.mesh, d);
        const auto pose = decl::loadMd5Anim(dir / set.folder / "af_pose.md5anim", d);
        INFO(d.str());
        REQUIRE(m);
        REQUIRE(pose);
        REQUIRE(pose->frames.size() == 5);
        REQUIRE(pose->numAnimatedComponents == 0);
        // The modelDefs give no `offset` (def/monster_zsec_*.def).
        const auto s = Skeleton::build(*m, *pose, Vector3d::Zero(), d, set.folder);
        REQUIRE(s);
        CHECK(d.empty()); // five identical frames: the load pose is the baseframe, so no §8 item 19 warning
        CHECK(s->jointCount() == set.joints);
        CHECK(s->findJoint("ORIGIN") == 0);
        CHECK(s->firstChild(-1) == 0);

        // The af_pose baseframe root translation is (0 0 0), so the exporter's bounds are in our model space.
        for (const decl::Md5Bounds& b : pose->bounds) CHECK(jointBoundsError(s->loadPose(), b) < 1e-3);
        // Runtime FK from afPoseLocal reproduces the load pose (docs/format.md §8 item 19 holds for these files).
        const auto runtime = figure::toModelSpace(s->afPoseLocal(), s->parents());
        for (std::size_t i = 0; i < runtime.size(); ++i) CHECK(near(runtime[i], s->loadPose()[i], 1e-9));

        // Measured: af_pose is a spread ragdoll pose, not the bind pose. The origin joint coincides; the
        // pelvis is 1.47 units lower and the hands move by over 10 units.
        double farthest = 0;
        for (int i = 0; i < s->jointCount(); ++i) {
            const auto k = static_cast<std::size_t>(i);
            CHECK(isRotation(s->loadPose()[k].rotation, 1e-9));
            farthest = std::max(farthest, (s->loadPose()[k].position - s->bindPose()[k].position).norm());
        }
        CHECK(near(s->loadPose()[0], s->bindPose()[0], 1e-6));
        CHECK(farthest > 10);

        // Bone lengths |joint − parent| agree between bind and load pose within 0.05 units for every real
        // bone (most within 1e-5; the limbs are stretched by up to 0.04). Measured exceptions, all control or
        // prop joints: the first child of origin (the pelvis height, 1.47), the knee IK targets (17-22), the
        // shoulder pads (0.8) and the machine gun (0.64).
        const std::vector<std::string> exceptions = {"Lknee", "Rknee", "lshldrpad", "rshldrpad", "gun"};
        int within1e3 = 0;
        for (int i = 1; i < s->jointCount(); ++i) {
            const auto k = static_cast<std::size_t>(i);
            const auto p = static_cast<std::size_t>(s->parent(i));
            const double bindLength = (s->bindPose()[k].position - s->bindPose()[p].position).norm();
            const double loadLength = (s->loadPose()[k].position - s->loadPose()[p].position).norm();
            const double diff = std::abs(bindLength - loadLength);
            if (diff < 1e-3) ++within1e3;
            const bool exempt = i == s->firstChild(0) ||
                                std::find(exceptions.begin(), exceptions.end(), s->name(i)) != exceptions.end();
            INFO(s->name(i) << " bone length differs by " << diff);
            if (!exempt) CHECK(diff < 0.05);
        }
        CHECK(within1e3 >= s->jointCount() - 15);

        // The walk/stand/run anims: every frame's joints fit the exporter's bounds (root at the origin here
        // too).
        for (const char* name : set.anims) {
            INFO(name);
            const auto a = decl::loadMd5Anim(dir / set.folder / name, d);
            REQUIRE(a);
            CHECK_FALSE(decl::hierarchyMismatch(*a, *m));
            CHECK(a->baseframe[0].position == decl::Vec3{});
            REQUIRE(a->numAnimatedComponents > 0);
            double worst = 0;
            for (std::size_t f = 0; f < a->frames.size(); ++f)
                worst = std::max(worst,
                                 jointBoundsError(figure::toModelSpace(figure::animFrameLocal(*a, static_cast<int>(f)),
                                                                       s->parents()),
                                                  a->bounds[f]));
            CHECK(worst < 1e-2); // measured at most 4.2e-3 (values are written with 10 decimals)
        }
    }
}

TEST_CASE("corpus: Bob.md5anim frames give proper rotations", "[figure][skeleton][corpus]") {
    AFB_REQUIRE_CORPUS(corpus);
    const auto dir = corpus / "assimp-md5/test/models-nonbsd/MD5";
    text::Diagnostics d;
    const auto m = decl::loadMd5Mesh(dir / "Bob.md5mesh", d);
    const auto a = decl::loadMd5Anim(dir / "Bob.md5anim", d);
    INFO(d.str());
    REQUIRE(m);
    REQUIRE(a);
    REQUIRE_FALSE(decl::hierarchyMismatch(*a, *m));
    REQUIRE(a->frames.size() == 140);
    std::vector<int> parents;
    for (const decl::Md5Joint& j : m->joints) parents.push_back(j.parent);
    for (std::size_t f = 0; f < a->frames.size(); ++f) {
        const auto local = figure::animFrameLocal(*a, static_cast<int>(f));
        REQUIRE(local.size() == m->joints.size());
        for (const Transform& t : local) CHECK(isRotation(t.rotation, 1e-12));
        for (const Transform& t : figure::toModelSpace(local, parents)) CHECK(isRotation(t.rotation, 1e-9));
    }
    // Between frames: still rotations, and translations are the straight-line blend.
    const double t = (10 + 0.25) / a->frameRate;
    const auto mid = figure::animPoseLocal(*a, t);
    const auto f10 = figure::animFrameLocal(*a, 10), f11 = figure::animFrameLocal(*a, 11);
    for (std::size_t j = 0; j < mid.size(); ++j) {
        CHECK(isRotation(mid[j].rotation, 1e-12));
        CHECK(near(mid[j].position, Vector3d(f10[j].position + 0.25 * (f11[j].position - f10[j].position)), 1e-9));
    }
    // Used as a (multi-frame, animated) af_pose it still builds, and build points at §8 item 19.
    text::Diagnostics bd;
    CHECK(Skeleton::build(*m, *a, Vector3d::Zero(), bd, "Bob"));
    CHECK_FALSE(bd.hasErrors());
}

TEST_CASE("bundled chain: af_pose baseframe is the bind pose", "[figure][skeleton]") {
    const auto dir = test::sourceDir() / "models/md5/props/chain";
    text::Diagnostics d;
    const auto m = decl::loadMd5Mesh(dir / "chain.md5mesh", d);
    const auto a = decl::loadMd5Anim(dir / "af_pose.md5anim", d);
    INFO(d.str());
    REQUIRE(m);
    REQUIRE(a);
    const Skeleton s = build(*m, *a);
    REQUIRE(s.jointCount() == 11);
    for (std::size_t i = 0; i < 11; ++i) CHECK(near(s.loadPose()[i], s.bindPose()[i], 1e-9));
    CHECK(near(s.loadPose()[10].position, Vector3d(0, 0, 28), 1e-12)); // link10: 100 − 9 × 8
    CHECK(s.jointAndDescendants(*s.findJoint("LINK9")) == std::vector<int>{9, 10});
}
