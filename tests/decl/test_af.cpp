// Spec-driven tests of the `.af` parser and writer (docs/format.md §1.1-§1.8, §8 items 1, 2, 3, 10, 11, 12, 13, 15;
// plus the project's policy: engine fallbacks become located errors or warnings, errors give nullopt).
#include <catch2/catch.hpp>

#include <cstdint>
#include <random>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "afb/decl/Af.h"
#include "afb/decl/AfParser.h"
#include "afb/text/Diagnostics.h"

using namespace afb::decl;
using afb::text::Diagnostic;
using afb::text::Diagnostics;
using afb::text::Severity;

namespace {

/// 1-based line and column of byte `offset` of `text`.
std::pair<std::uint32_t, std::uint32_t> lineColOf(std::string_view text, std::size_t offset) {
    std::uint32_t line = 1, col = 1;
    for (std::size_t i = 0; i < offset && i < text.size(); ++i) {
        if (text[i] == '\n') {
            ++line;
            col = 1;
        } else {
            ++col;
        }
    }
    return {line, col};
}

/// Line and column of the `occurrence`-th (1-based) occurrence of `needle`.
std::pair<std::uint32_t, std::uint32_t> posOf(std::string_view text, std::string_view needle, int occurrence = 1) {
    std::size_t at = std::string_view::npos, from = 0;
    for (int i = 0; i < occurrence; ++i) {
        at = text.find(needle, from);
        REQUIRE(at != std::string_view::npos);
        from = at + 1;
    }
    return lineColOf(text, at);
}

/// Wraps blocks in one figure.
std::string fig(const std::string& blocks) { return "articulatedFigure f {\n" + blocks + "\n}\n"; }

const Diagnostic* firstError(const Diagnostics& d) {
    for (const Diagnostic& x : d.items())
        if (x.severity == Severity::Error) return &x;
    return nullptr;
}

std::size_t countWarningsContaining(const Diagnostics& d, std::string_view what) {
    std::size_t n = 0;
    for (const Diagnostic& x : d.items())
        if (x.severity == Severity::Warning && x.message.find(what) != std::string::npos) ++n;
    return n;
}

/// parse(write(f)) == f, and writing is idempotent: write(parse(write(f))) == write(f).
void checkRoundTrip(const AfFile& f) {
    const std::string w1 = writeAf(f);
    Diagnostics d;
    const auto g = parseAf(w1, "roundtrip.af", d);
    INFO("written:\n" << w1 << "\ndiagnostics:\n" << d.str());
    REQUIRE(g.has_value());
    CHECK(d.errorCount() == 0);
    CHECK(*g == f);
    CHECK(writeAf(*g) == w1);
}

/// Parses text that must be valid; checks the round trip too. Warnings are allowed (and returned).
AfFile parseOk(const std::string& text, Diagnostics* warnings = nullptr) {
    Diagnostics d;
    const auto f = parseAf(text, "test.af", d);
    INFO("text:\n" << text << "\ndiagnostics:\n" << d.str());
    REQUIRE(f.has_value());
    REQUIRE(d.errorCount() == 0);
    checkRoundTrip(*f);
    if (warnings) warnings->append(d);
    return *f;
}

/// Parses valid text holding exactly one figure; returns it.
AfDecl parseOne(const std::string& text, Diagnostics* warnings = nullptr) {
    const AfFile f = parseOk(text, warnings);
    REQUIRE(f.decls.size() == 1);
    return f.decls[0];
}

/// `marked` contains one '@' placed just before the offending token. Parsing the text without the '@' must fail
/// (nullopt, at least one error), and the first error must be at the marked line and column.
void requireErrorAt(const std::string& marked) {
    const std::size_t at = marked.find('@');
    REQUIRE(at != std::string::npos);
    const std::string text = marked.substr(0, at) + marked.substr(at + 1);
    const auto [line, col] = lineColOf(text, at);
    Diagnostics d;
    const auto f = parseAf(text, "err.af", d);
    INFO("text:\n" << text << "\nexpected error at " << line << ":" << col << "\ndiagnostics:\n" << d.str());
    CHECK_FALSE(f.has_value());
    REQUIRE(d.errorCount() >= 1);
    const Diagnostic* e = firstError(d);
    REQUIRE(e != nullptr);
    CHECK(e->where.file == "err.af");
    CHECK(e->where.line == line);
    CHECK(e->where.column == col);
}

AfVector lit(double x, double y, double z, bool negated = false) {
    AfVector v = AfVector::fromLiteral({x, y, z});
    v.negated = negated;
    return v;
}
AfVector jointVec(const std::string& j, bool negated = false) {
    AfVector v;
    v.form = AfVector::Form::Joint;
    v.negated = negated;
    v.joint1 = j;
    return v;
}
AfVector twoJoints(AfVector::Form form, const std::string& a, const std::string& b, bool negated = false) {
    AfVector v;
    v.form = form;
    v.negated = negated;
    v.joint1 = a;
    v.joint2 = b;
    return v;
}

// A ~2 KB figure that uses every block type and nearly every key (used for values, round trips and mutations).
const std::string kEverything = R"AF(/*
	Written for the tests; exercises every block and key of docs/format.md §1.3-§1.7.
*/
articulatedFigure everything {
	settings {
		model "model_everything"
		skin "skins/everything.skin"
		mesh "models/md5/everything.md5mesh"
		anim "models/md5/everything_af.md5anim"
		friction 0.0099999998, 0.02, 0.8000000119, 0.4
		suspendSpeed 21, 31, 41.5, 61
		noMoveTime 1.5
		noMoveTranslation 11
		noMoveRotation 12
		minMoveTime 2
		maxMoveTime 15
		totalMass 250
		contents corpse, body
		clipMask solid, corpse, playerclip
		selfCollision 0
	}
	body "pelvis" {
		joint "origin"
		mod orientation
		model box( ( -6, -8, -4 ), ( 6, 8, 4.5 ) )
		origin ( 0, 0, 44 )
		angles ( 0, 90, 0 )
		density 0.2
		inertiaScale ( 1 0 0 0 2 0 0 0 -3.5 )
		friction 0.01, 0.01, 0.8
		contents corpse
		clipMask solid, corpse, monsterclip
		selfCollision 1
		containedJoints "*origin -*Spine"
		frictionDirection ( 1, 0, 0 )
		contactMotorDirection -( 0, 1, 0 )
	}
	body "chest" {
		joint "Spine"
		mod position
		model octahedron( joint( "Spine" ), -joint( Neck ) )
		origin bonecenter( "Spine", "Neck" )
	}
	body "head" {
		joint "Neck"
		mod both
		model dodecahedron( ( -4, -4, -4 ), ( 4, 4, 4 ) )
		origin -bonedir( "Neck", Head )
	}
	body "arm" {
		joint "Arm"
		model bone( joint( "Arm" ), joint( "Hand" ), 6.5 )
		origin bonecenter( Arm, Hand )
	}
	body "leg" { joint "Leg" model cylinder( ( -3, -3, -10 ), ( 3, 3, 10 ), 7 ) }
	body "foot" { joint "Foot" model cone( ( -2, -2, -5 ), ( 2, 2, 5 ), 4 ) }
	fixed "f" { body1 "pelvis" body2 "chest" }
	ballAndSocketJoint "bs" {
		body1 "head"
		body2 "chest"
		anchor joint( "Neck" )
		friction 0.3
		coneLimit ( 0, 0, 1 ), 60, ( 0, 0, 1 )
	}
	ballAndSocketJoint "bs2" { anchor ( 1, 2, 3 ) pyramidLimit ( 0, 0, -1 ), 30, 40, 50, -( 0, 1, 0 ) }
	universalJoint "u" {
		body1 "arm"
		body2 "chest"
		anchor joint( "Arm" )
		shafts ( 0, 0, 1 ), ( 0, 0, -1 )
		friction 0.4
		coneLimit ( 0, 0, 1 ), 90
	}
	universalJoint "u2" { body1 "leg" shafts ( 0, 1, 0 ), -( 0, 1, 0 ) pyramidLimit ( 0.4, -0.2, -0.9 ), 75, 30, 61 }
	hinge "h" {
		body1 "foot"
		body2 "leg"
		anchor joint( "Foot" )
		axis ( 0, -1, 0 )
		friction 0.4
		limit 130, 70, 90
	}
	slider "s" { body1 "arm" body2 "world" axis bonedir( "Arm", "Hand" ) friction 0.5 }
	spring "sp" {
		body1 "head"
		body2 "pelvis"
		anchor1 joint( "Head" )
		anchor2 ( 0, 0, 10 )
		friction 0.5
		stretch 100
		compress 200
		damping 0.5
		restLength 10
		minLength 5
		maxLength 20
	}
}
)AF";

} // namespace

// -------------------------------------------------------------------------------------------------------------
// The whole figure
// -------------------------------------------------------------------------------------------------------------

TEST_CASE("af: a figure with every block and key", "[af]") {
    Diagnostics warnings;
    const AfDecl d = parseOne(kEverything, &warnings);
    CHECK(warnings.empty());
    CHECK(d.name == "everything");
    CHECK(d.location.line == 4);
    CHECK(d.location.column == 1);
    REQUIRE(d.settings.size() == 1);
    REQUIRE(d.bodies.size() == 6);
    REQUIRE(d.constraints.size() == 8);

    SECTION("settings (§1.3)") {
        const AfSettings& s = d.settings[0];
        CHECK(s.location.line == 5);
        CHECK(s.location.column == 2);
        CHECK(s.model == "model_everything");
        CHECK(s.skin == "skins/everything.skin");
        CHECK(s.mesh == "models/md5/everything.md5mesh");
        CHECK(s.anim == "models/md5/everything_af.md5anim");
        REQUIRE(s.friction.has_value());
        CHECK(s.friction->linear == 0.0099999998);
        CHECK(s.friction->angular == 0.02);
        CHECK(s.friction->contact == 0.8000000119);
        CHECK(s.friction->constraint == 0.4);
        CHECK(s.suspendSpeed == std::array<double, 4>{21, 31, 41.5, 61});
        CHECK(s.noMoveTime == 1.5);
        CHECK(s.noMoveTranslation == 11.0);
        CHECK(s.noMoveRotation == 12.0);
        CHECK(s.minMoveTime == 2.0);
        CHECK(s.maxMoveTime == 15.0);
        CHECK(s.totalMass == 250.0);
        REQUIRE(s.contents.has_value());
        CHECK(s.contents->names == std::vector<std::string>{"corpse", "body"});
        REQUIRE(s.clipMask.has_value());
        CHECK(s.clipMask->names == std::vector<std::string>{"solid", "corpse", "playerclip"});
        CHECK(s.selfCollision == false);
        // Settings clipMask is not given CONTENTS_MOVEABLECLIP (§1.3, §8 item 13).
        CHECK(contentsBits(*s.clipMask) == (kContentsSolid | kContentsCorpse | kContentsPlayerClip));
        CHECK(contentsBits(*s.contents) == (kContentsCorpse | kContentsBody));
    }

    SECTION("the first body writes every body key (§1.4)") {
        const AfBody& b = d.bodies[0];
        CHECK(b.name == "pelvis");
        CHECK(b.location.line == 22);
        CHECK(b.location.column == 2);
        CHECK(b.joint == "origin");
        CHECK(b.mod == "orientation");
        REQUIRE(b.model.has_value());
        CHECK(b.model->kind == ShapeKind::Box);
        CHECK(b.model->v1 == lit(-6, -8, -4));
        CHECK(b.model->v2 == lit(6, 8, 4.5));
        CHECK(b.origin == lit(0, 0, 44));
        CHECK(b.angles == lit(0, 90, 0));
        CHECK(b.density == 0.2);
        CHECK(b.inertiaScale == std::array<double, 9>{1, 0, 0, 0, 2, 0, 0, 0, -3.5});
        REQUIRE(b.friction.has_value());
        CHECK(b.friction->linear == 0.01);
        CHECK(b.friction->angular == 0.01);
        CHECK(b.friction->contact == 0.8);
        CHECK(b.contents->names == std::vector<std::string>{"corpse"});
        CHECK(b.clipMask->names == std::vector<std::string>{"solid", "corpse", "monsterclip"});
        CHECK(contentsBits(*b.clipMask) == (kContentsSolid | kContentsCorpse | kContentsMonsterClip));
        CHECK(b.selfCollision == true);
        CHECK(b.containedJoints == "*origin -*Spine");
        CHECK(b.frictionDirection == lit(1, 0, 0));
        CHECK(b.contactMotorDirection == lit(0, 1, 0, true));
    }

    SECTION("bodies keep only the keys they wrote") {
        const AfBody& b = d.bodies[3];
        CHECK(b.name == "arm");
        CHECK(b.joint == "Arm");
        CHECK_FALSE(b.mod.has_value());
        CHECK_FALSE(b.angles.has_value());
        CHECK_FALSE(b.density.has_value());
        CHECK_FALSE(b.inertiaScale.has_value());
        CHECK_FALSE(b.friction.has_value());
        CHECK_FALSE(b.contents.has_value());
        CHECK_FALSE(b.clipMask.has_value());
        CHECK_FALSE(b.selfCollision.has_value());
        CHECK_FALSE(b.containedJoints.has_value());
        CHECK_FALSE(b.frictionDirection.has_value());
        CHECK_FALSE(b.contactMotorDirection.has_value());
    }

    SECTION("the six shapes (§1.5)") {
        CHECK(d.bodies[1].model->kind == ShapeKind::Octahedron);
        CHECK(d.bodies[1].model->v1 == jointVec("Spine"));
        CHECK(d.bodies[1].model->v2 == jointVec("Neck", true));
        CHECK(d.bodies[2].model->kind == ShapeKind::Dodecahedron);
        CHECK(d.bodies[2].model->v1 == lit(-4, -4, -4));
        CHECK(d.bodies[3].model->kind == ShapeKind::Bone);
        CHECK(d.bodies[3].model->v1 == jointVec("Arm"));
        CHECK(d.bodies[3].model->v2 == jointVec("Hand"));
        CHECK(d.bodies[3].model->width == 6.5);
        CHECK(d.bodies[4].model->kind == ShapeKind::Cylinder);
        CHECK(d.bodies[4].model->numSides == 7);
        CHECK(d.bodies[4].model->v2 == lit(3, 3, 10));
        CHECK(d.bodies[5].model->kind == ShapeKind::Cone);
        CHECK(d.bodies[5].model->numSides == 4);
    }

    SECTION("vector forms (§1.2)") {
        CHECK(d.bodies[1].origin == twoJoints(AfVector::Form::BoneCenter, "Spine", "Neck"));
        CHECK(d.bodies[2].origin == twoJoints(AfVector::Form::BoneDir, "Neck", "Head", true));
        CHECK(d.bodies[3].origin == twoJoints(AfVector::Form::BoneCenter, "Arm", "Hand")); // bare joint names
    }

    SECTION("mod values are kept as written") {
        CHECK(d.bodies[1].mod == "position");
        CHECK(d.bodies[2].mod == "both");
    }

    SECTION("fixed") {
        const AfConstraint& c = d.constraints[0];
        CHECK(c.type == ConstraintType::Fixed);
        CHECK(c.name == "f");
        CHECK(c.body1 == "pelvis");
        CHECK(c.body2 == "chest");
        CHECK(std::holds_alternative<std::monostate>(c.limit));
        CHECK_FALSE(c.friction.has_value());
    }

    SECTION("ballAndSocketJoint: cone limit with a shaft, pyramid limit with a shaft") {
        const AfConstraint& c = d.constraints[1];
        CHECK(c.type == ConstraintType::BallAndSocket);
        CHECK(c.name == "bs");
        CHECK(c.body1 == "head");
        CHECK(c.body2 == "chest");
        CHECK(c.anchor == jointVec("Neck"));
        CHECK(c.friction == 0.3);
        const auto* cone = std::get_if<ConeLimit>(&c.limit);
        REQUIRE(cone != nullptr);
        CHECK(cone->axis == lit(0, 0, 1));
        CHECK(cone->angleDeg == 60.0);
        CHECK(cone->shaft == lit(0, 0, 1));

        const AfConstraint& c2 = d.constraints[2];
        CHECK(c2.type == ConstraintType::BallAndSocket);
        CHECK_FALSE(c2.body1.has_value());
        CHECK_FALSE(c2.body2.has_value());
        CHECK(c2.anchor == lit(1, 2, 3));
        const auto* pyr = std::get_if<PyramidLimit>(&c2.limit);
        REQUIRE(pyr != nullptr);
        CHECK(pyr->axis == lit(0, 0, -1));
        CHECK(pyr->angle1Deg == 30.0);
        CHECK(pyr->angle2Deg == 40.0);
        CHECK(pyr->rollDeg == 50.0);
        CHECK(pyr->shaft == lit(0, 1, 0, true));
    }

    SECTION("universalJoint: shafts; cone and pyramid limits without a shaft") {
        const AfConstraint& c = d.constraints[3];
        CHECK(c.type == ConstraintType::Universal);
        CHECK(c.body1 == "arm");
        CHECK(c.body2 == "chest");
        CHECK(c.anchor == jointVec("Arm"));
        REQUIRE(c.shafts.has_value());
        CHECK((*c.shafts)[0] == lit(0, 0, 1));
        CHECK((*c.shafts)[1] == lit(0, 0, -1));
        CHECK(c.friction == 0.4);
        const auto* cone = std::get_if<ConeLimit>(&c.limit);
        REQUIRE(cone != nullptr);
        CHECK(cone->axis == lit(0, 0, 1));
        CHECK(cone->angleDeg == 90.0);
        CHECK_FALSE(cone->shaft.has_value());

        const AfConstraint& c2 = d.constraints[4];
        CHECK((*c2.shafts)[1] == lit(0, 1, 0, true));
        const auto* pyr = std::get_if<PyramidLimit>(&c2.limit);
        REQUIRE(pyr != nullptr);
        CHECK(pyr->axis == lit(0.4, -0.2, -0.9));
        CHECK(pyr->angle1Deg == 75.0);
        CHECK(pyr->angle2Deg == 30.0);
        CHECK(pyr->rollDeg == 61.0);
        CHECK_FALSE(pyr->shaft.has_value());
    }

    SECTION("hinge with limit") {
        const AfConstraint& c = d.constraints[5];
        CHECK(c.type == ConstraintType::Hinge);
        CHECK(c.body1 == "foot");
        CHECK(c.body2 == "leg");
        CHECK(c.anchor == jointVec("Foot"));
        CHECK(c.axis == lit(0, -1, 0));
        CHECK(c.friction == 0.4);
        const auto* h = std::get_if<HingeLimit>(&c.limit);
        REQUIRE(h != nullptr);
        CHECK(h->orientationDeg == 130.0);
        CHECK(h->widthDeg == 70.0);
        CHECK(h->angleDeg == 90.0);
    }

    SECTION("slider") {
        const AfConstraint& c = d.constraints[6];
        CHECK(c.type == ConstraintType::Slider);
        CHECK(c.body1 == "arm");
        CHECK(c.body2 == "world");
        CHECK(c.axis == twoJoints(AfVector::Form::BoneDir, "Arm", "Hand"));
        CHECK(c.friction == 0.5);
        CHECK_FALSE(c.anchor.has_value());
    }

    SECTION("spring: every key") {
        const AfConstraint& c = d.constraints[7];
        CHECK(c.type == ConstraintType::Spring);
        CHECK(c.body1 == "head");
        CHECK(c.body2 == "pelvis");
        CHECK(c.anchor == jointVec("Head")); // anchor1
        CHECK(c.anchor2 == lit(0, 0, 10));
        CHECK(c.friction == 0.5);
        CHECK(c.stretch == 100.0);
        CHECK(c.compress == 200.0);
        CHECK(c.damping == 0.5);
        CHECK(c.restLength == 10.0);
        CHECK(c.minLength == 5.0);
        CHECK(c.maxLength == 20.0);
    }

    SECTION("block order is preserved") {
        REQUIRE(d.order.size() == 1 + 6 + 8);
        CHECK(d.order[0] == AfBlockRef{AfBlockRef::Kind::Settings, 0});
        for (std::size_t i = 0; i < 6; ++i) CHECK(d.order[1 + i] == AfBlockRef{AfBlockRef::Kind::Body, i});
        for (std::size_t i = 0; i < 8; ++i) CHECK(d.order[7 + i] == AfBlockRef{AfBlockRef::Kind::Constraint, i});
    }

    SECTION("defaultBody1: the first body parsed before the constraint") { CHECK(d.defaultBody1(2) == "pelvis"); }
}

TEST_CASE("af: the illustrative example of docs/format.md §1.8", "[af]") {
    const std::string text = R"AF(articulatedFigure example_ragdoll {
	settings {
		model "example_model"
		skin ""
		friction 0.01, 0.01, 0.8, 0.5          // 4th value has no effect (§1.7)
		suspendSpeed 20, 30, 40, 60
		noMoveTime 1
		noMoveTranslation 10
		noMoveRotation 10
		minMoveTime -1
		maxMoveTime -1
		totalMass -1
		contents corpse
		clipMask solid, corpse
		selfCollision 1
	}
	body "pelvis" {
		joint "origin"                          // base body; drives the first child of joint "origin"
		mod orientation
		model box( ( -6, -8, -4 ), ( 6, 8, 4 ) )
		origin joint( "Hips" )
		angles ( 0, 0, 0 )
		density 0.2
		friction 0.01, 0.01, 0.8
		contents corpse
		clipMask solid, corpse
		selfCollision 1
		containedJoints "*origin -*Spine -*LeftUpLeg"
	}
	body "lthigh" {
		joint "LeftUpLeg"
		mod orientation
		model bone( joint( "LeftUpLeg" ), joint( "LeftLeg" ), 6 )
		origin bonecenter( "LeftUpLeg", "LeftLeg" )
		density 0.2
		containedJoints "*LeftUpLeg"
	}
	universalJoint "pelvis_lthigh" {
		body1 "lthigh"
		body2 "pelvis"
		anchor joint( "LeftUpLeg" )
		shafts ( 0, 0, -1 ), ( 0, 0, 1 )
		friction 0.5
		coneLimit ( 0, 0, -1 ), 90              // shaft 1 stays within 45° of -Z (fixed in pelvis)
	}
}
)AF";
    Diagnostics w;
    const AfDecl d = parseOne(text, &w);
    CHECK(w.empty());
    CHECK(d.name == "example_ragdoll");
    CHECK(d.settings[0].skin == "");
    CHECK(d.settings[0].minMoveTime == -1.0);
    CHECK(d.settings[0].totalMass == -1.0);
    REQUIRE(d.bodies.size() == 2);
    CHECK(d.bodies[0].origin == jointVec("Hips"));
    CHECK(d.bodies[1].model->kind == ShapeKind::Bone);
    CHECK(d.bodies[1].model->width == 6.0);
    REQUIRE(d.constraints.size() == 1);
    const auto* cone = std::get_if<ConeLimit>(&d.constraints[0].limit);
    REQUIRE(cone != nullptr);
    CHECK(cone->axis == lit(0, 0, -1));
    CHECK(cone->angleDeg == 90.0);
    // The figure's settings equal the built-in defaults, apart from the model name.
    AfSettingsValues expected;
    expected.model = "example_model";
    CHECK(d.finalSettings() == expected);
}

// -------------------------------------------------------------------------------------------------------------
// Settings (§1.3) and parse-order defaults (§1.8, §8 item 3)
// -------------------------------------------------------------------------------------------------------------

TEST_CASE("af: settings defaults are the engine's (§1.3)", "[af][settings]") {
    const AfSettingsValues v;
    CHECK(v.model == "");
    CHECK(v.skin == "");
    CHECK(v.friction.linear == 0.01);
    CHECK(v.friction.angular == 0.01);
    CHECK(v.friction.contact == 0.8);
    CHECK(v.constraintFriction == 0.5);
    CHECK(v.suspendSpeed == std::array<double, 4>{20, 30, 40, 60});
    CHECK(v.noMoveTime == 1.0);
    CHECK(v.noMoveTranslation == 10.0);
    CHECK(v.noMoveRotation == 10.0);
    CHECK(v.minMoveTime == -1.0);
    CHECK(v.maxMoveTime == -1.0);
    CHECK(v.totalMass == -1.0);
    CHECK(contentsBits(v.contents) == kContentsCorpse);
    CHECK(contentsBits(v.clipMask) == (kContentsSolid | kContentsCorpse));
    CHECK(v.selfCollision == true);

    // A figure without settings has exactly these values.
    const AfDecl d = parseOne(fig("body \"b\" { joint \"origin\" }"));
    CHECK(d.settings.empty());
    CHECK(d.finalSettings() == AfSettingsValues{});
    CHECK(d.settingsForBody(0) == AfSettingsValues{});
}

TEST_CASE("af: settings friction takes 3 or 4 values", "[af][settings]") {
    SECTION("three values") {
        const AfDecl d = parseOne(fig("settings { friction 0.1, 0.2, 0.3 }"));
        REQUIRE(d.settings[0].friction.has_value());
        CHECK(d.settings[0].friction->linear == 0.1);
        CHECK(d.settings[0].friction->angular == 0.2);
        CHECK(d.settings[0].friction->contact == 0.3);
        CHECK_FALSE(d.settings[0].friction->constraint.has_value());
        CHECK(d.finalSettings().constraintFriction == 0.5);
    }
    SECTION("four values") {
        const AfDecl d = parseOne(fig("settings { friction 0.1, 0.2, 0.3, 0.4 }"));
        CHECK(d.settings[0].friction->constraint == 0.4);
        CHECK(d.finalSettings().friction == BodyFriction{0.1, 0.2, 0.3});
        CHECK(d.finalSettings().constraintFriction == 0.4);
    }
    SECTION("negative values") {
        const AfDecl d = parseOne(fig("settings { friction -0.1, - 0.2, 0.3, -0.4 }"));
        CHECK(d.settings[0].friction->linear == -0.1);
        CHECK(d.settings[0].friction->angular == -0.2);
        CHECK(d.settings[0].friction->constraint == -0.4);
    }
}

TEST_CASE("af: settings suspendSpeed and scalar keys", "[af][settings]") {
    const AfDecl d = parseOne(fig("settings {\n suspendSpeed 1, 2.5, -3, 4e1\n noMoveTime 0.25\n"
                                  " noMoveTranslation 3\n noMoveRotation 4\n minMoveTime -1\n maxMoveTime 0\n"
                                  " totalMass 99.5\n}"));
    const AfSettings& s = d.settings[0];
    CHECK(s.suspendSpeed == std::array<double, 4>{1, 2.5, -3, 40});
    CHECK(s.noMoveTime == 0.25);
    CHECK(s.noMoveTranslation == 3.0);
    CHECK(s.noMoveRotation == 4.0);
    CHECK(s.minMoveTime == -1.0);
    CHECK(s.maxMoveTime == 0.0);
    CHECK(s.totalMass == 99.5);
    CHECK_FALSE(s.model.has_value());
    CHECK_FALSE(s.friction.has_value());
    CHECK_FALSE(s.contents.has_value());
    CHECK_FALSE(s.selfCollision.has_value());
    const AfSettingsValues v = d.finalSettings();
    CHECK(v.suspendSpeed == std::array<double, 4>{1, 2.5, -3, 40});
    CHECK(v.totalMass == 99.5);
    CHECK(v.friction == BodyFriction{0.01, 0.01, 0.8}); // unwritten keys keep the defaults
}

TEST_CASE("af: settings selfCollision is a number", "[af][settings]") {
    CHECK(parseOne(fig("settings { selfCollision 1 }")).settings[0].selfCollision == true);
    CHECK(parseOne(fig("settings { selfCollision 0 }")).settings[0].selfCollision == false);
    CHECK(parseOne(fig("settings { selfCollision 1.0 }")).settings[0].selfCollision == true);
    CHECK(parseOne(fig("settings { selfCollision 0.5 }")).settings[0].selfCollision == false);
    requireErrorAt(fig("settings { selfCollision @true }"));
    requireErrorAt(fig("body \"b\" { joint \"origin\" selfCollision @false }"));
}

TEST_CASE("af: settings are defaults only for bodies parsed after them (§1.8)", "[af][settings]") {
    const AfDecl d = parseOne(fig(R"(
body "early" { joint "origin" }
settings { friction 0.1, 0.2, 0.3 contents body clipMask solid selfCollision 0 totalMass 100 model "m" }
body "middle" { joint "a" }
settings { friction 0.4, 0.5, 0.6, 0.7 }
body "late" { joint "b" }
settings { totalMass 300 }
)"));
    REQUIRE(d.bodies.size() == 3);
    REQUIRE(d.settings.size() == 3);

    CHECK(d.settingsForBody(0) == AfSettingsValues{});

    const AfSettingsValues mid = d.settingsForBody(1);
    CHECK(mid.friction == BodyFriction{0.1, 0.2, 0.3});
    CHECK(mid.constraintFriction == 0.5);
    CHECK(mid.contents.names == std::vector<std::string>{"body"});
    CHECK(mid.clipMask.names == std::vector<std::string>{"solid"});
    CHECK(mid.selfCollision == false);
    CHECK(mid.totalMass == 100.0);
    CHECK(mid.model == "m");

    const AfSettingsValues late = d.settingsForBody(2);
    CHECK(late.friction == BodyFriction{0.4, 0.5, 0.6});
    CHECK(late.constraintFriction == 0.7);
    CHECK(late.contents.names == std::vector<std::string>{"body"}); // a later block only overrides what it writes
    CHECK(late.selfCollision == false);
    CHECK(late.totalMass == 100.0);

    const AfSettingsValues fin = d.finalSettings();
    CHECK(fin.totalMass == 300.0);
    CHECK(fin.friction == BodyFriction{0.4, 0.5, 0.6});
    CHECK(fin.model == "m");
}

// -------------------------------------------------------------------------------------------------------------
// Bodies (§1.4)
// -------------------------------------------------------------------------------------------------------------

TEST_CASE("af: a minimal body holds only its joint", "[af][body]") {
    const AfDecl d = parseOne(fig("body \"b\" { joint \"origin\" }"));
    REQUIRE(d.bodies.size() == 1);
    const AfBody& b = d.bodies[0];
    CHECK(b.name == "b");
    CHECK(b.joint == "origin");
    CHECK_FALSE(b.mod.has_value());
    CHECK_FALSE(b.model.has_value());
    CHECK_FALSE(b.origin.has_value());
    CHECK_FALSE(b.angles.has_value());
    CHECK_FALSE(b.density.has_value());
}

TEST_CASE("af: body mod", "[af][body]") {
    SECTION("the three known values, case-insensitively, without warnings") {
        for (const char* m : {"orientation", "position", "both", "Position", "BOTH", "Orientation"}) {
            INFO("mod " << m);
            Diagnostics w;
            const AfDecl d = parseOne(fig(std::string("body \"b\" { joint \"x\" mod ") + m + " }"), &w);
            CHECK(d.bodies[0].mod == m);
            CHECK(w.empty());
        }
    }
    SECTION("'mod' takes any token: a quoted known value is known (no warning)") {
        Diagnostics w;
        const AfDecl d = parseOne(fig("body \"b\" { joint \"x\" mod \"position\" }"), &w);
        CHECK(d.bodies[0].mod == "position");
        INFO(w.str());
        CHECK(w.warningCount() == 0);
    }
    SECTION("an unknown value is a located warning; the decl keeps it as written") {
        const std::string text = fig("body \"b\" { joint \"x\" mod rotation }");
        Diagnostics w;
        const AfDecl d = parseOne(text, &w);
        CHECK(d.bodies[0].mod == "rotation");
        REQUIRE(w.warningCount() == 1);
        const auto [line, col] = posOf(text, "rotation");
        CHECK(w.items()[0].where.line == line);
        CHECK(w.items()[0].where.column == col);
    }
}

TEST_CASE("af: vector forms with and without '-' (§1.2)", "[af][vector]") {
    struct Case {
        const char* text;
        AfVector expected;
    };
    const Case cases[] = {
        {"( 1, -2.5, 3 )", lit(1, -2.5, 3)},
        {"-( 1, 2, 3 )", lit(1, 2, 3, true)},
        {"- ( 0, 0, -1 )", lit(0, 0, -1, true)},
        {"joint( \"Hips\" )", jointVec("Hips")},
        {"-joint( \"Hips\" )", jointVec("Hips", true)},
        {"joint( Hips )", jointVec("Hips")},
        {"bonecenter( \"A\", \"B\" )", twoJoints(AfVector::Form::BoneCenter, "A", "B")},
        {"-bonecenter( A, \"B\" )", twoJoints(AfVector::Form::BoneCenter, "A", "B", true)},
        {"bonedir( \"A\", \"B\" )", twoJoints(AfVector::Form::BoneDir, "A", "B")},
        {"-bonedir( \"A\", B )", twoJoints(AfVector::Form::BoneDir, "A", "B", true)},
        {"joint(\"with space\")", jointVec("with space")},
    };
    for (const Case& c : cases) {
        INFO("vector: " << c.text);
        const std::string v = c.text;
        const AfDecl d = parseOne(fig("body \"b\" { joint \"x\" origin " + v + " frictionDirection " + v +
                                      " contactMotorDirection " + v + " model box( " + v + ", " + v + " ) }\n" +
                                      "hinge \"h\" { anchor " + v + " axis " + v + " }\n" + "spring \"s\" { anchor1 " +
                                      v + " anchor2 " + v + " }\n" + "universalJoint \"u\" { shafts " + v + ", " + v +
                                      " coneLimit " + v + ", 5 }"));
        const AfBody& b = d.bodies[0];
        CHECK(b.origin == c.expected);
        CHECK(b.frictionDirection == c.expected);
        CHECK(b.contactMotorDirection == c.expected);
        CHECK(b.model->v1 == c.expected);
        CHECK(b.model->v2 == c.expected);
        CHECK(d.constraints[0].anchor == c.expected);
        CHECK(d.constraints[0].axis == c.expected);
        CHECK(d.constraints[1].anchor == c.expected);
        CHECK(d.constraints[1].anchor2 == c.expected);
        CHECK((*d.constraints[2].shafts)[0] == c.expected);
        CHECK((*d.constraints[2].shafts)[1] == c.expected);
        CHECK(std::get<ConeLimit>(d.constraints[2].limit).axis == c.expected);
    }
}

TEST_CASE("af: vector errors", "[af][vector][error]") {
    // The keywords are case-sensitive (§1.2, §8 item 1).
    requireErrorAt(fig("body \"b\" { joint \"x\" origin @Joint( \"a\" ) }"));
    requireErrorAt(fig("body \"b\" { joint \"x\" origin @BoneCenter( \"a\", \"b\" ) }"));
    requireErrorAt(fig("body \"b\" { joint \"x\" origin -@BONEDIR( \"a\", \"b\" ) }"));
    // Any other leading token.
    requireErrorAt(fig("body \"b\" { joint \"x\" origin @vec( 1, 2, 3 ) }"));
    requireErrorAt(fig("body \"b\" { joint \"x\" origin @5 }"));
    // The commas in ( x, y, z ) are required.
    requireErrorAt(fig("body \"b\" { joint \"x\" origin ( 1 @2, 3 ) }"));
    requireErrorAt(fig("body \"b\" { joint \"x\" origin ( 1, 2, 3@, 4 ) }"));
    requireErrorAt(fig("body \"b\" { joint \"x\" origin bonecenter( \"a\" @\"b\" ) }"));
    requireErrorAt(fig("body \"b\" { joint \"x\" origin joint @\"a\" }"));
    // A non-number inside a literal vector.
    requireErrorAt(fig("body \"b\" { joint \"x\" origin ( 1, @y, 3 ) }"));
}

TEST_CASE("af: angles", "[af][body]") {
    SECTION("a literal (pitch, yaw, roll) without warnings") {
        Diagnostics w;
        const AfDecl d = parseOne(fig("body \"b\" { joint \"x\" angles ( 90, -45, 0.5 ) }"), &w);
        CHECK(d.bodies[0].angles == lit(90, -45, 0.5));
        CHECK(w.empty());
    }
    SECTION("a leading '-' is kept but warned about (the engine ignores it)") {
        const std::string text = fig("body \"b\" { joint \"x\" angles -( 1, 2, 3 ) }");
        Diagnostics w;
        const AfDecl d = parseOne(text, &w);
        CHECK(d.bodies[0].angles == lit(1, 2, 3, true));
        REQUIRE(w.warningCount() == 1);
        CHECK(w.items()[0].where.line == posOf(text, "-(").first);
        CHECK(w.items()[0].where.column == posOf(text, "-(").second);
    }
    SECTION("a joint form is kept but warned about (the engine gives 0)") {
        Diagnostics w;
        const AfDecl d = parseOne(fig("body \"b\" { joint \"x\" angles joint( \"y\" ) }"), &w);
        CHECK(d.bodies[0].angles == jointVec("y"));
        CHECK(w.warningCount() == 1);
    }
}

TEST_CASE("af: the six shapes and their parameters (§1.5)", "[af][shape]") {
    struct Case {
        const char* text;
        ShapeKind kind;
    };
    const Case cases[] = {
        {"box( ( -1, -2, -3 ), ( 1, 2, 3 ) )", ShapeKind::Box},
        {"octahedron( ( -1, -2, -3 ), ( 1, 2, 3 ) )", ShapeKind::Octahedron},
        {"dodecahedron( ( -1, -2, -3 ), ( 1, 2, 3 ) )", ShapeKind::Dodecahedron},
    };
    for (const Case& c : cases) {
        INFO(c.text);
        const AfShape s =
            *parseOne(fig(std::string("body \"b\" { joint \"x\" model ") + c.text + " }")).bodies[0].model;
        CHECK(s.kind == c.kind);
        CHECK(s.v1 == lit(-1, -2, -3));
        CHECK(s.v2 == lit(1, 2, 3));
    }
    SECTION("cylinder and cone take an integer side count, as written (clamping is later)") {
        const AfDecl d = parseOne(fig("body \"a\" { joint \"x\" model cylinder( ( -1, -1, -1 ), ( 1, 1, 1 ), 12 ) }\n"
                                      "body \"b\" { joint \"y\" model cone( ( -1, -1, -1 ), ( 1, 1, 1 ), 20 ) }\n"
                                      "body \"c\" { joint \"z\" model cylinder( ( -1, -1, -1 ), ( 1, 1, 1 ), 3 ) }"));
        CHECK(d.bodies[0].model->kind == ShapeKind::Cylinder);
        CHECK(d.bodies[0].model->numSides == 12);
        CHECK(d.bodies[1].model->kind == ShapeKind::Cone);
        CHECK(d.bodies[1].model->numSides == 20);
        CHECK(d.bodies[2].model->numSides == 3);
    }
    SECTION("bone takes two points and a float width") {
        const AfShape s =
            *parseOne(fig("body \"b\" { joint \"x\" model bone( joint( \"a\" ), bonecenter( \"b\", \"c\" ), "
                          "2.75 ) }"))
                 .bodies[0]
                 .model;
        CHECK(s.kind == ShapeKind::Bone);
        CHECK(s.v1 == jointVec("a"));
        CHECK(s.v2 == twoJoints(AfVector::Form::BoneCenter, "b", "c"));
        CHECK(s.width == 2.75);
    }
    SECTION("shape errors") {
        requireErrorAt(fig("body \"b\" { joint \"x\" model @custom( ( 0, 0, 0 ), ( 1, 1, 1 ) ) }"));
        requireErrorAt(fig("body \"b\" { joint \"x\" model @sphere( ( 0, 0, 0 ), ( 1, 1, 1 ) ) }"));
        requireErrorAt(fig("body \"b\" { joint \"x\" model @\"box\"( ( 0, 0, 0 ), ( 1, 1, 1 ) ) }"));
        requireErrorAt(fig("body \"b\" { joint \"x\" model box( ( 0, 0, 0 ) @) }"));
        requireErrorAt(fig("body \"b\" { joint \"x\" model box( ( 0, 0, 0 ), ( 1, 1, 1 ) @, 3 ) }"));
        // numSides is an integer (ParseInt logs an error for a float).
        requireErrorAt(fig("body \"b\" { joint \"x\" model cylinder( ( -1, -1, -1 ), ( 1, 1, 1 ), @5.5 ) }"));
        requireErrorAt(fig("body \"b\" { joint \"x\" model cone( ( -1, -1, -1 ), ( 1, 1, 1 ) @) }"));
        requireErrorAt(fig("body \"b\" { joint \"x\" model bone( joint( \"a\" ), joint( \"b\" ) @) }"));
        requireErrorAt(fig("body \"b\" { joint \"x\" model bone( joint( \"a\" ), joint( \"b\" ), @wide ) }"));
    }
}

TEST_CASE("af: inertiaScale is nine numbers without commas", "[af][body]") {
    const AfDecl d = parseOne(fig("body \"b\" { joint \"x\" inertiaScale ( 1 2 3\n 4 -5 6\n 7 8 0.5 ) }"));
    CHECK(d.bodies[0].inertiaScale == std::array<double, 9>{1, 2, 3, 4, -5, 6, 7, 8, 0.5});

    requireErrorAt(fig("body \"b\" { joint \"x\" inertiaScale ( 1@, 0, 0, 0, 1, 0, 0, 0, 1 ) }"));
    requireErrorAt(fig("body \"b\" { joint \"x\" inertiaScale ( 1 0 0 0 1 0 0 0 @) }"));
    requireErrorAt(fig("body \"b\" { joint \"x\" inertiaScale ( 1 0 0 0 1 0 0 0 1 @7 ) }"));
    requireErrorAt(fig("body \"b\" { joint \"x\" inertiaScale @1 0 0 0 1 0 0 0 1 }"));
}

TEST_CASE("af: body friction takes exactly three values", "[af][body]") {
    const AfDecl d = parseOne(fig("body \"b\" { joint \"x\" friction 0.1, -0.2, 0.3 }"));
    CHECK(d.bodies[0].friction == BodyFriction{0.1, -0.2, 0.3});
    requireErrorAt(fig("body \"b\" { joint \"x\" friction 0.1, 0.2, 0.3@, 0.4 }"));
    requireErrorAt(fig("body \"b\" { joint \"x\" friction 0.1 @0.2, 0.3 }"));
    requireErrorAt(fig("body \"b\" { joint \"x\" friction 0.1, 0.2 @0.3 }"));
}

TEST_CASE("af: contents lists (§1.6)", "[af][contents]") {
    SECTION("recognised names and their bits") {
        CHECK(contentsBitsOfName("none") == 0u);
        CHECK(contentsBitsOfName("solid") == 1u);
        CHECK(contentsBitsOfName("playerclip") == 8u);
        CHECK(contentsBitsOfName("monsterclip") == 16u);
        CHECK(contentsBitsOfName("body") == 256u);
        CHECK(contentsBitsOfName("corpse") == 1024u);
        CHECK(contentsBitsOfName("CORPSE") == 1024u);
        CHECK(contentsBitsOfName("PlayerClip") == 8u);
        CHECK_FALSE(contentsBitsOfName("trigger").has_value());
        CHECK_FALSE(contentsBitsOfName("moveableclip").has_value()); // not nameable in .af files
        CHECK(kContentsMoveableClip == (1u << 5));
    }
    SECTION("a list is OR-ed; none resets") {
        const AfDecl d = parseOne(fig("body \"b\" { joint \"x\" contents solid, Body, CORPSE "
                                      "clipMask solid, corpse, none, monsterclip }"));
        const AfBody& b = d.bodies[0];
        CHECK(b.contents->names == std::vector<std::string>{"solid", "Body", "CORPSE"}); // as written
        CHECK(contentsBits(*b.contents) == (1u | 256u | 1024u));
        CHECK(contentsBits(*b.clipMask) == 16u);
        CHECK(contentsBits(ContentsList{{"solid", "body", "none"}}) == 0u);
        CHECK(contentsBits(ContentsList{{"none"}}) == 0u);
        CHECK(contentsBits(ContentsList{}) == 0u);
    }
    SECTION("the first unknown name ends the list: a warning, the names kept as written") {
        const std::string text = fig("body \"b\" { joint \"x\" contents corpse, trigger, solid }");
        Diagnostics w;
        const AfDecl d = parseOne(text, &w);
        const ContentsList& c = *d.bodies[0].contents;
        CHECK(c.names == std::vector<std::string>{"corpse", "trigger", "solid"});
        std::optional<std::size_t> firstUnknown;
        CHECK(contentsBits(c, &firstUnknown) == kContentsCorpse); // solid is dropped too
        CHECK(firstUnknown == std::size_t{1});
        REQUIRE(w.warningCount() >= 1);
        CHECK(w.errorCount() == 0);
        CHECK(countWarningsContaining(w, "trigger") >= 1);
        CHECK(w.items()[0].severity == Severity::Warning);
        CHECK(w.items()[0].where.line == posOf(text, "trigger").first);
        CHECK(w.items()[0].where.column == posOf(text, "trigger").second);

        std::optional<std::size_t> none = std::size_t{7};
        CHECK(contentsBits(ContentsList{{"solid", "corpse"}}, &none) == 1025u);
        CHECK_FALSE(none.has_value());
    }
    SECTION("an unknown name first gives 0") {
        Diagnostics w;
        const AfDecl d = parseOne(fig("settings { contents moveableclip, corpse }"), &w);
        CHECK(contentsBits(*d.settings[0].contents) == 0u);
        CHECK(w.warningCount() >= 1);
    }
    SECTION("errors") {
        requireErrorAt(fig("body \"b\" { joint \"x\" contents solid, @} "));
        requireErrorAt(fig("body \"b\" { joint \"x\" contents @, solid }"));
    }
}

TEST_CASE("af: containedJoints and joint are double-quoted strings", "[af][body]") {
    const AfDecl d = parseOne(fig("body \"b\" { joint \"Spine 2\" containedJoints \"*Spine -*Neck Hips\" }"));
    CHECK(d.bodies[0].joint == "Spine 2");
    CHECK(d.bodies[0].containedJoints == "*Spine -*Neck Hips");
    requireErrorAt(fig("body \"b\" { joint \"x\" containedJoints @*Spine }"));
    requireErrorAt(fig("body \"b\" { joint \"x\" containedJoints @'*Spine' }"));
    requireErrorAt(fig("body \"b\" { joint @origin }"));
    requireErrorAt(fig("body \"b\" { joint @'origin' }"));
}

TEST_CASE("af: body density and numbers", "[af][body][number]") {
    SECTION("plain, exponent and suffixed numbers") {
        const AfDecl d = parseOne(fig("body \"a\" { joint \"x\" density 0.0199999996 }\n"
                                      "body \"b\" { joint \"y\" density 1e-5 }\n"
                                      "body \"c\" { joint \"z\" density 2.5f }\n"
                                      "body \"d\" { joint \"w\" density .5 }\n"
                                      "body \"e\" { joint \"v\" density -3 }"));
        CHECK(d.bodies[0].density == 0.0199999996);
        CHECK(d.bodies[1].density == 1e-5);
        CHECK(d.bodies[2].density == 2.5);
        CHECK(d.bodies[3].density == 0.5);
        CHECK(d.bodies[4].density == -3.0);
    }
    SECTION("a leading zero is octal, with a located warning") {
        const std::string text = fig("settings { totalMass 010 }");
        Diagnostics w;
        const AfDecl d = parseOne(text, &w);
        CHECK(d.settings[0].totalMass == 8.0);
        REQUIRE(w.warningCount() == 1);
        CHECK(w.items()[0].message.find("octal") != std::string::npos);
        CHECK(w.items()[0].where.line == posOf(text, "010").first);
        CHECK(w.items()[0].where.column == posOf(text, "010").second);
    }
    SECTION("number errors") {
        requireErrorAt(fig("settings { totalMass @09 }"));
        requireErrorAt(fig("settings { totalMass @08 }"));
        requireErrorAt(fig("settings { totalMass @abc }"));
        requireErrorAt(fig("settings { totalMass @1.#INF }"));
        requireErrorAt(fig("settings { totalMass @1e999 }"));
        requireErrorAt(fig("body \"b\" { joint \"x\" density @\"0.2\" }"));
        requireErrorAt(fig("body \"b\" { joint \"x\" density -@} "));
        requireErrorAt(fig("spring \"s\" { stretch @abc }"));
        requireErrorAt(fig("hinge \"h\" { friction @'0.5' }"));
    }
}

TEST_CASE("af: body errors", "[af][body][error]") {
    // Names must be double-quoted strings.
    requireErrorAt(fig("body @pelvis { joint \"origin\" }"));
    requireErrorAt(fig("body @'pelvis' { joint \"origin\" }"));
    // origin and world are reserved, case-insensitively; the offending token is the name.
    requireErrorAt(fig("body @\"origin\" { joint \"origin\" }"));
    requireErrorAt(fig("body @\"world\" { joint \"origin\" }"));
    requireErrorAt(fig("body @\"World\" { joint \"origin\" }"));
    requireErrorAt(fig("body @\"ORIGIN\" { joint \"origin\" }"));
    // Unknown keys; a missing '{'; end of file.
    requireErrorAt(fig("body \"b\" { joint \"x\" @mass 5 }"));
    requireErrorAt(fig("body \"b\" { joint \"x\" @limit 1, 2, 3 }"));
    requireErrorAt(fig("body \"b\" @joint \"x\" }"));
    requireErrorAt("articulatedFigure f { body \"b\" { joint \"x\"\n@");
    // The settings keys are not body keys and vice versa.
    requireErrorAt(fig("body \"b\" { joint \"x\" @totalMass 5 }"));
    requireErrorAt(fig("settings { @density 5 }"));
}

TEST_CASE("af: a missing joint is an error at the body", "[af][body][error]") {
    requireErrorAt(fig("@body \"b\" { mod orientation }"));
    requireErrorAt(fig("body \"a\" { joint \"origin\" }\n  @body \"b\" { }"));
}

TEST_CASE("af: settings errors", "[af][settings][error]") {
    requireErrorAt(fig("settings { @gravity 5 }"));
    requireErrorAt(fig("settings { friction 0.1 @0.2, 0.3 }"));
    requireErrorAt(fig("settings { friction 0.1, 0.2 @0.3 }"));
    requireErrorAt(fig("settings { friction 0.1, 0.2, 0.3, 0.4@, 0.5 }"));
    requireErrorAt(fig("settings { suspendSpeed 1, 2 @3, 4 }"));
    requireErrorAt(fig("settings { suspendSpeed 1, 2, 3 @}"));
    requireErrorAt(fig("settings { model @foo }"));
    requireErrorAt(fig("settings { model @'foo' }"));
    requireErrorAt(fig("settings { skin @'foo' }"));
    requireErrorAt(fig("settings @model \"x\" }"));
}

// -------------------------------------------------------------------------------------------------------------
// Constraints (§1.7)
// -------------------------------------------------------------------------------------------------------------

TEST_CASE("af: constraint defaults are left to the consumer / body1 defaults by parse order", "[af][constraint]") {
    const AfDecl d = parseOne(fig(R"(
fixed "before" { }
body "first" { joint "origin" }
body "second" { joint "a" }
hinge "after" { axis ( 0, 0, 1 ) }
ballAndSocketJoint "explicit" { body1 "second" }
)"));
    REQUIRE(d.constraints.size() == 3);
    CHECK_FALSE(d.constraints[0].body1.has_value());
    CHECK_FALSE(d.constraints[0].body2.has_value());
    CHECK(d.defaultBody1(0) == "world");
    CHECK(d.defaultBody1(1) == "first");
    CHECK(d.defaultBody1(2) == "first");
    CHECK(d.constraints[2].body1 == "second");
    CHECK_FALSE(d.constraints[1].anchor.has_value());
    CHECK_FALSE(d.constraints[1].friction.has_value());
    CHECK(std::holds_alternative<std::monostate>(d.constraints[1].limit));
}

TEST_CASE("af: constraint keys per type", "[af][constraint]") {
    SECTION("universalJoint: every key") {
        const AfConstraint c = parseOne(fig("universalJoint \"u\" { body1 \"a\" body2 \"b\" anchor ( 1, 2, 3 ) "
                                            "shafts joint( \"x\" ), -bonedir( \"x\", \"y\" ) friction 0.25 "
                                            "pyramidLimit ( 0, 0, 1 ), 10, 20, 30 }"))
                                   .constraints[0];
        CHECK(c.type == ConstraintType::Universal);
        CHECK(c.body1 == "a");
        CHECK(c.body2 == "b");
        CHECK(c.anchor == lit(1, 2, 3));
        CHECK((*c.shafts)[0] == jointVec("x"));
        CHECK((*c.shafts)[1] == twoJoints(AfVector::Form::BoneDir, "x", "y", true));
        CHECK(c.friction == 0.25);
        const auto& p = std::get<PyramidLimit>(c.limit);
        CHECK(p.angle1Deg == 10.0);
        CHECK(p.angle2Deg == 20.0);
        CHECK(p.rollDeg == 30.0);
        CHECK_FALSE(p.shaft.has_value());
    }
    SECTION("hinge: negative limit values") {
        const AfConstraint c = parseOne(fig("hinge \"h\" { axis ( 0, 1, 0 ) limit -10, 20.5, - 30 }")).constraints[0];
        const auto& h = std::get<HingeLimit>(c.limit);
        CHECK(h.orientationDeg == -10.0);
        CHECK(h.widthDeg == 20.5);
        CHECK(h.angleDeg == -30.0);
    }
    SECTION("slider: axis and friction only") {
        const AfConstraint c = parseOne(fig("slider \"s\" { axis ( 0, 0, 1 ) friction 0.1 }")).constraints[0];
        CHECK(c.type == ConstraintType::Slider);
        CHECK(c.axis == lit(0, 0, 1));
        CHECK(c.friction == 0.1);
    }
    SECTION("spring: keys may be omitted; the decl says which were written") {
        const AfConstraint c = parseOne(fig("spring \"s\" { anchor1 ( 1, 0, 0 ) stretch 5 }")).constraints[0];
        CHECK(c.anchor == lit(1, 0, 0));
        CHECK_FALSE(c.anchor2.has_value());
        CHECK(c.stretch == 5.0);
        CHECK_FALSE(c.compress.has_value());
        CHECK_FALSE(c.damping.has_value());
        CHECK_FALSE(c.restLength.has_value());
        CHECK_FALSE(c.minLength.has_value());
        CHECK_FALSE(c.maxLength.has_value());
    }
    SECTION("if several limits are given, the last one wins") {
        const AfDecl d = parseOne(
            fig("ballAndSocketJoint \"a\" { coneLimit ( 0, 0, 1 ), 30, ( 0, 0, 1 ) pyramidLimit ( 1, 0, 0 ), 1, 2, 3, "
                "( 0, 1, 0 ) }\n"
                "universalJoint \"b\" { pyramidLimit ( 1, 0, 0 ), 1, 2, 3 coneLimit ( 0, 0, -1 ), 45 }\n"
                "hinge \"c\" { limit 1, 2, 3 limit 4, 5, 6 }"));
        const auto& p = std::get<PyramidLimit>(d.constraints[0].limit);
        CHECK(p.axis == lit(1, 0, 0));
        CHECK(p.shaft == lit(0, 1, 0));
        const auto& c = std::get<ConeLimit>(d.constraints[1].limit);
        CHECK(c.axis == lit(0, 0, -1));
        CHECK(c.angleDeg == 45.0);
        const auto& h = std::get<HingeLimit>(d.constraints[2].limit);
        CHECK(h.orientationDeg == 4.0);
        CHECK(h.angleDeg == 6.0);
    }
    SECTION("body1 and body2 may name anything non-empty (resolution happens at load)") {
        const AfConstraint c = parseOne(fig("fixed \"f\" { body1 \"Typo\" body2 \"world\" }")).constraints[0];
        CHECK(c.body1 == "Typo");
        CHECK(c.body2 == "world");
    }
}

TEST_CASE("af: constraint errors", "[af][constraint][error]") {
    // Names must be double-quoted strings.
    requireErrorAt(fig("fixed @f1 { }"));
    requireErrorAt(fig("hinge @'h' { }"));
    requireErrorAt(fig("hinge \"h\" @axis ( 0, 0, 1 ) }"));
    // body1/body2: double-quoted and non-empty.
    requireErrorAt(fig("fixed \"f\" { body1 @\"\" }"));
    requireErrorAt(fig("hinge \"h\" { body1 \"a\" body2 @\"\" }"));
    requireErrorAt(fig("fixed \"f\" { body1 @pelvis }"));
    requireErrorAt(fig("fixed \"f\" { body2 @'pelvis' }"));
    // fixed has only body1 and body2.
    requireErrorAt(fig("fixed \"f\" { @friction 0.5 }"));
    requireErrorAt(fig("fixed \"f\" { @anchor ( 0, 0, 0 ) }"));
    // A spring uses anchor1/anchor2, not anchor.
    requireErrorAt(fig("spring \"s\" { @anchor ( 0, 0, 0 ) }"));
    requireErrorAt(fig("spring \"s\" { @axis ( 0, 0, 1 ) }"));
    // limit is accepted only inside hinge.
    for (const char* type : {"ballAndSocketJoint", "universalJoint", "slider", "spring", "fixed"}) {
        INFO(type);
        requireErrorAt(fig(std::string(type) + " \"c\" { @limit 1, 2, 3 }"));
    }
    // Keys that belong to other types.
    requireErrorAt(fig("slider \"s\" { @anchor ( 0, 0, 0 ) }"));
    requireErrorAt(fig("ballAndSocketJoint \"b\" { @shafts ( 0, 0, 1 ), ( 0, 0, -1 ) }"));
    requireErrorAt(fig("ballAndSocketJoint \"b\" { @axis ( 0, 0, 1 ) }"));
    requireErrorAt(fig("universalJoint \"u\" { @axis ( 0, 0, 1 ) }"));
    requireErrorAt(fig("hinge \"h\" { @coneLimit ( 0, 0, 1 ), 30 }"));
    requireErrorAt(fig("hinge \"h\" { @anchor1 ( 0, 0, 1 ) }"));
    requireErrorAt(fig("ballAndSocketJoint \"b\" { @stretch 5 }"));
    // No syntax for twist limits, motors, ...
    requireErrorAt(fig("hinge \"h\" { @limitRotation 1, 2, 3 }"));
    requireErrorAt(fig("hinge \"h\" { @motor 5 }"));
    // Universal cone/pyramid limits have no shaft; ball-and-socket limits require one.
    requireErrorAt(fig("universalJoint \"u\" { coneLimit ( 0, 0, 1 ), 90@, ( 0, 0, 1 ) }"));
    requireErrorAt(fig("universalJoint \"u\" { pyramidLimit ( 0, 0, 1 ), 1, 2, 3@, ( 0, 0, 1 ) }"));
    requireErrorAt(fig("ballAndSocketJoint \"b\" { coneLimit ( 0, 0, 1 ), 90 @}"));
    requireErrorAt(fig("ballAndSocketJoint \"b\" { pyramidLimit ( 0, 0, 1 ), 30, 40, @( 0, 0, 1 ) }"));
    // Missing commas.
    requireErrorAt(fig("universalJoint \"u\" { shafts ( 0, 0, 1 ) @( 0, 0, -1 ) }"));
    requireErrorAt(fig("hinge \"h\" { limit 1 @2, 3 }"));
    requireErrorAt(fig("ballAndSocketJoint \"b\" { coneLimit ( 0, 0, 1 ) @90, ( 0, 0, 1 ) }"));
}

// -------------------------------------------------------------------------------------------------------------
// Case sensitivity (§1.1, §8 item 1)
// -------------------------------------------------------------------------------------------------------------

TEST_CASE("af: block keywords and keys are case-insensitive", "[af][case]") {
    Diagnostics w;
    const AfDecl d = parseOne(fig(R"(
SETTINGS { TOTALMASS 5 SelfCollision 0 CONTENTS Corpse }
Body "b" { JOINT "origin" CONTAINEDJOINTS "*origin" Mod Both MODEL Box( ( 0, 0, 0 ), ( 1, 1, 1 ) ) ORIGIN ( 1, 2, 3 )
  InertiaScale ( 1 0 0 0 1 0 0 0 1 ) FRICTIONDIRECTION ( 1, 0, 0 ) contactmotordirection ( 0, 1, 0 ) }
BALLANDSOCKETJOINT "bs" { BODY1 "b" Anchor ( 0, 0, 0 ) CONELIMIT ( 0, 0, 1 ), 30, ( 0, 0, 1 ) }
universaljoint "u" { Shafts ( 0, 0, 1 ), ( 0, 0, -1 ) PyramidLimit ( 0, 0, 1 ), 1, 2, 3 }
HINGE "h" { AXIS ( 0, 0, 1 ) LIMIT 1, 2, 3 Friction 0.5 }
Slider "s" { BODY2 "b" }
SPRING "sp" { ANCHOR1 ( 0, 0, 0 ) Anchor2 ( 0, 0, 1 ) RESTLENGTH 3 MinLength 1 MAXLENGTH 9 STRETCH 1 Compress 2 DAMPING 3 }
FIXED "f" { }
)"),
                              &w);
    CHECK(w.empty());
    CHECK(d.settings[0].totalMass == 5.0);
    CHECK(d.settings[0].selfCollision == false);
    REQUIRE(d.bodies.size() == 1);
    CHECK(d.bodies[0].joint == "origin");
    CHECK(d.bodies[0].containedJoints == "*origin");
    CHECK(d.bodies[0].mod == "Both");
    CHECK(d.bodies[0].model->kind == ShapeKind::Box);
    CHECK(d.bodies[0].origin == lit(1, 2, 3));
    CHECK(d.bodies[0].inertiaScale.has_value());
    CHECK(d.bodies[0].frictionDirection == lit(1, 0, 0));
    CHECK(d.bodies[0].contactMotorDirection == lit(0, 1, 0));
    REQUIRE(d.constraints.size() == 6);
    CHECK(d.constraints[0].type == ConstraintType::BallAndSocket);
    CHECK(d.constraints[0].body1 == "b");
    CHECK(std::holds_alternative<ConeLimit>(d.constraints[0].limit));
    CHECK(d.constraints[1].type == ConstraintType::Universal);
    CHECK(std::holds_alternative<PyramidLimit>(d.constraints[1].limit));
    CHECK(d.constraints[2].type == ConstraintType::Hinge);
    CHECK(std::holds_alternative<HingeLimit>(d.constraints[2].limit));
    CHECK(d.constraints[3].type == ConstraintType::Slider);
    CHECK(d.constraints[3].body2 == "b");
    CHECK(d.constraints[4].type == ConstraintType::Spring);
    CHECK(d.constraints[4].restLength == 3.0);
    CHECK(d.constraints[4].maxLength == 9.0);
    CHECK(d.constraints[4].damping == 3.0);
    CHECK(d.constraints[5].type == ConstraintType::Fixed);
}

TEST_CASE("af: names are case-sensitive as written", "[af][case]") {
    const AfDecl d = parseOne(fig("body \"Pelvis\" { joint \"Origin\" }"));
    CHECK(d.bodies[0].name == "Pelvis");
    CHECK(d.bodies[0].joint == "Origin"); // not the base-body marker "origin"; kept as written
}

// -------------------------------------------------------------------------------------------------------------
// Duplicate names (§1.8)
// -------------------------------------------------------------------------------------------------------------

TEST_CASE("af: duplicate names", "[af][names]") {
    // '@' marks the second block's keyword and '^' its name; the error may point at either.
    auto expectDuplicateError = [](const std::string& marked) {
        const std::size_t kw = marked.find('@');
        const std::size_t nm = marked.find('^');
        REQUIRE(kw != std::string::npos);
        REQUIRE(nm != std::string::npos);
        REQUIRE(kw < nm);
        std::string text = marked;
        text.erase(nm, 1);
        text.erase(kw, 1);
        const auto keyword = lineColOf(text, kw);
        const auto name = lineColOf(text, nm - 1);
        Diagnostics d;
        const auto f = parseAf(text, "dup.af", d);
        INFO(text << "\n" << d.str());
        CHECK_FALSE(f.has_value());
        const Diagnostic* e = firstError(d);
        REQUIRE(e != nullptr);
        CHECK(e->where.line == keyword.first);
        CHECK((e->where.column == keyword.second || e->where.column == name.second));
    };
    SECTION("exact duplicate body names are an error") {
        expectDuplicateError(
            fig("body \"a\" { joint \"origin\" }\nbody \"b\" { joint \"x\" }\n  @body ^\"a\" { joint \"y\" }"));
    }
    SECTION("exact duplicate constraint names are an error, whatever the types") {
        expectDuplicateError(fig("fixed \"c\" { }\n @hinge ^\"c\" { }"));
        expectDuplicateError(fig("hinge \"c\" { }\n  @hinge ^\"c\" { }"));
    }
    SECTION("names differing only in case are a warning at the second") {
        const std::string text =
            fig("body \"head\" { joint \"origin\" }\nbody \"Head\" { joint \"x\" }\nhinge \"j\" { }\nslider \"J\" { }");
        Diagnostics w;
        const AfDecl d = parseOne(text, &w);
        CHECK(d.bodies.size() == 2);
        CHECK(d.constraints.size() == 2);
        CHECK(w.warningCount() == 2);
        CHECK(w.errorCount() == 0);
        bool sawBody = false, sawConstraint = false;
        for (const Diagnostic& x : w.items()) {
            if (x.where.line == posOf(text, "\"Head\"").first) sawBody = true;
            if (x.where.line == posOf(text, "\"J\"").first) sawConstraint = true;
        }
        CHECK(sawBody);
        CHECK(sawConstraint);
    }
    SECTION("a body and a constraint may share a name") {
        Diagnostics w;
        parseOne(fig("body \"waist\" { joint \"origin\" }\nbody \"chest\" { joint \"x\" }\n"
                     "universalJoint \"waist\" { body1 \"chest\" body2 \"waist\" }"),
                 &w);
        CHECK(w.empty());
    }
    SECTION("the same name in two figures is fine") {
        Diagnostics w;
        const AfFile f = parseOk("articulatedFigure a { body \"x\" { joint \"origin\" } }\n"
                                 "articulatedFigure b { body \"x\" { joint \"origin\" } }",
                                 &w);
        CHECK(f.decls.size() == 2);
        CHECK(w.empty());
    }
}

// -------------------------------------------------------------------------------------------------------------
// File level (§1.1)
// -------------------------------------------------------------------------------------------------------------

TEST_CASE("af: many decls per file, other decl types skipped with a warning", "[af][file]") {
    const std::string text = R"(// leading comment
articulatedFigure first {
	body "a" { joint "origin" }
}
table sometable { { 0, 1, 2 } }
articulatedFigure second { settings { totalMass 7 } }
articulatedFigure third {
}
)";
    Diagnostics w;
    const AfFile f = parseOk(text, &w);
    REQUIRE(f.decls.size() == 3);
    CHECK(f.decls[0].name == "first");
    CHECK(f.decls[0].location.line == 2);
    CHECK(f.decls[1].name == "second");
    CHECK(f.decls[1].settings[0].totalMass == 7.0);
    CHECK(f.decls[1].location.line == 6);
    CHECK(f.decls[2].name == "third");
    CHECK(f.decls[2].order.empty());
    CHECK(w.errorCount() == 0);
    REQUIRE(w.warningCount() == 1);
    CHECK(w.items()[0].where.line == 5);
    CHECK(w.items()[0].where.column == 1);

    SECTION("writeAf of one decl") {
        Diagnostics d;
        const auto g = parseAf(writeAf(f.decls[1]), "one.af", d);
        REQUIRE(g.has_value());
        REQUIRE(g->decls.size() == 1);
        CHECK(g->decls[0] == f.decls[1]);
    }
}

TEST_CASE("af: an empty file holds no decls", "[af][file]") {
    for (const char* text : {"", "  \n", "// nothing\n/* at all */"}) {
        const AfFile f = parseOk(text);
        CHECK(f.decls.empty());
    }
}

TEST_CASE("af: block order is preserved", "[af][file]") {
    const AfDecl d = parseOne(fig(R"(
hinge "h0" { }
body "b0" { joint "origin" }
settings { }
spring "s1" { }
body "b1" { joint "x" }
settings { totalMass 3 }
fixed "f2" { }
)"));
    using K = AfBlockRef::Kind;
    const std::vector<AfBlockRef> expected = {{K::Constraint, 0}, {K::Body, 0}, {K::Settings, 0},
                                              {K::Constraint, 1}, {K::Body, 1}, {K::Settings, 1},
                                              {K::Constraint, 2}};
    CHECK(d.order == expected);
    CHECK(d.constraints[0].name == "h0");
    CHECK(d.constraints[1].name == "s1");
    CHECK(d.constraints[2].name == "f2");
    CHECK(d.defaultBody1(0) == "world");
    CHECK(d.defaultBody1(1) == "b0");
    CHECK(d.defaultBody1(2) == "b0");
}

TEST_CASE("af: file-level errors", "[af][file][error]") {
    requireErrorAt(fig("@joint \"x\" { }"));
    requireErrorAt(fig("@constraint \"c\" { }"));
    requireErrorAt(fig("@{ }"));
    requireErrorAt("articulatedFigure @{ }");
    requireErrorAt("articulatedFigure f @body \"b\" { joint \"origin\" } }");
    requireErrorAt("articulatedFigure f {\n body \"b\" { joint \"origin\" }\n@");
    requireErrorAt("articulatedFigure f { }\n@}");
    requireErrorAt("articulatedFigure f { } @(");
    requireErrorAt("articulatedFigure f { body \"b\" { joint \"origin\" } }\n  @/* unterminated\n");
    requireErrorAt("table t { 1 2 @09 }\narticulatedFigure f { }");

    // A string left open at the end of a line: an error on that line.
    Diagnostics d;
    CHECK_FALSE(parseAf("articulatedFigure f {\n body \"b\" { joint \"origin } }\n}\n", "s.af", d).has_value());
    REQUIRE(firstError(d) != nullptr);
    CHECK(firstError(d)->where.line == 2);
}

TEST_CASE("af: an error anywhere means nothing is returned", "[af][error]") {
    // Errors in the last decl discard the earlier, valid ones (nothing half-loaded).
    Diagnostics d;
    const auto f = parseAf("articulatedFigure ok { body \"a\" { joint \"origin\" } }\n"
                           "articulatedFigure bad { body \"b\" { joint \"origin\" bogus } }",
                           "x.af", d);
    CHECK_FALSE(f.has_value());
    CHECK(d.errorCount() >= 1);
    CHECK(d.str().find("x.af:2:") != std::string::npos);
}

// -------------------------------------------------------------------------------------------------------------
// Writer
// -------------------------------------------------------------------------------------------------------------

TEST_CASE("af: writer round trips awkward values", "[af][writer]") {
    SECTION("numbers") {
        const AfDecl d = parseOne(fig("settings { totalMass 0.0099999998 noMoveTime 1e-300 noMoveRotation 1e300 "
                                      "noMoveTranslation 123456789012345678 minMoveTime -0 maxMoveTime 0.1 }"));
        CHECK(d.settings[0].noMoveTime == 1e-300);
        CHECK(d.settings[0].noMoveRotation == 1e300);
    }
    SECTION("large finite floats") {
        const AfDecl d =
            parseOne(fig("settings { totalMass 23456789012345678000.0 maxMoveTime 1.8446744073709552e19 }"));
        CHECK(d.settings[0].totalMass == 23456789012345678000.0);
    }
    SECTION("names with spaces and punctuation") {
        const AfFile f = parseOk("articulatedFigure \"fig with space\" {\n"
                                 "body \"a b{c}\" { joint \"j k\" mod \"odd mod\" containedJoints \"\" }\n"
                                 "hinge \"h-1\" { body1 \"a b{c}\" body2 \"x,y\" }\n}\n");
        CHECK(f.decls[0].name == "fig with space");
        CHECK(f.decls[0].bodies[0].mod == "odd mod");
    }
    SECTION("an untyped decl (the folder's default type)") {
        const AfFile f = parseOk("untyped { body \"a\" { joint \"origin\" } }");
        REQUIRE(f.decls.size() == 1);
        CHECK(f.decls[0].name == "untyped");
    }
    SECTION("the all-features figure is written canonically and stably") {
        Diagnostics d;
        const auto f = parseAf(kEverything, "e.af", d);
        REQUIRE(f.has_value());
        const std::string w1 = writeAf(*f);
        CHECK(w1.find("articulatedFigure everything {") == 0);
        CHECK(w1.find("anchor1") != std::string::npos); // a spring's anchor is written as anchor1
        CHECK(w1.find("inertiaScale ( 1 0 0 0 2 0 0 0 -3.5 )") != std::string::npos);
        checkRoundTrip(*f);
    }
}

// -------------------------------------------------------------------------------------------------------------
// Hostile input: truncations and byte mutations must never crash (the suite runs under ASan/UBSan in CI)
// -------------------------------------------------------------------------------------------------------------

namespace {
/// Either a clean parse (which must then round-trip) or nullopt with at least one error.
void checkHostile(const std::string& text, std::size_t& parsed, std::size_t& rejected) {
    Diagnostics d;
    const auto f = parseAf(text, "hostile.af", d);
    if (f) {
        ++parsed;
        if (d.errorCount() != 0) FAIL("parse succeeded with errors:\n" << text);
        const std::string w = writeAf(*f);
        Diagnostics d2;
        const auto g = parseAf(w, "hostile-rt.af", d2);
        if (!g || !(*g == *f)) FAIL("round trip failed for:\n" << text << "\nwritten:\n" << w << "\n" << d2.str());
    } else {
        ++rejected;
        if (d.errorCount() == 0) FAIL("nullopt without an error for:\n" << text);
    }
}
} // namespace

TEST_CASE("af: hostile input never crashes", "[af][hostile]") {
    const std::string& base = kEverything;
    REQUIRE(base.size() > 1500);
    std::size_t parsed = 0, rejected = 0;

    SECTION("every truncation") {
        for (std::size_t n = 0; n <= base.size(); ++n) checkHostile(base.substr(0, n), parsed, rejected);
        CHECK(parsed >= 1);   // the whole text, at least
        CHECK(rejected >= 1); // most prefixes
    }
    SECTION("deterministic byte mutations") {
        std::mt19937 rng(20240611u);
        std::uniform_int_distribution<int> byte(0, 255);
        std::uniform_int_distribution<int> count(1, 4);
        const char interesting[] = {'{', '}', '(', ')', ',', '-',  '"',  '\'', '/', '*',
                                    '0', '9', '.', '#', 'e', '\n', '\0', 'x',  ' ', '\\'};
        std::uniform_int_distribution<std::size_t> pick(0, sizeof interesting - 1);
        for (int i = 0; i < 600; ++i) {
            std::string text = base;
            const int n = count(rng);
            for (int k = 0; k < n; ++k) {
                if (text.empty()) break;
                const std::size_t p = rng() % text.size();
                switch (rng() % 4) {
                case 0: text[p] = static_cast<char>(byte(rng)); break;
                case 1: text[p] = interesting[pick(rng)]; break;
                case 2: text.erase(p, 1 + rng() % 8); break;
                default: text.insert(p, 1, interesting[pick(rng)]); break;
                }
            }
            checkHostile(text, parsed, rejected);
        }
        CHECK(parsed + rejected == 600);
    }
}
