// The bundled content exercises every parser and builder path: the shape kinds, constraint types, limit kinds
// and vector forms found across af/ are listed, and a missing one fails the test.
#include <catch2/catch.hpp>

#include <filesystem>
#include <set>
#include <string>

#include "TestSupport.h"
#include "afb/decl/AfParser.h"

namespace {

using namespace afb::decl;

struct Coverage {
    std::set<std::string> seen;
    void vector(const AfVector& v) {
        static const char* names[] = {"literal", "joint", "bonecenter", "bonedir"};
        seen.insert(std::string("vector ") + names[static_cast<int>(v.form)]);
        if (v.negated) seen.insert("vector negated");
    }
    void vector(const std::optional<AfVector>& v) {
        if (v) vector(*v);
    }
};

} // namespace

TEST_CASE("bundled content covers every shape, constraint, limit and vector form", "[content]") {
    Coverage c;
    int files = 0;
    for (const auto& entry : std::filesystem::directory_iterator(afb::test::sourceDir() / "af")) {
        if (entry.path().extension() != ".af") continue;
        afb::text::Diagnostics diags;
        const auto af = loadAf(entry.path(), diags);
        INFO(diags.str());
        REQUIRE(af);
        CHECK(diags.warningCount() == 0);
        ++files;
        for (const AfDecl& d : af->decls) {
            for (const AfSettings& s : d.settings)
                if (s.totalMass) c.seen.insert("settings totalMass");
            for (const AfBody& b : d.bodies) {
                static const char* shapes[] = {"box", "octahedron", "dodecahedron", "cylinder", "cone", "bone"};
                c.seen.insert(std::string("shape ") + shapes[static_cast<int>(b.model.value_or(AfShape{}).kind)]);
                if (b.model) {
                    c.vector(b.model->v1);
                    c.vector(b.model->v2);
                }
                c.vector(b.origin);
                if (b.inertiaScale) c.seen.insert("body inertiaScale");
                if (b.friction) c.seen.insert("body friction");
                if (b.selfCollision) c.seen.insert("body selfCollision");
                if (b.containedJoints && b.containedJoints->find('*') != std::string::npos)
                    c.seen.insert("containedJoints *");
                if (b.containedJoints && b.containedJoints->find('-') != std::string::npos)
                    c.seen.insert("containedJoints -");
            }
            for (const AfConstraint& k : d.constraints) {
                c.seen.insert(std::string("constraint ") + keywordOf(k.type));
                c.vector(k.anchor);
                c.vector(k.anchor2);
                c.vector(k.axis);
                if (k.shafts) {
                    c.vector(k.shafts->at(0));
                    c.vector(k.shafts->at(1));
                }
                const std::string t = keywordOf(k.type);
                if (std::holds_alternative<ConeLimit>(k.limit)) c.seen.insert(t + " coneLimit");
                if (std::holds_alternative<PyramidLimit>(k.limit)) c.seen.insert(t + " pyramidLimit");
                if (const auto* h = std::get_if<HingeLimit>(&k.limit)) {
                    c.seen.insert("hinge limit");
                    if (h->orientationDeg != h->angleDeg) c.seen.insert("hinge off-centre limit");
                }
                if (k.minLength || k.maxLength) c.seen.insert("spring min/max length");
            }
        }
    }
    CHECK(files >= 5);
    const char* required[] = {"shape box",
                              "shape octahedron",
                              "shape dodecahedron",
                              "shape cylinder",
                              "shape cone",
                              "shape bone",
                              "constraint fixed",
                              "constraint ballAndSocketJoint",
                              "constraint universalJoint",
                              "constraint hinge",
                              "constraint slider",
                              "constraint spring",
                              "ballAndSocketJoint coneLimit",
                              "ballAndSocketJoint pyramidLimit",
                              "universalJoint coneLimit",
                              "universalJoint pyramidLimit",
                              "hinge off-centre limit",
                              "spring min/max length",
                              "vector literal",
                              "vector joint",
                              "vector bonecenter",
                              "vector bonedir",
                              "vector negated",
                              "containedJoints *",
                              "containedJoints -",
                              "body selfCollision",
                              "body friction",
                              "settings totalMass",
                              "body inertiaScale"};
    for (const char* r : required) {
        INFO("missing from af/: " << r);
        CHECK(c.seen.count(r) == 1);
    }
}
