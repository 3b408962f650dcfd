// Unit tests of the md5mesh and md5anim parsers (docs/format.md §7.3, §7.4) on small texts written for the
// purpose.
#include <catch2/catch.hpp>

#include <string>

#include "afb/decl/Md5Anim.h"
#include "afb/decl/Md5Mesh.h"

using namespace afb;
using decl::Vec3;

namespace {

// Line numbers in the error tests below refer to this text.
const std::string kMesh = R"(MD5Version 10
commandline "made by hand"

numJoints 3
numMeshes 2

joints {
	"origin" -1 ( 0 0 0 ) ( 0 0 0 )		// root
	"Body" 0 ( 1 2 3 ) ( -0.5 0.5 -0.5 )
	"body" 1 ( 4 5 -6 ) ( 0 0 0.7071 )
}

mesh {
	name "skin"
	shader "models/test/skin"
	numverts 3
	vert 0 ( 0 1 ) 0 1
	vert 1 ( 0.5 -0.25 ) 1 2
	vert 2 ( 1 1 ) 0 3
	numtris 1
	tri 0 0 2 1
	numweights 3
	weight 0 0 1 ( 0 0 0 )
	weight 1 1 0.75 ( 1 -2 3.5 )
	weight 2 2 0.25 ( -1e2 0 .5 )
}

mesh {
	shader ""
	numverts 0
	numtris 0
	numweights 0
}
)";

// Line numbers in the error tests below refer to this text.
const std::string kAnim = R"(MD5Version 10
commandline "by hand"

numFrames 2
numJoints 3
frameRate 24
numAnimatedComponents 4

hierarchy {
	"origin" -1 0 0
	"Body" 0 7 0	// Tx Ty Tz
	"Head" 1 32 3	// Qz
}

bounds {
	( -1 -2 -3 ) ( 1 2 3 )
	( -1.5 -2 -3 ) ( 1 2 3.5 )
}

baseframe {
	( 0 0 0 ) ( 0 0 0 )
	( 0 0 40 ) ( -0.5 -0.5 -0.5 )
	( 1 0 0 ) ( 0 0 0.25 )
}

frame 0 {
	0 0 40 0.25
}

frame 1 {
	1 -2 40.5 -0.125
}
)";

// `text` with its only occurrence of `from` replaced by `to`.
std::string replaced(const std::string& text, const std::string& from, const std::string& to) {
    const auto pos = text.find(from);
    REQUIRE(pos != std::string::npos);
    REQUIRE(text.find(from, pos + 1) == std::string::npos);
    return text.substr(0, pos) + to + text.substr(pos + from.size());
}

// Parses `text`, requires it to fail with exactly one error on `line` whose message contains `needle`.
template <class Parse>
void requireError(Parse parse, const std::string& text, const std::string& needle, std::uint32_t line) {
    text::Diagnostics diags;
    const auto result = parse(text, "test.md5", diags);
    INFO(diags.str());
    CHECK_FALSE(result.has_value());
    REQUIRE(diags.errorCount() == 1);
    REQUIRE(diags.items().size() == 1);
    const text::Diagnostic& d = diags.items()[0];
    CHECK(d.severity == text::Severity::Error);
    CHECK(d.message.find(needle) != std::string::npos);
    CHECK(d.where.file == "test.md5");
    CHECK(d.where.line == line);
    CHECK(d.str().rfind("test.md5:" + std::to_string(line) + ":", 0) == 0);
}

void requireMeshError(const std::string& text, const std::string& needle, std::uint32_t line) {
    requireError(decl::parseMd5Mesh, text, needle, line);
}

void requireAnimError(const std::string& text, const std::string& needle, std::uint32_t line) {
    requireError(decl::parseMd5Anim, text, needle, line);
}

} // namespace

// --- md5mesh ---------------------------------------------------------------------------------------------

TEST_CASE("md5mesh: values are kept as written", "[md5][mesh]") {
    text::Diagnostics diags;
    const auto mesh = decl::parseMd5Mesh(kMesh, "hand.md5mesh", diags);
    INFO(diags.str());
    REQUIRE(mesh);
    CHECK(diags.empty());
    CHECK(mesh->version == 10);
    CHECK(mesh->commandline == "made by hand");

    REQUIRE(mesh->joints.size() == 3);
    CHECK(mesh->joints[0] == decl::Md5Joint{"origin", -1, {0, 0, 0}, {0, 0, 0}});
    CHECK(mesh->joints[1] == decl::Md5Joint{"Body", 0, {1, 2, 3}, {-0.5, 0.5, -0.5}});
    CHECK(mesh->joints[2] == decl::Md5Joint{"body", 1, {4, 5, -6}, {0, 0, 0.7071}});

    REQUIRE(mesh->meshes.size() == 2);
    const decl::Md5SubMesh& skin = mesh->meshes[0];
    CHECK(skin.name == "skin");
    CHECK(skin.shader == "models/test/skin");
    REQUIRE(skin.verts.size() == 3);
    CHECK(skin.verts[1] == decl::Md5Vert{0.5, -0.25, 1, 2});
    CHECK(skin.verts[2] == decl::Md5Vert{1, 1, 0, 3});
    REQUIRE(skin.tris.size() == 1);
    CHECK(skin.tris[0].v[0] == 0);
    CHECK(skin.tris[0].v[1] == 2);
    CHECK(skin.tris[0].v[2] == 1);
    REQUIRE(skin.weights.size() == 3);
    CHECK(skin.weights[1] == decl::Md5Weight{1, 0.75, {1, -2, 3.5}});
    CHECK(skin.weights[2] == decl::Md5Weight{2, 0.25, {-100, 0, 0.5}});

    const decl::Md5SubMesh& empty = mesh->meshes[1];
    CHECK(empty.name.empty());
    CHECK(empty.shader.empty());
    CHECK(empty.verts.empty());
    CHECK(empty.tris.empty());
    CHECK(empty.weights.empty());

    CHECK(decl::totalVertCount(*mesh) == 3);
    CHECK(decl::totalTriCount(*mesh) == 1);
    CHECK(decl::totalWeightCount(*mesh) == 3);
}

TEST_CASE("md5mesh: joint lookup ignores case and returns the first match", "[md5][mesh]") {
    text::Diagnostics diags;
    const auto mesh = decl::parseMd5Mesh(kMesh, "hand.md5mesh", diags);
    REQUIRE(mesh);
    CHECK(decl::findJoint(*mesh, "origin") == 0);
    CHECK(decl::findJoint(*mesh, "ORIGIN") == 0);
    CHECK(decl::findJoint(*mesh, "body") == 1); // "Body" (1) shadows "body" (2), docs/format.md §8 item 22
    CHECK(decl::findJoint(*mesh, "BODY") == 1);
    CHECK_FALSE(decl::findJoint(*mesh, "head"));
    CHECK_FALSE(decl::findJoint(*mesh, ""));
}

TEST_CASE("md5mesh: equality ignores where the text came from", "[md5][mesh]") {
    text::Diagnostics diags;
    const auto a = decl::parseMd5Mesh(kMesh, "a.md5mesh", diags);
    const auto b = decl::parseMd5Mesh("// leading comment\n" + kMesh, "b.md5mesh", diags);
    const auto c = decl::parseMd5Mesh(replaced(kMesh, "0.75", "0.5"), "c.md5mesh", diags);
    REQUIRE(a);
    REQUIRE(b);
    REQUIRE(c);
    CHECK(*a == *b);
    CHECK_FALSE(*a == *c);
}

TEST_CASE("md5mesh: an octal-looking number is read as octal with a warning", "[md5][mesh]") {
    text::Diagnostics diags;
    const auto mesh = decl::parseMd5Mesh(replaced(kMesh, "vert 2 ( 1 1 ) 0 3", "vert 2 ( 1 1 ) 00 03"), "t", diags);
    REQUIRE(mesh);
    CHECK(diags.errorCount() == 0);
    CHECK(diags.warningCount() == 2);
    CHECK(mesh->meshes[0].verts[2].weightCount == 3);
}

TEST_CASE("md5mesh: header errors", "[md5][mesh][errors]") {
    requireMeshError("", "empty md5mesh file", 1);
    requireMeshError("  // only a comment\n", "empty md5mesh file", 2);
    requireMeshError(replaced(kMesh, "MD5Version 10", "MD5Version 11"), "MD5Version 11 is not supported", 1);
    requireMeshError(replaced(kMesh, "MD5Version 10", "MD5version 10"), "expected 'MD5Version'", 1);
    requireMeshError(replaced(kMesh, "\"made by hand\"", "made"), "commandline", 2);
    requireMeshError(replaced(kMesh, "numJoints 3", "numJoints -3"), "numJoints", 4);
    requireMeshError(replaced(kMesh, "numJoints 3", "numJoints 3.5"), "numJoints", 4);
    requireMeshError(replaced(kMesh, "numMeshes 2", "numSurfaces 2"), "expected 'numMeshes'", 5);
}

TEST_CASE("md5mesh: counts larger than the input are rejected before allocating", "[md5][mesh][errors]") {
    requireMeshError(replaced(kMesh, "numJoints 3", "numJoints 2000000000"),
                     "numJoints 2000000000 is more than the file can hold", 4);
    requireMeshError(replaced(kMesh, "numMeshes 2", "numMeshes 2000000000"),
                     "numMeshes 2000000000 is more than the file can hold", 5);
    requireMeshError(replaced(kMesh, "numverts 3", "numverts 2147483647"), "numverts 2147483647 is more than", 16);
    requireMeshError(replaced(kMesh, "numtris 1", "numtris 100000"), "numtris 100000 is more than", 20);
    requireMeshError(replaced(kMesh, "numweights 3", "numweights 1000"), "numweights 1000 is more than", 22);
    requireMeshError(replaced(kMesh, "numJoints 3", "numJoints 99999999999"), "numJoints", 4);
    requireMeshError("MD5Version 10 commandline \"\" numJoints 2 numMeshes 0 joints {", "numJoints 2 is more", 1);
}

TEST_CASE("md5mesh: joints block errors", "[md5][mesh][errors]") {
    requireMeshError(replaced(kMesh, "numJoints 3", "numJoints 4"), "the joints block ends after 3 joints", 11);
    requireMeshError(replaced(kMesh, "numJoints 3", "numJoints 2"), "more joints than numJoints", 10);
    requireMeshError(replaced(kMesh, "\"Body\" 0", "\"Body\" 2"), "parents must precede children", 9);
    requireMeshError(replaced(kMesh, "\"Body\" 0", "\"Body\" 1"), "joint 1 \"Body\" has parent 1", 9);
    requireMeshError(replaced(kMesh, "\"Body\" 0", "\"Body\" -2"), "has parent -2", 9);
    requireMeshError(replaced(kMesh, "\"Body\" 0", "Body 0"), "joint name", 9);
    requireMeshError(replaced(kMesh, "( 1 2 3 ) ( -0.5", "( 1 2 ) ( -0.5"), "joint position", 9);
    requireMeshError(replaced(kMesh, "( 4 5 -6 )", "( 4 5 -6"), "expected ')'", 10);
}

TEST_CASE("md5mesh: a root joint may appear anywhere", "[md5][mesh]") {
    text::Diagnostics diags;
    const auto mesh = decl::parseMd5Mesh(replaced(kMesh, "\"body\" 1", "\"body\" -1"), "t", diags);
    REQUIRE(mesh);
    CHECK(mesh->joints[2].parent == -1);
}

TEST_CASE("md5mesh: mesh block structure errors", "[md5][mesh][errors]") {
    requireMeshError(replaced(kMesh, "numMeshes 2", "numMeshes 3"), "the file ends after 2 mesh blocks", 34);
    requireMeshError(replaced(kMesh, "numMeshes 2", "numMeshes 1"), "more mesh blocks than numMeshes 1", 28);
    requireMeshError(kMesh + "extra\n", "unexpected 'extra' after the last mesh block", 34);
    requireMeshError(replaced(kMesh, "shader \"models/test/skin\"", "material \"x\""), "expected 'shader'", 15);
    requireMeshError(replaced(kMesh, "name \"skin\"", "name skin"), "mesh name", 14);
    requireMeshError(replaced(kMesh, "numtris 1", "numtris 1\n\tflat 1"), "expected 'tri' line 0 of numtris 1", 21);
    requireMeshError(replaced(kMesh, "\tnumweights 0\n}", "\tnumweights 0\n\tflags 1\n}"),
                     "expected '}' closing mesh block 1", 33);
}

TEST_CASE("md5mesh: vertex errors", "[md5][mesh][errors]") {
    requireMeshError(replaced(kMesh, "vert 1 ( 0.5", "vert 2 ( 0.5"), "vertex index 2 should be 1", 18);
    requireMeshError(replaced(kMesh, "numverts 3", "numverts 4"), "expected 'vert' line 3 of numverts 4", 20);
    requireMeshError(replaced(kMesh, "numverts 3", "numverts 2"), "more 'vert' lines than numverts 2", 19);
    requireMeshError(replaced(kMesh, "( 1 1 ) 0 3", "( 1 1 ) 0 0"), "vertex 2 has no weights", 19);
    requireMeshError(replaced(kMesh, "( 1 1 ) 0 3", "( 1 1 ) 1 3"),
                     "vertex 2 uses weights 1..3, out of range (numweights 3)", 19);
    requireMeshError(replaced(kMesh, "( 1 1 ) 0 3", "( 1 1 ) -1 3"), "negative first weight", 19);
    requireMeshError(replaced(kMesh, "( 1 1 ) 0 3", "( 1 1 ) 0 2.5"), "weight count", 19);
}

TEST_CASE("md5mesh: triangle errors", "[md5][mesh][errors]") {
    requireMeshError(replaced(kMesh, "tri 0 0 2 1", "tri 1 0 2 1"), "triangle index 1 should be 0", 21);
    requireMeshError(replaced(kMesh, "tri 0 0 2 1", "tri 0 0 3 1"), "triangle 0 uses vertex 3, out of range", 21);
    requireMeshError(replaced(kMesh, "tri 0 0 2 1", "tri 0 0 2 -1"), "triangle 0 uses vertex -1", 21);
    requireMeshError(replaced(kMesh, "numtris 1", "numtris 0"), "more 'tri' lines than numtris 0", 21);
}

TEST_CASE("md5mesh: weight errors", "[md5][mesh][errors]") {
    requireMeshError(replaced(kMesh, "weight 1 1 0.75", "weight 1 3 0.75"),
                     "weight 1 refers to joint 3, out of range (numJoints 3)", 24);
    requireMeshError(replaced(kMesh, "weight 1 1 0.75", "weight 1 -1 0.75"), "refers to joint -1", 24);
    requireMeshError(replaced(kMesh, "weight 2 2", "weight 1 2"), "weight index 1 should be 2", 25);
    requireMeshError(replaced(kMesh, "numweights 3", "numweights 2"), "more 'weight' lines than numweights 2", 25);
    requireMeshError(replaced(kMesh, "numweights 3", "numweights 4"), "expected 'weight' line 3 of numweights 4", 26);
}

TEST_CASE("md5mesh: lexical damage is an error, not a crash", "[md5][mesh][errors]") {
    // A truncated file usually fails the room check of the count before the cut...
    requireMeshError(kMesh.substr(0, kMesh.find("( 1 -2 3.5")), "numweights 3 is more than the file can hold", 22);
    // ...and otherwise where the text stops.
    requireMeshError(kMesh.substr(0, kMesh.find(" .5 )")), "expected a number for the weight offset, found end", 25);
    requireMeshError(replaced(kMesh, "\"made by hand\"", "\"made by hand"), "newline inside a quoted string", 2);
    requireMeshError(replaced(kMesh, "( 0.5 -0.25 )", std::string("( 0.5 \0 )", 9)), "NUL byte", 18);
    requireMeshError(replaced(kMesh, "-1e2", "1.#INF"), "special float", 25);

    // Every prefix of the text is rejected (or, for the complete text, accepted) without a crash.
    for (std::size_t n = 0; n < kMesh.size(); ++n) {
        text::Diagnostics diags;
        const auto mesh = decl::parseMd5Mesh(std::string_view(kMesh).substr(0, n), "t", diags);
        const bool complete = n > kMesh.rfind('}');
        CHECK(mesh.has_value() == complete);
        CHECK(diags.hasErrors() != complete);
    }
}

TEST_CASE("md5mesh: loading a missing file is an error", "[md5][mesh][errors]") {
    text::Diagnostics diags;
    CHECK_FALSE(decl::loadMd5Mesh("/nonexistent/dir/x.md5mesh", diags));
    REQUIRE(diags.errorCount() == 1);
    CHECK(diags.items()[0].message == "no such file");
}

// --- md5anim ---------------------------------------------------------------------------------------------

TEST_CASE("md5anim: values are kept as written", "[md5][anim]") {
    text::Diagnostics diags;
    const auto anim = decl::parseMd5Anim(kAnim, "hand.md5anim", diags);
    INFO(diags.str());
    REQUIRE(anim);
    CHECK(diags.empty());
    CHECK(anim->version == 10);
    CHECK(anim->commandline == "by hand");
    CHECK(anim->frameRate == 24);
    CHECK(anim->numAnimatedComponents == 4);

    REQUIRE(anim->hierarchy.size() == 3);
    CHECK(anim->hierarchy[0] == decl::Md5HierarchyEntry{"origin", -1, 0, 0});
    CHECK(anim->hierarchy[1] == decl::Md5HierarchyEntry{"Body", 0, decl::kMd5Tx | decl::kMd5Ty | decl::kMd5Tz, 0});
    CHECK(anim->hierarchy[2] == decl::Md5HierarchyEntry{"Head", 1, decl::kMd5Qz, 3});

    REQUIRE(anim->bounds.size() == 2);
    CHECK(anim->bounds[1] == decl::Md5Bounds{{-1.5, -2, -3}, {1, 2, 3.5}});
    REQUIRE(anim->baseframe.size() == 3);
    CHECK(anim->baseframe[1] == decl::Md5BaseJoint{{0, 0, 40}, {-0.5, -0.5, -0.5}});
    CHECK(anim->baseframe[2] == decl::Md5BaseJoint{{1, 0, 0}, {0, 0, 0.25}});

    REQUIRE(anim->frames.size() == 2);
    CHECK(anim->frames[0] == std::vector<double>{0, 0, 40, 0.25});
    CHECK(anim->frames[1] == std::vector<double>{1, -2, 40.5, -0.125});
}

TEST_CASE("md5anim: the root translation is kept, not zeroed", "[md5][anim]") {
    text::Diagnostics diags;
    const auto anim = decl::parseMd5Anim(replaced(kAnim, "( 0 0 0 ) ( 0 0 0 )", "( 5 6 7 ) ( 0 0 0 )"), "t", diags);
    REQUIRE(anim);
    CHECK(anim->baseframe[0].position == Vec3{5, 6, 7});
}

TEST_CASE("md5anim: an anim without animated components has empty frames", "[md5][anim]") {
    const std::string still = R"(MD5Version 10
commandline ""
numFrames 2
numJoints 1
frameRate 0
numAnimatedComponents 0
hierarchy { "origin" -1 0 0 }
bounds { ( 0 0 0 ) ( 1 1 1 ) ( 0 0 0 ) ( 1 1 1 ) }
baseframe { ( 0 0 0 ) ( 0 0 0 ) }
frame 0 { }
frame 1 {
}
)";
    text::Diagnostics diags;
    const auto anim = decl::parseMd5Anim(still, "t", diags);
    INFO(diags.str());
    REQUIRE(anim);
    CHECK(anim->frameRate == 0);
    REQUIRE(anim->frames.size() == 2);
    CHECK(anim->frames[0].empty());
    CHECK(anim->frames[1].empty());
    requireAnimError(replaced(still, "frame 1 {\n}", "frame 1 { 0 }"), "frame 1 has more values than", 11);
}

TEST_CASE("md5anim: component counting", "[md5][anim]") {
    CHECK(decl::animatedComponentCount(0) == 0);
    CHECK(decl::animatedComponentCount(decl::kMd5Qz) == 1);
    CHECK(decl::animatedComponentCount(7) == 3);
    CHECK(decl::animatedComponentCount(decl::kMd5AllComponents) == 6);
}

TEST_CASE("md5anim: header errors", "[md5][anim][errors]") {
    requireAnimError("", "empty md5anim file", 1);
    requireAnimError(replaced(kAnim, "MD5Version 10", "MD5Version 6"), "MD5Version 6 is not supported", 1);
    requireAnimError(replaced(kAnim, "numFrames 2", "numFrames 0"), "at least one frame", 4);
    requireAnimError(replaced(kAnim, "numJoints 3", "numJoints 0"), "at least one joint", 5);
    requireAnimError(replaced(kAnim, "frameRate 24", "frameRate -1"), "frameRate -1 is negative", 6);
    requireAnimError(replaced(kAnim, "frameRate 24", "frameRate 24.5"), "frameRate", 6);
    requireAnimError(replaced(kAnim, "numAnimatedComponents 4", "numAnimatedComponents 19"),
                     "numAnimatedComponents 19 is more than 6 per joint (at most 18", 7);
    requireAnimError(replaced(kAnim, "numAnimatedComponents 4", "numAnimatedComponents -4"), "numAnimatedComponents",
                     7);
    requireAnimError(replaced(kAnim, "frameRate 24", "framerate 24"), "expected 'frameRate'", 6);
    requireAnimError(replaced(kAnim, "bounds {", "bbox {"), "expected 'bounds'", 15);
}

TEST_CASE("md5anim: counts larger than the input are rejected before allocating", "[md5][anim][errors]") {
    requireAnimError(replaced(kAnim, "numFrames 2", "numFrames 2000000000"),
                     "numFrames 2000000000 is more than the file can hold", 4);
    requireAnimError(replaced(kAnim, "numJoints 3", "numJoints 2000000000"),
                     "numJoints 2000000000 is more than the file can hold", 5);
    // Ten frames would fit without values, but not with 18 values each.
    requireAnimError(replaced(replaced(kAnim, "numFrames 2", "numFrames 10"), "numAnimatedComponents 4",
                              "numAnimatedComponents 18"),
                     "numFrames 10 with numAnimatedComponents 18 values each is more than the file can hold", 4);
}

TEST_CASE("md5anim: hierarchy errors", "[md5][anim][errors]") {
    requireAnimError(replaced(kAnim, "\"origin\" -1 0 0", "\"origin\" 0 0 0"), "the first joint must be the root", 10);
    requireAnimError(replaced(kAnim, "\"Body\" 0 7 0", "\"Body\" -1 7 0"), "only joint 0 may be a root", 11);
    requireAnimError(replaced(kAnim, "\"Head\" 1 32 3", "\"Head\" 2 32 3"), "parents must precede children", 12);
    requireAnimError(replaced(kAnim, "\"Head\" 1 32 3", "\"Head\" 1 64 3"), "has flags 64, out of range 0..63", 12);
    requireAnimError(replaced(kAnim, "\"Head\" 1 32 3", "\"Head\" 1 -1 3"), "has flags -1", 12);
    requireAnimError(replaced(kAnim, "\"Head\" 1 32 3", "\"Head\" 1 32 4"),
                     "reads 1 components from start index 4, past numAnimatedComponents 4", 12);
    requireAnimError(replaced(kAnim, "\"Body\" 0 7 0", "\"Body\" 0 7 2"), "reads 3 components from start index 2", 11);
    requireAnimError(replaced(kAnim, "\"Head\" 1 32 3", "\"Head\" 1 32 -1"), "start index -1", 12);
    requireAnimError(replaced(kAnim, "numJoints 3", "numJoints 4"), "the hierarchy block ends after 3 lines", 13);
    requireAnimError(replaced(kAnim, "numJoints 3", "numJoints 2"), "more lines than numJoints", 12);
}

TEST_CASE("md5anim: bounds, baseframe and frame errors", "[md5][anim][errors]") {
    requireAnimError(replaced(kAnim, "numFrames 2", "numFrames 3"), "the bounds block ends after 2 lines", 18);
    requireAnimError(replaced(kAnim, "\t( 1 0 0 ) ( 0 0 0.25 )\n", ""), "the baseframe block ends after 2 lines", 23);
    requireAnimError(replaced(kAnim, "( 0 0 40 ) ( -0.5 -0.5 -0.5 )", "( 0 0 40 ) -0.5 -0.5 -0.5"),
                     "baseframe orientation", 22);
    requireAnimError(replaced(kAnim, "frame 1 {", "frame 2 {"), "frame index 2 should be 1", 30);
    requireAnimError(replaced(kAnim, "frame 1 {", "frame -1 {"), "frame index", 30);
    requireAnimError(replaced(kAnim, "frame 1 {", "frames 1 {"), "expected 'frame 1'", 30);
    requireAnimError(replaced(kAnim, "1 -2 40.5 -0.125", "1 -2 40.5"),
                     "frame 1 has 3 values, but numAnimatedComponents is 4", 32);
    requireAnimError(replaced(kAnim, "1 -2 40.5 -0.125", "1 -2 40.5 -0.125 7"),
                     "frame 1 has more values than numAnimatedComponents 4", 31);
    requireAnimError(replaced(kAnim, "1 -2 40.5 -0.125", "1 -2 40.5 -0.125 -7"), "frame 1 has more values", 31);
    requireAnimError(kAnim + "frame 2 { 0 0 0 0 }\n", "more frames than numFrames 2", 33);
    requireAnimError(kAnim + "}\n", "unexpected '}' after the last frame", 33);
    requireAnimError(kAnim.substr(0, kAnim.find("frame 1")), "the file ends after 1 frames, but numFrames is 2", 30);
}

TEST_CASE("md5anim: every prefix is rejected without a crash", "[md5][anim][errors]") {
    const std::size_t lastBrace = kAnim.rfind('}');
    for (std::size_t n = 0; n < kAnim.size(); ++n) {
        text::Diagnostics diags;
        const auto anim = decl::parseMd5Anim(std::string_view(kAnim).substr(0, n), "t", diags);
        CHECK(anim.has_value() == (n > lastBrace));
        CHECK(diags.hasErrors() == (n <= lastBrace));
    }
}

TEST_CASE("md5anim: hierarchy must match the mesh exactly", "[md5][anim]") {
    text::Diagnostics diags;
    const std::string mesh3 = R"(MD5Version 10
commandline ""
numJoints 3
numMeshes 0
joints {
	"origin" -1 ( 0 0 0 ) ( 0 0 0 )
	"Body" 0 ( 0 0 0 ) ( 0 0 0 )
	"Head" 1 ( 0 0 0 ) ( 0 0 0 )
}
)";
    const auto mesh = decl::parseMd5Mesh(mesh3, "m", diags);
    const auto anim = decl::parseMd5Anim(kAnim, "a", diags);
    INFO(diags.str());
    REQUIRE(mesh);
    REQUIRE(anim);
    CHECK_FALSE(decl::hierarchyMismatch(*anim, *mesh));

    const auto lowerCase = decl::parseMd5Mesh(replaced(mesh3, "\"Head\"", "\"head\""), "m", diags);
    REQUIRE(lowerCase);
    const auto nameMismatch = decl::hierarchyMismatch(*anim, *lowerCase);
    REQUIRE(nameMismatch);
    CHECK(*nameMismatch == "joint 2 is \"Head\" in the anim but \"head\" in the mesh (names are compared "
                           "case-sensitively)");

    const auto reparented = decl::parseMd5Mesh(replaced(mesh3, "\"Head\" 1", "\"Head\" 0"), "m", diags);
    REQUIRE(reparented);
    const auto parentMismatch = decl::hierarchyMismatch(*anim, *reparented);
    REQUIRE(parentMismatch);
    CHECK(parentMismatch->find("has parent 1 in the anim but 0 in the mesh") != std::string::npos);

    const auto shorter = decl::parseMd5Mesh(replaced(replaced(mesh3, "numJoints 3", "numJoints 2"),
                                                     "\t\"Head\" 1 ( 0 0 0 ) ( 0 0 0 )\n", ""),
                                            "m", diags);
    REQUIRE(shorter);
    const auto countMismatch = decl::hierarchyMismatch(*anim, *shorter);
    REQUIRE(countMismatch);
    CHECK(*countMismatch == "the anim has 3 joints, the mesh has 2");
}

TEST_CASE("md5anim: a hierarchy mismatch is reported at the lines of the joint", "[md5][anim][errors]") {
    text::Diagnostics diags;
    const std::string mesh = R"(MD5Version 10
commandline ""
numJoints 3
numMeshes 0
joints {
	"origin" -1 ( 0 0 0 ) ( 0 0 0 )
	"Body" 0 ( 0 0 0 ) ( 0 0 0 )
	"Head" 0 ( 0 0 0 ) ( 0 0 0 )
}
)";
    const auto reparented = decl::parseMd5Mesh(mesh, "m.md5mesh", diags);
    const auto anim = decl::parseMd5Anim(kAnim, "a.md5anim", diags);
    INFO(diags.str());
    REQUIRE(reparented);
    REQUIRE(anim);
    REQUIRE(anim->hierarchyLocations.size() == 3);
    const auto d = decl::hierarchyMismatchDiagnostic(*anim, *reparented, "af_pose: ");
    REQUIRE(d);
    CHECK(d->str() == "a.md5anim:12:2: error: af_pose: joint 2 \"Head\" has parent 1 in the anim but 0 in the mesh "
                      "(the mesh's joint 2: m.md5mesh:8:2)");

    // One joint fewer in the mesh: the anim's line of the joint the mesh lacks.
    const auto shorter = decl::parseMd5Mesh(replaced(replaced(mesh, "numJoints 3", "numJoints 2"),
                                                     "\t\"Head\" 0 ( 0 0 0 ) ( 0 0 0 )\n", ""),
                                            "m.md5mesh", diags);
    REQUIRE(shorter);
    const auto count = decl::hierarchyMismatchDiagnostic(*anim, *shorter, "");
    REQUIRE(count);
    CHECK(count->str() == "a.md5anim:12:2: error: the anim has 3 joints, the mesh has 2");

    // An anim built in code has no lines (and equals the parsed one): the mesh's line is the one known.
    decl::Md5Anim built = *anim;
    built.hierarchyLocations.clear();
    CHECK(built == *anim);
    const auto unlocated = decl::hierarchyMismatchDiagnostic(built, *reparented, "");
    REQUIRE(unlocated);
    CHECK(unlocated->where.line == 8); // the mesh's line, the only one known
    const auto matching = decl::parseMd5Mesh(replaced(mesh, "\"Head\" 0", "\"Head\" 1"), "m.md5mesh", diags);
    REQUIRE(matching);
    CHECK_FALSE(decl::hierarchyMismatchDiagnostic(*anim, *matching, ""));
}
