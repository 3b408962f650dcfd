// afb gen's maxMergeGrowth rule on the branches it keeps together: small bones that each grow their body within
// the limit alone but past it together are cut, those that grow it most first, a left and a right one together
// (docs/cli.md, afb gen).
#include <catch2/catch.hpp>

#include <cmath>
#include <string>

#include "afb/gen/Generate.h"

namespace {

constexpr double kMetresPerUnit = 0.0254;

// Points on the surface of an axis-aligned box (a 5 × 5 × 5 grid's outer layer: 98 points), Doom units.
void addBox(afb::gen::RigSurface& s, int joint, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
    for (int i = 0; i <= 4; ++i)
        for (int j = 0; j <= 4; ++j)
            for (int k = 0; k <= 4; ++k) {
                if (i % 4 != 0 && j % 4 != 0 && k % 4 != 0) continue;
                afb::gen::RigVertex v;
                v.position = lo + (hi - lo).cwiseProduct(Eigen::Vector3d(i, j, k) / 4);
                v.influences = {{joint, 1.0}};
                s.vertices.push_back(v);
            }
}

// A pelvis, a chest and a head, each a box of vertices weighted to its bone (the head's 8 × 7 × 10 units: x -4..4,
// y -3.5..3.5, z 64..74, 560 units³), and two flaps on the head's sides: small bones (6 vertices each, too few for
// a body of their own, so they merge into the head's) whose vertices fill 2-unit cubes at x -1..1, z 68..70, out to
// y = `leftY` and y = `rightY`. Their joints lie above the head joint, on its
// axis, so the head's body keeps its axis along Z with them.
afb::gen::Rig flapRig(double leftY, double rightY) {
    afb::gen::Rig rig;
    rig.joints = {{"origin", -1, {}},
                  {"pelvis", 0, {Eigen::Matrix3d::Identity(), {0, 0, 36}}},
                  {"chest", 1, {Eigen::Matrix3d::Identity(), {0, 0, 48}}},
                  {"head", 2, {Eigen::Matrix3d::Identity(), {0, 0, 64}}},
                  {"l_flap", 3, {Eigen::Matrix3d::Identity(), {0, 0, 66}}},
                  {"r_flap", 3, {Eigen::Matrix3d::Identity(), {0, 0, 66}}}};
    afb::gen::RigSurface body{"body", "models/test/body", {}, {}};
    addBox(body, 1, {-5, -8, 36}, {5, 8, 48});
    addBox(body, 2, {-6, -10, 48}, {6, 10, 64});
    addBox(body, 3, {-4, -3.5, 64}, {4, 3.5, 74});
    for (int side = 0; side < 2; ++side)
        for (int k = 0; k < 6; ++k) {
            afb::gen::RigVertex v;
            const double y = side == 0 ? leftY - 1 : rightY + 1;
            v.position = Eigen::Vector3d(k % 2 ? 1 : -1, y + (k / 2 - 1.0), 69 + (k % 3 - 1.0));
            v.influences = {{4 + side, 1.0}};
            body.vertices.push_back(v);
        }
    rig.surfaces = {body};
    return rig;
}

afb::gen::Generated generate(const afb::gen::Rig& rig, const afb::gen::GenRules& rules = afb::gen::defaultRules()) {
    afb::gen::GenOptions options;
    options.name = "test_figure";
    options.rules = rules;
    afb::text::Diagnostics diags;
    const auto generated = afb::gen::generateFigure(rig, options, diags);
    INFO(diags.str());
    REQUIRE(generated);
    CHECK_FALSE(diags.hasErrors());
    return *generated;
}

double headVolume(const afb::gen::Generated& g) {
    for (const auto& b : g.bodies)
        if (b.joint == "head") return b.volumeUnits3;
    FAIL("no body at head");
    return 0;
}

// The three boxes' volume, 6320 units³, at 500 kg/m³.
const double kBoxesMassKg = 500 * 6320 * std::pow(kMetresPerUnit, 3);

} // namespace

// The left flap reaches 3.5 units past the head's side, the right one 3.3 (a hand-made model's left and right differ
// a little): alone the left makes the head's body 8 × 10.5 × 10 (1.5 times its box, within 1.6), the right 10.3 / 7;
// both make it 13.8 / 7. Cutting the left one alone would be enough; the right, within 2 % of its growth, goes with
// it.
TEST_CASE("gen: two small branches each within maxMergeGrowth alone but past it together are cut together", "[gen]") {
    const double tolerance = 1e-6; // the fitted boxes enclose the vertices exactly: rounding alone
    const afb::gen::Generated both = generate(flapRig(7, -6.8));
    CHECK(headVolume(both) == Approx(560).epsilon(tolerance));
    CHECK(both.totalMassKg == Approx(kBoxesMassKg).epsilon(1e-3));
    REQUIRE(both.stray.size() == 2);
    for (const auto& s : both.stray) {
        INFO(s.joint);
        CHECK(s.rule == "maxMergeGrowth");
        CHECK(s.body == "head");
        CHECK(s.vertices == 6);
        CHECK(s.together);
        CHECK(s.growth == Approx(13.8 / 7).epsilon(tolerance));
    }
    CHECK(both.stray[0].joint == "l_flap");
    CHECK(both.stray[1].joint == "r_flap");

    // One flap alone stays in the head's body: 1.5 times its box.
    afb::gen::Rig one = flapRig(7, -6.8);
    one.surfaces[0].vertices.resize(one.surfaces[0].vertices.size() - 6);
    const afb::gen::Generated left = generate(one);
    CHECK(left.stray.empty());
    CHECK(headVolume(left) == Approx(560 * 1.5).epsilon(tolerance));

    // With the rule off, both stay.
    afb::gen::GenRules off = afb::gen::defaultRules();
    off.maxMergeGrowth = 0;
    const afb::gen::Generated merged = generate(flapRig(7, -6.8), off);
    CHECK(merged.stray.empty());
    CHECK(headVolume(merged) == Approx(560 * 13.8 / 7).epsilon(tolerance));
}

// The right flap reaches 2 units past the head's side (alone 9 / 7 of its box), the left one 3.5 (1.5 times); both
// make the head 12.5 / 7 of it. The left one grows it most, beyond the near-equal margin of the right's, and
// cutting it alone brings the body within the limit: the right one stays.
TEST_CASE("gen: of branches past maxMergeGrowth together, the one growing the body most is cut first", "[gen]") {
    const double tolerance = 1e-6;
    const afb::gen::Generated g = generate(flapRig(7, -5.5));
    REQUIRE(g.stray.size() == 1);
    CHECK(g.stray[0].joint == "l_flap");
    CHECK(g.stray[0].rule == "maxMergeGrowth");
    CHECK(g.stray[0].together);
    CHECK(g.stray[0].growth == Approx(12.5 / 7).epsilon(tolerance));
    CHECK(headVolume(g) == Approx(560 * 9.0 / 7).epsilon(tolerance));
}
