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

    // With the rule off, maxPropGrowth finds the prop instead (a sixth of the head bone's vertices, 26 of 124)...
    afb::gen::GenRules off = afb::gen::defaultRules();
    off.strayFactor = 0;
    afb::text::Diagnostics offDiags;
    const auto byProps = generate(rig, offDiags, off);
    REQUIRE(byProps);
    CHECK(byProps->totalMassKg == Approx(kMassWithoutPropKg).epsilon(0.02));
    REQUIRE(byProps->stray.size() == 1);
    CHECK(byProps->stray[0].rule == "maxPropGrowth");
    CHECK(byProps->stray[0].vertices == 26);
    // ... and with both off, the head's body stretches over the prop: from x = -41.5 to 4, over 5 times its box.
    off.maxPropGrowth = 0;
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

// dwarf.x's head bone carries a horned helmet: its horns and crest reach 29-54 cm from the bone, past 1.5 times
// the median of its 1688 vertices (19 cm), and more than double the head's body. Its beard ends in two braids of
// small bones (Joint36-39-40-41 and Joint37-38-42-43) merged into the head's body. Judged alone, only their ends
// (Joint40, Joint43) grow it past 1.6 times; the rest, kept together, make it 2.27 times its own bones' body, and
// the bones growing it most alone (5-9 % apart, left and right) are cut until it is within the limit: every braid
// bone. Each braid is big enough for a body of its own, hanging from the head; no other body changes.
TEST_CASE("gen: dwarf.x's helmet horns are left out of the head's body and its braids made bodies", "[gen][corpus]") {
    AFB_REQUIRE_CORPUS(corpus);
    afb::text::Diagnostics diags;
    const auto rig = afb::gen::importRig(corpus / "assimp-rigs/test/models-nonbsd/X/dwarf.x", {}, diags);
    REQUIRE(rig);
    const auto withRules = [&](double maxMergeGrowth, double maxPropGrowth) {
        afb::gen::GenRules rules = afb::gen::defaultRules();
        rules.maxMergeGrowth = maxMergeGrowth;
        rules.maxPropGrowth = maxPropGrowth;
        const auto g = generate(*rig, diags, rules);
        REQUIRE(g);
        return *g;
    };
    const afb::gen::GenRules defaults = afb::gen::defaultRules();
    const afb::gen::Generated byDefault = withRules(defaults.maxMergeGrowth, defaults.maxPropGrowth);
    const afb::gen::Generated off = withRules(0, defaults.maxPropGrowth);
    const afb::gen::Generated withHorns = withRules(defaults.maxMergeGrowth, 0);
    const afb::gen::Generated ownOnly = withRules(1, defaults.maxPropGrowth); // every merged branch cut
    INFO(diags.str());
    REQUIRE(byDefault.stray.size() == 1);
    const auto& horns = byDefault.stray[0];
    CHECK(horns.rule == "maxPropGrowth");
    CHECK(horns.joint == "head");
    CHECK(horns.growth > defaults.maxPropGrowth);
    CHECK(horns.vertices <= horns.boneVertices / 4);
    REQUIRE(off.stray.size() == 1);
    CHECK(off.stray[0].rule == "maxPropGrowth");
    REQUIRE(byDefault.bodies.size() == off.bodies.size() + 2);
    const auto head = [](const afb::gen::Generated& g) { return bodyOf(g, "head"); };
    for (const auto& b : off.bodies) {
        INFO(b.name);
        if (b.joint == "head") CHECK(head(byDefault).vertices < b.vertices);
        else CHECK(bodyOf(byDefault, b.joint).volumeUnits3 == b.volumeUnits3);
    }
    // The head is its own bones' body, as with every merged branch cut: under half what it was with its horns, and
    // no longer the heaviest body (the chest, spine2, is).
    CHECK(head(byDefault).volumeUnits3 == Approx(head(ownOnly).volumeUnits3).epsilon(1e-9));
    CHECK(head(byDefault).volumeUnits3 < 0.5 * head(withHorns).volumeUnits3);
    CHECK(head(byDefault).massKg < bodyOf(byDefault, "spine2").massKg);
    CHECK(head(byDefault).massKg < 0.12 * byDefault.totalMassKg);
    CHECK(byDefault.totalMassKg < withHorns.totalMassKg);
    for (const afb::gen::Generated* g : {&byDefault, &ownOnly})
        for (const std::string braid : {"Joint36", "Joint37"}) {
            INFO(braid);
            const auto& b = bodyOf(*g, braid);
            CHECK(b.joints.size() == 4);
            int jointed = 0;
            for (const auto& j : g->joints)
                if (g->bodies[static_cast<std::size_t>(j.body1)].joint == braid &&
                    g->bodies[static_cast<std::size_t>(j.body2)].joint == "head")
                    ++jointed;
            CHECK(jointed == 1);
        }
}

namespace {

// propRig's pelvis and chest, its head box lowered to the head joint at its centre (x -4..4, y -3.5..3.5,
// z 59..69), and a horn on the head bone's own skin: a 2 × 16.5 × 2 bar (26 vertices) from the head box's side
// (y = 3.5) out to y = 20, at z 63..65. It is a fifth of the head bone's vertices and adjoins its skin, so
// strayFactor's median and deviation leave it in.
afb::gen::Rig hornRig() {
    afb::gen::Rig rig = propRig();
    rig.surfaces.pop_back();
    afb::gen::RigSurface body{"body", "models/test/body", {}, {}};
    addBox(body, 1, {-5, -8, 36}, {5, 8, 48});
    addBox(body, 2, {-6, -10, 48}, {6, 10, 64});
    addBox(body, 3, {-4, -3.5, 59}, {4, 3.5, 69});
    addBox(body, 3, {-1, 3.5, 63}, {1, 20, 65}, 2);
    rig.surfaces = {body};
    return rig;
}

} // namespace

TEST_CASE("gen: a prop on a body bone's own skin is left out of its body (maxPropGrowth)", "[gen]") {
    const afb::gen::Rig rig = hornRig();
    afb::text::Diagnostics diags;
    const auto generated = generate(rig, diags);
    REQUIRE(generated);
    INFO(diags.str());
    CHECK_FALSE(diags.hasErrors());
    // The head box's vertices lie within 7.3 units of the head joint (its corners, √(4² + 3.5² + 5²)), the horn's
    // at 3.5 to 20.05: past 1.5 × the median of all 124 (5.7) lie the horn's 17 at y 11.75 and 20 ((±1, 11.75, 64)
    // nearest, (±1, 20, 63 or 65) farthest); its 9 at y = 3.5 lie on the head box's side. The head's body is its
    // box again: 8 × 7 × 10 = 560 units³, and the figure weighs the three boxes' 6320 units³.
    CHECK(bodyOf(*generated, "head").volumeUnits3 == Approx(560).epsilon(1e-6));
    CHECK(generated->totalMassKg == Approx(kMassWithoutPropKg).epsilon(1e-3));
    REQUIRE(generated->stray.size() == 1);
    const auto& s = generated->stray[0];
    CHECK(s.rule == "maxPropGrowth");
    CHECK(s.joint == "head");
    CHECK(s.body == "head");
    CHECK(s.vertices == 17);
    CHECK(s.boneVertices == 98 + 26);
    CHECK(s.nearestM == Approx(std::hypot(1.0, 11.75) * kMetresPerUnit).margin(1e-9));
    CHECK(s.farthestM == Approx(std::sqrt(1.0 + 400.0 + 1.0) * kMetresPerUnit).margin(1e-9));
    CHECK(s.limitM > std::sqrt(16.0 + 12.25 + 25.0) * kMetresPerUnit);
    CHECK(s.limitM < std::hypot(1.0, 11.75) * kMetresPerUnit);
    CHECK(s.limitM == Approx(1.5 * s.medianM));
    // With the horn, the head's body reaches from y = -3.5 to 20: 23.5 / 7 times its box's volume.
    CHECK(s.growth == Approx(23.5 / 7).epsilon(1e-6));
    CHECK(diags.str().find("17 of the 124 vertices of bone \"head\"") != std::string::npos);
    CHECK(diags.str().find("rules: maxPropGrowth") != std::string::npos);

    // With the rule off, strayFactor alone leaves the horn in and the head's body stretches over it.
    afb::text::Diagnostics ruleDiags;
    const auto off = afb::gen::parseRules(R"({"maxPropGrowth": 0})", "rules.json", ruleDiags);
    REQUIRE(off);
    const auto stretched = generate(rig, ruleDiags, *off);
    REQUIRE(stretched);
    CHECK(stretched->stray.empty());
    CHECK(bodyOf(*stretched, "head").volumeUnits3 == Approx(560 * 23.5 / 7).epsilon(1e-6));
    // A radius past the horn's far end leaves it in too; the keys are checked.
    const auto wide = afb::gen::parseRules(R"({"propRadius": 3})", "rules.json", ruleDiags);
    REQUIRE(wide);
    CHECK(wide->propRadius == 3);
    const auto wideFit = generate(rig, ruleDiags, *wide);
    REQUIRE(wideFit);
    CHECK(wideFit->stray.empty());
    CHECK_FALSE(afb::gen::parseRules(R"({"maxPropGrowth": 0.5})", "rules.json", ruleDiags));
    CHECK(ruleDiags.str().find("rules.json: error: \"maxPropGrowth\" must be 0 (off) or in [1, 1000]") !=
          std::string::npos);
    CHECK_FALSE(afb::gen::parseRules(R"({"propRadius": 0})", "rules.json", ruleDiags));
    CHECK(ruleDiags.str().find("rules.json: error: \"propRadius\" must be in [1, 1000]") != std::string::npos);
}

// An arm off the chest: a 4 × 20 × 4 box of 98 vertices on bone "arm" at (0, 10, 60), big enough for a body by the
// size rules, but 320 units³ against the chest's 3840 (under minVolumeRatio's tenth), so it merges into the chest;
// there it would double the chest's body (y -10..10 to -10..30), so maxMergeGrowth cuts it.
TEST_CASE("gen: a branch cut from a body for its growth becomes a body of its own (maxMergeGrowth)", "[gen]") {
    afb::gen::Rig rig = propRig();
    rig.surfaces.pop_back();
    rig.joints.push_back({"arm", 2, {Eigen::Matrix3d::Identity(), {0, 10, 60}}});
    addBox(rig.surfaces[0], 4, {-2, 10, 58}, {2, 30, 62});
    afb::text::Diagnostics diags;
    const auto generated = generate(rig, diags);
    REQUIRE(generated);
    INFO(diags.str());
    CHECK_FALSE(diags.hasErrors());
    CHECK(generated->stray.empty());
    REQUIRE(generated->bodies.size() == 4);
    const auto& arm = bodyOf(*generated, "arm");
    CHECK(arm.vertices == 98);
    CHECK(arm.joints == std::vector<int>{4});
    CHECK(arm.volumeUnits3 == Approx(320).epsilon(1e-6));
    CHECK(bodyOf(*generated, "chest").volumeUnits3 == Approx(3840).epsilon(1e-6));
    CHECK(bodyOf(*generated, "chest").joints == std::vector<int>{2});
    const double massKg = 500 * (6320 + 320) * std::pow(kMetresPerUnit, 3);
    CHECK(generated->totalMassKg == Approx(massKg).epsilon(1e-3));
    // Jointed to the chest, the body it would have merged into.
    int armJoints = 0;
    for (const auto& j : generated->joints) {
        const auto& child = generated->bodies[static_cast<std::size_t>(j.body1)];
        if (child.joint != "arm") continue;
        ++armJoints;
        CHECK(generated->bodies[static_cast<std::size_t>(j.body2)].joint == "chest");
    }
    CHECK(armJoints == 1);
    REQUIRE(generated->figure);
    CHECK(generated->figure->bodies.size() == 4);

    // With maxMergeGrowth off, the arm stays merged and the chest's body stretches over it.
    afb::gen::GenRules off = afb::gen::defaultRules();
    off.maxMergeGrowth = 0;
    const auto merged = generate(rig, diags, off);
    REQUIRE(merged);
    CHECK(merged->bodies.size() == 3);
    CHECK(bodyOf(*merged, "chest").volumeUnits3 == Approx(2 * 3840).epsilon(1e-6));
}
