// Real-world `.af` files: every one parses cleanly and round-trips; spot checks of facts read from the files
// by hand (not from the parser's output).
#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <variant>
#include <vector>

#include "TestSupport.h"
#include "afb/decl/Af.h"
#include "afb/decl/AfParser.h"
#include "afb/text/Diagnostics.h"

namespace fs = std::filesystem;
using namespace afb::decl;
using afb::text::Diagnostics;

namespace {

std::vector<fs::path> afFilesUnder(const fs::path& dir) {
    std::vector<fs::path> out;
    for (const auto& e : fs::recursive_directory_iterator(dir, fs::directory_options::skip_permission_denied)) {
        if (!e.is_regular_file()) continue;
        std::string ext = e.path().extension().string();
        std::transform(ext.begin(), ext.end(), ext.begin(),
                       [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
        if (ext == ".af") out.push_back(e.path());
    }
    std::sort(out.begin(), out.end());
    return out;
}

std::string readText(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

/// Counts lines whose first word is `keyword` followed by a quoted name: an independent count of the blocks of
/// the editor-written corpus files (one block header per line, no blocks in comments).
std::size_t countBlockLines(const std::string& text, const std::vector<std::string>& keywords) {
    std::istringstream in(text);
    std::string line;
    std::size_t n = 0;
    while (std::getline(in, line)) {
        std::istringstream words(line);
        std::string first, second;
        words >> first >> second;
        if (second.empty() || second[0] != '"') continue;
        for (const std::string& k : keywords)
            if (first == k) ++n;
    }
    return n;
}

AfVector lit(double x, double y, double z) { return AfVector::fromLiteral({x, y, z}); }
AfVector jointVec(const std::string& j) { return AfVector::fromJoint(j); }
AfVector boneCenter(const std::string& a, const std::string& b) { return AfVector::fromBoneCenter(a, b); }

const AfBody* bodyNamed(const AfDecl& d, const std::string& name) {
    for (const AfBody& b : d.bodies)
        if (b.name == name) return &b;
    return nullptr;
}
const AfConstraint* constraintNamed(const AfDecl& d, const std::string& name) {
    for (const AfConstraint& c : d.constraints)
        if (c.name == name) return &c;
    return nullptr;
}

std::optional<AfFile> loadCorpusFile(const fs::path& p) {
    Diagnostics d;
    auto f = parseAf(readText(p), p.string(), d);
    INFO(p.string() << "\n" << d.str());
    CHECK(d.errorCount() == 0);
    return f;
}

} // namespace

TEST_CASE("corpus: every .af file parses without errors and round-trips", "[corpus][af]") {
    AFB_REQUIRE_CORPUS(dir);
    const auto files = afFilesUnder(dir);
    if (files.empty()) {
        WARN("no .af files under " << dir.string());
        return;
    }
    for (const fs::path& p : files) {
        INFO(p.string());
        const std::string text = readText(p);
        Diagnostics d;
        const auto f = parseAf(text, p.string(), d);
        INFO(d.str());
        REQUIRE(f.has_value());
        CHECK(d.errorCount() == 0);
        // The editor-written files use only known contents names and mods, literal angles, no leading zeros and
        // no case-only duplicate names: nothing to warn about either.
        CHECK(d.warningCount() == 0);
        CHECK_FALSE(f->decls.empty());

        // An independent count of the block headers in the text.
        std::size_t bodies = 0, constraints = 0, settings = 0;
        for (const AfDecl& decl : f->decls) {
            bodies += decl.bodies.size();
            constraints += decl.constraints.size();
            settings += decl.settings.size();
            CHECK(decl.order.size() == decl.bodies.size() + decl.constraints.size() + decl.settings.size());
        }
        CHECK(bodies == countBlockLines(text, {"body"}));
        CHECK(constraints ==
              countBlockLines(text, {"fixed", "ballAndSocketJoint", "universalJoint", "hinge", "slider", "spring"}));

        // Round trip and idempotent writing.
        const std::string w1 = writeAf(*f);
        Diagnostics d2;
        const auto g = parseAf(w1, p.string() + " (rewritten)", d2);
        INFO(d2.str());
        REQUIRE(g.has_value());
        CHECK(d2.errorCount() == 0);
        CHECK(*g == *f);
        CHECK(writeAf(*g) == w1);
    }
}

TEST_CASE("corpus: loadAf reads a file from disk", "[corpus][af]") {
    AFB_REQUIRE_CORPUS(dir);
    const fs::path p = dir / "doom3-kroom3/base/af/monster_zombie_security_pistol.af";
    if (!fs::exists(p)) {
        WARN("missing " << p.string());
        return;
    }
    Diagnostics d;
    const auto f = loadAf(p, d);
    INFO(d.str());
    REQUIRE(f.has_value());
    CHECK(d.errorCount() == 0);
    REQUIRE(f->decls.size() == 1);
    CHECK(f->decls[0].name == "monster_zombie_security_pistol");

    Diagnostics d2;
    CHECK_FALSE(loadAf(dir / "no/such/file.af", d2).has_value());
    CHECK(d2.errorCount() >= 1);
}

TEST_CASE("corpus: monster_zombie_security_pistol.af spot checks", "[corpus][af]") {
    AFB_REQUIRE_CORPUS(dir);
    const fs::path p = dir / "doom3-kroom3/base/af/monster_zombie_security_pistol.af";
    if (!fs::exists(p)) {
        WARN("missing " << p.string());
        return;
    }
    const auto f = loadCorpusFile(p);
    REQUIRE(f.has_value());
    REQUIRE(f->decls.size() == 1);
    const AfDecl& d = f->decls[0];
    CHECK(d.name == "monster_zombie_security_pistol");
    CHECK(d.location.line == 8);
    CHECK(d.location.column == 1);

    // settings
    REQUIRE(d.settings.size() == 1);
    const AfSettings& s = d.settings[0];
    CHECK(s.location.line == 10);
    CHECK(s.model == "model_monster_zsec_pistol");
    CHECK(s.skin == "skins/monsters/zombies/zsecurity.skin");
    REQUIRE(s.friction.has_value());
    CHECK(s.friction->linear == Approx(0.01).epsilon(1e-6));
    CHECK(s.friction->contact == 0.5);
    REQUIRE(s.friction->constraint.has_value()); // the 4th value, 0.400000006
    CHECK(*s.friction->constraint == Approx(0.4).epsilon(1e-6));
    CHECK(s.suspendSpeed == std::array<double, 4>{20, 30, 40, 60});
    CHECK(s.minMoveTime == 2.0);
    CHECK(s.maxMoveTime == 15.0);
    CHECK(s.totalMass == 250.0);
    CHECK(s.selfCollision == true);
    CHECK(contentsBits(*s.contents) == kContentsCorpse);
    CHECK(contentsBits(*s.clipMask) == (kContentsSolid | kContentsCorpse));

    // bodies
    REQUIRE(d.bodies.size() == 11);
    const AfBody& waist = d.bodies[0];
    CHECK(waist.name == "waist");
    CHECK(waist.joint == "origin");
    CHECK(waist.location.line == 26);
    CHECK(waist.mod == "orientation");
    REQUIRE(waist.model.has_value());
    CHECK(waist.model->kind == ShapeKind::Box);
    CHECK(waist.model->v1 == lit(-5.5, -7.5, -6));
    CHECK(waist.model->v2 == lit(5.5, 7.5, 6));
    CHECK(waist.origin == lit(0, 0, 44));
    CHECK(*waist.density == Approx(0.02).epsilon(1e-6));
    CHECK(waist.containedJoints == "*origin -*Waist -*Rupleg -*Lupleg");

    const AfBody* ruparm = bodyNamed(d, "ruparm");
    REQUIRE(ruparm != nullptr);
    CHECK(ruparm->joint == "Ruparm");
    CHECK(ruparm->model->kind == ShapeKind::Bone);
    CHECK(ruparm->model->v1 == jointVec("Ruparm"));
    CHECK(ruparm->model->v2 == jointVec("Rloarm"));
    CHECK(ruparm->model->width == 9.0);
    CHECK(ruparm->origin == boneCenter("Ruparm", "Rloarm"));
    CHECK(ruparm->selfCollision == false);

    const AfBody* rloarm = bodyNamed(d, "rloarm");
    REQUIRE(rloarm != nullptr);
    CHECK(rloarm->model->width == 7.0);

    const AfBody* rloleg = bodyNamed(d, "rloleg");
    REQUIRE(rloleg != nullptr);
    CHECK(rloleg->model->kind == ShapeKind::Cone);
    CHECK(rloleg->model->numSides == 3);
    CHECK(rloleg->model->v1 == lit(-7.5, -4, -10.5));
    CHECK(rloleg->angles == lit(0, 180, 0));
    CHECK(rloleg->origin == jointVec("Rloleg"));
    CHECK(rloleg->friction->linear == Approx(0.02).epsilon(1e-6));

    // constraints
    REQUIRE(d.constraints.size() == 10);
    const AfConstraint* head = constraintNamed(d, "head");
    REQUIRE(head != nullptr);
    CHECK(head->type == ConstraintType::Universal);
    CHECK(head->body1 == "head");
    CHECK(head->body2 == "chest");
    CHECK(head->anchor == jointVec("neckcontrol"));
    REQUIRE(head->shafts.has_value());
    CHECK((*head->shafts)[0] == lit(0, 0, 1));
    CHECK((*head->shafts)[1] == lit(0, 0, -1));
    const auto* cone = std::get_if<ConeLimit>(&head->limit);
    REQUIRE(cone != nullptr);
    CHECK(cone->angleDeg == 60.0);
    CHECK_FALSE(cone->shaft.has_value());

    const AfConstraint* rupleg = constraintNamed(d, "rupleg");
    REQUIRE(rupleg != nullptr);
    const auto* pyr = std::get_if<PyramidLimit>(&rupleg->limit);
    REQUIRE(pyr != nullptr);
    CHECK(pyr->axis.literal.x == Approx(0.4).epsilon(1e-6));
    CHECK(pyr->axis.literal.z == Approx(-0.9).epsilon(1e-6));
    CHECK(pyr->angle1Deg == 75.0);
    CHECK(pyr->angle2Deg == 30.0);
    CHECK(pyr->rollDeg == 61.0);

    const AfConstraint* knee = constraintNamed(d, "rloleg");
    REQUIRE(knee != nullptr);
    CHECK(knee->type == ConstraintType::Hinge);
    CHECK(knee->anchor == jointVec("Rloleg"));
    CHECK(knee->axis == lit(0, -1, 0));
    const auto* h = std::get_if<HingeLimit>(&knee->limit);
    REQUIRE(h != nullptr);
    CHECK(h->orientationDeg == 130.0);
    CHECK(h->widthDeg == 70.0);
    CHECK(h->angleDeg == 90.0);

    // Every body comes after the settings block, so each takes its values (docs/format.md §1.8).
    CHECK(d.settingsForBody(0).friction.contact == 0.5);
    CHECK(d.finalSettings().totalMass == 250.0);
}

TEST_CASE("corpus: monster_demon_pink.af spot checks", "[corpus][af]") {
    AFB_REQUIRE_CORPUS(dir);
    const fs::path p = dir / "doom3-kroom3/base/af/monster_demon_pink.af";
    if (!fs::exists(p)) {
        WARN("missing " << p.string());
        return;
    }
    const auto f = loadCorpusFile(p);
    REQUIRE(f.has_value());
    REQUIRE(f->decls.size() == 1);
    const AfDecl& d = f->decls[0];
    CHECK(d.name == "monster_demon_pink");
    CHECK(d.settings[0].skin == "");
    CHECK(d.settings[0].totalMass == 550.0);
    CHECK(d.settings[0].suspendSpeed == std::array<double, 4>{30, 40, 80, 100});
    CHECK(d.settings[0].minMoveTime == -1.0);
    REQUIRE(d.bodies.size() == 14);
    REQUIRE(d.constraints.size() == 13);
    // The base body is the first one here.
    CHECK(d.bodies[0].name == "chest");
    CHECK(d.bodies[0].joint == "origin");
    CHECK(d.bodies[0].model->kind == ShapeKind::Cylinder);
    CHECK(d.bodies[0].model->numSides == 5);
    CHECK(d.bodies[0].model->v1 == lit(-22.5, -17, -24));
    CHECK(d.bodies[0].angles == lit(90, 0, 0));
    CHECK(d.bodies[0].containedJoints == "*origin -*Waist2 -*Head -*Ruparm -*Luparm");
    CHECK(d.bodies[13].name == "Jaw"); // case kept
    const AfConstraint* rloarm = constraintNamed(d, "rloarm");
    REQUIRE(rloarm != nullptr);
    CHECK(rloarm->type == ConstraintType::Hinge);
}
