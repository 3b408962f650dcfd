// Tracking results as JSON and CSV: one table of fields feeds both and the help text, as the drop reports do.

#include "ReportFields.h"
#include "afb/sim/Report.h"
#include "afb/sim/Track.h"

namespace afb::sim {
namespace {

using nlohmann::json;

using TrackField = detail::ReportField<TrackResult>;

const std::vector<TrackField>& trackFields() {
    using R = TrackResult;
    static const std::vector<TrackField> table = {
        {"figure", "entity's figure name", [](const R& r) { return json(r.figure); }},
        {"precision", "Bullet build, float or double", [](const R& r) { return json(r.precision); }},
        {"method", "the method's preset name (its knobs follow in JSON as \"method\", in CSV as method.*)",
         [](const R& r) { return json(r.method.name); }},
        {"root", "keyframed (body 0 on the animation) or free (the legs on it)",
         [](const R& r) { return json(toString(r.root)); }},
        {"strength", "the gains' scale (--strength)", [](const R& r) { return json(r.strength); }},
        {"motor_hz", "every joint motor's frequency at that strength",
         [](const R& r) { return json(r.gains.frequencyHz); }},
        {"motor_damping_ratio", "their damping ratio at that strength",
         [](const R& r) { return json(r.gains.dampingRatio); }},
        {"keyframed_bodies", "the bodies keyframed on the animation, space-separated",
         [](const R& r) {
             std::string s;
             for (const std::string& b : r.keyframed) s += (s.empty() ? "" : " ") + b;
             return json(s);
         }},
        {"loop_s", "the animation's cycle (numFrames - 1 frames)", [](const R& r) { return json(r.loopSeconds); }},
        {"bodies", "bodies of the figure", [](const R& r) { return json(r.bodies); }},
        {"constraints", "constraints of the figure", [](const R& r) { return json(r.constraints); }},
        {"joints", "md5 joints the errors are taken over", [](const R& r) { return json(r.joints); }},
        {"steps", "frames stepped", [](const R& r) { return json(r.steps); }},
        {"tracking_rms_m", "root mean square of every joint's world distance from the animation's, after the warm-up",
         [](const R& r) { return json(r.trackingRmsM); }},
        {"tracking_max_m", "the largest such distance", [](const R& r) { return json(r.trackingMaxM); }},
        {"worst_joint", "the joint where it happened", [](const R& r) { return json(r.worstJoint); }},
        {"tracking_rms_deg", "root mean square of the angle between every joint's world rotation and the animation's",
         [](const R& r) { return json(r.trackingRmsDeg); }},
        {"tracking_max_deg", "the largest such angle", [](const R& r) { return json(r.trackingMaxDeg); }},
        {"anim_limit_excess_deg",
         "largest excess of the animation's own pose over the figure's joint limits: a floor under the errors",
         [](const R& r) { return json(r.animLimitExcessDeg); }},
        {"anim_limit_joint", "the constraint where it happened", [](const R& r) { return json(r.animLimitJoint); }},
        {"cut_max_rel_rad_s",
         "largest angular speed of a simulated body joined to a keyframed one relative to its target, after the "
         "warm-up",
         [](const R& r) { return json(r.cutMaxRelRadS); }},
        {"cut_body", "the body where it happened (empty when no body lies at the cut)",
         [](const R& r) { return json(r.cutBody); }},
        {"anim_locked_excess_deg",
         "largest turn of the animation's own pose about an axis a joint locks (a universal joint's twist, a hinge's "
         "tilt, a fixed joint): a floor under the errors",
         [](const R& r) { return json(r.animLockedExcessDeg); }},
        {"anim_locked_joint", "the constraint where it happened", [](const R& r) { return json(r.animLockedJoint); }},
        {"hit_body", "the body --hit struck (empty without one)", [](const R& r) { return json(r.hitBody); }},
        {"hit_at_s", "when it struck", [](const R& r) { return jsonOrNull(r.hitAtS); }},
        {"pre_hit_max_m", "largest joint distance between the warm-up and the hit (0 without a hit)",
         [](const R& r) { return json(r.preHitMaxM); }},
        {"pre_hit_max_deg", "largest joint angle between the warm-up and the hit",
         [](const R& r) { return json(r.preHitMaxDeg); }},
        {"recovery_s",
         "from the hit until the largest joint errors stay within 1.1 x the pre-hit ones + 1 mm / 0.5 deg; null "
         "without a hit or when they never did",
         [](const R& r) { return jsonOrNull(r.recoveryS); }},
        {"max_speed_mps", "fastest body", [](const R& r) { return json(r.maxSpeedMps); }},
        {"max_anchor_error_m", "largest separation of a constraint's two anchor copies",
         [](const R& r) { return json(r.maxAnchorErrorM); }},
        {"max_energy_gain_j",
         "largest kinetic + potential energy above the start; holding a still pose it must stay 0 (the motors "
         "start relaxed), on a moving animation it counts the animation's work",
         [](const R& r) { return json(r.maxEnergyGainJ); }},
        {"exploded", "NaN, a speed over 100 m/s or an anchor error over 0.1 m",
         [](const R& r) { return json(r.exploded); }},
        {"exploded_at_s", "when it first exploded", [](const R& r) { return jsonOrNull(r.explodedAtS); }},
        {"wall_ms", "wall time of the whole run", [](const R& r) { return json(r.wallMs); }},
        {"us_per_step", "wall time of stepping per step", [](const R& r) { return json(r.usPerStep); }},
        {"awake_body_steps", "body-steps not asleep (keyframed bodies included)",
         [](const R& r) { return json(r.awakeBodySteps); }},
        {"step_cpu_ms", "thread CPU time inside the steps", [](const R& r) { return json(r.stepCpuMs); }},
        {"awake_step_cpu_ms", "of it, the steps that began or ended with a body awake",
         [](const R& r) { return json(r.awakeStepCpuMs); }},
        {"cpu_us_per_awake_body_step", "awake_step_cpu_ms per awake body-step, in us (as afb drop's)",
         [](const R& r) { return json(r.cpuUsPerAwakeBodyStep); }},
    };
    return table;
}

} // namespace

json trackOptionsJson(const TrackOptions& o, const figure::Figure& figure) {
    json hit = nullptr;
    if (o.hit)
        hit = {{"body", figure.bodies.at(static_cast<std::size_t>(o.hit->body)).name},
               {"impulse_ns", o.hit->impulseNs},
               {"at_s", o.hit->atSeconds},
               {"direction", "world +X"},
               {"strength_after", o.hit->reaction.strength},
               {"regain_s", o.hit->reaction.regainSeconds}};
    return {{"seconds", o.seconds},          {"hz", o.hz}, {"root", toString(o.root)},
            {"strength", o.strength},        {"hit", hit}, {"warmup_s", o.warmupSeconds},
            {"method", methodJson(o.method)}};
}

json trackResultJson(const TrackResult& r) {
    json j = detail::fieldsJson(trackFields(), r);
    j["method"] = methodJson(r.method);
    return j;
}

std::string trackCsvHeader() { return detail::fieldsCsvHeader(trackFields()); }

std::string trackCsvRow(const TrackResult& r) { return detail::fieldsCsvRow(trackFields(), r, r.method); }

std::string trackFieldsHelp() { return detail::fieldsHelp(trackFields()); }

} // namespace afb::sim
