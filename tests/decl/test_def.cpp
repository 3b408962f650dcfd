// Unit tests of the .def parser (docs/format.md §7.1 model decls, §7.2 entityDef keys) on texts written for the
// purpose.
#include <catch2/catch.hpp>

#include <string>

#include "afb/decl/Def.h"

using namespace afb;
using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;

namespace {

std::optional<decl::DefFile> parse(const std::string& textIn, text::Diagnostics& diags) {
    return decl::parseDef(textIn, "test.def", diags);
}

// The first error of a text that must fail, as `file:line:col: error: message`.
std::string firstError(const std::string& textIn) {
    text::Diagnostics diags;
    const auto parsed = parse(textIn, diags);
    CHECK_FALSE(parsed);
    for (const text::Diagnostic& d : diags.items())
        if (d.severity == text::Severity::Error) return d.str();
    FAIL("no error reported");
    return {};
}

std::string firstWarning(const text::Diagnostics& diags) {
    for (const text::Diagnostic& d : diags.items())
        if (d.severity == text::Severity::Warning) return d.str();
    return {};
}

// Line numbers in the tests below refer to this text.
const std::string kDef = R"(// a comment
model model_base {
	mesh			models/md5/base/base.md5mesh
	"skin"			skins/base.skin
	offset			( 1 -2.5 0 )
	channel torso	( *Waist )
	channel legs	( origin Body2 *Hips -*Waist SPINNER )
	anim af_pose	models/md5/base/af_pose.md5anim
	anim walk		models/md5/base/walk.md5anim, models/md5/base/walk_b.md5anim, models/md5/base/walk_c.md5anim {
		frame 4		sound_body footstep
		frame 12	{ nested { braces } }
	}
	anim pain1		models/md5/base/pain1.md5anim {}
}

entityDef monster_base {
	"inherit"		"zombie_default"
	"model"			"model_base"
	"Ragdoll"		"monster_base"
	"health"		"55"
	"look_joint Waist"	"0.1333 0.1333 0"
	"number"		12
}

export fred {
	options -prefix MUM_
	mesh	models/x.mb -dest models/md5/x
}

skin skins/base.skin {
	models/x	models/y
}

untyped_entity {
	"model"	"model_child"
}

model model_child {
	inherit model_base
	anim walk		models/md5/base/walk2.md5anim
	remove pain
}
)";

} // namespace

TEST_CASE("parseDef reads entityDefs and model decls, and skips other decl types", "[def]") {
    text::Diagnostics diags;
    const auto file = parse(kDef, diags);
    INFO(diags.str());
    REQUIRE(file);
    CHECK(diags.empty());
    REQUIRE(file->entityDefs.size() == 2);
    REQUIRE(file->models.size() == 2);

    SECTION("entityDef keys, in file order, as written") {
        const decl::EntityDef& e = file->entityDefs[0];
        CHECK(e.name == "monster_base");
        CHECK(e.location.line == 16);
        CHECK(e.location.file == "test.def");
        REQUIRE(e.keyValues.size() == 6);
        CHECK(e.keyValues[0] == std::pair<std::string, std::string>{"inherit", "zombie_default"});
        CHECK(e.keyValues[2] == std::pair<std::string, std::string>{"Ragdoll", "monster_base"});
        CHECK(e.keyValues[5] == std::pair<std::string, std::string>{"number", "12"}); // an unquoted value
        CHECK(e.get("ragdoll") == "monster_base");                                    // case-insensitive, as idDict
        CHECK(e.get("LOOK_JOINT waist") == "0.1333 0.1333 0");
        CHECK_FALSE(e.get("missing"));
        CHECK(e.has("MODEL"));
    }

    SECTION("an untyped decl in a .def file is an entityDef") {
        const decl::EntityDef& e = file->entityDefs[1];
        CHECK(e.name == "untyped_entity");
        CHECK(e.location.line == 34);
        CHECK(e.get("model") == "model_child");
    }

    SECTION("model decl statements") {
        const decl::ModelDef& m = file->models[0];
        CHECK(m.name == "model_base");
        CHECK(m.location.line == 2);
        CHECK_FALSE(m.inherit);
        CHECK(m.mesh == "models/md5/base/base.md5mesh");
        CHECK(m.skin == "skins/base.skin"); // a quoted keyword is a keyword, as in env.def
        CHECK(m.offset == decl::Vec3{1, -2.5, 0});
        REQUIRE(m.channels.size() == 2);
        CHECK(m.channels[0].name == "torso");
        CHECK(m.channels[0].joints == "*Waist");
        CHECK(m.channels[1].name == "legs");
        CHECK(m.channels[1].joints == "origin Body2 *Hips -*Waist SPINNER");
        CHECK(m.channels[1].location.line == 7);
        REQUIRE(m.anims.size() == 3);
        CHECK(m.anims[0].name == "af_pose");
        CHECK(m.anims[0].files == std::vector<std::string>{"models/md5/base/af_pose.md5anim"});
        CHECK_FALSE(m.anims[0].block);
        CHECK(m.anims[1].name == "walk");
        CHECK(m.anims[1].files.size() == 3);
        CHECK(m.anims[1].files[2] == "models/md5/base/walk_c.md5anim");
        REQUIRE(m.anims[1].block);
        CHECK(*m.anims[1].block == "\n\t\tframe 4\t\tsound_body footstep\n\t\tframe 12\t{ nested { braces } }\n\t");
        CHECK(m.anims[1].location.line == 9);
        CHECK(m.anims[2].name == "pain1");
        CHECK(m.anims[2].alias() == "pain");
        CHECK(m.anims[2].block == std::string{});
        CHECK(m.findAnim("af_pose") == &m.anims[0]);
        CHECK(m.findAnim("AF_POSE") == nullptr); // anim names are case-sensitive
        CHECK(m.removes.empty());
    }

    SECTION("inherit and remove") {
        const decl::ModelDef& m = file->models[1];
        CHECK(m.inherit == "model_base");
        CHECK_FALSE(m.mesh);
        REQUIRE(m.anims.size() == 1);
        CHECK(m.anims[0].name == "walk");
        CHECK(m.removes == std::vector<std::string>{"pain"});
    }
}

TEST_CASE("parseDef values compare by content, not location", "[def]") {
    text::Diagnostics diags;
    const auto a = parse(kDef, diags);
    const auto b = decl::parseDef("\n\n" + kDef, "other.def", diags);
    REQUIRE(a);
    REQUIRE(b);
    CHECK(*a == *b);
    auto c = *a;
    c.models[0].anims[1].files[0] = "x.md5anim";
    CHECK_FALSE(*a == c);
}

TEST_CASE("a duplicate entityDef key is a warning and the later value wins", "[def]") {
    text::Diagnostics diags;
    const auto file = parse("entityDef e {\n  \"model\" \"a\"\n  \"MODEL\" \"b\"\n}\n", diags);
    REQUIRE(file);
    CHECK(diags.errorCount() == 0);
    CHECK(diags.warningCount() == 1);
    CHECK_THAT(firstWarning(diags),
               StartsWith("test.def:3:3: warning:") && Contains("'MODEL' already defined") && Contains("line 2"));
    CHECK(file->entityDefs[0].keyValues.size() == 2);
    CHECK(file->entityDefs[0].get("model") == "b");
}

TEST_CASE("entityDef errors are located and load nothing", "[def]") {
    CHECK_THAT(firstError("entityDef e {\n  model \"x\"\n}\n"),
               StartsWith("test.def:2:3: error:") && Contains("expected a \"quoted\" key"));
    CHECK_THAT(firstError("entityDef e {\n  \"model\" }\n"),
               StartsWith("test.def:2:11: error:") && Contains("\"model\"") && Contains("has no value"));
    CHECK_THAT(firstError("entityDef e {\n  \"model\" \"x\"\n"),
               StartsWith("test.def:3:1: error:") && Contains("missing '}'"));
    CHECK_THAT(firstError("entityDef e {\n  \"model\""), Contains("has no value"));
    CHECK_THAT(firstError("entityDef e \"x\" {\n}\n"), StartsWith("test.def:1:13: error:") && Contains("'{'"));
}

TEST_CASE("model decl errors name the problem and its line", "[def]") {
    SECTION("keywords are case-sensitive") {
        CHECK_THAT(firstError("model m {\n\tMesh models/a.md5mesh\n}\n"), StartsWith("test.def:2:2: error:") &&
                                                                              Contains("unknown keyword 'Mesh'") &&
                                                                              Contains("case-sensitive"));
    }
    SECTION("mesh needs the md5mesh extension") {
        CHECK_THAT(firstError("model m {\n\tmesh models/a.lwo\n}\n"),
                   StartsWith("test.def:2:7: error:") && Contains("models/a.lwo") && Contains(".md5mesh"));
        CHECK_THAT(firstError("model m {\n\tmesh models/a.MD5MESH\n}\n"), Contains("not an .md5mesh file"));
    }
    SECTION("anim and channel need a mesh first (or inherit)") {
        CHECK_THAT(firstError("model m {\n\tanim af_pose a.md5anim\n\tmesh a.md5mesh\n}\n"),
                   StartsWith("test.def:2:2: error:") && Contains("'anim' before 'mesh'"));
        CHECK_THAT(firstError("model m {\n\tchannel torso ( *Waist )\n}\n"), Contains("'channel' before 'mesh'"));
        text::Diagnostics diags;
        CHECK(parse("model m {\n\tinherit p\n\tanim af_pose a.md5anim\n}\n", diags));
    }
    SECTION("offset takes three numbers without commas") {
        CHECK_THAT(firstError("model m {\n\toffset ( 1, 2, 3 )\n}\n"),
                   StartsWith("test.def:2:12: error:") && Contains("without commas"));
        CHECK_THAT(firstError("model m {\n\toffset 1 2 3\n}\n"), Contains("expected '('"));
        CHECK_THAT(firstError("model m {\n\toffset ( 1 2 3 4 )\n}\n"), Contains("expected ')'"));
    }
    SECTION("channel names and joint lists") {
        CHECK_THAT(firstError("model m {\n\tmesh a.md5mesh\n\tchannel arms ( *Waist )\n}\n"),
                   StartsWith("test.def:3:10: error:") && Contains("unknown channel 'arms'"));
        // idDeclModelDef::Parse searches the channel names after ANIMCHANNEL_ALL: "all" is rejected.
        CHECK_THAT(firstError("model m {\n\tmesh a.md5mesh\n\tchannel all ( *Waist )\n}\n"),
                   Contains("unknown channel 'all'"));
        CHECK_THAT(firstError("model m {\n\tmesh a.md5mesh\n\tchannel legs ( *Hips\n}\n"),
                   StartsWith("test.def:4:1: error:") && Contains("expected ')'"));
        text::Diagnostics diags;
        const auto f = parse("model m {\n\tmesh a.md5mesh\n\tchannel EYELIDS ( - * Leye * Reye )\n}\n", diags);
        REQUIRE(f);
        CHECK(f->models[0].channels[0].joints == "-*Leye *Reye");
    }
    SECTION("anims: at most three files, valid names, no duplicates") {
        CHECK_THAT(firstError(
                       "model m {\n\tmesh a.md5mesh\n\tanim walk a.md5anim, b.md5anim, c.md5anim, d.md5anim\n}\n"),
                   StartsWith("test.def:3:45: error:") && Contains("more than 3"));
        CHECK_THAT(firstError("model m {\n\tmesh a.md5mesh\n\tanim a1 a.md5anim\n}\n"),
                   StartsWith("test.def:3:7: error:") && Contains("invalid animation name 'a1'"));
        CHECK_THAT(firstError("model m {\n\tmesh a.md5mesh\n\tanim 12 a.md5anim\n}\n"),
                   Contains("invalid animation name '12'"));
        CHECK_THAT(firstError("model m {\n\tmesh a.md5mesh\n\tanim walk a.md5anim\n\tanim walk b.md5anim\n}\n"),
                   StartsWith("test.def:4:7: error:") && Contains("duplicate anim 'walk'"));
        CHECK_THAT(firstError("model m {\n\tmesh a.md5mesh\n\tanim walk a.md5anim,\n}\n"),
                   StartsWith("test.def:4:1: error:") && Contains("expected an .md5anim file"));
        CHECK_THAT(firstError("model m {\n\tmesh a.md5mesh\n\tanim walk a.md5anim {\n\t\tframe 1 { x\n}\n"),
                   StartsWith("test.def:3:22: error:") && Contains("unterminated { } block of anim 'walk'"));
    }
    SECTION("remove needs something inherited") {
        CHECK_THAT(firstError("model m {\n\tmesh a.md5mesh\n\tremove pain\n}\n"),
                   StartsWith("test.def:3:9: error:") && Contains("inherits nothing"));
        CHECK_THAT(firstError("model m {\n\tinherit p\n\tanim pain2 a.md5anim\n\tremove pain\n}\n"),
                   StartsWith("test.def:4:9: error:") && Contains("own anim 'pain2'"));
    }
    SECTION("unterminated decl") {
        CHECK_THAT(firstError("model m {\n\tmesh a.md5mesh\n"),
                   StartsWith("test.def:3:1: error:") && Contains("missing '}'"));
    }
}

TEST_CASE("inherit after other statements drops them, as the engine's CopyDecl does", "[def]") {
    text::Diagnostics diags;
    const auto f =
        parse("model m {\n\tmesh a.md5mesh\n\tanim af_pose a.md5anim\n\tinherit p\n\toffset ( 0 0 1 )\n}\n", diags);
    REQUIRE(f);
    CHECK(diags.warningCount() == 1);
    CHECK_THAT(firstWarning(diags), StartsWith("test.def:4:2: warning:") && Contains("dropped"));
    const decl::ModelDef& m = f->models[0];
    CHECK(m.name == "m");
    CHECK(m.inherit == "p");
    CHECK_FALSE(m.mesh);
    CHECK(m.anims.empty());
    CHECK(m.offset == decl::Vec3{0, 0, 1});
}

TEST_CASE("anim name rules and aliases follow idDeclModelDef::ParseAnim", "[def]") {
    CHECK(decl::isValidAnimName("af_pose"));
    CHECK(decl::isValidAnimName("ab"));
    CHECK(decl::isValidAnimName("1b"));
    CHECK_FALSE(decl::isValidAnimName(""));
    CHECK_FALSE(decl::isValidAnimName("a"));
    CHECK_FALSE(decl::isValidAnimName("a1"));
    CHECK_FALSE(decl::isValidAnimName("x12"));
    CHECK_FALSE(decl::isValidAnimName("123"));
    CHECK(decl::ModelAnim{"pain12", {}, {}, {}}.alias() == "pain");
    CHECK(decl::ModelAnim{"af_pose", {}, {}, {}}.alias() == "af_pose");
    CHECK(decl::isModelChannelName("Torso"));
    CHECK_FALSE(decl::isModelChannelName("all"));
}

TEST_CASE("parseDef survives hostile nesting and garbage without recursion", "[def]") {
    SECTION("deeply nested anim block") {
        const std::string deep = "model m {\n mesh a.md5mesh\n anim walk a.md5anim " + std::string(200000, '{') +
                                 std::string(200000, '}') + "\n}\n";
        text::Diagnostics diags;
        const auto f = parse(deep, diags);
        REQUIRE(f);
        CHECK(f->models[0].anims[0].block->size() == 2 * 200000 - 2);
    }
    SECTION("deeply nested skipped decl") {
        const std::string deep = "table t " + std::string(200000, '{') + std::string(200000, '}') + "\n";
        text::Diagnostics diags;
        CHECK(parse(deep, diags));
        CHECK(diags.empty());
    }
    SECTION("unbalanced nesting is an error, not a hang") {
        text::Diagnostics diags;
        CHECK_FALSE(parse("export e " + std::string(100000, '{'), diags));
        CHECK(diags.hasErrors());
    }
    SECTION("empty input") {
        text::Diagnostics diags;
        const auto f = parse("", diags);
        REQUIRE(f);
        CHECK(f->entityDefs.empty());
        CHECK(f->models.empty());
    }
}

TEST_CASE("loadDef reports a missing file", "[def]") {
    text::Diagnostics diags;
    CHECK_FALSE(decl::loadDef("/nonexistent/dir/x.def", diags));
    CHECK(diags.hasErrors());
}

TEST_CASE("a backslash between strings continues the string (LEXFL_ALLOWBACKSLASHSTRINGCONCAT)", "[def]") {
    // As in monster_default.def's "editor_var trigger"; the shared lexer joins the strings.
    text::Diagnostics diags;
    const auto f =
        parse("entityDef e {\n\t\"a\"\t\"one, \" \\\n\t\t\"two\" \\ /* c */ \"!\"\n\t\"b\" \"x\"\n}\n", diags);
    INFO(diags.str());
    REQUIRE(f);
    REQUIRE(f->entityDefs[0].keyValues.size() == 2);
    CHECK(f->entityDefs[0].get("a") == "one, two!");
    CHECK(f->entityDefs[0].get("b") == "x");
    CHECK_THAT(firstError("entityDef e {\n\t\"a\" \"x\" \\\n\tb\n}\n"),
               StartsWith("test.def:2:10: error:") && Contains("after '\\'"));
}
