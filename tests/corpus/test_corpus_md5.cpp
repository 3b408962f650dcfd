// The md5 parsers on real files written by other tools (../shared/data; skipped when absent). The facts
// checked here were read off the files with grep, independently of the parser.
#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "TestSupport.h"
#include "afb/decl/Md5Anim.h"
#include "afb/decl/Md5Mesh.h"

using namespace afb;
namespace fs = std::filesystem;

namespace {

bool isMalformedInput(const fs::path& p) {
    for (const fs::path& part : p)
        if (part == "invalid") return true;
    return p.filename() == "malformed_weight_index.md5mesh";
}

// Every .md5mesh/.md5anim under `root`, sorted for a stable order.
std::vector<fs::path> md5Files(const fs::path& root) {
    std::vector<fs::path> files;
    for (const auto& entry : fs::recursive_directory_iterator(root)) {
        if (!entry.is_regular_file()) continue;
        const auto ext = entry.path().extension();
        if (ext == ".md5mesh" || ext == ".md5anim") files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());
    return files;
}

const char* const kZsecDir = "doom3-kroom3/base/models/md5/monsters/zombies";

} // namespace

TEST_CASE("corpus md5: every well-formed file parses without errors", "[corpus][md5]") {
    AFB_REQUIRE_CORPUS(dir);
    std::size_t meshes = 0, anims = 0;
    for (const fs::path& file : md5Files(dir)) {
        if (isMalformedInput(fs::relative(file, dir))) continue;
        INFO(file.string());
        text::Diagnostics diags;
        bool ok = false;
        if (file.extension() == ".md5mesh") {
            ok = decl::loadMd5Mesh(file, diags).has_value();
            ++meshes;
        } else {
            ok = decl::loadMd5Anim(file, diags).has_value();
            ++anims;
        }
        INFO(diags.str());
        CHECK(ok);
        CHECK(diags.errorCount() == 0);
    }
    // At least: 3 zsec meshes, 2 weapons, SimpleCube, Bob, BoarMan; 3 af_pose, 5 other zsec anims, Bob.
    CHECK(meshes >= 8);
    CHECK(anims >= 9);
}

TEST_CASE("corpus md5: every well-formed file reads back equal after writing", "[corpus][md5][writer]") {
    AFB_REQUIRE_CORPUS(dir);
    std::size_t files = 0;
    for (const fs::path& file : md5Files(dir)) {
        if (isMalformedInput(fs::relative(file, dir))) continue;
        INFO(file.string());
        text::Diagnostics diags;
        if (file.extension() == ".md5mesh") {
            const auto mesh = decl::loadMd5Mesh(file, diags);
            REQUIRE(mesh);
            const auto again = decl::parseMd5Mesh(decl::writeMd5Mesh(*mesh), "written.md5mesh", diags);
            INFO(diags.str());
            REQUIRE(again);
            CHECK(*again == *mesh);
        } else {
            const auto anim = decl::loadMd5Anim(file, diags);
            REQUIRE(anim);
            const auto again = decl::parseMd5Anim(decl::writeMd5Anim(*anim), "written.md5anim", diags);
            INFO(diags.str());
            REQUIRE(again);
            CHECK(*again == *anim);
        }
        CHECK(diags.errorCount() == 0);
        ++files;
    }
    CHECK(files >= 17);
}

TEST_CASE("corpus md5: malformed files are rejected with a located, specific error", "[corpus][md5]") {
    AFB_REQUIRE_CORPUS(dir);
    struct Case {
        const char* path;
        const char* needle;
        std::uint32_t line;
    };
    const Case cases[] = {
        {"assimp-md5/test/models/MD5/invalid/InvalidBoneIndex.md5mesh", "refers to joint 999", 23},
        {"assimp-md5/test/models/MD5/invalid/OverflowingTriangleIndex.md5mesh", "triangle index 4294967295", 18},
        {"assimp-md5/test/models/MD5/invalid/OverflowingVertexIndex.md5mesh", "vertex index 4294967295", 15},
        {"assimp-md5/test/models/MD5/invalid/OverflowingWeightIndex.md5mesh", "weight index 4294967295", 21},
        {"assimp-md5/test/models/MD5/malformed_weight_index.md5mesh", "uses weights 1000000..1000001", 18},
        {"assimp-md5/test/models/invalid/empty.md5mesh", "empty", 1},
    };
    std::size_t seen = 0;
    for (const Case& c : cases) {
        const fs::path file = dir / c.path;
        INFO(file.string());
        REQUIRE(fs::exists(file));
        text::Diagnostics diags;
        CHECK_FALSE(decl::loadMd5Mesh(file, diags));
        INFO(diags.str());
        REQUIRE(diags.errorCount() == 1);
        const text::Diagnostic& d = diags.items()[0];
        CHECK(d.message.find(c.needle) != std::string::npos);
        CHECK(d.where.line == c.line);
        CHECK(d.where.file == file.string());
        ++seen;
    }
    // No malformed .md5mesh in the corpus goes untested.
    std::size_t malformed = 0;
    for (const fs::path& file : md5Files(dir))
        if (isMalformedInput(fs::relative(file, dir)) && file.extension() == ".md5mesh") ++malformed;
    CHECK(malformed == seen);
}

TEST_CASE("corpus md5: the zsec af_pose anims are still poses matching their mesh", "[corpus][md5]") {
    AFB_REQUIRE_CORPUS(dir);
    struct Set {
        const char* folder;
        const char* mesh;
        std::size_t joints;
    };
    const Set sets[] = {
        {"zsec_machinegun", "zsecmachinegun.md5mesh", 57},
        {"zsec_pistol", "zsecpistol.md5mesh", 61},
        {"zsec_shotgun", "zsecshotgun.md5mesh", 59},
    };
    for (const Set& s : sets) {
        const fs::path folder = dir / kZsecDir / s.folder;
        INFO(folder.string());
        text::Diagnostics diags;
        const auto mesh = decl::loadMd5Mesh(folder / s.mesh, diags);
        const auto pose = decl::loadMd5Anim(folder / "af_pose.md5anim", diags);
        INFO(diags.str());
        REQUIRE(mesh);
        REQUIRE(pose);
        CHECK(pose->numAnimatedComponents == 0);
        CHECK(pose->frameRate == 24);
        CHECK(pose->frames.size() == 5);
        for (const auto& frame : pose->frames) CHECK(frame.empty());
        CHECK(pose->bounds.size() == 5);

        REQUIRE(mesh->joints.size() == s.joints);
        REQUIRE(pose->hierarchy.size() == s.joints);
        REQUIRE(pose->baseframe.size() == s.joints);
        for (std::size_t i = 0; i < s.joints; ++i) {
            CHECK(pose->hierarchy[i].name == mesh->joints[i].name); // case-sensitive, docs/format.md §7.4
            CHECK(pose->hierarchy[i].parent == mesh->joints[i].parent);
            CHECK(pose->hierarchy[i].flags == 0);
        }
        CHECK_FALSE(decl::hierarchyMismatch(*pose, *mesh));

        // The other anims of the set drive the same skeleton.
        for (const auto& entry : fs::directory_iterator(folder)) {
            if (entry.path().extension() != ".md5anim") continue;
            INFO(entry.path().string());
            const auto anim = decl::loadMd5Anim(entry.path(), diags);
            REQUIRE(anim);
            const auto mismatch = decl::hierarchyMismatch(*anim, *mesh);
            CHECK_FALSE(mismatch);
        }
    }
}

TEST_CASE("corpus md5: known facts of the zsec pistol mesh", "[corpus][md5]") {
    AFB_REQUIRE_CORPUS(dir);
    text::Diagnostics diags;
    const auto mesh = decl::loadMd5Mesh(dir / kZsecDir / "zsec_pistol/zsecpistol.md5mesh", diags);
    INFO(diags.str());
    REQUIRE(mesh);
    CHECK(mesh->commandline == "Exported by Blender 4.2.0 idTech Tools 1.4.0");
    REQUIRE(mesh->joints.size() == 61);
    CHECK(mesh->joints[0].name == "origin");
    CHECK(mesh->joints[0].parent == -1);
    CHECK(mesh->joints[1].name == "Body");
    CHECK(mesh->joints[1].position.z == Approx(44.9718208313));
    CHECK(mesh->joints[9].name == "Lknee");
    CHECK(mesh->joints[9].parent == 5);
    // The .af files spell joints in another case (docs/format.md §8 item 1); lookup ignores it.
    CHECK(decl::findJoint(*mesh, "rupleg") == 10);
    CHECK(decl::findJoint(*mesh, "Rupleg") == 10);
    REQUIRE(mesh->meshes.size() == 4);
    CHECK(mesh->meshes[0].shader == "models/monsters/zsecurity/zsheild");
    CHECK(mesh->meshes[0].verts.size() == 36);
    CHECK(mesh->meshes[3].shader == "models/monsters/skeleton/skeleton01");
    CHECK(decl::totalVertCount(*mesh) == 1479);
    CHECK(decl::totalTriCount(*mesh) == 2154);
    CHECK(decl::totalWeightCount(*mesh) == 3068);
}

TEST_CASE("corpus md5: known facts of Bob and BoarMan", "[corpus][md5]") {
    AFB_REQUIRE_CORPUS(dir);
    const fs::path folder = dir / "assimp-md5/test/models-nonbsd/MD5";
    text::Diagnostics diags;
    const auto bob = decl::loadMd5Mesh(folder / "Bob.md5mesh", diags);
    const auto bobAnim = decl::loadMd5Anim(folder / "Bob.md5anim", diags);
    const auto boar = decl::loadMd5Mesh(folder / "BoarMan.md5mesh", diags);
    INFO(diags.str());
    REQUIRE(bob);
    REQUIRE(bobAnim);
    REQUIRE(boar);

    CHECK(bob->joints.size() == 33);
    CHECK(bob->meshes.size() == 6);
    CHECK(decl::totalVertCount(*bob) == 875);
    CHECK(decl::totalTriCount(*bob) == 1027);
    CHECK(decl::totalWeightCount(*bob) == 1358);

    CHECK(bobAnim->commandline.empty());
    CHECK(bobAnim->frames.size() == 140);
    CHECK(bobAnim->frameRate == 24);
    CHECK(bobAnim->numAnimatedComponents == 198);
    REQUIRE(bobAnim->hierarchy.size() == 33);
    CHECK(bobAnim->hierarchy[2] == decl::Md5HierarchyEntry{"sword", 1, 63, 12});
    for (const auto& frame : bobAnim->frames) CHECK(frame.size() == 198);
    CHECK(bobAnim->frames[0][1] == Approx(0.016430));
    CHECK(bobAnim->baseframe[1].orientation.z == Approx(0.852233));
    CHECK_FALSE(decl::hierarchyMismatch(*bobAnim, *bob));

    // BoarMan: one joint and 14 meshes, some of them empty.
    CHECK(boar->joints.size() == 1);
    REQUIRE(boar->meshes.size() == 14);
    CHECK(boar->meshes[0].verts.empty());
    CHECK(decl::totalVertCount(*boar) == 1552);
    CHECK(decl::totalTriCount(*boar) == 2812);
}
