// The .def parser and the Library on real files (../shared/data; skipped when absent).
#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "TestSupport.h"
#include "afb/decl/Def.h"
#include "afb/decl/Library.h"

using namespace afb;
namespace fs = std::filesystem;
using Catch::Matchers::Contains;

TEST_CASE("corpus: every .def file parses without errors", "[corpus][def]") {
    AFB_REQUIRE_CORPUS(dir);
    std::vector<fs::path> files;
    for (const auto& entry : fs::recursive_directory_iterator(dir))
        if (entry.is_regular_file() && entry.path().extension() == ".def") files.push_back(entry.path());
    std::sort(files.begin(), files.end());
    REQUIRE(files.size() >= 11);

    std::size_t entityDefs = 0, models = 0;
    for (const fs::path& path : files) {
        text::Diagnostics diags;
        const auto def = decl::loadDef(path, diags);
        INFO(path.string() << "\n" << diags.str());
        REQUIRE(def);
        CHECK(diags.errorCount() == 0);
        entityDefs += def->entityDefs.size();
        models += def->models.size();
    }
    CHECK(entityDefs > 100);
    CHECK(models > 50);
}

TEST_CASE("corpus: known decls read as written", "[corpus][def]") {
    AFB_REQUIRE_CORPUS(dir);
    const fs::path base = dir / "doom3-kroom3/base";
    text::Diagnostics diags;
    const auto def = decl::loadDef(base / "def/monster_zsec_pistol.def", diags);
    INFO(diags.str());
    REQUIRE(def);
    REQUIRE(def->models.size() == 2);
    const decl::ModelDef& m = def->models[0];
    CHECK(m.name == "model_monster_zsec_pistol");
    CHECK(m.skin == "skins/monsters/zombies/zsecurity_pistol.skin");
    REQUIRE(m.channels.size() == 2);
    CHECK(m.channels[1].joints == "origin Body Body2 *Hips -*Waist SPINNER");
    const decl::ModelAnim* walk = m.findAnim("walk");
    REQUIRE(walk);
    REQUIRE(walk->block);
    CHECK_THAT(*walk->block, Contains("frame 22"));
    CHECK(def->models[1].inherit == "model_monster_zsec_pistol");
    REQUIRE(def->entityDefs.size() == 2);
    CHECK(def->entityDefs[0].get("ragdoll") == "monster_zombie_security_pistol");
    CHECK(def->entityDefs[0].get("look_joint Ruparm") == "-0.4 0 0");

    // env.def writes a quoted "skin" keyword in a model decl, and holds export decls to skip.
    text::Diagnostics envDiags;
    const auto env = decl::loadDef(base / "def/env.def", envDiags);
    INFO(envDiags.str());
    REQUIRE(env);
    const auto boney = std::find_if(env->models.begin(), env->models.end(),
                                    [](const decl::ModelDef& x) { return x.name == "env_ragdoll_boney"; });
    REQUIRE(boney != env->models.end());
    CHECK(boney->skin == "skins/monsters/zombies/boney.skin");
}

TEST_CASE("corpus: the zsec entities resolve to mesh, af_pose and figure", "[corpus][library]") {
    AFB_REQUIRE_CORPUS(dir);
    // The Library reports absolute, lexically normal paths (the corpus folder may be given as
    // "x/../shared/data").
    const fs::path base = fs::absolute(dir / "doom3-kroom3/base").lexically_normal();
    text::Diagnostics diags;
    const auto lib = decl::Library::open(dir / "doom3-kroom3/base", diags);
    INFO(diags.str());
    REQUIRE(lib);
    CHECK(diags.errorCount() == 0);
    CHECK(lib->failedFiles().empty());
    CHECK(lib->files().size() == 18 + 11);
    CHECK(lib->baseDir() == base);

    SECTION("the three complete sets") {
        struct Expected {
            const char* entity;
            const char* folder;
            const char* mesh;
            const char* figure;
            std::vector<std::string> chain;
        };
        const std::vector<Expected> expected = {
            {"monster_zsec_pistol",
             "zsec_pistol",
             "zsecpistol.md5mesh",
             "monster_zombie_security_pistol",
             {"monster_zsec_pistol", "zombie_default", "monster_default"}},
            {"monster_zsec_shotgun",
             "zsec_shotgun",
             "zsecshotgun.md5mesh",
             "monster_zombie_security_shotgun",
             {"monster_zsec_shotgun", "monster_zsec_pistol", "zombie_default", "monster_default"}},
            {"monster_zsec_machinegun",
             "zsec_machinegun",
             "zsecmachinegun.md5mesh",
             "monster_zombie_security_machinegun",
             {"monster_zsec_machinegun", "monster_zsec_shotgun", "monster_zsec_pistol", "zombie_default",
              "monster_default"}},
        };
        for (const Expected& e : expected) {
            text::Diagnostics rd;
            const auto r = lib->resolveEntity(e.entity, rd);
            INFO(e.entity << "\n" << rd.str());
            REQUIRE(r);
            CHECK(rd.errorCount() == 0);
            const fs::path folder = base / "models/md5/monsters/zombies" / e.folder;
            CHECK(r->entityChain == e.chain);
            CHECK(r->modelName == std::string("model_") + e.entity);
            CHECK(r->meshPath == folder / e.mesh);
            CHECK(r->afPoseAnim == "af_pose");
            CHECK(r->afPosePath == folder / "af_pose.md5anim");
            CHECK(fs::is_regular_file(r->meshPath));
            CHECK(fs::is_regular_file(r->afPosePath));
            CHECK(r->figureKey == "ragdoll");
            CHECK(r->figureName == e.figure);
            CHECK(r->figureFile == base / "af" / (std::string(e.figure) + ".af"));
            CHECK(r->figureLocation.line == 8);
            CHECK(r->get("model") == std::string("model_") + e.entity); // the child's model, not the parent's
        }
    }

    SECTION("a model decl that inherits") {
        text::Diagnostics rd;
        const auto r = lib->resolveEntity("monster_zsec_pistol_slowfire", rd);
        INFO(rd.str());
        REQUIRE(r);
        CHECK(r->modelChain ==
              std::vector<std::string>{"model_monster_zsec_pistol_slowfire", "model_monster_zsec_pistol"});
        CHECK(r->meshPath == base / "models/md5/monsters/zombies/zsec_pistol/zsecpistol.md5mesh");
        CHECK(r->figureName == "monster_zombie_security_pistol");
    }

    SECTION("an entity whose mesh is not in the corpus names the missing file") {
        text::Diagnostics rd;
        CHECK_FALSE(lib->resolveEntity("env_ragdoll_boney", rd));
        CHECK_THAT(rd.str(), Contains("mesh file 'models/md5/monsters/zombies/boney/boney.md5mesh' not found"));
    }
}
