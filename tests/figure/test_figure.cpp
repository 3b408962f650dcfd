// figure::buildFigure against the spec (docs/format.md §0, §1.2, §1.7, §1.8, §2.2–§2.4, §3.1–§3.4, §4.1–§4.7, §5.3,
// §6.2, §8) and the findings the builder reports. Expected values are worked out by hand from the spec, not from
// the code under test; figures are built from inline `.af` text on hand-made skeletons (identity orientations).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <numbers>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "FigureFixture.h"
#include "afb/decl/AfParser.h"
#include "afb/figure/Collision.h"
#include "afb/figure/Figure.h"
#include "afb/figure/Skeleton.h"

using namespace afb;
using Eigen::Matrix3d;
using Eigen::Vector3d;
using figure::Figure;
using figure::FigureBody;
using figure::FigureConstraint;
using figure::Transform;
using test::TestJoint;

namespace {

constexpr double kS = 0.0254; // default metres per Doom unit
constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kTight = 1e-12;

// A small humanoid skeleton, Doom units, identity orientations. Joint 1 (Hips) is the first child of origin.
const std::vector<TestJoint>& humanoid() {
    static const std::vector<TestJoint> joints = {
        {"origin", -1, 0, 0, 0},      // 0
        {"Hips", 0, 0, 0, 40},        // 1
        {"Spine", 1, 0, 0, 50},       // 2
        {"Head", 2, 0, 0, 70},        // 3
        {"LeftUpLeg", 1, 0, 6, 38},   // 4
        {"LeftLeg", 4, 2, 6, 20},     // 5
        {"RightUpLeg", 1, 0, -6, 38}, // 6
    };
    return joints;
}

// A figure built from text, with the builder's findings kept apart from the parser's.
struct Built {
    std::optional<Figure> figure;
    text::Diagnostics parse;    // parser and skeleton messages
    text::Diagnostics findings; // buildFigure's own
    std::string text;

    // 1-based line of the first line of the text that contains `marker`.
    std::uint32_t lineOf(const std::string& marker) const {
        const std::size_t at = text.find(marker);
        REQUIRE(at != std::string::npos);
        return static_cast<std::uint32_t>(std::count(text.begin(), text.begin() + static_cast<long>(at), '\n') + 1);
    }

    // A finding of `severity` located at `line` of test.af whose message mentions `needle` (case-insensitive).
    bool has(text::Severity severity, std::uint32_t line, const std::string& needle = "") const {
        auto lower = [](std::string s) {
            for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
            return s;
        };
        return std::any_of(findings.items().begin(), findings.items().end(), [&](const text::Diagnostic& d) {
            return d.severity == severity && d.where.file == "test.af" && d.where.line == line &&
                   lower(d.message).find(lower(needle)) != std::string::npos;
        });
    }
    bool hasError(const std::string& marker, const std::string& needle = "") const {
        return has(text::Severity::Error, lineOf(marker), needle);
    }
    bool hasWarning(const std::string& marker, const std::string& needle = "") const {
        return has(text::Severity::Warning, lineOf(marker), needle);
    }

    const FigureBody& body(const std::string& name) const {
        REQUIRE(figure);
        for (const FigureBody& b : figure->bodies)
            if (b.name == name) return b;
        FAIL("no body " << name);
        throw; // unreachable
    }
    int bodyIndex(const std::string& name) const { return static_cast<int>(&body(name) - figure->bodies.data()); }
    const FigureConstraint& constraint(const std::string& name) const {
        REQUIRE(figure);
        for (const FigureConstraint& c : figure->constraints)
            if (c.name == name) return c;
        FAIL("no constraint " << name);
        throw; // unreachable
    }
};

decl::AfDecl parseDecl(const std::string& af) {
    text::Diagnostics d;
    const auto file = decl::parseAf(af, "test.af", d);
    INFO(d.str());
    REQUIRE(file);
    REQUIRE(file->decls.size() == 1);
    return file->decls[0];
}

figure::Skeleton skeletonOf(const std::vector<TestJoint>& joints) {
    text::Diagnostics d;
    auto skeleton = figure::Skeleton::build(test::md5Mesh(joints), test::md5Anim(joints), Vector3d::Zero(), d, "test");
    INFO(d.str());
    REQUIRE(skeleton);
    return *skeleton;
}

Built build(const std::string& af, const std::vector<TestJoint>& joints = humanoid(), figure::UnitSystem units = {}) {
    Built out;
    out.text = af;
    const auto file = decl::parseAf(af, "test.af", out.parse);
    INFO(out.parse.str());
    REQUIRE(file);
    REQUIRE(file->decls.size() == 1);
    const figure::Skeleton skeleton = skeletonOf(joints);
    out.figure = figure::buildFigure({&file->decls[0], &skeleton, units}, out.findings);
    return out;
}

// Builds and requires success.
Built buildOk(const std::string& af, const std::vector<TestJoint>& joints = humanoid(), figure::UnitSystem units = {}) {
    Built b = build(af, joints, units);
    INFO(b.findings.str());
    REQUIRE(b.figure);
    REQUIRE_FALSE(b.findings.hasErrors());
    return b;
}

Vector3d joint(const std::string& name) {
    for (const TestJoint& j : humanoid())
        if (j.name == name) return {j.x, j.y, j.z};
    FAIL("no joint " << name);
    return {};
}

bool near(const Vector3d& a, const Vector3d& b, double tol) { return (a - b).cwiseAbs().maxCoeff() <= tol; }
bool near(const Matrix3d& a, const Matrix3d& b, double tol) { return (a - b).cwiseAbs().maxCoeff() <= tol; }

bool isRotation(const Matrix3d& r) {
    return near(Matrix3d(r.transpose() * r), Matrix3d::Identity(), 1e-12) && std::abs(r.determinant() - 1) < 1e-12;
}

// Model-space frame of a constraint as attached to body1 and to body2 (model space itself for the world).
std::pair<Transform, Transform> framesModel(const Figure& f, const FigureConstraint& c) {
    const Transform a = f.bodies[static_cast<std::size_t>(c.body1)].loadPose * c.frameInBody1;
    const Transform b =
        c.body2 >= 0 ? f.bodies[static_cast<std::size_t>(c.body2)].loadPose * c.frameInBody2 : c.frameInBody2;
    return {a, b};
}

// The engine's distortion of a rotation angle about a non-unit axis of length L (docs/format.md §4.5).
double g(double thetaRad, double length) {
    return std::atan2(length * std::sin(thetaRad), 1.0 - length * length * (1.0 - std::cos(thetaRad)));
}

const char* const kSimpleBodies = R"(
	body "pelvis" {
		joint "origin"
		model box( ( -6, -8, -4 ), ( 6, 8, 4 ) )
		origin joint( "Hips" )
	}
	body "chest" {
		joint "Spine"
		model box( ( -5, -7, 0 ), ( 5, 7, 16 ) )
		origin joint( "Spine" )
	}
)";

} // namespace

// --- origin body (§1.8, §2.4, §8 item 5) ---------------------------------------------------------------------

TEST_CASE("figure: the first body on joint \"origin\" is swapped to body 0 and drives origin's first child",
          "[figure]") {
    const std::string af = R"(articulatedFigure t {
	body "thigh" {
		joint "LeftUpLeg"
		model box( ( -2, -2, -8 ), ( 2, 2, 8 ) )
		origin bonecenter( "LeftUpLeg", "LeftLeg" )
		containedJoints "*LeftUpLeg"
	}
	body "chest" {
		joint "Spine"
		model box( ( -5, -7, 0 ), ( 5, 7, 16 ) )
		origin joint( "Spine" )
		containedJoints "*Spine"
	}
	body "pelvis" {
		joint "origin"
		mod position
		model box( ( -6, -8, -4 ), ( 6, 8, 4 ) )
		origin joint( "Hips" )
		angles ( 0, 30, 0 )
		containedJoints "*origin -*Spine -*LeftUpLeg"
	}
}
)";
    const Built b = build(af);
    INFO(b.findings.str());
    REQUIRE(b.figure);
    const Figure& f = *b.figure;
    REQUIRE(f.bodies.size() == 3);
    // A swap, not a move: the original first body takes the origin body's old slot.
    CHECK(f.bodies[0].name == "pelvis");
    CHECK(f.bodies[1].name == "chest");
    CHECK(f.bodies[2].name == "thigh");
    // §2.4: AXIS mode whatever its mod says, on the first child of the joint named "origin" (Hips, joint 1).
    CHECK(f.bodies[0].joint == 1);
    CHECK(f.bodies[0].mod == figure::JointMod::Orientation);
    CHECK(f.bodies[1].joint == 2);
    CHECK(f.bodies[2].joint == 4);
    // The joint→body offset (§2.3): body pose ∘ jointInBody = the driven joint's load pose.
    for (const FigureBody& body : f.bodies) {
        const Transform jointModel = body.loadPose * body.jointInBody;
        const Vector3d expected = joint(humanoid()[static_cast<std::size_t>(body.joint)].name) * kS;
        CHECK(near(jointModel.position, expected, kTight));
        CHECK(near(jointModel.rotation, Matrix3d::Identity(), kTight));
    }
    // containedJoints and jointBody follow the swapped order.
    CHECK(f.jointBody == std::vector<int>{0, 0, 1, 1, 2, 2, 0});
    CHECK(f.bodies[0].containedJoints == std::vector<int>{0, 1, 6});
}

TEST_CASE("figure: the origin body is swapped, the first body moves to its slot (three bodies)", "[figure]") {
    const Built b = buildOk(R"(articulatedFigure t {
	body "a" { joint "Spine" model box( ( -5, -5, -5 ), ( 5, 5, 5 ) ) origin ( 0, 0, 60 ) }
	body "b" { joint "Head" model box( ( -5, -5, -5 ), ( 5, 5, 5 ) ) origin ( 0, 0, 80 ) }
	body "c" { joint "origin" model box( ( -5, -5, -5 ), ( 5, 5, 5 ) ) origin ( 0, 0, 40 ) }
}
)");
    REQUIRE(b.figure->bodies.size() == 3);
    CHECK(b.figure->bodies[0].name == "c");
    CHECK(b.figure->bodies[1].name == "b");
    CHECK(b.figure->bodies[2].name == "a");
}

TEST_CASE("figure: without a body on joint exactly \"origin\" the build fails with an error", "[figure]") {
    SECTION("no origin body at all") {
        const Built b = build(R"(articulatedFigure t {
	body "chest" { joint "Spine" model box( ( -5, -5, -5 ), ( 5, 5, 5 ) ) }
}
)");
        CHECK_FALSE(b.figure);
        CHECK(b.findings.hasErrors());
        CHECK(b.hasError("articulatedFigure t"));
    }
    SECTION("joint \"Origin\" (capitalised) does not make the origin body (§2.4, §8 item 5)") {
        const Built b = build(R"(articulatedFigure t {
	body "pelvis" { joint "Origin" model box( ( -5, -5, -5 ), ( 5, 5, 5 ) ) }
}
)");
        CHECK_FALSE(b.figure);
        CHECK(b.findings.hasErrors());
    }
}

TEST_CASE("figure: without a joint named origin the origin body drives joint 0 (§2.4)", "[figure]") {
    const std::vector<TestJoint> joints = {{"root", -1, 0, 0, 0}, {"pelvis", 0, 0, 0, 30}, {"spine", 1, 0, 0, 40}};
    const Built b = build(R"(articulatedFigure t {
	body "pelvis" { joint "origin" model box( ( -5, -5, -5 ), ( 5, 5, 5 ) ) origin ( 0, 0, 30 ) }
}
)",
                          joints);
    INFO(b.findings.str());
    REQUIRE(b.figure);
    CHECK(b.figure->bodies[0].joint == 0);
}

// --- vector expressions and placement (§1.2, §2.2, §0) ---------------------------------------------------------

TEST_CASE("figure: vector forms are evaluated at the load pose, negation applied once", "[figure]") {
    const std::string af = R"(articulatedFigure t {
	body "pelvis" { joint "origin" model box( ( -1, -1, -1 ), ( 1, 1, 1 ) ) origin joint( "Head" ) }
	body "j" { joint "Spine" model box( ( -1, -1, -1 ), ( 1, 1, 1 ) ) origin joint( "lEFTleg" ) }
	body "bc" { joint "Spine" model box( ( -1, -1, -1 ), ( 1, 1, 1 ) ) origin bonecenter( "LeftUpLeg", LeftLeg ) }
	body "bd" { joint "Spine" model box( ( -1, -1, -1 ), ( 1, 1, 1 ) ) origin bonedir( "LeftUpLeg", "LeftLeg" ) }
	body "neglit" { joint "Spine" model box( ( -1, -1, -1 ), ( 1, 1, 1 ) ) origin -( 1, 2, 3 ) }
	body "negjoint" { joint "Spine" model box( ( -1, -1, -1 ), ( 1, 1, 1 ) ) origin -joint( "LeftLeg" ) }
	body "negdir" { joint "Spine" model box( ( -1, -1, -1 ), ( 1, 1, 1 ) ) origin -bonedir( "LeftUpLeg", "LeftLeg" ) }
}
)";
    const decl::AfDecl decl = parseDecl(af);
    const figure::Skeleton skeleton = skeletonOf(humanoid());
    // The engine's bug (§1.2): a negated literal flips on every load. Building twice must give the same figure.
    for (int load = 0; load < 2; ++load) {
        INFO("load " << load);
        text::Diagnostics findings;
        const auto f = figure::buildFigure({&decl, &skeleton, {}}, findings);
        INFO(findings.str());
        REQUIRE(f);
        auto pos = [&](const std::string& name) {
            for (const FigureBody& body : f->bodies)
                if (body.name == name) return body.loadPose.position;
            FAIL("no body " << name);
            return Vector3d();
        };
        const Vector3d up = joint("LeftUpLeg"), leg = joint("LeftLeg");
        CHECK(near(pos("pelvis"), joint("Head") * kS, kTight));
        CHECK(near(pos("j"), leg * kS, kTight)); // joint names are looked up case-insensitively
        CHECK(near(pos("bc"), 0.5 * (up + leg) * kS, kTight));
        CHECK(near(pos("bd"), (leg - up) * kS, kTight)); // not normalized
        CHECK(near(pos("neglit"), Vector3d(-1, -2, -3) * kS, kTight));
        CHECK(near(pos("negjoint"), -leg * kS, kTight));
        CHECK(near(pos("negdir"), (up - leg) * kS, kTight));
    }
}

TEST_CASE("figure: an asymmetric box's body origin is origin + R·c (COM shift, §2.2)", "[figure]") {
    const Built b = buildOk(R"(articulatedFigure t {
	body "pelvis" {
		joint "origin"
		model box( ( -5, -5, 0 ), ( 5, 5, 20 ) )
		origin ( 1, 2, 3 )
		angles ( 90, 0, 0 )
	}
	body "yawed" {
		joint "Spine"
		model box( ( 0, -1, -2 ), ( 8, 1, 2 ) )
		origin ( 10, 20, 30 )
		angles ( 0, 90, 0 )
	}
}
)");
    // R = Ry(90°): the local centre (0, 0, 10) goes to (10, 0, 0).
    const FigureBody& p = b.body("pelvis");
    CHECK(near(p.loadPose.position, Vector3d(11, 2, 3) * kS, kTight));
    // Pitch 90 points the body's +X down (§0: forward = (cos p cos y, cos p sin y, −sin p)).
    CHECK(near(Vector3d(p.loadPose.rotation.col(0)), Vector3d(0, 0, -1), kTight));
    CHECK(near(Vector3d(p.loadPose.rotation.col(1)), Vector3d(0, 1, 0), kTight));
    // Yaw 90 turns +X toward +Y: local centre (4, 0, 0) goes to (0, 4, 0).
    const FigureBody& y = b.body("yawed");
    CHECK(near(y.loadPose.position, Vector3d(10, 24, 30) * kS, kTight));
    CHECK(near(Vector3d(y.loadPose.rotation.col(0)), Vector3d(0, 1, 0), kTight));
    // The shape is centred on the COM: the body-frame box spans ±(4, 1, 2) units.
    for (const FigureBody* body : {&p, &y}) {
        Vector3d lo = Vector3d::Constant(1e9), hi = Vector3d::Constant(-1e9);
        for (const Vector3d& v : body->shape.vertices) {
            lo = lo.cwiseMin(v);
            hi = hi.cwiseMax(v);
        }
        CHECK(near(lo, -hi, kTight));
    }
    CHECK(near(Vector3d(p.shape.vertices[0].cwiseAbs()), Vector3d(5, 5, 10) * kS, kTight));
}

TEST_CASE("figure: angles follow R = Rz(yaw)·Ry(pitch)·Rx(roll) (§0)", "[figure]") {
    const Built b = buildOk(R"(articulatedFigure t {
	body "pelvis" { joint "origin" model box( ( -1, -2, -3 ), ( 1, 2, 3 ) ) angles ( 0, 0, 90 ) }
	body "pitch" { joint "Spine" model box( ( -1, -2, -3 ), ( 1, 2, 3 ) ) angles ( 30, 0, 0 ) }
	body "all" { joint "Spine" model box( ( -1, -2, -3 ), ( 1, 2, 3 ) ) angles ( 30, 40, 50 ) }
	body "neg" { joint "Spine" model box( ( -1, -2, -3 ), ( 1, 2, 3 ) ) angles -( 30, 40, 50 ) }
}
)");
    // Roll 90 turns +Y toward +Z.
    CHECK(near(Vector3d(b.body("pelvis").loadPose.rotation.col(1)), Vector3d(0, 0, 1), kTight));
    const double p = 30 * kDeg;
    CHECK(near(Vector3d(b.body("pitch").loadPose.rotation.col(0)), Vector3d(std::cos(p), 0, -std::sin(p)), kTight));
    const Matrix3d expected =
        (Eigen::AngleAxisd(40 * kDeg, Vector3d::UnitZ()) * Eigen::AngleAxisd(30 * kDeg, Vector3d::UnitY()) *
         Eigen::AngleAxisd(50 * kDeg, Vector3d::UnitX()))
            .toRotationMatrix();
    CHECK(near(b.body("all").loadPose.rotation, expected, kTight));
    // §1.2: a leading '-' is ignored for angles.
    CHECK(near(b.body("neg").loadPose.rotation, expected, kTight));
}

TEST_CASE("figure: a bone body's frame runs from v1 to v2, centred on origin, angles ignored (§3.1)", "[figure]") {
    const Built b = build(R"(articulatedFigure t {
	body "pelvis" {
		joint "origin"
		model bone( joint( "Spine" ), joint( "Hips" ), 4 )
		origin bonecenter( "Hips", "Spine" )
	}
	body "thigh" {
		joint "LeftUpLeg"
		model bone( joint( "LeftUpLeg" ), joint( "LeftLeg" ), 6 )
		origin ( 5, 5, 5 )
		angles ( 0, 90, 0 )
	}
}
)");
    INFO(b.findings.str());
    REQUIRE(b.figure);
    // Vertical bone (Spine → Hips, d = −Z): the exact zero test gives left = +X; Y = d × left = −Y.
    const FigureBody& p = b.body("pelvis");
    CHECK(near(p.loadPose.rotation, Matrix3d(Eigen::Vector3d(1, -1, -1).asDiagonal()), kTight));
    CHECK(near(p.loadPose.position, Vector3d(0, 0, 45) * kS, kTight));
    // Slanted bone: d = (2, 0, −18)/L, left = (−d.y, d.x, 0)/|…| = (0, 1, 0), Y = d × left.
    const FigureBody& t = b.body("thigh");
    const Vector3d d = (joint("LeftLeg") - joint("LeftUpLeg")).normalized();
    const Vector3d left(0, 1, 0);
    CHECK(near(Vector3d(t.loadPose.rotation.col(2)), d, kTight));
    CHECK(near(Vector3d(t.loadPose.rotation.col(0)), left, kTight));
    CHECK(near(Vector3d(t.loadPose.rotation.col(1)), Vector3d(d.cross(left)), kTight));
    // Centred on `origin`, not on v1 (the bone's COM is its origin).
    CHECK(near(t.loadPose.position, Vector3d(5, 5, 5) * kS, kTight));
    // Local vertices (0,0,±L/2), (0,−w/2,0), (±w/2, w/4, 0): the tip of the cross-section is at −Y.
    const double L = (joint("LeftLeg") - joint("LeftUpLeg")).norm();
    std::vector<Vector3d> expected = {{0, 0, -L / 2}, {0, -3, 0}, {3, 1.5, 0}, {-3, 1.5, 0}, {0, 0, L / 2}};
    REQUIRE(t.shape.vertices.size() == expected.size());
    for (const Vector3d& e : expected) {
        INFO("vertex " << e.transpose());
        CHECK(std::any_of(t.shape.vertices.begin(), t.shape.vertices.end(),
                          [&](const Vector3d& v) { return near(v, e * kS, 1e-12); }));
    }
    // Mass w²·L/8 at the default density 0.2.
    CHECK(t.massKg == Approx(0.2 * 36 * L / 8).epsilon(1e-12));
}

// --- mass, inertia, units, damping (§3.2–§3.4) -----------------------------------------------------------------

TEST_CASE("figure: mass = density × volume, volume and inertia in SI (§3.2, units)", "[figure]") {
    const std::string af = R"(articulatedFigure t {
	body "pelvis" { joint "origin" model box( ( -2, -3, -4 ), ( 2, 3, 4 ) ) density 0.5 }
	body "oct" { joint "Spine" model octahedron( ( -3, -3, -6 ), ( 3, 3, 6 ) ) origin ( 0, 0, 60 ) density 0.3 }
}
)";
    const Built b = buildOk(af);
    const FigureBody& box = b.body("pelvis");
    // Box 4 × 6 × 8 = 192 in³.
    CHECK(box.volumeM3 == Approx(192 * kS * kS * kS).epsilon(1e-12));
    CHECK(box.massKg == Approx(0.5 * 192).epsilon(1e-12));
    const double m = 96;
    CHECK(box.inertiaKgM2.x() == Approx(m * (36 + 64) / 12 * kS * kS).epsilon(1e-12));
    CHECK(box.inertiaKgM2.y() == Approx(m * (16 + 64) / 12 * kS * kS).epsilon(1e-12));
    CHECK(box.inertiaKgM2.z() == Approx(m * (16 + 36) / 12 * kS * kS).epsilon(1e-12));
    // Octahedron: volume ex·ey·ez/6, <x²> = hx²/10.
    const FigureBody& oct = b.body("oct");
    const double vol = 6 * 6 * 12 / 6.0, mo = 0.3 * vol;
    CHECK(oct.volumeM3 == Approx(vol * kS * kS * kS).epsilon(1e-12));
    CHECK(oct.massKg == Approx(mo).epsilon(1e-12));
    CHECK(oct.inertiaKgM2.x() == Approx(mo * (0.9 + 3.6) * kS * kS).epsilon(1e-12));
    CHECK(oct.inertiaKgM2.z() == Approx(mo * (0.9 + 0.9) * kS * kS).epsilon(1e-12));

    SECTION("the unit length is a parameter: mass unchanged, lengths × s, volume × s³, inertia × s²") {
        figure::UnitSystem inches;
        inches.metresPerUnit = 1.0;
        const Built raw = buildOk(af, humanoid(), inches);
        for (const FigureBody& body : b.figure->bodies) {
            const FigureBody& r = raw.body(body.name);
            INFO(body.name);
            CHECK(body.massKg == Approx(r.massKg).epsilon(1e-12));
            CHECK(body.volumeM3 == Approx(r.volumeM3 * kS * kS * kS).epsilon(1e-12));
            CHECK(near(body.inertiaKgM2, Vector3d(r.inertiaKgM2 * kS * kS), 1e-12 * r.inertiaKgM2.norm() * kS * kS));
            CHECK(near(body.loadPose.position, Vector3d(r.loadPose.position * kS), kTight));
        }
    }
}

TEST_CASE("figure: totalMass rescales every body and keeps the density ratios (§3.3)", "[figure]") {
    const std::string bodies = R"(
	body "pelvis" { joint "origin" model box( ( -5, -5, -5 ), ( 5, 5, 5 ) ) origin ( 0, 0, 40 ) density 0.2 }
	body "chest" { joint "Spine" model box( ( -5, -5, -5 ), ( 5, 5, 5 ) ) origin ( 0, 0, 60 ) density 0.6
		inertiaScale ( 2 0 0 0 1 0 0 0 1 ) }
}
)";
    const Built plain = buildOk("articulatedFigure t {" + bodies);
    const Built scaled = buildOk("articulatedFigure t {\n\tsettings { totalMass 40 }" + bodies);
    CHECK(plain.body("pelvis").massKg == Approx(200).epsilon(1e-12));
    CHECK(plain.body("chest").massKg == Approx(600).epsilon(1e-12));
    CHECK(plain.figure->totalMassKg == Approx(800).epsilon(1e-12));
    CHECK(scaled.body("pelvis").massKg == Approx(10).epsilon(1e-12));
    CHECK(scaled.body("chest").massKg == Approx(30).epsilon(1e-12));
    CHECK(scaled.figure->totalMassKg == Approx(40).epsilon(1e-12));
    // Inertia scales with the same factor; inertiaScale was applied before the scaling.
    for (const char* name : {"pelvis", "chest"}) {
        INFO(name);
        const Vector3d expected = plain.body(name).inertiaKgM2 * (40.0 / 800.0);
        CHECK(near(scaled.body(name).inertiaKgM2, expected, 1e-12 * expected.norm()));
    }
    CHECK(scaled.body("chest").inertiaKgM2.x() == Approx(2 * scaled.body("chest").inertiaKgM2.y()).epsilon(1e-12));
}

TEST_CASE("figure: inertiaScale is a matrix product (§3.3)", "[figure]") {
    SECTION("diag(2, 1, 1) doubles the first principal moment") {
        const Built plain = buildOk(R"(articulatedFigure t {
	body "pelvis" { joint "origin" model box( ( -2, -3, -4 ), ( 2, 3, 4 ) ) angles ( 10, 20, 30 ) }
}
)");
        const Built scaled = buildOk(R"(articulatedFigure t {
	body "pelvis" { joint "origin" model box( ( -2, -3, -4 ), ( 2, 3, 4 ) ) angles ( 10, 20, 30 )
		inertiaScale ( 2 0 0 0 1 0 0 0 1 ) }
}
)");
        const FigureBody& p = plain.body("pelvis");
        const FigureBody& s = scaled.body("pelvis");
        // The moments are about the body frame axes: compare the tensors in model space.
        auto tensor = [](const FigureBody& body) {
            return Matrix3d(body.loadPose.rotation * body.inertiaKgM2.asDiagonal() *
                            body.loadPose.rotation.transpose());
        };
        const Matrix3d base = Vector3d(p.inertiaKgM2).asDiagonal();
        const Matrix3d expectedLocal = base * Vector3d(2, 1, 1).asDiagonal();
        const Matrix3d r = plain.body("pelvis").loadPose.rotation;
        CHECK(near(tensor(s), Matrix3d(r * expectedLocal * r.transpose()), 1e-12 * base.norm()));
        CHECK(near(tensor(p), Matrix3d(r * base * r.transpose()), 1e-12 * base.norm()));
        CHECK(s.massKg == Approx(p.massKg).epsilon(1e-12));
    }
    SECTION("an off-diagonal scale gives principal axes; the body frame's tensor rotated back is I·S") {
        const Built b = buildOk(R"(articulatedFigure t {
	body "pelvis" { joint "origin" model box( ( -5, -5, -5 ), ( 5, 5, 5 ) ) origin ( 1, 2, 3 ) angles ( 0, 30, 0 )
		inertiaScale ( 1 0.2 0 0.2 1 0 0 0 1 ) }
}
)");
        const FigureBody& p = b.body("pelvis");
        const double m = 0.2 * 1000, a = m * 200 / 12; // cube: I = a·E
        Matrix3d scale;
        scale << 1, 0.2, 0, 0.2, 1, 0, 0, 0, 1;
        const Matrix3d R = Eigen::AngleAxisd(30 * kDeg, Vector3d::UnitZ()).toRotationMatrix();
        const Matrix3d expected = R * (a * scale) * R.transpose() * kS * kS;
        CHECK(isRotation(p.loadPose.rotation));
        const Matrix3d got = p.loadPose.rotation * p.inertiaKgM2.asDiagonal() * p.loadPose.rotation.transpose();
        CHECK(near(got, expected, 1e-12 * expected.norm()));
        // The principal moments are a·(1 − 0.2), a, a·(1 + 0.2) in some order.
        std::vector<double> moments(p.inertiaKgM2.data(), p.inertiaKgM2.data() + 3);
        std::sort(moments.begin(), moments.end());
        CHECK(moments[0] == Approx(0.8 * a * kS * kS).epsilon(1e-12));
        CHECK(moments[1] == Approx(a * kS * kS).epsilon(1e-12));
        CHECK(moments[2] == Approx(1.2 * a * kS * kS).epsilon(1e-12));
        // The geometry did not turn with the principal axes: its model-space corners are still the cube's.
        REQUIRE(p.shape.vertices.size() == 8);
        for (const Vector3d& v : p.shape.vertices) {
            const Vector3d model = R.transpose() * (p.loadPose.apply(v) / kS - Vector3d(1, 2, 3));
            INFO("corner " << model.transpose());
            CHECK(near(model.cwiseAbs(), Vector3d(5, 5, 5), 1e-9));
        }
        // The COM stays where the cube's centre is.
        CHECK(near(p.loadPose.position, Vector3d(1, 2, 3) * kS, kTight));
    }
}

TEST_CASE("figure: per-step friction becomes per-second damping d = 1 − (1 − f)^(1/0.016) (§3.4)", "[figure]") {
    const Built b = buildOk(R"(articulatedFigure t {
	body "pelvis" { joint "origin" model box( ( -5, -5, -5 ), ( 5, 5, 5 ) ) }
	body "chest" { joint "Spine" model box( ( -5, -5, -5 ), ( 5, 5, 5 ) ) origin ( 0, 0, 60 )
		friction 0.02, 0.05, 0.3 }
}
)");
    const FigureBody& p = b.body("pelvis");
    CHECK(p.linearFrictionPerStep == Approx(0.01));
    CHECK(p.angularFrictionPerStep == Approx(0.01));
    CHECK(p.contactFriction == Approx(0.8));
    CHECK(p.linearDamping == Approx(1 - std::pow(0.99, 62.5)).epsilon(1e-12));
    CHECK(p.linearDamping == Approx(0.466).margin(0.001)); // the spec's example
    CHECK(p.angularDamping == Approx(1 - std::pow(0.99, 62.5)).epsilon(1e-12));
    const FigureBody& c = b.body("chest");
    CHECK(c.linearFrictionPerStep == Approx(0.02));
    CHECK(c.angularFrictionPerStep == Approx(0.05));
    CHECK(c.contactFriction == Approx(0.3));
    CHECK(c.linearDamping == Approx(1 - std::pow(0.98, 62.5)).epsilon(1e-12));
    CHECK(c.angularDamping == Approx(1 - std::pow(0.95, 62.5)).epsilon(1e-12));
}

TEST_CASE("figure: out-of-range body friction falls back to the physics defaults (§3.4)", "[figure]") {
    SECTION("valid settings: the figure's settings values") {
        const Built b = build(R"(articulatedFigure t {
	body "pelvis" { joint "origin" model box( ( -5, -5, -5 ), ( 5, 5, 5 ) ) friction 1.5, 0.02, 0.3 }
	settings { friction 0.1, 0.2, 0.3 }
}
)");
        INFO(b.findings.str());
        REQUIRE(b.figure);
        CHECK(b.hasWarning("body \"pelvis\"", "friction"));
        // idAF::Load calls SetDefaultFriction with the decl's (final) settings values; a rejected body uses them.
        const FigureBody& p = b.body("pelvis");
        CHECK(p.linearFrictionPerStep == Approx(0.1));
        CHECK(p.angularFrictionPerStep == Approx(0.2));
        CHECK(p.contactFriction == Approx(0.3));
        CHECK(p.linearDamping == Approx(1 - std::pow(0.9, 62.5)).epsilon(1e-12));
    }
    SECTION("settings that fail their own check (contact > 1): 0.005, 0.005, 0.8") {
        const Built b = build(R"(articulatedFigure t {
	settings { friction 0.01, 0.01, 1.5 }
	body "pelvis" { joint "origin" model box( ( -5, -5, -5 ), ( 5, 5, 5 ) ) friction 0.5, -0.1, 0.3 }
	body "chest" { joint "Spine" model box( ( -5, -5, -5 ), ( 5, 5, 5 ) ) origin ( 0, 0, 60 ) }
}
)");
        INFO(b.findings.str());
        REQUIRE(b.figure);
        const FigureBody& p = b.body("pelvis");
        CHECK(p.linearFrictionPerStep == Approx(0.005));
        CHECK(p.angularFrictionPerStep == Approx(0.005));
        CHECK(p.contactFriction == Approx(0.8));
        // A body without its own friction takes the settings values through the body check (contact ≥ 0 only).
        const FigureBody& c = b.body("chest");
        CHECK(c.linearFrictionPerStep == Approx(0.01));
        CHECK(c.contactFriction == Approx(1.5));
    }
}

TEST_CASE("figure: rest rules in SI (§1.3, §6.1)", "[figure]") {
    const Built b = buildOk(R"(articulatedFigure t {
	settings {
		suspendSpeed 20, 30, 40, 60
		noMoveTime 2
		noMoveTranslation 10
		noMoveRotation 10
		minMoveTime 0.5
		maxMoveTime 8
	}
	body "pelvis" { joint "origin" model box( ( -5, -5, -5 ), ( 5, 5, 5 ) ) }
}
)");
    const figure::RestRules& r = b.figure->rest;
    CHECK(r.linearSpeedMps == Approx(20 * kS));
    CHECK(r.angularSpeedRadps == Approx(30)); // already rad/s
    CHECK(r.linearAccelMps2 == Approx(40 * kS));
    CHECK(r.angularAccelRadps2 == Approx(60));
    CHECK(r.noMoveTimeS == Approx(2));
    CHECK(r.noMoveTranslationM == Approx(10 * kS));
    CHECK(r.noMoveRotationRad == Approx(10 * kDeg)); // degrees in the decl
    CHECK(r.minMoveTimeS == Approx(0.5));
    CHECK(r.maxMoveTimeS == Approx(8));
}

TEST_CASE("figure: a cone's apex is at the body-local origin / its COM is 3/4 of the height below (§2.2, §3.1)",
          "[figure]") {
    const Built b = build(R"(articulatedFigure t {
	body "pelvis" { joint "origin" model cone( ( -3, -3, 0 ), ( 3, 3, 10 ), 6 ) origin ( 0, 0, 40 ) }
	body "offcentre" { joint "Spine" model cone( ( 0, -3, 5 ), ( 6, 3, 15 ), 6 ) origin ( 0, 0, 80 ) angles ( 0, 90, 0 ) }
}
)");
    INFO(b.findings.str());
    REQUIRE(b.figure);
    CHECK(near(b.body("pelvis").loadPose.position, Vector3d(0, 0, 40 - 7.5) * kS, kTight));
    // Bounds off-centre in x: the apex stays at (0, 0, 0) and the base hexagon is centred on (3, 0, −10), so the
    // exact COM is apex + 3/4·(base centre − apex) = (2.25, 0, −7.5); yaw 90 turns it to (0, 2.25, −7.5).
    CHECK(near(b.body("offcentre").loadPose.position, Vector3d(0, 2.25, 80 - 7.5) * kS, 1e-12));
}

TEST_CASE("figure: settings are captured in parse order (§1.8, §8 item 3)", "[figure]") {
    const Built b = buildOk(R"(articulatedFigure t {
	body "pelvis" { joint "origin" model box( ( -5, -5, -5 ), ( 5, 5, 5 ) ) origin ( 0, 0, 40 ) }
	settings {
		friction 0.1, 0.2, 0.3
		contents body
		clipMask solid
		selfCollision 0
	}
	body "chest" { joint "Spine" model box( ( -5, -5, -5 ), ( 5, 5, 5 ) ) origin ( 0, 0, 60 ) }
}
)");
    const FigureBody& p = b.body("pelvis");
    CHECK(p.linearFrictionPerStep == Approx(0.01));
    CHECK(p.angularFrictionPerStep == Approx(0.01));
    CHECK(p.contactFriction == Approx(0.8));
    CHECK(p.contents == figure::kContentsCorpse);
    CHECK(p.clipMask == (figure::kContentsSolid | figure::kContentsCorpse | figure::kContentsMoveableClip));
    CHECK(p.selfCollision);
    const FigureBody& c = b.body("chest");
    CHECK(c.linearFrictionPerStep == Approx(0.1));
    CHECK(c.angularFrictionPerStep == Approx(0.2));
    CHECK(c.contactFriction == Approx(0.3));
    CHECK(c.contents == figure::kContentsBody);
    CHECK(c.clipMask == (figure::kContentsSolid | figure::kContentsMoveableClip)); // MOVEABLECLIP always added
    CHECK_FALSE(c.selfCollision);
    CHECK_FALSE(b.figure->selfCollision); // the switch is the final settings value
}

// --- constraints (§1.7, §4) ------------------------------------------------------------------------------------

namespace {

const char* const kAllConstraints = R"(articulatedFigure t {
	settings { friction 0.01, 0.01, 0.8, 0.9 }
	body "pelvis" { joint "origin" model box( ( -6, -8, -4 ), ( 6, 8, 4 ) ) origin joint( "Hips" ) angles ( 10, 20, 30 ) }
	body "chest" { joint "Spine" model box( ( -5, -7, 0 ), ( 5, 7, 16 ) ) origin joint( "Spine" ) angles ( 0, 45, 5 ) }
	body "head" { joint "Head" model octahedron( ( -4, -4, -4 ), ( 4, 4, 6 ) ) origin joint( "Head" ) angles ( -20, 0, 10 ) }
	body "lthigh" { joint "LeftUpLeg" model bone( joint( "LeftUpLeg" ), joint( "LeftLeg" ), 5 )
		origin bonecenter( "LeftUpLeg", "LeftLeg" ) }
	body "rthigh" { joint "RightUpLeg" model cylinder( ( -3, -3, -9 ), ( 3, 3, 9 ), 8 ) origin ( 0, -6, 29 )
		angles ( 15, 0, 0 ) }
	body "lshin" { joint "LeftLeg" model dodecahedron( ( -3, -3, -9 ), ( 3, 3, 9 ) ) origin ( 2, 6, 11 ) angles ( 0, 10, 0 ) }
	body "tail" { joint "Hips" model cone( ( -3, -3, 0 ), ( 3, 3, 10 ), 6 ) origin ( -8, 0, 40 ) angles ( 0, 0, 20 ) }
	fixed "f" { body1 "head" body2 "chest" }
	ballAndSocketJoint "b" { body1 "chest" body2 "pelvis" anchor joint( "Spine" ) coneLimit ( 0, 0, 1 ), 60, ( 0, 0, 1 ) }
	universalJoint "u" { body1 "lthigh" body2 "pelvis" anchor joint( "LeftUpLeg" ) shafts ( 0, 0, -1 ), ( 0, 0, 1 )
		pyramidLimit ( 0, 0, -1 ), 60, 40, 10 }
	hinge "h" { body1 "lshin" body2 "lthigh" anchor joint( "LeftLeg" ) axis ( 0, 1, 0 ) limit 0, 90, 0 }
	slider "s" { body1 "tail" body2 "pelvis" axis ( 1, 0, 0 ) }
	spring "sp" { body1 "rthigh" body2 "lshin" anchor1 ( 0, -6, 25 ) anchor2 ( 2, 6, 15 ) stretch 10 compress 5
		damping 1 restLength 12 }
	ballAndSocketJoint "wb" { body1 "rthigh" body2 "world" anchor joint( "RightUpLeg" ) }
	universalJoint "wu" { body1 "head" anchor joint( "Head" ) shafts ( 1, 0, 0 ), ( -1, 0, 0 ) }
	hinge "wh" { body1 "tail" body2 "world" anchor ( -8, 0, 45 ) axis ( 0, 1, 1 ) }
	slider "ws" { body1 "chest" axis ( 0, 0, 1 ) }
	universalJoint "pyr" { body1 "rthigh" body2 "pelvis" anchor joint( "RightUpLeg" ) shafts ( 0, 0, -1 ), ( 0, 0, 1 )
		pyramidLimit ( 0.4, -0.2, -0.9 ), 75, 30, 61 }
	fixed "wf" { body1 "lshin" }
}
)";

} // namespace

TEST_CASE("figure: constraint frames coincide at the load pose for every constraint type (§4.1)", "[figure]") {
    const Built b = build(kAllConstraints);
    INFO(b.findings.str());
    REQUIRE(b.figure);
    const Figure& f = *b.figure;
    REQUIRE(f.constraints.size() == 12);
    for (const FigureConstraint& c : f.constraints) {
        INFO("constraint " << c.name);
        CHECK(isRotation(c.frameInBody1.rotation));
        CHECK(isRotation(c.frameInBody2.rotation));
        const auto [a, w] = framesModel(f, c);
        if (c.type == figure::JointType::Spring) continue; // anchors differ by design, checked below
        CHECK(near(a.position, w.position, kTight));
        CHECK(near(a.rotation, w.rotation, kTight));
    }
    // The frame's meaning per type (Figure.h): origin = anchor; universal X = shaft 1; hinge Z = axis; slider X = axis.
    CHECK(near(framesModel(f, b.constraint("b")).first.position, joint("Spine") * kS, kTight));
    CHECK(near(framesModel(f, b.constraint("u")).first.position, joint("LeftUpLeg") * kS, kTight));
    CHECK(near(Vector3d(framesModel(f, b.constraint("u")).first.rotation.col(0)), Vector3d(0, 0, -1), kTight));
    CHECK(near(framesModel(f, b.constraint("h")).first.position, joint("LeftLeg") * kS, kTight));
    CHECK(near(Vector3d(framesModel(f, b.constraint("h")).first.rotation.col(2)), Vector3d(0, 1, 0), kTight));
    CHECK(near(Vector3d(framesModel(f, b.constraint("s")).first.rotation.col(0)), Vector3d(1, 0, 0), kTight));
    CHECK(near(framesModel(f, b.constraint("wb")).second.position, joint("RightUpLeg") * kS, kTight));
    CHECK(near(framesModel(f, b.constraint("wh")).second.position, Vector3d(-8, 0, 45) * kS, kTight));
    CHECK(near(Vector3d(framesModel(f, b.constraint("wh")).second.rotation.col(2)), Vector3d(0, 1, 1).normalized(),
               kTight));
    CHECK(near(Vector3d(framesModel(f, b.constraint("ws")).second.rotation.col(0)), Vector3d(0, 0, 1), kTight));
    // Spring: anchor1 fixed in body1, anchor2 in body2 (§4.7).
    const auto [s1, s2] = framesModel(f, b.constraint("sp"));
    CHECK(near(s1.position, Vector3d(0, -6, 25) * kS, kTight));
    CHECK(near(s2.position, Vector3d(2, 6, 15) * kS, kTight));

    // Bodies and world attachment.
    CHECK(b.constraint("f").body1 == b.bodyIndex("head"));
    CHECK(b.constraint("f").body2 == b.bodyIndex("chest"));
    for (const char* name : {"wb", "wu", "wh", "ws", "wf"}) {
        INFO(name);
        CHECK(b.constraint(name).body2 == -1);
    }
    // §1.7, §8 item 2: joint friction is 0.5 whatever settings' 4th value; fixed, slider and spring have none.
    CHECK(b.constraint("b").friction == Approx(0.5));
    CHECK(b.constraint("u").friction == Approx(0.5));
    CHECK(b.constraint("h").friction == Approx(0.5));
    CHECK(b.constraint("f").friction == 0);
    CHECK(b.constraint("s").friction == 0);
    CHECK(b.constraint("sp").friction == 0);
    // §4.1: every type but spring disables collision between its bodies.
    for (const FigureConstraint& c : f.constraints) {
        INFO(c.name);
        CHECK(c.disablesCollision == (c.type != figure::JointType::Spring));
    }
}

TEST_CASE("figure: cone and pyramid limits (§4.3, §4.4)", "[figure]") {
    const Built b = build(kAllConstraints);
    INFO(b.findings.str());
    REQUIRE(b.figure);
    const Figure& f = *b.figure;
    const FigureConstraint& ball = b.constraint("b");
    const auto* cone = std::get_if<figure::ConeLimit>(&ball.limit);
    REQUIRE(cone);
    // Full apex angle 60 → half-angle 30°; axis fixed in body2, shaft in body1, both (0, 0, 1) at the load pose.
    CHECK(cone->halfAngleRad == Approx(30 * kDeg).epsilon(1e-12));
    const Matrix3d r1 = f.bodies[static_cast<std::size_t>(ball.body1)].loadPose.rotation;
    const Matrix3d r2 = f.bodies[static_cast<std::size_t>(ball.body2)].loadPose.rotation;
    CHECK(near(Vector3d(r2 * cone->axisInBody2), Vector3d(0, 0, 1), kTight));
    CHECK(near(Vector3d(r1 * cone->shaftInBody1), Vector3d(0, 0, 1), kTight));

    const FigureConstraint& uni = b.constraint("u");
    const auto* pyr = std::get_if<figure::PyramidLimit>(&uni.limit);
    REQUIRE(pyr);
    CHECK(pyr->halfAngle1Rad == Approx(30 * kDeg).epsilon(1e-12));
    CHECK(pyr->halfAngle2Rad == Approx(20 * kDeg).epsilon(1e-12));
    const Matrix3d u1 = f.bodies[static_cast<std::size_t>(uni.body1)].loadPose.rotation;
    const Matrix3d u2 = f.bodies[static_cast<std::size_t>(uni.body2)].loadPose.rotation;
    // S = shaft 1 for a universal joint; basis column f = A normalized.
    CHECK(near(Vector3d(u1 * pyr->shaftInBody1), Vector3d(0, 0, -1), kTight));
    const Matrix3d basisModel = u2 * pyr->basisInBody2;
    CHECK(near(Vector3d(basisModel.col(0)), Vector3d(0, 0, -1), kTight));
    CHECK(isRotation(basisModel));
    // A exactly vertical: l starts as +Y, then turns right-handedly about f by roll = 10°.
    const Vector3d l = Eigen::AngleAxisd(10 * kDeg, Vector3d(0, 0, -1)) * Vector3d::UnitY();
    CHECK(near(Vector3d(basisModel.col(1)), l, 1e-12));

    // A general axis: f = A/|A|; l starts as (−sin yaw, cos yaw, 0) with yaw = atan2(A.y, A.x), then turns
    // right-handedly about f by the roll (61°); the third column is f × l.
    const FigureConstraint& gen = b.constraint("pyr");
    const auto* pg = std::get_if<figure::PyramidLimit>(&gen.limit);
    REQUIRE(pg);
    const Matrix3d basisGen = f.bodies[static_cast<std::size_t>(gen.body2)].loadPose.rotation * pg->basisInBody2;
    const Vector3d fa = Vector3d(0.4, -0.2, -0.9).normalized();
    const double yaw = std::atan2(-0.2, 0.4);
    const Vector3d lg = Eigen::AngleAxisd(61 * kDeg, fa) * Vector3d(-std::sin(yaw), std::cos(yaw), 0);
    CHECK(near(Vector3d(basisGen.col(0)), fa, 1e-12));
    CHECK(near(Vector3d(basisGen.col(1)), lg, 1e-12));
    CHECK(near(Vector3d(basisGen.col(2)), Vector3d(fa.cross(lg)), 1e-12));
    CHECK(pg->halfAngle1Rad == Approx(37.5 * kDeg).epsilon(1e-12));
    CHECK(pg->halfAngle2Rad == Approx(15 * kDeg).epsilon(1e-12));
}

TEST_CASE("figure: hinge range φ ∈ [a2 − a0 − a1/2, a2 − a0 + a1/2] (§4.5)", "[figure]") {
    const Built b = build(R"(articulatedFigure t {
	body "pelvis" { joint "origin" model box( ( -5, -5, -5 ), ( 5, 5, 5 ) ) origin ( 0, 0, 40 ) }
	body "chest" { joint "Spine" model box( ( -5, -5, -5 ), ( 5, 5, 5 ) ) origin ( 0, 0, 60 ) }
	hinge "sym" { body1 "chest" body2 "pelvis" anchor ( 0, 0, 50 ) axis ( 0, 1, 0 ) limit 0, 90, 0 }
	hinge "off" { body1 "chest" body2 "pelvis" anchor ( 0, 0, 50 ) axis ( 0, 1, 0 ) limit 30, 90, 0 }
	hinge "a2" { body1 "chest" body2 "pelvis" anchor ( 0, 0, 50 ) axis ( 1, 0, 0 ) limit 0, 60, 20 }
	hinge "long" { body1 "chest" body2 "pelvis" anchor ( 0, 0, 50 ) axis ( 0, 0, 2 ) limit 30, 90, 0 }
	hinge "longeq" { body1 "chest" body2 "pelvis" anchor ( 0, 0, 50 ) axis ( 0, 2, 0 ) limit 20, 90, 20 }
	hinge "bonedir" { body1 "chest" body2 "pelvis" anchor ( 0, 0, 50 ) axis bonedir( "Hips", "Spine" ) limit 0, 40, 10 }
	hinge "free" { body1 "chest" body2 "pelvis" anchor ( 0, 0, 50 ) axis ( 0, 1, 0 ) }
}
)");
    INFO(b.findings.str());
    REQUIRE(b.figure);
    auto range = [&](const char* name) {
        const auto* r = std::get_if<figure::HingeRange>(&b.constraint(name).limit);
        REQUIRE(r);
        return std::pair<double, double>{r->lowerRad, r->upperRad};
    };
    auto checkRange = [&](const char* name, double lowDeg, double highDeg) {
        INFO(name);
        const auto [lo, hi] = range(name);
        CHECK(lo == Approx(lowDeg * kDeg).margin(1e-12));
        CHECK(hi == Approx(highDeg * kDeg).margin(1e-12));
    };
    checkRange("sym", -45, 45);
    checkRange("off", -75, 15); // the spec's example
    checkRange("a2", -10, 50);
    // Non-unit axis of length L: [g(a2) − g(a0) − a1/2, g(a2) − g(a0) + a1/2].
    const double centre = (g(0, 2) - g(30 * kDeg, 2)) / kDeg;
    REQUIRE(centre == Approx(-65.1).margin(0.05));
    checkRange("long", centre - 45, centre + 45);
    checkRange("longeq", -45, 45); // a0 == a2: the distortion cancels
    // bonedir is not normalized: its length in Doom units (10) is the L of the distortion.
    const double centreBone = (g(10 * kDeg, 10) - g(0, 10)) / kDeg;
    checkRange("bonedir", centreBone - 20, centreBone + 20);
    CHECK(std::holds_alternative<std::monostate>(b.constraint("free").limit));
}

TEST_CASE("figure: body2 typo attaches to the world with a warning / body1 unknown is an error (§1.7)", "[figure]") {
    SECTION("body2") {
        const Built b = build(std::string("articulatedFigure t {") + kSimpleBodies + R"(
	hinge "h" {
		body1 "chest"
		body2 "pelvsi"
		anchor ( 0, 0, 50 )
		axis ( 0, 1, 0 )
	}
	ballAndSocketJoint "caseOnly" { body1 "CHEST" body2 "PELVIS" anchor ( 0, 0, 50 ) }
}
)");
        INFO(b.findings.str());
        REQUIRE(b.figure);
        CHECK_FALSE(b.findings.hasErrors());
        CHECK(b.hasWarning("hinge \"h\"", "pelvsi"));
        CHECK(b.constraint("h").body2 == -1);
        CHECK(figure::attachedToWorld(*b.figure, b.bodyIndex("chest")));
        // Body names are looked up case-insensitively at load.
        CHECK(b.constraint("caseOnly").body1 == b.bodyIndex("chest"));
        CHECK(b.constraint("caseOnly").body2 == b.bodyIndex("pelvis"));
    }
    SECTION("body1") {
        const Built b = build(std::string("articulatedFigure t {") + kSimpleBodies + R"(
	hinge "h" {
		body1 "chset"
		body2 "pelvis"
		anchor ( 0, 0, 50 )
		axis ( 0, 1, 0 )
	}
}
)");
        CHECK_FALSE(b.figure);
        CHECK(b.hasError("hinge \"h\"", "chset"));
    }
    SECTION("body1 == body2 (case-insensitively) is an error") {
        const Built b = build(std::string("articulatedFigure t {") + kSimpleBodies + R"(
	fixed "same" {
		body1 "chest"
		body2 "CHEST"
	}
}
)");
        CHECK_FALSE(b.figure);
        CHECK(b.hasError("fixed \"same\""));
    }
    SECTION("a missing body1 means the first body parsed before the constraint") {
        const Built b = buildOk(std::string("articulatedFigure t {") + kSimpleBodies + R"(
	hinge "h" { body2 "chest" anchor ( 0, 0, 50 ) axis ( 0, 1, 0 ) }
}
)");
        CHECK(b.constraint("h").body1 == b.bodyIndex("pelvis"));
        CHECK(b.constraint("h").body2 == b.bodyIndex("chest"));
    }
}

TEST_CASE("figure: springs (§4.7)", "[figure]") {
    SECTION("a missing stretch is an error") {
        const Built b = build(std::string("articulatedFigure t {") + kSimpleBodies + R"(
	spring "sp" {
		body1 "chest"
		body2 "pelvis"
		anchor1 ( 0, 0, 60 )
		anchor2 ( 0, 0, 40 )
		compress 5
		damping 1
		restLength 12
	}
}
)");
        CHECK_FALSE(b.figure);
        CHECK(b.hasError("spring \"sp\"", "stretch"));
    }
    SECTION("SI conversion: k / s, damping × s, lengths × s") {
        const Built b = buildOk(std::string("articulatedFigure t {") + kSimpleBodies + R"(
	spring "sp" { body1 "chest" body2 "pelvis" anchor1 ( 0, 0, 60 ) anchor2 ( 0, 0, 40 ) stretch 100 compress 50
		damping 2 restLength 10 minLength 5 maxLength 20 }
}
)");
        const figure::SpringParams& s = b.constraint("sp").spring;
        // F = k·ΔL² with F in mass·unit/s² and ΔL in units: F_SI = s·k·(ΔL_SI/s)² = (k/s)·ΔL_SI².
        CHECK(s.stretchNPerM2 == Approx(100 / kS).epsilon(1e-12));
        CHECK(s.compressNPerM2 == Approx(50 / kS).epsilon(1e-12));
        // D = damping·|Δv·n|/L: speeds and lengths scale alike, the force by s.
        CHECK(s.dampingNs == Approx(2 * kS).epsilon(1e-12));
        CHECK(s.restLengthM == Approx(10 * kS).epsilon(1e-12));
        CHECK(s.minLengthM == Approx(5 * kS).epsilon(1e-12));
        CHECK(s.maxLengthM == Approx(20 * kS).epsilon(1e-12));
        CHECK_FALSE(b.constraint("sp").disablesCollision);
    }
}

TEST_CASE("figure findings: a spring without an anchor, or starting outside [minLength, maxLength] (§4.7)",
          "[figure]") {
    // Found by fuzz_e2e: `anchor1` written twice leaves anchor2 at the model origin, 50 units from anchor1
    // (0, 0, 50); that is above maxLength 20, so the length row yanks the bodies at once.
    const Built b = build(std::string("articulatedFigure t {") + kSimpleBodies + R"(
	spring "twice" { body1 "chest" body2 "pelvis" anchor1 ( 0, 0, 60 ) anchor1 ( 0, 0, 50 ) stretch 10 compress 10
		damping 1 restLength 10 minLength 5 maxLength 20 }
	spring "short" { body1 "chest" body2 "pelvis" anchor1 ( 0, 0, 52 ) anchor2 ( 0, 0, 48 ) stretch 10 compress 10
		damping 1 restLength 10 minLength 5 maxLength 20 }
	spring "fine" { body1 "chest" body2 "pelvis" anchor1 ( 0, 0, 60 ) anchor2 ( 0, 0, 40 ) stretch 10 compress 10
		damping 1 restLength 10 minLength 5 maxLength 20 }
}
)");
    INFO(b.findings.str());
    REQUIRE(b.figure);
    CHECK(b.hasWarning("spring \"twice\"", "no anchor2; the engine places it at the model origin"));
    CHECK(b.hasWarning("spring \"twice\"", "start 1.27 m apart, above maxLength 0.508 m")); // 50 and 20 units
    CHECK(b.hasWarning("spring \"short\"", "below minLength"));
    CHECK_FALSE(b.hasWarning("spring \"short\"", "no anchor"));
    CHECK_FALSE(b.hasWarning("spring \"fine\""));
}

// --- collision filtering (§4.1, §6.2) --------------------------------------------------------------------------

TEST_CASE("figure: selfCollisionPairs and attachedToWorld (§6.2)", "[figure]") {
    const std::string bodies = R"(
	body "a" { joint "origin" model box( ( -2, -2, -2 ), ( 2, 2, 2 ) ) origin ( 0, 0, 0 ) }
	body "b" { joint "Hips" model box( ( -2, -2, -2 ), ( 2, 2, 2 ) ) origin ( 0, 0, 10 ) }
	body "c" { joint "Spine" model box( ( -2, -2, -2 ), ( 2, 2, 2 ) ) origin ( 0, 0, 20 ) }
	body "d" { joint "Head" model box( ( -2, -2, -2 ), ( 2, 2, 2 ) ) origin ( 0, 0, 30 ) selfCollision 0 }
	body "e" { joint "LeftUpLeg" model box( ( -2, -2, -2 ), ( 2, 2, 2 ) ) origin ( 0, 0, 40 ) contents body clipMask solid }
	body "f" { joint "LeftLeg" model box( ( -2, -2, -2 ), ( 2, 2, 2 ) ) origin ( 0, 0, 50 ) }
	hinge "ab" { body1 "b" body2 "a" anchor ( 0, 0, 5 ) axis ( 0, 1, 0 ) }
	spring "bc" { body1 "c" body2 "b" anchor1 ( 0, 0, 20 ) anchor2 ( 0, 0, 10 ) stretch 1 compress 1 damping 0 restLength 10 }
	fixed "fw" { body1 "f" body2 "world" }
	spring "cw" { body1 "c" body2 "world" anchor1 ( 0, 0, 20 ) anchor2 ( 0, 0, 100 ) stretch 1 compress 1 damping 0 restLength 10 }
}
)";
    const Built on = buildOk("articulatedFigure t {" + bodies);
    const Figure& f = *on.figure;
    const int a = on.bodyIndex("a"), b = on.bodyIndex("b"), c = on.bodyIndex("c"), ff = on.bodyIndex("f");
    std::vector<std::pair<int, int>> expected = {{a, c}, {b, c}, {a, ff}, {b, ff}, {c, ff}};
    for (auto& p : expected)
        if (p.first > p.second) std::swap(p.first, p.second);
    std::sort(expected.begin(), expected.end());
    // a–b joined by a hinge; b–c only by a spring (springs never disable collision); d has selfCollision 0;
    // e's contents (body) are outside everyone's clipMask and its clipMask (solid) excludes corpse.
    CHECK(figure::selfCollisionPairs(f) == expected);
    CHECK(figure::attachedToWorld(f, ff));
    CHECK_FALSE(figure::attachedToWorld(f, c)); // a spring to the world does not
    CHECK_FALSE(figure::attachedToWorld(f, a));
    CHECK_FALSE(figure::attachedToWorld(f, b));

    const Built off = buildOk("articulatedFigure t {\n\tsettings { selfCollision 0 }" + bodies);
    CHECK(figure::selfCollisionPairs(*off.figure).empty());
    CHECK_FALSE(off.figure->selfCollision);
}

// --- findings (errors stop the build, warnings do not) -----------------------------------------------------------

TEST_CASE("figure findings: unknown joints", "[figure]") {
    SECTION("a body's joint") {
        const Built b = build(std::string("articulatedFigure t {") + kSimpleBodies + R"(
	body "arm" {
		joint "LeftArm"
		model box( ( -1, -1, -1 ), ( 1, 1, 1 ) )
		origin ( 0, 10, 50 )
	}
}
)");
        CHECK_FALSE(b.figure); // a fatal gameLocal.Error in the engine (§2.3)
        CHECK(b.hasError("body \"arm\"", "LeftArm"));
    }
    SECTION("a vector expression's joint") {
        const Built b = build(std::string("articulatedFigure t {") + kSimpleBodies + R"(
	body "arm" {
		joint "Head"
		model box( ( -1, -1, -1 ), ( 1, 1, 1 ) )
		origin joint( "LeftHand" )
	}
}
)");
        const std::uint32_t line = b.lineOf("body \"arm\"");
        CHECK((b.has(text::Severity::Error, line, "LeftHand") || b.has(text::Severity::Warning, line, "LeftHand")));
    }
    SECTION("a containedJoints entry") {
        const Built b = build(std::string("articulatedFigure t {") + kSimpleBodies + R"(
	body "head" {
		joint "Head"
		model box( ( -1, -1, -1 ), ( 1, 1, 1 ) )
		origin ( 0, 0, 80 )
		containedJoints "*Head *Neck"
	}
}
)");
        CHECK(b.hasWarning("body \"head\"", "Neck"));
    }
}

TEST_CASE("figure findings: unknown contents names end the list (§1.6)", "[figure]") {
    const Built b = build(std::string("articulatedFigure t {") + kSimpleBodies + R"(
	body "head" {
		joint "Head"
		model box( ( -1, -1, -1 ), ( 1, 1, 1 ) )
		origin ( 0, 0, 80 )
		contents corpse, trigger, solid
	}
}
)");
    INFO(b.findings.str());
    REQUIRE(b.figure);
    CHECK(b.hasWarning("body \"head\"", "trigger"));
    CHECK(b.body("head").contents == figure::kContentsCorpse);
}

TEST_CASE("figure findings: joints contained by no body or by two (§5.3)", "[figure]") {
    const Built b = build(R"(articulatedFigure t {
	body "pelvis" {
		joint "origin"
		model box( ( -6, -8, -4 ), ( 6, 8, 4 ) )
		origin joint( "Hips" )
		containedJoints "origin Hips Spine"
	}
	body "chest" {
		joint "Spine"
		model box( ( -5, -7, 0 ), ( 5, 7, 16 ) )
		origin joint( "Spine" )
		containedJoints "*Spine"
	}
}
)");
    INFO(b.findings.str());
    REQUIRE(b.figure);
    // LeftUpLeg, LeftLeg and RightUpLeg are in no body: one warning at the decl.
    CHECK(b.hasWarning("articulatedFigure t", "LeftUpLeg"));
    // Spine is claimed twice: the later body wins, with a warning at it.
    CHECK(b.hasWarning("body \"chest\"", "Spine"));
    CHECK(b.figure->jointBody[2] == b.bodyIndex("chest"));
    CHECK(b.figure->jointBody[3] == b.bodyIndex("chest"));
    CHECK(b.figure->jointBody[4] == -1);
    CHECK(b.body("pelvis").containedJoints == std::vector<int>{0, 1});
}

TEST_CASE("figure: an omitted containedJoints means `*origin` / the later body wins (§5.3, §8 item 4)", "[figure]") {
    const Built b = build(R"(articulatedFigure t {
	body "pelvis" { joint "origin" model box( ( -6, -8, -4 ), ( 6, 8, 4 ) ) origin joint( "Hips" ) containedJoints "*Hips" }
	body "chest" { joint "Spine" model box( ( -5, -7, 0 ), ( 5, 7, 16 ) ) origin joint( "Spine" ) }
}
)");
    INFO(b.findings.str());
    REQUIRE(b.figure);
    const int chest = b.bodyIndex("chest");
    CHECK(b.figure->jointBody == std::vector<int>(humanoid().size(), chest));
    CHECK(b.body("pelvis").containedJoints.empty());
    CHECK(b.body("chest").containedJoints == std::vector<int>{0, 1, 2, 3, 4, 5, 6});
    CHECK(b.hasWarning("body \"chest\"", "Hips"));
}

TEST_CASE("figure findings: names that differ only in case are errors (§1.8, §8 item 1)", "[figure]") {
    SECTION("bodies") {
        const Built b = build(std::string("articulatedFigure t {") + kSimpleBodies + R"(
	body "Chest" {
		joint "Head"
		model box( ( -1, -1, -1 ), ( 1, 1, 1 ) )
		origin ( 0, 0, 80 )
	}
}
)");
        CHECK_FALSE(b.figure);
        CHECK(b.hasError("body \"Chest\"", "Chest"));
    }
    SECTION("constraints") {
        const Built b = build(std::string("articulatedFigure t {") + kSimpleBodies + R"(
	fixed "joint" { body1 "chest" body2 "pelvis" }
	fixed "JOINT" { body1 "chest" body2 "pelvis" }
}
)");
        CHECK_FALSE(b.figure);
        CHECK(b.hasError("fixed \"JOINT\"", "JOINT"));
    }
}

TEST_CASE("figure findings: mass outside [1, 100], mass ratio above 10:1, inertia more than 10:1 apart", "[figure]") {
    const Built b = build(R"(articulatedFigure t {
	body "pelvis" { joint "origin" model box( ( -5, -5, -5 ), ( 5, 5, 5 ) ) origin ( 0, 0, 40 ) density 0.05 }
	body "light" { joint "Spine" model box( ( -1, -1, -1 ), ( 1, 1, 1 ) ) origin ( 0, 0, 60 ) density 0.1 }
	body "heavy" { joint "Head" model box( ( -10, -10, -10 ), ( 10, 10, 10 ) ) origin ( 0, 0, 90 ) density 0.2 }
	body "thin" { joint "LeftUpLeg" model box( ( -1, -1, -20 ), ( 1, 1, 20 ) ) origin ( 0, 30, 20 ) density 0.1 }
	body "ok" { joint "RightUpLeg" model box( ( -2, -2, -2 ), ( 2, 2, 2 ) ) origin ( 0, -30, 20 ) density 0.2 }
	ballAndSocketJoint "ratio" { body1 "ok" body2 "pelvis" anchor ( 0, -20, 30 ) }
	ballAndSocketJoint "fine" { body1 "thin" body2 "pelvis" anchor ( 0, 20, 30 ) }
}
)");
    INFO(b.findings.str());
    REQUIRE(b.figure); // warnings only
    CHECK_FALSE(b.findings.hasErrors());
    CHECK(b.body("light").massKg == Approx(0.8));
    CHECK(b.body("heavy").massKg == Approx(1600));
    CHECK(b.hasWarning("body \"light\"", "mass"));
    CHECK(b.hasWarning("body \"heavy\"", "mass"));
    CHECK_FALSE(b.hasWarning("body \"ok\"", "mass"));
    // ok: 12.8, pelvis: 50 → 3.9:1 is fine; thin: 16, pelvis: 50 fine. Use a ratio that is not:
    CHECK_FALSE(b.hasWarning("ballAndSocketJoint \"ratio\""));
    // thin: Ixx/Izz = (4 + 1600)/(4 + 4) ≈ 200.
    CHECK(b.hasWarning("body \"thin\"", "10:1"));
    CHECK_FALSE(b.hasWarning("body \"pelvis\"", "10:1"));

    const Built r = build(R"(articulatedFigure t {
	body "pelvis" { joint "origin" model box( ( -5, -5, -5 ), ( 5, 5, 5 ) ) origin ( 0, 0, 40 ) density 0.05 }
	body "small" { joint "Spine" model box( ( -1, -1, -1 ), ( 1, 1, 1 ) ) origin ( 0, 0, 60 ) density 0.5 }
	ballAndSocketJoint "ratio" { body1 "small" body2 "pelvis" anchor ( 0, 0, 50 ) }
}
)");
    INFO(r.findings.str());
    REQUIRE(r.figure);
    // small: 4, pelvis: 50 → 12.5:1.
    CHECK(r.hasWarning("ballAndSocketJoint \"ratio\"", "10:1"));
}

TEST_CASE("figure findings: limits the load pose already exceeds (§4.3, §4.5)", "[figure]") {
    // The chest is turned (yaw 90°): the lint measures on the built frames, which must not matter.
    const Built b = build(R"(articulatedFigure t {
	body "pelvis" { joint "origin" model box( ( -5, -5, -5 ), ( 5, 5, 5 ) ) origin ( 0, 0, 40 ) }
	body "chest" { joint "Spine" model box( ( -5, -5, -5 ), ( 5, 5, 5 ) ) origin ( 0, 0, 60 ) angles ( 0, 90, 0 ) }
	ballAndSocketJoint "coneIn" { body1 "chest" body2 "pelvis" anchor ( 0, 0, 50 ) coneLimit ( 0, 0, 1 ), 60, ( 0, 0.5, 1 ) }
	ballAndSocketJoint "coneOut" { body1 "chest" body2 "pelvis" anchor ( 0, 0, 50 ) coneLimit ( 0, 0, 1 ), 60, ( 0, 1, 1 ) }
	ballAndSocketJoint "pyrIn" { body1 "chest" body2 "pelvis" anchor ( 0, 0, 50 ) pyramidLimit ( 1, 0, 0 ), 60, 40, 0, ( 1, 0.5, 0.3 ) }
	ballAndSocketJoint "pyrOut" { body1 "chest" body2 "pelvis" anchor ( 0, 0, 50 ) pyramidLimit ( 1, 0, 0 ), 60, 40, 0, ( 1, 0, 0.5 ) }
	hinge "hingeIn" { body1 "chest" body2 "pelvis" anchor ( 0, 0, 50 ) axis ( 0, 1, 0 ) limit 30, 90, 0 }
	hinge "hingeOut" { body1 "chest" body2 "pelvis" anchor ( 0, 0, 50 ) axis ( 0, 1, 0 ) limit 0, 60, 60 }
	ballAndSocketJoint "worldOut" { body1 "pelvis" body2 "world" anchor ( 0, 0, 40 ) coneLimit ( 1, 0, 0 ), 20, ( 0, 0, 1 ) }
}
)");
    INFO(b.findings.str());
    REQUIRE(b.figure);
    CHECK_FALSE(b.hasWarning("ballAndSocketJoint \"coneIn\"", "starts"));
    CHECK(
        b.hasWarning("ballAndSocketJoint \"coneOut\"", "starts 45 deg from the cone axis, outside the half-angle 30"));
    CHECK_FALSE(b.hasWarning("ballAndSocketJoint \"pyrIn\"", "starts"));
    CHECK(b.hasWarning("ballAndSocketJoint \"pyrOut\"", "deg from its axis; limits 30, 20 deg"));
    CHECK_FALSE(b.hasWarning("hinge \"hingeIn\"", "excludes"));
    CHECK(b.hasWarning("hinge \"hingeOut\"", "[30, 90] deg excludes the load pose"));
    CHECK(b.hasWarning("ballAndSocketJoint \"worldOut\"", "starts 90 deg from the cone axis"));
}

TEST_CASE("figure findings: self-colliding bodies that overlap or touch at the load pose", "[figure]") {
    auto figureWith = [](const std::string& chestZ, const std::string& joint) {
        return "articulatedFigure t {\n"
               "\tbody \"pelvis\" { joint \"origin\" model box( ( -5, -5, -5 ), ( 5, 5, 5 ) ) origin ( 0, 0, 40 ) }\n"
               "\tbody \"chest\" { joint \"Spine\" model box( ( -5, -5, -5 ), ( 5, 5, 5 ) ) origin ( 0, 0, " +
               chestZ + " ) }\n" + joint + "}\n";
    };
    auto flagged = [](const Built& b) {
        const std::uint32_t l1 = b.lineOf("body \"pelvis\""), l2 = b.lineOf("body \"chest\"");
        bool found = false;
        for (const char* what : {"overlap", "touch"})
            found = found || b.has(text::Severity::Warning, l1, what) || b.has(text::Severity::Warning, l2, what);
        return found;
    };
    {
        const Built b = build(figureWith("48", ""));
        INFO(b.findings.str());
        REQUIRE(b.figure);
        CHECK(flagged(b)); // 2 units of overlap
    }
    {
        const Built b = build(figureWith("50", ""));
        INFO(b.findings.str());
        REQUIRE(b.figure);
        CHECK(flagged(b)); // face to face
    }
    {
        const Built b = build(figureWith("52", ""));
        INFO(b.findings.str());
        REQUIRE(b.figure);
        CHECK_FALSE(flagged(b)); // 2 units apart
    }
    {
        // Joined by a collision-disabling constraint: not a self-colliding pair, nothing to report.
        const Built b = build(
            figureWith("48", "\tballAndSocketJoint \"j\" { body1 \"chest\" body2 \"pelvis\" anchor ( 0, 0, 44 ) }\n"));
        INFO(b.findings.str());
        REQUIRE(b.figure);
        CHECK_FALSE(flagged(b));
    }
}

TEST_CASE("figure findings: zero or negative volume is an error", "[figure]") {
    SECTION("flat box") {
        const Built b = build(std::string("articulatedFigure t {") + kSimpleBodies + R"(
	body "flat" {
		joint "Head"
		model box( ( -5, -5, 0 ), ( 5, 5, 0 ) )
		origin ( 0, 0, 80 )
	}
}
)");
        CHECK_FALSE(b.figure);
        CHECK(b.hasError("body \"flat\"", "volume"));
    }
    SECTION("inverted bounds") {
        const Built b = build(std::string("articulatedFigure t {") + kSimpleBodies + R"(
	body "inverted" {
		joint "Head"
		model box( ( 5, 5, 5 ), ( -5, -5, -5 ) )
		origin ( 0, 0, 80 )
	}
}
)");
        CHECK_FALSE(b.figure);
        CHECK(b.hasError("body \"inverted\"", "volume"));
    }
    SECTION("two-sided cone") {
        const Built b = build(std::string("articulatedFigure t {") + kSimpleBodies + R"(
	body "cone2" {
		joint "Head"
		model cone( ( -5, -5, 0 ), ( 5, 5, 10 ), 2 )
		origin ( 0, 0, 80 )
	}
}
)");
        CHECK_FALSE(b.figure);
        CHECK(b.hasError("body \"cone2\"", "volume"));
    }
}
