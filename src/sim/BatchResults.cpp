// Exact JSON of stress and drop results (Batch.h): every field, every double bit for bit.
#include <stdexcept>

#include "afb/sim/Batch.h"
#include "afb/sim/Report.h"

namespace afb::sim {
namespace {

using nlohmann::json;

json optionalNumber(const std::optional<double>& v) { return v ? exactNumber(*v) : json(nullptr); }
std::optional<double> fromOptionalNumber(const json& v) {
    if (v.is_null()) return std::nullopt;
    return fromExactNumber(v);
}

json numbers(const double* v, std::size_t n) {
    json a = json::array();
    for (std::size_t i = 0; i < n; ++i) a.push_back(exactNumber(v[i]));
    return a;
}
void readNumbers(const json& a, double* v, std::size_t n) {
    if (!a.is_array() || a.size() != n) throw std::runtime_error("expected " + std::to_string(n) + " numbers");
    for (std::size_t i = 0; i < n; ++i) v[i] = fromExactNumber(a[i]);
}

json transformExact(const figure::Transform& t) {
    return {{"rotation", numbers(t.rotation.data(), 9)}, {"position", numbers(t.position.data(), 3)}};
}
figure::Transform transformFromExact(const json& j) {
    figure::Transform t;
    readNumbers(j.at("rotation"), t.rotation.data(), 9);
    readNumbers(j.at("position"), t.position.data(), 3);
    return t;
}

StressCause causeFromString(const std::string& s) {
    for (StressCause c : {StressCause::None, StressCause::NonFinite, StressCause::Speed, StressCause::Anchor,
                          StressCause::Limit, StressCause::Penetration, StressCause::Jitter, StressCause::EnergyGain,
                          StressCause::NoRest, StressCause::Skipped})
        if (toString(c) == s) return c;
    throw std::runtime_error("unknown stress cause " + s);
}

} // namespace

json stressResultExact(const StressResult& r) {
    return {{"scenario", r.scenario},
            {"method", r.method},
            {"yaw_deg", exactNumber(r.yawDeg)},
            {"cause", std::string(toString(r.cause))},
            {"failed_at_s", optionalNumber(r.failedAtS)},
            {"detail", r.detail},
            {"simulated_s", exactNumber(r.simulatedS)},
            {"rest_at_s", optionalNumber(r.restAtS)},
            {"bodies", r.bodies},
            {"max_speed_mps", exactNumber(r.maxSpeedMps)},
            {"max_anchor_error_m", exactNumber(r.maxAnchorErrorM)},
            {"max_limit_overshoot_deg", exactNumber(r.maxLimitOvershootDeg)},
            {"max_penetration_m", exactNumber(r.maxPenetrationM)},
            {"max_energy_gain_j", exactNumber(r.maxEnergyGainJ)},
            {"cpu_ms", exactNumber(r.cpuMs)}};
}

StressResult stressResultFromExact(const json& j) {
    StressResult r;
    r.scenario = j.at("scenario").get<std::string>();
    r.method = j.at("method").get<std::string>();
    r.yawDeg = fromExactNumber(j.at("yaw_deg"));
    r.cause = causeFromString(j.at("cause").get<std::string>());
    r.failedAtS = fromOptionalNumber(j.at("failed_at_s"));
    r.detail = j.at("detail").get<std::string>();
    r.simulatedS = fromExactNumber(j.at("simulated_s"));
    r.restAtS = fromOptionalNumber(j.at("rest_at_s"));
    r.bodies = j.at("bodies").get<int>();
    r.maxSpeedMps = fromExactNumber(j.at("max_speed_mps"));
    r.maxAnchorErrorM = fromExactNumber(j.at("max_anchor_error_m"));
    r.maxLimitOvershootDeg = fromExactNumber(j.at("max_limit_overshoot_deg"));
    r.maxPenetrationM = fromExactNumber(j.at("max_penetration_m"));
    r.maxEnergyGainJ = fromExactNumber(j.at("max_energy_gain_j"));
    r.cpuMs = fromExactNumber(j.at("cpu_ms"));
    return r;
}

json dropResultExact(const DropResult& r) {
    json pose = json::array();
    for (const JointPose& p : r.finalPose)
        pose.push_back(
            {{"joint", p.name}, {"position", numbers(p.position, 3)}, {"quaternion", numbers(p.quaternion, 4)}});
    json bodies = json::array();
    for (const figure::Transform& t : r.firstBodies) bodies.push_back(transformExact(t));
    return {{"figure", r.figure},
            {"precision", r.precision},
            {"method", methodJson(r.method)},
            {"counts", {r.bodies, r.constraints, r.steps}},
            {"lod_bodies", r.lodBodies ? json(*r.lodBodies) : json(nullptr)},
            {"motors", r.motors ? json({exactNumber(r.motors->frequencyHz), exactNumber(r.motors->dampingRatio)})
                                : json(nullptr)},
            {"timing", {exactNumber(r.wallMs), exactNumber(r.usPerStep), exactNumber(r.usPerBodyStep)}},
            {"awake_body_steps", r.awakeBodySteps},
            {"cpu", {exactNumber(r.stepCpuMs), exactNumber(r.awakeStepCpuMs), exactNumber(r.cpuUsPerAwakeBodyStep)}},
            {"errors",
             {exactNumber(r.maxAnchorErrorM), exactNumber(r.maxLimitViolationDeg), exactNumber(r.maxPenetrationM),
              exactNumber(r.maxEnergyGainJ), exactNumber(r.restPenetrationM), exactNumber(r.maxSpeedMps)}},
            {"worst", {r.worstAnchorJoint, r.worstLimitJoint, r.worstContact}},
            {"exploded", r.exploded},
            {"exploded_at_s", optionalNumber(r.explodedAtS)},
            {"non_finite", r.nonFinite},
            {"settle_time_s", optionalNumber(r.settleTimeS)},
            {"entity", numbers(r.entity, 7)},
            {"final_pose", pose},
            {"first_bodies", bodies},
            {"first_spawn", transformExact(r.firstSpawn)}};
}

DropResult dropResultFromExact(const json& j) {
    DropResult r;
    r.figure = j.at("figure").get<std::string>();
    r.precision = j.at("precision").get<std::string>();
    if (const auto m = j.find("method"); m != j.end())
        if (std::string e = methodFromJson(*m, r.method); !e.empty()) throw std::runtime_error(e);
    const json& counts = j.at("counts");
    r.bodies = counts.at(0).get<int>();
    r.constraints = counts.at(1).get<int>();
    r.steps = counts.at(2).get<int>();
    if (!j.at("lod_bodies").is_null()) r.lodBodies = j.at("lod_bodies").get<int>();
    if (const json motors = j.value("motors", json(nullptr)); !motors.is_null()) {
        double gains[2];
        readNumbers(motors, gains, 2);
        r.motors = bullet::MotorGains{gains[0], gains[1]};
    }
    double timing[3], cpu[3], errors[6];
    readNumbers(j.at("timing"), timing, 3);
    readNumbers(j.at("cpu"), cpu, 3);
    readNumbers(j.at("errors"), errors, 6);
    r.wallMs = timing[0], r.usPerStep = timing[1], r.usPerBodyStep = timing[2];
    r.stepCpuMs = cpu[0], r.awakeStepCpuMs = cpu[1], r.cpuUsPerAwakeBodyStep = cpu[2];
    r.maxAnchorErrorM = errors[0], r.maxLimitViolationDeg = errors[1], r.maxPenetrationM = errors[2];
    r.maxEnergyGainJ = errors[3], r.restPenetrationM = errors[4], r.maxSpeedMps = errors[5];
    r.awakeBodySteps = j.at("awake_body_steps").get<long long>();
    const json& worst = j.at("worst");
    r.worstAnchorJoint = worst.at(0).get<std::string>();
    r.worstLimitJoint = worst.at(1).get<std::string>();
    r.worstContact = worst.at(2).get<std::string>();
    r.exploded = j.at("exploded").get<bool>();
    r.explodedAtS = fromOptionalNumber(j.at("exploded_at_s"));
    r.nonFinite = j.at("non_finite").get<bool>();
    r.settleTimeS = fromOptionalNumber(j.at("settle_time_s"));
    readNumbers(j.at("entity"), r.entity, 7);
    for (const json& p : j.at("final_pose")) {
        JointPose pose{p.at("joint").get<std::string>(), {}, {}};
        readNumbers(p.at("position"), pose.position, 3);
        readNumbers(p.at("quaternion"), pose.quaternion, 4);
        r.finalPose.push_back(std::move(pose));
    }
    for (const json& b : j.at("first_bodies")) r.firstBodies.push_back(transformFromExact(b));
    r.firstSpawn = transformFromExact(j.at("first_spawn"));
    return r;
}

} // namespace afb::sim
