// Unit tests of decl::Library: indexing a content folder and resolving entity → model → mesh/af_pose/figure
// (docs/format.md §7.1, §7.2), on a temporary folder written by the tests.
#include <catch2/catch.hpp>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>

#include "TestSupport.h"
#include "afb/decl/Library.h"

using namespace afb;
namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using Catch::Matchers::EndsWith;
using Catch::Matchers::StartsWith;

namespace {

// A content folder under the system temp folder, removed when the test ends.
class TempBase {
  public:
    TempBase() {
        static std::atomic<int> counter{0};
        const auto stamp = std::chrono::steady_clock::now().time_since_epoch().count();
        // Normal and absolute, as the Library reports paths.
        m_root = (fs::absolute(fs::temp_directory_path()) /
                  ("afb_test_library_" + std::to_string(stamp) + "_" + std::to_string(counter++)))
                     .lexically_normal();
        fs::create_directories(m_root);
    }
    ~TempBase() {
        std::error_code ec;
        fs::remove_all(m_root, ec);
    }
    TempBase(const TempBase&) = delete;
    TempBase& operator=(const TempBase&) = delete;

    const fs::path& root() const { return m_root; }
    void write(const std::string& relative, const std::string& content) const {
        const fs::path path = m_root / relative;
        fs::create_directories(path.parent_path());
        std::ofstream(path, std::ios::binary) << content;
    }

  private:
    fs::path m_root;
};

const std::string kFigure = R"(
articulatedFigure fig_a {
	body "b" {
		joint "origin"
		model box( ( -1, -1, -1 ), ( 1, 1, 1 ) )
	}
}
)";

// Line numbers in the tests below refer to this text.
const std::string kDefs = R"(model model_parent {
	mesh		models/m/parent.md5mesh
	skin		skins/s.skin
	offset		( 0 0 4 )
	channel torso	( *Waist )
	anim af_pose	models/m/af_pose.md5anim
	anim idle		models/m/idle.md5anim
	anim pain1		models/m/pain1.md5anim
	anim pain2		models/m/pain2.md5anim
}
model model_child {
	inherit model_parent
	channel TORSO	( *Chest )
	anim idle		models/m/idle2.md5anim { frame 1 sound x }
	anim run		models/m/run.md5anim
	remove pain
}
model Model_NoPose {
	mesh		models/m/parent.md5mesh
	anim idle	models/m/idle.md5anim
}
model model_cycle_a { inherit model_cycle_b }
model model_cycle_b { inherit model_cycle_a }
model model_variant {
	mesh		models/m/parent.md5mesh
	anim af_pose2	models/m/af_pose.md5anim
}
model model_bad_remove {
	inherit model_parent
	remove walk
}
model model_missing_mesh {
	mesh		models/m/nothere.md5mesh
	anim af_pose	models/m/af_pose.md5anim
}
model model_escape {
	mesh		../outside.md5mesh
	anim af_pose	models/m/af_pose.md5anim
}
entityDef base_monster {
	"health"			"10"
	"size"				"1"
	"articulatedFigure"	"fig_a.af"
}
entityDef monster {
	"inherit"	"base_monster"
	"model"		"model_child"
	"health"	"20"
}
entityDef ent_cycle1 { "inherit" "ent_cycle2" }
entityDef ent_cycle2 { "inherit" "ent_cycle3" }
entityDef ent_cycle3 { "inherit" "ENT_CYCLE1" }
entityDef ent_missing_parent { "inherit" "nobody" }
entityDef ent_nopose { "model" "Model_NoPose" "ragdoll" "fig_a" }
entityDef ent_mesh_model { "model" "models/m/parent.md5mesh" "ragdoll" "fig_a" }
entityDef ent_missing_fig { "model" "model_parent" "ragdoll" "fig_zzz" }
entityDef ent_no_fig { "model" "model_parent" }
entityDef ent_both { "model" "model_parent" "ragdoll" "fig_b" "articulatedFigure" "fig_a" }
entityDef ent_variant { "model" "model_variant" "ragdoll" "fig_a" }
entityDef diamond_top { "a" "top" "b" "top" "c" "top" }
entityDef diamond_left { "inherit" "diamond_top" "a" "left" }
entityDef diamond_right { "inherit" "diamond_top" "b" "right" "c" "right" }
entityDef diamond { "inherit" "diamond_left" "inherit2" "diamond_right" "model" "model_parent" "ragdoll" "fig_a" }
entityDef ent_bad_remove { "model" "model_bad_remove" "ragdoll" "fig_a" }
entityDef ent_missing_mesh { "model" "model_missing_mesh" "ragdoll" "fig_a" }
entityDef ent_escape { "model" "model_escape" "ragdoll" "fig_a" }
)";

// Writes the standard test folder: two .af files, three .def files (one broken), the referenced model files.
void writeStandard(const TempBase& base) {
    base.write("af/a.af", kFigure);
    base.write("af/b.af", "articulatedFigure fig_b {\n\tbody \"b\" {\n\t\tjoint \"origin\"\n\t}\n}\n"
                          "articulatedFigure FIG_A {\n\tbody \"c\" {\n\t\tjoint \"origin\"\n\t}\n}\n");
    base.write("def/x.def", kDefs);
    base.write("def/y.def", "\nentityDef MONSTER {\n\t\"model\" \"model_parent\"\n}\n");
    base.write("def/broken.def", "entityDef broken_ent {\n\t\"model\" \"m\"\n\tmodel \"m\"\n}\n");
    base.write("def/notes.txt", "not a def file {");
    base.write("models/m/parent.md5mesh", "MD5Version 10\n");
    base.write("models/m/af_pose.md5anim", "MD5Version 10\n");
}

std::string joined(const text::Diagnostics& diags) { return diags.str(); }

} // namespace

TEST_CASE("Library::open indexes af/ and def/, reports broken files and keeps the rest", "[library]") {
    TempBase base;
    writeStandard(base);
    text::Diagnostics diags;
    const auto lib = decl::Library::open(base.root(), diags);
    INFO(diags.str());
    REQUIRE(lib);

    SECTION("a broken file is an error and none of its decls is indexed") {
        CHECK(diags.errorCount() == 1);
        CHECK_THAT(joined(diags), Contains("broken.def:3:2: error:") && Contains("expected a \"quoted\" key"));
        REQUIRE(lib->failedFiles().size() == 1);
        CHECK(lib->failedFiles()[0].filename() == "broken.def");
        CHECK_FALSE(lib->findEntityDef("broken_ent"));
        CHECK(lib->files().size() == 4); // a.af, b.af, x.def, y.def — not notes.txt
    }

    SECTION("lookups are case-insensitive and give the file") {
        const auto e = lib->findEntityDef("MoNsTeR");
        REQUIRE(e);
        CHECK(e->decl.name == "monster");
        CHECK(e->file.filename() == "x.def");
        CHECK(e->file.is_absolute());
        CHECK(e->decl.location.line == 45);
        const auto m = lib->findModelDef("model_noPOSE");
        REQUIRE(m);
        CHECK(m->decl.name == "Model_NoPose");
        const auto f = lib->findFigure("FIG_b");
        REQUIRE(f);
        CHECK(f->decl.name == "fig_b");
        CHECK(f->file.filename() == "b.af");
        CHECK_FALSE(lib->findFigure("model_parent")); // decl types are separate namespaces
        CHECK_FALSE(lib->findEntityDef("nothing"));
    }

    SECTION("duplicates (case-insensitive) are warnings with both locations; the first in path order wins") {
        CHECK_THAT(joined(diags),
                   Contains("y.def:2:1: warning: entityDef 'MONSTER' is also defined at ") && Contains("x.def:45:1"));
        CHECK_THAT(joined(diags), Contains("b.af:6:1: warning: articulatedFigure 'FIG_A' is also defined at ") &&
                                      Contains("a.af:2:1"));
        CHECK(lib->findEntityDef("monster")->file.filename() == "x.def");
        CHECK(lib->findFigure("fig_a")->file.filename() == "a.af");
        CHECK(lib->findFigure("fig_a")->decl.bodies[0].name == "b");
    }

    SECTION("name lists") {
        const auto figures = lib->figureNames();
        CHECK(figures == std::vector<std::string>{"fig_a", "fig_b"});
        CHECK(lib->entityDefNames().size() == 19);
        CHECK(lib->modelDefNames().front() == "model_bad_remove");
    }
}

TEST_CASE("Library::open fails only without a folder", "[library]") {
    text::Diagnostics diags;
    CHECK_FALSE(decl::Library::open("/nonexistent/afb/base", diags));
    CHECK_THAT(joined(diags), Contains("/nonexistent/afb/base: error: content folder not found"));

    TempBase empty;
    text::Diagnostics emptyDiags;
    const auto lib = decl::Library::open(empty.root(), emptyDiags);
    REQUIRE(lib);
    CHECK(emptyDiags.errorCount() == 0);
    CHECK(emptyDiags.warningCount() == 1);
    CHECK_THAT(joined(emptyDiags), Contains("no af/ or def/ folder"));
    CHECK(lib->files().empty());
}

TEST_CASE("resolveEntity merges inherit chains and finds mesh, af_pose and figure", "[library]") {
    TempBase base;
    writeStandard(base);
    text::Diagnostics openDiags;
    const auto lib = decl::Library::open(base.root(), openDiags);
    REQUIRE(lib);

    text::Diagnostics diags;
    const auto r = lib->resolveEntity("MONSTER", diags);
    INFO(diags.str());
    REQUIRE(r);
    CHECK(diags.empty());

    CHECK(r->entityName == "monster");
    CHECK(r->entityLocation.line == 45);
    CHECK(r->entityChain == std::vector<std::string>{"monster", "base_monster"});
    CHECK(r->get("health") == "20"); // the child wins
    CHECK(r->get("SIZE") == "1");    // inherited
    CHECK_FALSE(r->get("inherit"));  // consumed, as the engine deletes it
    REQUIRE(r->keyValues.size() == 4);
    CHECK(r->keyValues[0].first == "model"); // the child's keys first, then the inherited ones it lacks
    CHECK(r->keyValues[3].first == "articulatedFigure");

    CHECK(r->modelName == "model_child");
    CHECK(r->modelLocation.line == 11);
    CHECK(r->modelChain == std::vector<std::string>{"model_child", "model_parent"});
    CHECK(r->model.mesh == "models/m/parent.md5mesh");
    CHECK(r->model.skin == "skins/s.skin");
    CHECK(r->model.offset == decl::Vec3{0, 0, 4});
    CHECK_FALSE(r->model.inherit);
    CHECK(r->model.removes.empty());
    REQUIRE(r->model.channels.size() == 1); // TORSO replaces torso (channel names are case-insensitive)
    CHECK(r->model.channels[0].joints == "*Chest");
    REQUIRE(r->model.anims.size() == 3); // pain1 and pain2 removed by alias, idle overridden in place, run added
    CHECK(r->model.anims[0].name == "af_pose");
    CHECK(r->model.anims[1].name == "idle");
    CHECK(r->model.anims[1].files[0] == "models/m/idle2.md5anim");
    CHECK(r->model.anims[1].block == std::string(" frame 1 sound x "));
    CHECK(r->model.anims[2].name == "run");

    CHECK(r->meshPath == base.root() / "models/m/parent.md5mesh");
    CHECK(r->meshPath.is_absolute());
    CHECK(r->afPoseAnim == "af_pose");
    CHECK(r->afPosePath == base.root() / "models/m/af_pose.md5anim");
    CHECK(r->figureKey == "articulatedFigure");
    CHECK(r->figureName == "fig_a"); // "fig_a.af" with its extension stripped, as idAF::Load does
    CHECK(r->figureLocation.line == 2);
    CHECK(r->figureFile.filename() == "a.af");
}

TEST_CASE("resolveEntity follows diamonds in inherit order", "[library]") {
    TempBase base;
    writeStandard(base);
    text::Diagnostics diags;
    const auto lib = decl::Library::open(base.root(), diags);
    REQUIRE(lib);
    const auto r = lib->resolveEntity("diamond", diags);
    INFO(diags.str());
    REQUIRE(r);
    CHECK(r->entityChain == std::vector<std::string>{"diamond", "diamond_left", "diamond_top", "diamond_right"});
    CHECK(r->get("a") == "left");
    CHECK(r->get("b") == "top"); // diamond_left's parents fill in before diamond_right (idDict::SetDefaults order)
    CHECK(r->get("c") == "top");
    CHECK_FALSE(r->get("inherit2"));
}

TEST_CASE("resolveEntity reports each kind of broken reference", "[library]") {
    TempBase base;
    writeStandard(base);
    text::Diagnostics openDiags;
    const auto lib = decl::Library::open(base.root(), openDiags);
    REQUIRE(lib);
    const auto errorOf = [&](const std::string& name) {
        text::Diagnostics diags;
        CHECK_FALSE(lib->resolveEntity(name, diags));
        CHECK(diags.hasErrors());
        return diags.str();
    };

    CHECK_THAT(errorOf("nope"), Contains("error: entityDef 'nope' not found"));
    CHECK_THAT(errorOf("ent_cycle2"),
               Contains("x.def:50:1: error: entityDef inherit cycle: ent_cycle2 -> ent_cycle3 -> ent_cycle1 -> "
                        "ent_cycle2"));
    CHECK_THAT(errorOf("ent_missing_parent"),
               Contains("x.def:53:1: error: entityDef 'ent_missing_parent' inherits 'nobody', which is not defined"));
    CHECK_THAT(errorOf("ent_nopose"),
               Contains("x.def:18:1: error: model decl Model_NoPose has no anim af_pose (a ragdoll needs it)"));
    CHECK_THAT(errorOf("ent_mesh_model"), Contains("a mesh file, not a model decl"));
    CHECK_THAT(errorOf("ent_missing_fig"), Contains("articulatedFigure 'fig_zzz'") && Contains("not found in af/"));
    CHECK_THAT(errorOf("ent_no_fig"), Contains("neither \"articulatedFigure\" nor \"ragdoll\""));
    CHECK_THAT(errorOf("ent_bad_remove"),
               Contains("x.def:28:1: error: model decl 'model_bad_remove' removes anim 'walk', which it does not "
                        "inherit"));
    CHECK_THAT(errorOf("ent_missing_mesh"),
               Contains("x.def:32:1: error: mesh file 'models/m/nothere.md5mesh' not found"));
    CHECK_THAT(errorOf("ent_escape"), Contains("mesh path '../outside.md5mesh' must be relative"));

    text::Diagnostics diags;
    CHECK_FALSE(lib->resolveModel("model_cycle_a", diags));
    CHECK_THAT(diags.str(),
               Contains("error: model decl inherit cycle: model_cycle_a -> model_cycle_b -> model_cycle_a"));
}

TEST_CASE("resolveEntity: figure key choice and af_pose variants", "[library]") {
    TempBase base;
    writeStandard(base);
    text::Diagnostics openDiags;
    const auto lib = decl::Library::open(base.root(), openDiags);
    REQUIRE(lib);

    SECTION("articulatedFigure wins over ragdoll, with a warning when they differ") {
        text::Diagnostics diags;
        const auto r = lib->resolveEntity("ent_both", diags);
        REQUIRE(r);
        CHECK(r->figureKey == "articulatedFigure");
        CHECK(r->figureName == "fig_a");
        CHECK(diags.warningCount() == 1);
        CHECK_THAT(diags.str(), Contains("sets both"));
    }
    SECTION("a lone random variant af_pose2 is what GetAnim(\"af_pose\") finds") {
        text::Diagnostics diags;
        const auto r = lib->resolveEntity("ent_variant", diags);
        REQUIRE(r);
        CHECK(r->afPoseAnim == "af_pose2");
        CHECK(r->figureKey == "ragdoll");
        CHECK(diags.empty());
    }
}

TEST_CASE("long inherit chains resolve without recursion", "[library]") {
    TempBase base;
    constexpr int kDepth = 20000;
    std::string defs = "model m0 {\n mesh models/m.md5mesh\n anim af_pose models/p.md5anim\n}\n"
                       "entityDef e0 { \"model\" \"m" +
                       std::to_string(kDepth - 1) + "\" \"ragdoll\" \"fig_a\" }\n";
    for (int i = 1; i < kDepth; ++i) {
        defs += "model m" + std::to_string(i) + " { inherit m" + std::to_string(i - 1) + " }\n";
        defs += "entityDef e" + std::to_string(i) + " { \"inherit\" \"e" + std::to_string(i - 1) + "\" \"k" +
                std::to_string(i) + "\" \"v\" }\n";
    }
    base.write("def/chain.def", defs);
    base.write("af/a.af", kFigure);
    base.write("models/m.md5mesh", "x");
    base.write("models/p.md5anim", "x");
    text::Diagnostics diags;
    const auto lib = decl::Library::open(base.root(), diags);
    REQUIRE(lib);
    const auto r = lib->resolveEntity("e" + std::to_string(kDepth - 1), diags);
    INFO(diags.str());
    REQUIRE(r);
    CHECK(r->entityChain.size() == kDepth);
    CHECK(r->modelChain.size() == kDepth);
    CHECK(r->keyValues.size() == kDepth + 1);
    CHECK(r->afPosePath == base.root() / "models/p.md5anim");
}

TEST_CASE("the repository's bundled content resolves", "[library]") {
    text::Diagnostics diags;
    const auto lib = decl::Library::open(test::sourceDir(), diags);
    INFO(diags.str());
    REQUIRE(lib);
    CHECK(diags.errorCount() == 0);
    const auto r = lib->resolveEntity("chain", diags);
    REQUIRE(r);
    CHECK_THAT(r->meshPath.string(), EndsWith("models/md5/props/chain/chain.md5mesh"));
    CHECK_THAT(r->afPosePath.string(), EndsWith("models/md5/props/chain/af_pose.md5anim"));
    CHECK(r->figureName == "chain");
    CHECK(r->figureKey == "articulatedFigure");
}
