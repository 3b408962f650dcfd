// afb gen on rigs as they come: the units and up axis of an md5mesh (a one unit tall fixture authored in metres),
// vertices far from the bone that weighs them (a prop skinned to the head) left out of the bodies, and small bones
// merged into a body only while they do not stretch it (maxMergeGrowth).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "TestSupport.h"
#include "afb/decl/Md5Mesh.h"
#include "afb/gen/Generate.h"

namespace {

namespace fs = std::filesystem;
using afb::gen::RigUnits;
constexpr double kMetresPerUnit = 0.0254;

fs::path tinyMetres() { return afb::test::sourceDir() / "tests/gen/data/tiny_metres.md5mesh"; }

// The fixture's joints as its file writes them (metres, Z up).
const Eigen::Vector3d kHeadInFile(0, 0, 0.8), kLeftThighInFile(0, 0.07, 0.4);

const afb::gen::RigJoint& joint(const afb::gen::Rig& rig, const std::string& name) {
    for (const auto& j : rig.joints)
        if (j.name == name) return j;
    FAIL("no joint " << name);
    return rig.joints.front();
}

// Every vertex of the md5mesh afb gen writes, skinned at its bind pose, is where the rig has it.
double writtenVertexGap(const afb::gen::Rig& rig, const afb::gen::Generated& generated) {
    const auto skinned = afb::gen::skinnedBindVertices(generated.mesh);
    double gap = 0;
    for (std::size_t s = 0; s < rig.surfaces.size(); ++s)
        for (std::size_t v = 0; v < rig.surfaces[s].vertices.size(); ++v)
            gap = std::max(gap, (skinned[s][v] - rig.surfaces[s].vertices[v].position).norm());
    return gap;
}

std::optional<afb::gen::Generated> generate(const afb::gen::Rig& rig, afb::text::Diagnostics& diags,
                                            const afb::gen::GenRules& rules = afb::gen::defaultRules()) {
    afb::gen::GenOptions options;
    options.name = "test_figure";
    options.rules = rules;
    return afb::gen::generateFigure(rig, options, diags);
}

} // namespace

TEST_CASE("gen: an md5mesh one unit tall is read as metres, and --unit-m and --height override that", "[gen]") {
    afb::text::Diagnostics diags;
    const auto rig = afb::gen::importRig(tinyMetres(), {}, diags);
    INFO(diags.str());
    REQUIRE(rig);
    CHECK(rig->units.source == RigUnits::Source::Detected);
    CHECK(rig->units.metresPerUnit == 1.0);
    CHECK(rig->units.fileHeight == Approx(1.0));
    CHECK(afb::gen::modelHeight(*rig) * kMetresPerUnit == Approx(1.0));
    CHECK((joint(*rig, "head").bind.position * kMetresPerUnit - kHeadInFile).norm() < 1e-9);
    const auto generated = generate(*rig, diags);
    REQUIRE(generated);
    CHECK_FALSE(diags.hasErrors());
    CHECK(writtenVertexGap(*rig, *generated) < 1e-6);
    // Five boxes, 25.84 litres: at 500 kg/m³ the bodies that enclose them weigh at least 12.92 kg (rounded to 0.1).
    CHECK(generated->totalMassKg >= 12.85);
    CHECK(generated->totalMassKg < 2 * 12.9);

    afb::gen::ImportOptions half;
    half.metresPerUnit = 0.5;
    const auto halfRig = afb::gen::importRig(tinyMetres(), half, diags);
    REQUIRE(halfRig);
    CHECK(halfRig->units.source == RigUnits::Source::Option);
    CHECK(afb::gen::modelHeight(*halfRig) * kMetresPerUnit == Approx(0.5));
    CHECK((joint(*halfRig, "head").bind.position * kMetresPerUnit - 0.5 * kHeadInFile).norm() < 1e-9);

    afb::gen::ImportOptions tall;
    tall.heightM = 1.8;
    const auto tallRig = afb::gen::importRig(tinyMetres(), tall, diags);
    REQUIRE(tallRig);
    CHECK(tallRig->units.source == RigUnits::Source::Height);
    CHECK(afb::gen::modelHeight(*tallRig) * kMetresPerUnit == Approx(1.8));
}

TEST_CASE("gen: a Doom-sized md5mesh keeps Doom units", "[gen]") {
    afb::text::Diagnostics diags;
    const auto rig = afb::gen::importRig(afb::test::sourceDir() / "models/md5/humanoid/humanoid.md5mesh", {}, diags);
    REQUIRE(rig);
    CHECK(rig->units.source == RigUnits::Source::Format);
    CHECK(rig->units.metresPerUnit == kMetresPerUnit);
    CHECK(afb::gen::modelHeight(*rig) == Approx(rig->units.fileHeight));
}

// --up y: the model's Y becomes Doom's Z (up) and its Z Doom's X (forward), as for every assimp format.
TEST_CASE("gen: --up y turns an md5mesh as it turns other formats", "[gen]") {
    afb::text::Diagnostics diags;
    afb::gen::ImportOptions yUp;
    yUp.up = 'y';
    yUp.metresPerUnit = 1;
    const auto rig = afb::gen::importRig(tinyMetres(), yUp, diags);
    INFO(diags.str());
    REQUIRE(rig);
    CHECK(rig->units.up == 'y');
    const auto doom = [](const Eigen::Vector3d& file) { return Eigen::Vector3d(file.z(), file.x(), file.y()); };
    CHECK((joint(*rig, "head").bind.position * kMetresPerUnit - doom(kHeadInFile)).norm() < 1e-9);
    CHECK((joint(*rig, "l_thigh").bind.position * kMetresPerUnit - doom(kLeftThighInFile)).norm() < 1e-9);
    // The joints turn with the positions: the written mesh skins to the same vertices.
    const auto generated = generate(*rig, diags);
    REQUIRE(generated);
    CHECK(writtenVertexGap(*rig, *generated) < 1e-6);
    // Read with Z up (the default), the same file stands 1 m tall; read Y up it lies along Doom's X.
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e9), hi = -lo;
    for (const auto& v : rig->surfaces[0].vertices) {
        lo = lo.cwiseMin(v.position * kMetresPerUnit);
        hi = hi.cwiseMax(v.position * kMetresPerUnit);
    }
    CHECK(hi.x() - lo.x() == Approx(1.0));
    CHECK(hi.z() - lo.z() == Approx(0.26));
}

namespace {

// Points on the surface of an axis-aligned box (a 5 × 5 × 5 grid's outer layer: 98 points), Doom units.
void addBox(afb::gen::RigSurface& s, int joint, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int steps = 4) {
    for (int i = 0; i <= steps; ++i)
        for (int j = 0; j <= steps; ++j)
            for (int k = 0; k <= steps; ++k) {
                if (i % steps != 0 && j % steps != 0 && k % steps != 0) continue;
                afb::gen::RigVertex v;
                v.position = lo + (hi - lo).cwiseProduct(Eigen::Vector3d(i, j, k) / steps);
                v.influences = {{joint, 1.0}};
                s.vertices.push_back(v);
            }
}

// A pelvis, a chest and a head, each a box of vertices weighted to its bone, and a 3-unit cube skinned to the
// head 40 units behind it (a prop without a bone of its own), in its own surface.
afb::gen::Rig propRig() {
    afb::gen::Rig rig;
    rig.joints = {{"origin", -1, {}},
                  {"pelvis", 0, {Eigen::Matrix3d::Identity(), {0, 0, 36}}},
                  {"chest", 1, {Eigen::Matrix3d::Identity(), {0, 0, 48}}},
                  {"head", 2, {Eigen::Matrix3d::Identity(), {0, 0, 64}}}};
    afb::gen::RigSurface body{"body", "models/test/body", {}, {}};
    addBox(body, 1, {-5, -8, 36}, {5, 8, 48});
    addBox(body, 2, {-6, -10, 48}, {6, 10, 64});
    addBox(body, 3, {-4, -3.5, 64}, {4, 3.5, 74});
    afb::gen::RigSurface prop{"helmet_crest", "models/test/crest", {}, {}};
    addBox(prop, 3, {-41.5, -1.5, 68.5}, {-38.5, 1.5, 71.5}, 2);
    rig.surfaces = {body, prop};
    return rig;
}

// The three boxes' volume, 6320 units³, at 500 kg/m³.
const double kMassWithoutPropKg = 500 * 6320 * kMetresPerUnit * kMetresPerUnit * kMetresPerUnit;

} // namespace

TEST_CASE("gen: vertices far from the bone that weighs them are reported and no body is fitted to them", "[gen]") {
    const afb::gen::Rig rig = propRig();
    afb::text::Diagnostics diags;
    const auto generated = generate(rig, diags);
    REQUIRE(generated);
    INFO(diags.str());
    CHECK_FALSE(diags.hasErrors());
    CHECK(generated->totalMassKg == Approx(kMassWithoutPropKg).epsilon(0.02));
    REQUIRE(generated->stray.size() == 1);
    CHECK(generated->stray[0].joint == "head");
    CHECK(generated->stray[0].vertices == 26);
    CHECK(generated->stray[0].boneVertices == 98 + 26);
    CHECK(generated->stray[0].nearestM > generated->stray[0].limitM);
    CHECK(diags.str().find("26 of the 124 vertices weighted to bone \"head\"") != std::string::npos);
    // The head's body holds its box and stays clear of the prop (40 units behind it).
    for (const auto& b : generated->bodies)
        if (b.joint == "head") CHECK(b.centre.x() > -5);

    // With the rule off, the head's body stretches over the prop: from x = -41.5 to 4, over 5 times its box.
    afb::gen::GenRules off = afb::gen::defaultRules();
    off.strayFactor = 0;
    afb::text::Diagnostics offDiags;
    const auto stretched = generate(rig, offDiags, off);
    REQUIRE(stretched);
    CHECK(stretched->stray.empty());
    CHECK(stretched->totalMassKg > 1.3 * kMassWithoutPropKg);
    for (const auto& b : stretched->bodies)
        if (b.joint == "head") CHECK(b.centre.x() < -15);
}

TEST_CASE("gen: a surface named by skipSurfaces is not fitted", "[gen]") {
    afb::text::Diagnostics diags;
    const auto rules = afb::gen::parseRules(R"({"strayFactor": 0, "skipSurfaces": ["crest"]})", "rules.json", diags);
    REQUIRE(rules);
    const auto generated = generate(propRig(), diags, *rules);
    REQUIRE(generated);
    CHECK(generated->totalMassKg == Approx(kMassWithoutPropKg).epsilon(0.02));
    REQUIRE(generated->stray.size() == 1);
    CHECK(generated->stray[0].surface == "helmet_crest");
    CHECK(generated->stray[0].vertices == 26);
    CHECK_FALSE(afb::gen::parseRules(R"({"strayFactor": -1})", "rules.json", diags));
    CHECK(diags.str().find("rules.json: error: \"strayFactor\" must be in [0, 1000]") != std::string::npos);
}

// A real rig whose bones carry no prop loses no vertex to the rule (the bundled humanoid: tubes round its bones).
TEST_CASE("gen: the bundled humanoid has no stray vertices", "[gen]") {
    afb::text::Diagnostics diags;
    const auto rig = afb::gen::importRig(afb::test::sourceDir() / "models/md5/humanoid/humanoid.md5mesh", {}, diags);
    REQUIRE(rig);
    std::vector<afb::gen::StrayVertices> report;
    const auto mask = afb::gen::strayVertices(*rig, afb::gen::defaultRules(), report);
    CHECK(report.empty());
    REQUIRE(mask.size() == rig->surfaces.size());
}

namespace {

// propRig's pelvis, chest and head without the prop, and a small bone `name` (6 vertices: too few for a body of its
// own, so it merges into the head's) at `joint` under the head, its vertices a 2-unit cube centred at `cluster`.
afb::gen::Rig smallBoneRig(const std::string& name, const Eigen::Vector3d& joint, const Eigen::Vector3d& cluster) {
    afb::gen::Rig rig = propRig();
    rig.surfaces.pop_back();
    rig.joints.push_back({name, 3, {Eigen::Matrix3d::Identity(), joint}});
    afb::gen::RigSurface small{"small", "models/test/small", {}, {}};
    for (int k = 0; k < 6; ++k) {
        afb::gen::RigVertex v;
        v.position = cluster + Eigen::Vector3d(k % 2 ? 1 : -1, k / 2 - 1.0, k % 3 - 1.0);
        v.influences = {{4, 1.0}};
        small.vertices.push_back(v);
    }
    rig.surfaces.push_back(small);
    return rig;
}

const afb::gen::GeneratedBody& bodyOf(const afb::gen::Generated& g, const std::string& joint) {
    for (const auto& b : g.bodies)
        if (b.joint == joint) return b;
    FAIL("no body at " << joint);
    return g.bodies.front();
}

} // namespace

// The head's box is 8 × 7 × 10 units (x -4..4, z 64..74); a braid hangs 20 units below its front edge.
TEST_CASE("gen: a small bone hanging far off a body is left out of it and reported (maxMergeGrowth)", "[gen]") {
    const afb::gen::Rig rig = smallBoneRig("braid", {10, 0, 50}, {10, 0, 44});
    afb::text::Diagnostics diags;
    const auto generated = generate(rig, diags);
    REQUIRE(generated);
    INFO(diags.str());
    CHECK_FALSE(diags.hasErrors());
    // The bodies are the three boxes again: the braid's bone is in the head's body, its vertices in no body.
    CHECK(generated->totalMassKg == Approx(kMassWithoutPropKg).epsilon(0.02));
    const auto& head = bodyOf(*generated, "head");
    CHECK(head.vertices == 98);
    CHECK(std::count(head.joints.begin(), head.joints.end(), 4) == 1);
    REQUIRE(generated->stray.size() == 1);
    const auto& s = generated->stray[0];
    CHECK(s.joint == "braid");
    CHECK(s.body == "head");
    CHECK(s.vertices == 6);
    // From the head joint (0, 0, 64) to the braid's vertices: (9, 0, 45) is the nearest, (11, 0, 43) the farthest.
    CHECK(s.nearestM == Approx(std::hypot(9.0, 19.0) * kMetresPerUnit).margin(1e-9));
    CHECK(s.farthestM == Approx(std::hypot(11.0, 21.0) * kMetresPerUnit).margin(1e-9));
    CHECK(s.growth > afb::gen::defaultRules().maxMergeGrowth);
    CHECK(diags.str().find("6 of the 6 vertices of bone \"braid\"") != std::string::npos);
    CHECK(diags.str().find("rules: maxMergeGrowth") != std::string::npos);

    // With the rule off, the head's body reaches down over the braid: its box alone would be 560 units³.
    afb::gen::GenRules off = afb::gen::defaultRules();
    off.maxMergeGrowth = 0;
    afb::text::Diagnostics offDiags;
    const auto stretched = generate(rig, offDiags, off);
    REQUIRE(stretched);
    CHECK(stretched->stray.empty());
    CHECK(bodyOf(*stretched, "head").vertices == 98 + 6);
    CHECK(bodyOf(*stretched, "head").volumeUnits3 > 3 * 560);
}

TEST_CASE("gen: a small bone whose vertices lie inside its body's is merged (maxMergeGrowth)", "[gen]") {
    const afb::gen::Rig rig = smallBoneRig("chin", {0, 0, 66}, {0, 0, 68});
    afb::text::Diagnostics diags;
    const auto generated = generate(rig, diags);
    REQUIRE(generated);
    INFO(diags.str());
    CHECK(generated->stray.empty());
    CHECK(bodyOf(*generated, "head").vertices == 98 + 6);
    CHECK(generated->totalMassKg == Approx(kMassWithoutPropKg).epsilon(0.02));
    CHECK(diags.str().find("maxMergeGrowth") == std::string::npos);

    afb::text::Diagnostics ruleDiags;
    const auto rules = afb::gen::parseRules(R"({"maxMergeGrowth": 3})", "rules.json", ruleDiags);
    REQUIRE(rules);
    CHECK(rules->maxMergeGrowth == 3);
    CHECK_FALSE(afb::gen::parseRules(R"({"maxMergeGrowth": 0.5})", "rules.json", ruleDiags));
    CHECK(ruleDiags.str().find("rules.json: error: \"maxMergeGrowth\" must be 0 (off) or in [1, 1000]") !=
          std::string::npos);
}

// dwarf.x's beard ends in two braids of small bones (Joint36-39-40-41 and Joint37-38-42-43) merged into the head's
// body. Their lower ends hang 30-48 cm below the head joint: they are left out, and only the head changes.
TEST_CASE("gen: dwarf.x's braid ends are left out of the head's body", "[gen][corpus]") {
    AFB_REQUIRE_CORPUS(corpus);
    afb::text::Diagnostics diags;
    const auto rig = afb::gen::importRig(corpus / "assimp-rigs/test/models-nonbsd/X/dwarf.x", {}, diags);
    REQUIRE(rig);
    const auto withRule = [&](double maxMergeGrowth) {
        afb::gen::GenRules rules = afb::gen::defaultRules();
        rules.maxMergeGrowth = maxMergeGrowth;
        const auto g = generate(*rig, diags, rules);
        REQUIRE(g);
        return *g;
    };
    const afb::gen::Generated byDefault = withRule(afb::gen::defaultRules().maxMergeGrowth);
    const afb::gen::Generated off = withRule(0);
    const afb::gen::Generated ownOnly = withRule(1); // every merged bone that hangs off a body left out
    INFO(diags.str());
    int leftOut = 0;
    std::vector<std::string> cut;
    for (const auto& s : byDefault.stray) {
        CHECK(s.body == "head");
        CHECK(s.growth > afb::gen::defaultRules().maxMergeGrowth);
        leftOut += s.vertices;
        cut.push_back(s.joint);
    }
    CHECK(cut == std::vector<std::string>{"Joint40", "Joint42"});
    CHECK(off.stray.empty());
    REQUIRE(byDefault.bodies.size() == off.bodies.size());
    for (std::size_t i = 0; i < off.bodies.size(); ++i) {
        INFO(off.bodies[i].name);
        if (off.bodies[i].joint == "head") {
            CHECK(byDefault.bodies[i].vertices == off.bodies[i].vertices - leftOut);
            CHECK(byDefault.bodies[i].volumeUnits3 < off.bodies[i].volumeUnits3);
        } else {
            CHECK(byDefault.bodies[i].volumeUnits3 == off.bodies[i].volumeUnits3);
        }
    }
    // Each braid, judged apart from the other, grows the head's own body by at most 0.6 of it: two braids, 2.2.
    const auto headVolume = [](const afb::gen::Generated& g) { return bodyOf(g, "head").volumeUnits3; };
    CHECK(headVolume(byDefault) <= 2.2 * headVolume(ownOnly));
    CHECK(headVolume(ownOnly) < headVolume(byDefault));
}
