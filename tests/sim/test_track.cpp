// Tracking runs (afb track): a powered ragdoll following a walk and an idle, limp against powered, a hit and its
// recovery, the legs of a figure, and a real Doom 3 walk from the corpus.
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
    // Measured at 60 Hz: 0.058 m and 8.1 deg rms powered (the feet and toes, at the end of the legs' chains, lag
    // most), 0.22 m and 34 deg limp. The bounds leave about half as much again; the walk stays within the
    // humanoid's limits, so no error here is the animation's own.
    CHECK(powered.animLimitExcessDeg < 0.5);
    CHECK(powered.steps == 180);
    CHECK_FALSE(powered.exploded);
    CHECK(powered.trackingRmsM < 0.09);
    CHECK(powered.trackingRmsDeg < 12);
    CHECK(powered.trackingMaxM < 0.35);
    CHECK(limp.trackingRmsM > 2.5 * powered.trackingRmsM);
    CHECK(limp.trackingRmsDeg > 2.5 * powered.trackingRmsDeg);
    CHECK(limp.gains.frequencyHz == 0);
    CHECK_FALSE(powered.recoveryS);
}

TEST_CASE("track: a hit at the torso throws the humanoid off its walk and it comes back", "[sim][track]") {
    const auto loaded = test::loadEntity("humanoid");
    const decl::Md5Anim walk = loadAnim(test::sourceDir() / "models/md5/humanoid/walk.md5anim");
    sim::TrackOptions o = threeSeconds();
    o.seconds = 4;
    const sim::TrackResult calm = track(loaded.figure, walk, o);
    o.hit = sim::TrackHit{bodyNamed(loaded.figure, "torso"), 40.0, 2.0};
    const sim::TrackResult hit = track(loaded.figure, walk, o);
    INFO("without the hit " << calm.trackingMaxM << " m max; with it " << hit.trackingMaxM << " m max, before it "
                            << hit.preHitMaxM << " m; recovered after "
                            << (hit.recoveryS ? std::to_string(*hit.recoveryS) : "never") << " s");
    REQUIRE(hit.hitAtS);
    CHECK(*hit.hitAtS == Approx(2.0));
    CHECK(hit.hitBody == "torso");
    // Up to the hit the two runs are the same run.
    CHECK(hit.preHitMaxM <= calm.trackingMaxM);
    // 40 N·s on a 70 kg figure hanging from its pelvis: the torso is knocked well past anything the walk did.
    CHECK(hit.trackingMaxM > 1.2 * hit.preHitMaxM);
    REQUIRE(hit.recoveryS);
    CHECK(*hit.recoveryS > 0);
    CHECK(*hit.recoveryS < 1.5); // measured 0.53 s: the motors regain full strength 0.5 s after the hit
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

TEST_CASE("track: the humanoid's idle loops seamlessly inside its limits and is followed closely", "[sim][track]") {
    const auto loaded = test::loadEntity("humanoid");
    const decl::Md5Anim idle = loadAnim(test::sourceDir() / "models/md5/humanoid/idle.md5anim");
    // The last frame is the first again (the engine loops over numFrames - 1 frames): no jump at the seam.
    REQUIRE(idle.frames.size() == 97);
    CHECK(idle.frames.front() == idle.frames.back());
    sim::TrackOptions o = threeSeconds();
    o.seconds = 4.5; // one whole cycle after the warm-up
    const sim::TrackResult hanging = track(loaded.figure, idle, o);
    o.root = sim::TrackRoot::Free;
    const sim::TrackResult standing = track(loaded.figure, idle, o);
    INFO("root keyframed: " << hanging.trackingRmsM << " m rms, " << hanging.trackingMaxM << " m max, "
                            << hanging.trackingRmsDeg << " deg rms; legs keyframed: " << standing.trackingRmsM
                            << " m rms, " << standing.trackingMaxM << " m max, " << standing.trackingRmsDeg
                            << " deg rms");
    CHECK(hanging.loopSeconds == Approx(4.0));
    // Every pose of the idle lies inside the humanoid's joint limits, so every error is the motors'.
    CHECK(hanging.animLimitExcessDeg == 0);
    CHECK(standing.animLimitExcessDeg == 0);
    CHECK_FALSE(hanging.exploded);
    CHECK_FALSE(standing.exploded);
    // Measured at 60 Hz: hanging from the pelvis 0.021 m and 2.8 deg rms, 0.064 m max (a fingertip, at the end of the
    // arm's chain); standing on keyframed legs 0.033 m and 2.7 deg rms. The bounds leave about half as much again, and
    // stay below the walk's, whose limbs swing far further.
    CHECK(hanging.trackingRmsM < 0.032);
    CHECK(hanging.trackingRmsDeg < 4.2);
    CHECK(hanging.trackingMaxM < 0.1);
    CHECK(standing.trackingRmsM < 0.05);
    CHECK(standing.trackingRmsDeg < 4.2);
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
