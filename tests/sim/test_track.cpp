// Tracking runs (afb track): a powered ragdoll following a walk, limp against powered, a hit and its recovery, the
// legs of a figure, and a real Doom 3 walk from the corpus.
#include <catch2/catch.hpp>

#include <algorithm>
#include <string>
#include <vector>

#include "EntityFixture.h"
#include "TestSupport.h"
#include "afb/decl/Md5Anim.h"
#include "afb/sim/Track.h"

using namespace afb;

namespace {

decl::Md5Anim loadAnim(const std::filesystem::path& path) {
    text::Diagnostics diags;
    auto anim = decl::loadMd5Anim(path, diags);
    INFO(diags.str());
    REQUIRE(anim);
    return std::move(*anim);
}

sim::TrackResult track(const figure::Figure& figure, const decl::Md5Anim& anim, const sim::TrackOptions& options) {
    text::Diagnostics diags;
    auto result = sim::runTrack(figure, anim, options, diags);
    INFO(diags.str());
    REQUIRE(result);
    return std::move(*result);
}

sim::TrackOptions threeSeconds() {
    sim::TrackOptions o;
    o.seconds = 3;
    o.method = *bullet::methodPreset("default");
    return o;
}

int bodyNamed(const figure::Figure& f, const std::string& name) {
    for (std::size_t b = 0; b < f.bodies.size(); ++b)
        if (f.bodies[b].name == name) return static_cast<int>(b);
    FAIL("no body " << name);
    return -1;
}

} // namespace

TEST_CASE("track: the legs of the humanoid are the thighs, shins and feet below its pelvis", "[sim][track]") {
    const auto loaded = test::loadEntity("humanoid");
    const figure::Figure& f = loaded.figure;
    std::vector<int> expected;
    for (const char* leg : {"l_thigh", "l_shin", "l_foot", "r_thigh", "r_shin", "r_foot"})
        expected.push_back(bodyNamed(f, leg));
    std::sort(expected.begin(), expected.end());
    CHECK(sim::trackLegBodies(f) == expected);
}

TEST_CASE("track: the humanoid follows its walk powered, far closer than limp", "[sim][track]") {
    const auto loaded = test::loadEntity("humanoid");
    const decl::Md5Anim walk = loadAnim(test::sourceDir() / "models/md5/humanoid/walk.md5anim");
    sim::TrackOptions o = threeSeconds();
    const sim::TrackResult powered = track(loaded.figure, walk, o);
    o.strength = 0;
    const sim::TrackResult limp = track(loaded.figure, walk, o);
    INFO("powered: " << powered.trackingRmsM << " m rms, " << powered.trackingMaxM << " m max, "
                     << powered.trackingRmsDeg << " deg rms; limp: " << limp.trackingRmsM << " m rms, "
                     << limp.trackingRmsDeg << " deg rms");
    // Measured at 60 Hz: 0.014 m and 4.2 deg rms, 0.053 m and 9.3 deg at most powered, 0.22 m and 34 deg rms
    // limp. The walk stays within the humanoid's limits, but it twists the upper arms about their shafts, which
    // the universal shoulders lock (up to 9.8 deg): the arms' errors are that twist, which no motor can follow.
    CHECK(powered.animLimitExcessDeg < 0.5);
    CHECK(powered.animLockedExcessDeg > 5);
    CHECK(powered.animLockedJoint.find("shoulder") != std::string::npos);
    CHECK(powered.steps == 180);
    CHECK_FALSE(powered.exploded);
    CHECK(powered.trackingRmsM < 0.02);
    CHECK(powered.trackingRmsDeg < 6);
    CHECK(powered.trackingMaxM < 0.08);
    CHECK(limp.trackingRmsM > 2.5 * powered.trackingRmsM);
    CHECK(limp.trackingRmsDeg > 2.5 * powered.trackingRmsDeg);
    CHECK(limp.gains.frequencyHz == 0);
    CHECK_FALSE(powered.recoveryS);
}

TEST_CASE("track: with ball joints for shoulders, waist and hips the humanoid follows its walk within 1 cm and 3 deg",
          "[sim][track]") {
    // The same walk on the humanoid whose universal joints (which lock the twist about their shafts) are ball
    // joints without limits: nothing of the walk lies on a locked axis or past a limit, so what is left is the
    // motors' own error.
    auto loaded = test::loadEntity("humanoid");
    figure::Figure f = loaded.figure;
    int changed = 0;
    for (figure::FigureConstraint& c : f.constraints)
        if (c.type == figure::JointType::Universal) {
            c.type = figure::JointType::BallAndSocket;
            c.limit = std::monostate{};
            ++changed;
        }
    CHECK(changed == 5);
    const decl::Md5Anim walk = loadAnim(test::sourceDir() / "models/md5/humanoid/walk.md5anim");
    const sim::TrackResult r = track(f, walk, threeSeconds());
    INFO(r.trackingRmsM << " m and " << r.trackingRmsDeg << " deg rms, " << r.trackingMaxM << " m and "
                        << r.trackingMaxDeg << " deg at most (" << r.worstJoint << ")");
    CHECK(r.animLockedExcessDeg < 0.5); // the fixed wrists: the walk does not bend them
    CHECK_FALSE(r.exploded);
    CHECK(r.trackingRmsM < 0.01);
    CHECK(r.trackingRmsDeg < 3);
    CHECK(r.trackingMaxM < 0.03);
    CHECK(r.trackingMaxDeg < 8);
}

TEST_CASE("track: a hit at the torso throws the humanoid off its walk and it comes back", "[sim][track]") {
    const auto loaded = test::loadEntity("humanoid");
    const decl::Md5Anim walk = loadAnim(test::sourceDir() / "models/md5/humanoid/walk.md5anim");
    sim::TrackOptions o = threeSeconds();
    o.seconds = 4;
    const sim::TrackResult calm = track(loaded.figure, walk, o);
    o.hit = sim::TrackHit{bodyNamed(loaded.figure, "torso"), 80.0, 2.0};
    const sim::TrackResult hit = track(loaded.figure, walk, o);
    INFO("without the hit " << calm.trackingMaxM << " m max; with it " << hit.trackingMaxM << " m max, before it "
                            << hit.preHitMaxM << " m; recovered after "
                            << (hit.recoveryS ? std::to_string(*hit.recoveryS) : "never") << " s");
    REQUIRE(hit.hitAtS);
    CHECK(*hit.hitAtS == Approx(2.0));
    CHECK(hit.hitBody == "torso");
    // Up to the hit the two runs are the same run.
    CHECK(hit.preHitMaxM <= calm.trackingMaxM);
    // 80 N·s on a 70 kg figure hanging from its pelvis: the torso is knocked well past anything the walk did
    // (measured 0.11 m against 0.053 m).
    CHECK(hit.trackingMaxM > 1.5 * hit.preHitMaxM);
    REQUIRE(hit.recoveryS);
    CHECK(*hit.recoveryS > 0);
    CHECK(*hit.recoveryS < 1.5); // measured 0.25 s: the motors are back to half strength 0.25 s after the hit
    CHECK_FALSE(hit.exploded);
}

TEST_CASE("track: the legs keyframed, the humanoid stands and follows its walk on the ground", "[sim][track]") {
    const auto loaded = test::loadEntity("humanoid");
    const decl::Md5Anim walk = loadAnim(test::sourceDir() / "models/md5/humanoid/walk.md5anim");
    sim::TrackOptions o = threeSeconds();
    o.root = sim::TrackRoot::Free;
    const sim::TrackResult r = track(loaded.figure, walk, o);
    INFO(r.trackingRmsM << " m rms, " << r.trackingMaxM << " m max");
    CHECK(r.keyframed == std::vector<std::string>{"l_thigh", "l_shin", "l_foot", "r_thigh", "r_shin", "r_foot"});
    CHECK_FALSE(r.exploded);
    CHECK(r.trackingRmsM < 0.08); // measured 0.046 m: the pelvis is held by both hips
}

TEST_CASE("track: the zsec machinegun walk of the corpus, root keyframed at 60 Hz", "[sim][track][corpus]") {
    AFB_REQUIRE_CORPUS(corpus);
    const std::filesystem::path base = corpus / "doom3-kroom3/base";
    if (!std::filesystem::is_directory(base)) {
        WARN("no doom3-kroom3/base in the corpus: skipped");
        return;
    }
    const auto loaded = test::loadEntity("monster_zsec_machinegun", base);
    const decl::Md5Anim walk = loadAnim(base / "models/md5/monsters/zombies/zsec_machinegun/machinegun_walk.md5anim");
    sim::TrackOptions o = threeSeconds();
    const sim::TrackResult powered = track(loaded.figure, walk, o);
    o.strength = 0;
    const sim::TrackResult limp = track(loaded.figure, walk, o);
    INFO("powered: " << powered.trackingRmsM << " m rms, " << powered.trackingMaxM
                     << " m max; limp: " << limp.trackingRmsM << " m rms; the walk passes the limits by "
                     << powered.animLimitExcessDeg << " deg at " << powered.animLimitJoint);
    CHECK(powered.keyframed == std::vector<std::string>{"waist"});
    CHECK_FALSE(powered.exploded);
    // The walk itself bends the arms and knees well past the figure's limits (measured 39 deg at the right elbow;
    // its knees' range, -75 to -5 deg, excludes a straight leg), which hold: those joints cannot follow it.
    // Measured 0.19 m rms (the hands, at the end of the arms the limits stop) powered, 0.40 m limp.
    CHECK(powered.animLimitExcessDeg > 20);
    CHECK(powered.trackingRmsM < 0.26);
    CHECK(limp.trackingRmsM > 1.6 * powered.trackingRmsM);
}
