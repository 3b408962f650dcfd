// afb gen: rigs in and out of md5, rules, defensive import, and generated figures judged against the
// hand-made zsec figures and on the assimp rigs of the corpus (skipped when ../shared/data is absent).
#include <catch2/catch.hpp>

#include <cstdio>
#include <filesystem>
#include <random>

#include <dlfcn.h>
#include <unistd.h>

#include "TestSupport.h"
#include "afb/decl/AfParser.h"
#include "afb/decl/Def.h"
#include "afb/decl/Library.h"
#include "afb/detail/DoomMath.h"
#include "afb/figure/Load.h"
#include "afb/figure/Placement.h"
#include "afb/gen/Generate.h"
#include "afb/sim/Drop.h"

namespace {

using afb::gen::Rig;
namespace fs = std::filesystem;

fs::path scratchDir(const std::string& tag) {
    const fs::path dir = fs::temp_directory_path() / ("afb_gen_" + tag + "_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

// A three-joint arm with rotated bind frames and vertices blended between joints.
Rig testRig() {
    Rig rig;
    const auto rot = [](double deg, Eigen::Vector3d axis) {
        return Eigen::AngleAxisd(deg * M_PI / 180, axis.normalized()).toRotationMatrix();
    };
    rig.joints.push_back({"origin", -1, {}});
    rig.joints.push_back({"upper", 0, {rot(30, {1, 2, 3}), {0.5, -1.25, 40}}});
    rig.joints.push_back({"lower", 1, {rot(-75, {0, 1, 0.2}), {0.25, 12, 38.5}}});
    afb::gen::RigSurface s{"skin", "models/test/skin", {}, {}};
    std::mt19937 random(7);
    std::uniform_real_distribution<double> u(-3, 3);
    for (int i = 0; i < 24; ++i) {
        afb::gen::RigVertex v;
        v.position = Eigen::Vector3d(u(random), i * 1.0, 40 + u(random));
        v.s = i / 24.0;
        v.t = 1 - i / 24.0;
        const double w = std::clamp((i - 6) / 12.0, 0.0, 1.0);
        if (w < 1) v.influences.push_back({1, 1 - w});
        if (w > 0) v.influences.push_back({2, w});
        s.vertices.push_back(v);
    }
    for (int i = 0; i + 2 < 24; ++i) s.triangles.push_back({i, i + 1, i + 2});
    rig.surfaces.push_back(s);
    return rig;
}

double rotationGap(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) { return (a - b).cwiseAbs().maxCoeff(); }

} // namespace

TEST_CASE("gen: md5 orientations and Doom angles invert the engine's conversions", "[gen]") {
    std::mt19937 random(3);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int i = 0; i < 200; ++i) {
        const Eigen::Matrix3d r =
            Eigen::Quaterniond(u(random), u(random), u(random), u(random)).normalized().toRotationMatrix();
        const Eigen::Vector3d q = afb::gen::md5Orientation(r);
        CHECK(rotationGap(afb::figure::rotationFromMd5(q.x(), q.y(), q.z()), r) < 1e-12);
        const Eigen::Vector3d a = afb::figure::rotationToAngles(r);
        CHECK(rotationGap(afb::figure::anglesToRotation(a.x(), a.y(), a.z()), r) < 1e-9);
    }
    // Gimbal lock: forward straight down or up.
    for (const double pitch : {90.0, -90.0}) {
        const Eigen::Matrix3d r = afb::figure::anglesToRotation(pitch, 30, 0);
        const Eigen::Vector3d a = afb::figure::rotationToAngles(r);
        CHECK(rotationGap(afb::figure::anglesToRotation(a.x(), a.y(), a.z()), r) < 1e-9);
    }
}

TEST_CASE("gen: a rig written as md5mesh + af_pose reads back with the same joints and vertices", "[gen]") {
    const Rig rig = testRig();
    const std::string meshText = afb::decl::writeMd5Mesh(afb::gen::toMd5Mesh(rig, "test"));
    const std::string animText = afb::decl::writeMd5Anim(afb::gen::bindPoseAnim(rig, "test"));
    afb::text::Diagnostics diags;
    const auto mesh = afb::decl::parseMd5Mesh(meshText, "rig.md5mesh", diags);
    const auto anim = afb::decl::parseMd5Anim(animText, "af_pose.md5anim", diags);
    REQUIRE(mesh);
    REQUIRE(anim);
    const Rig back = afb::gen::rigFromMd5(*mesh);
    REQUIRE(back.joints.size() == rig.joints.size());
    for (std::size_t j = 0; j < rig.joints.size(); ++j) {
        CHECK(back.joints[j].name == rig.joints[j].name);
        CHECK(back.joints[j].parent == rig.joints[j].parent);
        CHECK((back.joints[j].bind.position - rig.joints[j].bind.position).norm() < 1e-12);
        CHECK(rotationGap(back.joints[j].bind.rotation, rig.joints[j].bind.rotation) < 1e-12);
    }
    REQUIRE(back.surfaces.size() == 1);
    REQUIRE(back.surfaces[0].vertices.size() == rig.surfaces[0].vertices.size());
    CHECK(back.surfaces[0].triangles == rig.surfaces[0].triangles);
    CHECK(back.surfaces[0].material == rig.surfaces[0].material);
    for (std::size_t i = 0; i < rig.surfaces[0].vertices.size(); ++i) {
        const auto& a = rig.surfaces[0].vertices[i];
        const auto& b = back.surfaces[0].vertices[i];
        CHECK((a.position - b.position).norm() < 1e-9);
        REQUIRE(a.influences.size() == b.influences.size());
        for (std::size_t k = 0; k < a.influences.size(); ++k) {
            CHECK(a.influences[k].joint == b.influences[k].joint);
            CHECK(a.influences[k].weight == Approx(b.influences[k].weight).margin(1e-12));
        }
    }
    // The af_pose's load pose is the bind pose (the model offset puts the root back, docs/format.md §2.1).
    const auto skeleton = afb::figure::Skeleton::build(*mesh, *anim, rig.joints[0].bind.position, diags, "test");
    REQUIRE(skeleton);
    for (std::size_t j = 0; j < rig.joints.size(); ++j) {
        CHECK((skeleton->loadPose()[j].position - rig.joints[j].bind.position).norm() < 1e-9);
        CHECK(rotationGap(skeleton->loadPose()[j].rotation, rig.joints[j].bind.rotation) < 1e-9);
    }
    CHECK_FALSE(diags.hasErrors());
}

TEST_CASE("gen: an md5mesh without an origin joint gets one, and its weights follow", "[gen]") {
    afb::decl::Md5Mesh mesh;
    mesh.joints.push_back({"Bone", -1, {1, 2, 3}, {0.5, 0, 0}});
    afb::decl::Md5SubMesh m;
    m.shader = "x";
    m.verts = {{0, 0, 0, 1}};
    m.weights = {{0, 1.0, {1, 0, 0}}};
    mesh.meshes.push_back(m);
    const Rig rig = afb::gen::rigFromMd5(mesh);
    REQUIRE(rig.joints.size() == 2);
    CHECK(rig.joints[0].name == "origin");
    CHECK(rig.joints[1].parent == 0);
    REQUIRE(rig.md5);
    CHECK(rig.md5->meshes[0].weights[0].joint == 1);
    const auto verts = afb::gen::skinnedBindVertices(mesh);
    CHECK((rig.surfaces[0].vertices[0].position - verts[0][0]).norm() < 1e-12);
}

TEST_CASE("gen: rules files override the template and name their errors", "[gen]") {
    afb::text::Diagnostics diags;
    const auto rules = afb::gen::parseRules(
        R"({"weightThreshold": 0.4, "merge": ["^fx_"], "densityKgM3": 800, "forward": [0, -2, 0],
            "joints": [{"role": "tail", "pattern": "tail", "type": "hinge", "minDeg": -30, "maxDeg": 30}]})",
        "rules.json", diags);
    REQUIRE(rules);
    CHECK(rules->weightThreshold == 0.4);
    CHECK(rules->merge == std::vector<std::string>{"^fx_"});
    CHECK(rules->densityKgM3 == 800);
    CHECK((*rules->forward - Eigen::Vector3d(0, -1, 0)).norm() < 1e-12);
    REQUIRE(rules->joints.size() == afb::gen::defaultRules().joints.size() + 1);
    CHECK(rules->joints[0].role == "tail");
    CHECK(rules->joints[0].type == afb::decl::ConstraintType::Hinge);
    for (const char* bad : {R"({"weightTreshold": 0.4})", R"({"merge": ["(unclosed"]})", R"({"minVertices": "8"})",
                            R"({"joints": [{"pattern": "x", "type": "hinge", "minDeg": 10, "maxDeg": 0}]})", "{",
                            R"([1, 2])", R"({"shapes": ["sphere"]})"}) {
        afb::text::Diagnostics d;
        CHECK_FALSE(afb::gen::parseRules(bad, "bad.json", d));
        REQUIRE(d.hasErrors());
        CHECK(d.str().find("bad.json") != std::string::npos);
    }
}

TEST_CASE("gen: malformed models are errors, never crashes", "[gen]") {
    const std::string garbage[] = {"",
                                   "not a model at all",
                                   std::string("\0\1\2\3glTF\xff\xff\xff\xff", 13),
                                   "Kaydara FBX Binary  \x00\x1a\x00\xe8\x1c\x00\x00",
                                   "xof 0303txt 0032\nFrame {",
                                   "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"};
    for (const char* hint : {"fbx", "glb", "gltf", "x", "b3d", "dae", "obj"})
        for (const std::string& bytes : garbage) {
            afb::text::Diagnostics diags;
            CHECK_FALSE(afb::gen::importRigFromMemory(bytes.data(), bytes.size(), std::string(hint), {}, diags));
            CHECK(diags.hasErrors());
        }
    afb::text::Diagnostics diags;
    CHECK_FALSE(afb::gen::importRig("no/such/model.fbx", {}, diags));
    CHECK(diags.hasErrors());
}

// The replacement of assimp's assert handler (RigAssimp.cpp): the symbol assimp's own calls bind to (the first
// definition in the process's global scope) is ours, and it throws instead of aborting.
namespace Assimp {
void aiAssertViolation(const char* failedExpression, const char* file, int line);
}

TEST_CASE("gen: a failed assimp assert throws instead of aborting the process", "[gen]") {
    void* bound = ::dlsym(RTLD_DEFAULT, "_ZN6Assimp17aiAssertViolationEPKcS1_i");
    REQUIRE(bound != nullptr);
    CHECK(bound == reinterpret_cast<void*>(&Assimp::aiAssertViolation));
    CHECK_THROWS_WITH(Assimp::aiAssertViolation("out_idx != nullptr", "FBXConverter.cpp", 1523),
                      Catch::Contains("out_idx != nullptr") && Catch::Contains("FBXConverter.cpp:1523"));
}

TEST_CASE("gen: the malformed md5 files of assimp's test suite are errors", "[gen][corpus]") {
    AFB_REQUIRE_CORPUS(corpus);
    const fs::path dir = corpus / "assimp-md5/test/models";
    for (const char* f : {"MD5/invalid/InvalidBoneIndex.md5mesh", "MD5/invalid/OverflowingTriangleIndex.md5mesh",
                          "MD5/invalid/OverflowingVertexIndex.md5mesh", "MD5/invalid/OverflowingWeightIndex.md5mesh",
                          "MD5/malformed_weight_index.md5mesh", "invalid/empty.md5mesh"}) {
        afb::text::Diagnostics diags;
        CHECK_FALSE(afb::gen::importRig(dir / f, {}, diags));
        CHECK(diags.hasErrors());
    }
}

namespace {

struct GenRun {
    afb::gen::Generated generated;
    std::optional<afb::figure::LoadedFigure> loaded;
    afb::text::Diagnostics diags; ///< of generation and of loading the written folder
    std::string afText;
};

// Generates from `model`, writes the content folder and loads it back through decl::Library, as `afb inspect
// --base DIR N` and `afb drop` do.
std::optional<GenRun> generateAndLoad(const fs::path& model, const std::string& name,
                                      const afb::gen::ImportOptions& import = {}) {
    GenRun run;
    const auto rig = afb::gen::importRig(model, import, run.diags);
    if (!rig) return std::nullopt;
    afb::gen::GenOptions options;
    options.name = name;
    auto generated = afb::gen::generateFigure(*rig, options, run.diags);
    if (!generated) return std::nullopt;
    const fs::path dir = scratchDir(name);
    if (!afb::gen::writeContent(*generated, dir, run.diags)) return std::nullopt;
    run.afText = afb::decl::writeAf(generated->af);
    run.generated = std::move(*generated);
    const auto library = afb::decl::Library::open(dir, run.diags);
    if (!library) return std::nullopt;
    auto loaded = afb::figure::loadEntityFigure(*library, name, {}, run.diags);
    fs::remove_all(dir);
    if (!loaded) return std::nullopt;
    run.loaded = std::move(loaded);
    return run;
}

// The spawn pose of `afb drop` (steps 0): every md5 joint where the bind pose has it.
double spawnBindGapM(const GenRun& run) {
    afb::sim::DropOptions o;
    o.steps = 0;
    const auto result = afb::sim::runDrop(run.loaded->figure, o);
    const auto& bind = run.loaded->figure.skeleton.bindPose();
    double gap = 0;
    for (std::size_t j = 0; j < result.finalPose.size(); ++j) {
        const Eigen::Vector3d p(result.finalPose[j].position[0], result.finalPose[j].position[1],
                                result.finalPose[j].position[2]);
        gap = std::max(gap, (p - bind[j].position * run.loaded->figure.units.metresPerUnit).norm());
    }
    return gap;
}

afb::sim::DropResult dropOneMetre(const afb::figure::Figure& figure, double seconds) {
    afb::sim::DropOptions o;
    o.heightM = 1.0;
    o.seconds = seconds;
    o.stopAtRest = true;
    return afb::sim::runDrop(figure, o);
}

void checkGenerated(const GenRun& run) {
    INFO(run.diags.str());
    CHECK_FALSE(run.diags.hasErrors());
    // `afb fmt --check`: the written .af is canonical.
    afb::text::Diagnostics d;
    const auto parsed = afb::decl::parseAf(run.afText, "gen.af", d);
    REQUIRE(parsed);
    CHECK(afb::decl::writeAf(*parsed) == run.afText);
    // Every md5 joint is driven: contained by exactly one body.
    for (int body : run.loaded->figure.jointBody) CHECK(body >= 0);
}

} // namespace

TEST_CASE("gen: the bundled humanoid's mesh gives a figure that spawns in its bind pose and settles", "[gen]") {
    const auto run = generateAndLoad(afb::test::sourceDir() / "models/md5/humanoid/humanoid.md5mesh", "humanoid_gen");
    REQUIRE(run);
    checkGenerated(*run);
    CHECK(run->loaded->figure.bodies.size() >= 10);
    CHECK(spawnBindGapM(*run) < 1e-4);
    const auto drop = dropOneMetre(run->loaded->figure, 12);
    CHECK_FALSE(drop.exploded);
    CHECK(drop.settleTimeS.has_value());
}

namespace {

// The hand-made zsec figure against the one generated from its md5mesh alone: both in model space, metres.
struct ZsecComparison {
    std::size_t handBodies = 0, genBodies = 0;
    double handMassKg = 0, genMassKg = 0;
    double meanCentreM = 0, maxCentreM = 0; ///< each hand-made body's COM to the nearest generated COM
    double meanAnchorM = 0, maxAnchorM = 0; ///< each hand-made constraint anchor to the nearest generated anchor
    double afPoseVsBindM = 0;               ///< how far the hand-made load pose (af_pose) is from the bind pose
    afb::sim::DropResult genDrop, handDrop;
};

std::vector<Eigen::Vector3d> anchors(const afb::figure::Figure& f, const std::vector<afb::figure::Transform>& bodies) {
    std::vector<Eigen::Vector3d> out;
    for (const auto& c : f.constraints)
        out.push_back(bodies[static_cast<std::size_t>(c.body1)].apply(c.frameInBody1.position));
    return out;
}

double nearest(const Eigen::Vector3d& p, const std::vector<Eigen::Vector3d>& set) {
    double best = std::numeric_limits<double>::infinity();
    for (const auto& q : set) best = std::min(best, (p - q).norm());
    return best;
}

std::optional<ZsecComparison> compareZsec(const fs::path& corpus, const std::string& set, const std::string& mesh) {
    const fs::path base = corpus / "doom3-kroom3/base";
    afb::text::Diagnostics diags;
    const auto library = afb::decl::Library::open(base, diags);
    if (!library) return std::nullopt;
    const auto hand = afb::figure::loadEntityFigure(*library, "monster_zsec_" + set, {}, diags);
    const auto rig = afb::gen::importRig(base / ("models/md5/monsters/zombies/zsec_" + set) / mesh, {}, diags);
    if (!hand || !rig) return std::nullopt;
    afb::gen::GenOptions options;
    options.name = "zsec_" + set;
    const auto gen = afb::gen::generateFigure(*rig, options, diags);
    if (!gen || !gen->figure) return std::nullopt;
    const afb::figure::Figure& g = *gen->figure;
    const afb::figure::Figure& h = hand->figure;
    ZsecComparison c;
    c.handBodies = h.bodies.size();
    c.genBodies = g.bodies.size();
    c.handMassKg = h.totalMassKg;
    c.genMassKg = g.totalMassKg;
    // The generated figure is built on the bind pose; the hand-made one on the zsec af_pose (arms and legs spread):
    // the generated bodies are put in the af_pose through their joints (docs/format.md §2.5) before comparing.
    if (g.skeleton.jointCount() != h.skeleton.jointCount()) return std::nullopt;
    const auto genBodies = afb::figure::bodiesFromJoints(g, {}, afb::figure::jointsInMetres(h));
    std::vector<Eigen::Vector3d> genCentres;
    for (const auto& b : genBodies) genCentres.push_back(b.position);
    for (const auto& b : h.bodies) {
        const double d = nearest(b.loadPose.position, genCentres);
        c.meanCentreM += d / static_cast<double>(h.bodies.size());
        c.maxCentreM = std::max(c.maxCentreM, d);
    }
    std::vector<afb::figure::Transform> handBodies;
    for (const auto& b : h.bodies) handBodies.push_back(b.loadPose);
    const auto genAnchors = anchors(g, genBodies), handAnchors = anchors(h, handBodies);
    for (const auto& a : handAnchors) {
        const double d = nearest(a, genAnchors);
        c.meanAnchorM += d / static_cast<double>(handAnchors.size());
        c.maxAnchorM = std::max(c.maxAnchorM, d);
    }
    for (int j = 0; j < h.skeleton.jointCount(); ++j)
        c.afPoseVsBindM = std::max(c.afPoseVsBindM, (h.skeleton.loadPose()[static_cast<std::size_t>(j)].position -
                                                     h.skeleton.bindPose()[static_cast<std::size_t>(j)].position)
                                                            .norm() *
                                                        h.units.metresPerUnit);
    c.genDrop = dropOneMetre(g, 12);
    c.handDrop = dropOneMetre(h, 12);
    return c;
}

const std::pair<const char*, const char*> kZsecSets[] = {{"pistol", "zsecpistol.md5mesh"},
                                                         {"shotgun", "zsecshotgun.md5mesh"},
                                                         {"machinegun", "zsecmachinegun.md5mesh"}};

} // namespace

// Bounds (docs/cli.md, afb gen): the generator fits the mesh, the hand-made figures are thinner (bones, small boxes)
// and fewer (hands, clavicles, the neck merged), so the counts, masses and positions agree within these margins.
TEST_CASE("gen: the zsec figures generated from their meshes against the hand-made ones", "[gen][corpus]") {
    AFB_REQUIRE_CORPUS(corpus);
    for (const auto& [set, mesh] : kZsecSets) {
        INFO(set);
        const auto c = compareZsec(corpus, set, mesh);
        REQUIRE(c);
        CHECK(c->genBodies >= c->handBodies);
        CHECK(c->genBodies <= c->handBodies + 3);
        CHECK(c->genMassKg / c->handMassKg == Approx(1.0).margin(0.2));
        CHECK(c->meanCentreM < 0.08);
        CHECK(c->maxCentreM < 0.15);
        CHECK(c->meanAnchorM < 0.05);
        CHECK(c->maxAnchorM < 0.16);
        CHECK_FALSE(c->genDrop.exploded);
        CHECK(c->genDrop.settleTimeS.has_value());
    }
}

// A comparison table for docs/cli.md (afb gen): `afb_tests "[.gen-table]"`.
TEST_CASE("gen: zsec comparison table", "[.gen-table]") {
    AFB_REQUIRE_CORPUS(corpus);
    std::printf(
        "| set | bodies hand / gen | mass kg hand / gen | body centre to nearest, mean / max m | joint anchor to "
        "nearest, mean / max m | af_pose vs bind m | 1 m drop hand: settle s, anchor m | gen: settle s, anchor m |\n"
        "|---|---|---|---|---|---|---|---|\n");
    for (const auto& [set, mesh] : kZsecSets) {
        const auto c = compareZsec(corpus, set, mesh);
        REQUIRE(c);
        std::printf("| %s | %zu / %zu | %.0f / %.1f | %.3f / %.3f | %.3f / %.3f | %.3f | %.2f, %.4f | %.2f, %.4f |\n",
                    set, c->handBodies, c->genBodies, c->handMassKg, c->genMassKg, c->meanCentreM, c->maxCentreM,
                    c->meanAnchorM, c->maxAnchorM, c->afPoseVsBindM, c->handDrop.settleTimeS.value_or(-1),
                    c->handDrop.maxAnchorErrorM, c->genDrop.settleTimeS.value_or(-1), c->genDrop.maxAnchorErrorM);
    }
}

namespace {

struct RigCase {
    const char* path;
    std::optional<double> heightM;
};

const RigCase kRigs[] = {
    {"assimp-md5/test/models-nonbsd/MD5/Bob.md5mesh", {}},
    {"assimp-md5/test/models-nonbsd/MD5/BoarMan.md5mesh", {}},
    {"assimp-rigs/test/models-nonbsd/X/dwarf.x", {}},
    {"assimp-rigs/test/models-nonbsd/B3D/dwarf2.b3d", {}},
    {"assimp-rigs/test/models/FBX/animation_with_skeleton.fbx", {}},
    {"assimp-rigs/test/models/FBX/huesitos.fbx", {}},
    {"assimp-rigs/test/models/glTF2/simple_skin/simple_skin.gltf", {}},
    {"assimp-rigs/test/models/glTF2/simple_skin/quad_skin.glb", 1.0},
};

struct RigResult {
    std::size_t joints = 0, bodies = 0, constraints = 0;
    double massKg = 0, heightM = 0;
    bool errors = false, allDriven = true;
    double vertexGapM = 0, jointGapM = 0, spawnGapM = 0;
    afb::sim::DropResult drop;
};

std::optional<RigResult> runRig(const fs::path& corpus, const RigCase& c, std::string& messages) {
    afb::text::Diagnostics diags;
    afb::gen::ImportOptions import;
    import.heightM = c.heightM;
    const auto rig = afb::gen::importRig(corpus / c.path, import, diags);
    afb::gen::GenOptions options;
    options.name = afb::gen::figureNameFor(c.path);
    std::optional<afb::gen::Generated> gen;
    if (rig) gen = afb::gen::generateFigure(*rig, options, diags);
    messages = diags.str();
    if (!gen || !gen->figure) return std::nullopt;
    const afb::figure::Figure& f = *gen->figure;
    RigResult r;
    r.errors = diags.hasErrors();
    r.joints = rig->joints.size();
    r.bodies = f.bodies.size();
    r.constraints = f.constraints.size();
    r.massKg = f.totalMassKg;
    r.heightM = afb::gen::modelHeight(*rig) * f.units.metresPerUnit;
    for (int body : f.jointBody) r.allDriven = r.allDriven && body >= 0;
    // The written files read back to the same skeleton and skin.
    afb::text::Diagnostics d;
    const auto mesh = afb::decl::parseMd5Mesh(afb::decl::writeMd5Mesh(gen->mesh), "gen.md5mesh", d);
    if (!mesh || mesh->joints.size() != rig->joints.size()) return std::nullopt;
    const auto skinned = afb::gen::skinnedBindVertices(*mesh);
    for (std::size_t s = 0; s < rig->surfaces.size(); ++s)
        for (std::size_t v = 0; v < rig->surfaces[s].vertices.size(); ++v)
            r.vertexGapM = std::max(r.vertexGapM, (skinned[s][v] - rig->surfaces[s].vertices[v].position).norm() *
                                                      f.units.metresPerUnit);
    for (std::size_t j = 0; j < rig->joints.size(); ++j)
        r.jointGapM = std::max(r.jointGapM, (f.skeleton.loadPose()[j].position - rig->joints[j].bind.position).norm() *
                                                f.units.metresPerUnit);
    // Spawned, every joint is where the bind pose has it.
    afb::sim::DropOptions spawn;
    spawn.steps = 0;
    const auto atSpawn = afb::sim::runDrop(f, spawn);
    for (std::size_t j = 0; j < atSpawn.finalPose.size(); ++j)
        r.spawnGapM =
            std::max(r.spawnGapM, (Eigen::Vector3d(atSpawn.finalPose[j].position[0], atSpawn.finalPose[j].position[1],
                                                   atSpawn.finalPose[j].position[2]) -
                                   rig->joints[j].bind.position * f.units.metresPerUnit)
                                      .norm());
    r.drop = dropOneMetre(f, 15);
    return r;
}

} // namespace

// The corpus rigs: each generates a figure that passes the checks, spawns exactly in its bind pose and
// settles from a 1 m drop. quad_skin's armature is scaled 100 in a metre file (200 m): it is generated 1 m tall.
TEST_CASE("gen: the corpus rigs spawn in their bind pose and settle", "[gen][corpus]") {
    AFB_REQUIRE_CORPUS(corpus);
    for (const RigCase& c : kRigs) {
        INFO(c.path);
        std::string messages;
        const auto r = runRig(corpus, c, messages);
        INFO(messages);
        REQUIRE(r);
        CHECK_FALSE(r->errors);
        CHECK(r->allDriven);
        CHECK(r->vertexGapM < 1e-6);
        CHECK(r->jointGapM < 1e-6);
        CHECK(r->spawnGapM < 1e-4);
        CHECK_FALSE(r->drop.exploded);
        CHECK(r->drop.settleTimeS.has_value());
    }
}

// The rigs table of docs/cli.md (afb gen): `afb_tests "[.gen-table]"`.
TEST_CASE("gen: rigs table", "[.gen-table]") {
    AFB_REQUIRE_CORPUS(corpus);
    std::printf(
        "| model | joints | bodies / constraints | height m | mass kg | spawn: worst joint from bind m | 1 m drop: "
        "settle s, worst anchor m |\n|---|---|---|---|---|---|---|\n");
    for (const RigCase& c : kRigs) {
        std::string messages;
        const auto r = runRig(corpus, c, messages);
        REQUIRE(r);
        std::printf("| %s | %zu | %zu / %zu | %.2f | %.1f | %.1e | %.2f, %.4f |\n", fs::path(c.path).filename().c_str(),
                    r->joints, r->bodies, r->constraints, r->heightM, r->massKg, r->spawnGapM,
                    r->drop.settleTimeS.value_or(-1), r->drop.maxAnchorErrorM);
    }
}
