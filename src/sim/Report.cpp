// Drop and method serialisation: one table of result fields feeds the JSON, the CSV and the help text.
#include "afb/sim/Report.h"

#include <functional>
#include <sstream>

#include "ReportFields.h"
#include "afb/sim/RawRagdoll.h"

namespace afb::sim {
namespace {

using nlohmann::json;

using Field = detail::ReportField<DropResult>;

const std::vector<Field>& fields() {
    static const std::vector<Field> table = {
        {"figure", "entity's figure name", [](const DropResult& r) { return json(r.figure); }},
        {"precision", "Bullet build, float or double", [](const DropResult& r) { return json(r.precision); }},
        {"method", "the method's preset name (its knobs follow in JSON as \"method\", in CSV as method.*)",
         [](const DropResult& r) { return json(r.method.name); }},
        {"bodies", "bodies over all instances", [](const DropResult& r) { return json(r.bodies); }},
        {"constraints", "constraints over all instances", [](const DropResult& r) { return json(r.constraints); }},
        {"lod_bodies", "rigid bodies per instance at the level of detail (--lod), empty at full detail",
         [](const DropResult& r) { return r.lodBodies ? json(*r.lodBodies) : json(nullptr); }},
        {"motor_hz", "the joint motors' frequency when the instances held their pose with motors (--motor-hz)",
         [](const DropResult& r) { return r.motors ? json(r.motors->frequencyHz) : json(nullptr); }},
        {"motor_damping_ratio", "their damping ratio (--motor-damping), empty without motors",
         [](const DropResult& r) { return r.motors ? json(r.motors->dampingRatio) : json(nullptr); }},
        {"steps", "frames stepped", [](const DropResult& r) { return json(r.steps); }},
        {"wall_ms", "wall time of the whole run", [](const DropResult& r) { return json(r.wallMs); }},
        {"us_per_step", "stepping only, the slowest world", [](const DropResult& r) { return json(r.usPerStep); }},
        {"us_per_body_step", "us_per_step × threads / bodies",
         [](const DropResult& r) { return json(r.usPerBodyStep); }},
        {"awake_body_steps", "body-steps not asleep", [](const DropResult& r) { return json(r.awakeBodySteps); }},
        {"step_cpu_ms", "thread CPU time inside the steps, all worlds",
         [](const DropResult& r) { return json(r.stepCpuMs); }},
        {"awake_step_cpu_ms", "of it, the steps that began or ended with a body awake",
         [](const DropResult& r) { return json(r.awakeStepCpuMs); }},
        {"cpu_us_per_awake_body_step", "awake_step_cpu_ms per awake body-step, in us (the cost afb chart plots)",
         [](const DropResult& r) { return json(r.cpuUsPerAwakeBodyStep); }},
        {"max_anchor_error_m", "largest separation of a constraint's two anchor copies (sliders: off-axis only)",
         [](const DropResult& r) { return json(r.maxAnchorErrorM); }},
        {"worst_anchor_joint", "the constraint where it happened",
         [](const DropResult& r) { return json(r.worstAnchorJoint); }},
        {"max_limit_violation_deg", "largest excess over a cone, pyramid or hinge limit",
         [](const DropResult& r) { return json(r.maxLimitViolationDeg); }},
        {"worst_limit_joint", "the constraint where it happened",
         [](const DropResult& r) { return json(r.worstLimitJoint); }},
        {"max_penetration_m", "deepest contact (ground and between bodies)",
         [](const DropResult& r) { return json(r.maxPenetrationM); }},
        {"worst_contact", "the pair where it happened", [](const DropResult& r) { return json(r.worstContact); }},
        {"rest_penetration_m", "deepest contact over the last simulated second",
         [](const DropResult& r) { return json(r.restPenetrationM); }},
        {"max_energy_gain_j", "kinetic + potential above the start",
         [](const DropResult& r) { return json(r.maxEnergyGainJ); }},
        {"max_speed_mps", "fastest body", [](const DropResult& r) { return json(r.maxSpeedMps); }},
        {"exploded", "NaN, a speed over 100 m/s or an anchor error over 0.1 m",
         [](const DropResult& r) { return json(r.exploded); }},
        {"exploded_at_s", "when it first exploded", [](const DropResult& r) { return jsonOrNull(r.explodedAtS); }},
        {"non_finite", "a body's pose or velocity became NaN or infinite (a runtime failure, never expected)",
         [](const DropResult& r) { return json(r.nonFinite); }},
        {"settle_time_s", "every instance at rest by its figure's rules, else null",
         [](const DropResult& r) { return jsonOrNull(r.settleTimeS); }},
        {"frozen_before_contact",
         "instances put to rest by their rules (maxMoveTime) before they touched anything: frozen in the air",
         [](const DropResult& r) { return json(r.frozenBeforeContact); }},
    };
    return table;
}

} // namespace

json jsonOrNull(const std::optional<double>& value) { return value ? json(*value) : json(nullptr); }

std::string csvCell(const json& v) {
    if (v.is_null()) return "";
    if (v.is_boolean()) return v.get<bool>() ? "1" : "0";
    if (v.is_string()) {
        const std::string s = v.get<std::string>();
        if (s.find_first_of(",\"\n") == std::string::npos) return s;
        std::string q = "\"";
        for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
        return q + "\"";
    }
    return v.dump();
}

nlohmann::json schemaJson(const ReportSchema& schema) { return {{"name", schema.name}, {"version", schema.version}}; }

std::string checkSchema(const nlohmann::json& document, const ReportSchema& schema) {
    if (!document.is_object() || !document.contains("schema")) return {};
    const nlohmann::json& s = document["schema"];
    if (!s.is_object() || !s.contains("name") || !s["name"].is_string() || !s.contains("version") ||
        !s["version"].is_number_integer())
        return "\"schema\" is not {\"name\": …, \"version\": …}";
    const std::string name = s["name"].get<std::string>();
    if (name != schema.name) return "a " + name + " document, not " + std::string(schema.name);
    const auto version = s["version"].get<long long>();
    if (version > schema.version || version < 1)
        return std::string(schema.name) + " version " + std::to_string(version) + ": this afb reads up to version " +
               std::to_string(schema.version);
    return {};
}

json methodJson(const bullet::Method& m) {
    json j = {{"name", m.name}};
    for (const bullet::MethodKnob& k : bullet::methodKnobs()) {
        const std::string text = bullet::knobValue(m, k);
        json value;
        if (std::holds_alternative<int bullet::Method::*>(k.field)) value = m.*std::get<int bullet::Method::*>(k.field);
        else if (std::holds_alternative<double bullet::Method::*>(k.field))
            value = m.*std::get<double bullet::Method::*>(k.field);
        else if (std::holds_alternative<bool bullet::Method::*>(k.field))
            value = m.*std::get<bool bullet::Method::*>(k.field);
        else value = text;
        j[std::string(k.name)] = value;
    }
    return j;
}

std::string methodFromJson(const json& j, bullet::Method& out) {
    if (!j.is_object()) return "method: not an object";
    const std::string name = j.value("name", std::string("default"));
    auto m = methodByName(name);
    if (!m) {
        m = bullet::Method{};
        m->name = name; // a recorded custom name: its knobs follow
    }
    for (const bullet::MethodKnob& k : bullet::methodKnobs()) {
        if (!j.contains(k.name)) continue;
        const json& v = j[std::string(k.name)];
        std::string text;
        if (v.is_boolean()) text = v.get<bool>() ? "on" : "off";
        else if (v.is_number_integer()) text = std::to_string(v.get<long long>());
        else if (v.is_number()) text = v.dump();
        else if (v.is_string()) text = v.get<std::string>();
        else return "method: " + std::string(k.name) + ": unexpected value " + v.dump();
        if (std::string err = bullet::setKnob(*m, k, text); !err.empty()) return "method: " + err;
    }
    out = *m;
    return {};
}

std::vector<std::string> missingKnobs(const json& method) {
    std::vector<std::string> out;
    if (!method.is_object()) return out;
    for (const bullet::MethodKnob& k : bullet::methodKnobs())
        if (!method.contains(k.name)) out.emplace_back(k.name);
    return out;
}

json dropOptionsJson(const DropOptions& o) {
    json j = {{"height_m", o.heightM},         {"count", o.count},
              {"seconds", o.seconds},          {"hz", o.hz},
              {"sleeping", o.sleeping},        {"seed", o.seed ? json(*o.seed) : json(nullptr)},
              {"method", methodJson(o.method)}};
    if (o.lod) j["lod"] = *o.lod; // only when set: records made before levels of detail stay as they were
    return j;
}

std::string dropOptionsFromJson(const json& j, DropOptions& o) {
    if (!j.is_object()) return "options: not an object";
    try {
        o.heightM = j.value("height_m", o.heightM);
        o.count = j.value("count", o.count);
        o.seconds = j.value("seconds", o.seconds);
        o.hz = j.value("hz", o.hz);
        o.sleeping = j.value("sleeping", o.sleeping);
        if (j.contains("seed") && !j["seed"].is_null()) o.seed = j["seed"].get<std::uint32_t>();
        if (j.contains("lod") && !j["lod"].is_null()) o.lod = j["lod"].get<int>();
        if (j.contains("method")) return methodFromJson(j["method"], o.method);
        // Recorded before methods: the knobs that existed then, on top of the default method.
        o.method = *bullet::methodPreset("default");
        o.method.substeps = j.value("substeps", o.method.substeps);
        o.method.iterations = j.value("iterations", o.method.iterations);
        o.method.jointIterations = j.value("joint_iterations", o.method.jointIterations);
    } catch (const json::exception& e) {
        return std::string("options: ") + e.what();
    }
    return {};
}

json poseJson(const std::vector<JointPose>& pose) {
    json out = json::array();
    for (const JointPose& j : pose)
        out.push_back({{"joint", j.name},
                       {"position", {j.position[0], j.position[1], j.position[2]}},
                       {"quaternion", {j.quaternion[0], j.quaternion[1], j.quaternion[2], j.quaternion[3]}}});
    return out;
}

json dropResultJson(const DropResult& r) {
    json j = detail::fieldsJson(fields(), r);
    j["method"] = methodJson(r.method);
    j["final_pose"] = {{"entity",
                        {{"position", {r.entity[0], r.entity[1], r.entity[2]}},
                         {"quaternion", {r.entity[3], r.entity[4], r.entity[5], r.entity[6]}}}},
                       {"joints", poseJson(r.finalPose)}};
    return j;
}

std::string dropCsvHeader() { return detail::fieldsCsvHeader(fields()); }

std::string dropCsvRow(const DropResult& r) { return detail::fieldsCsvRow(fields(), r, r.method); }

std::string dropFieldsHelp() {
    std::ostringstream out;
    out << detail::fieldsHelp(fields());
    out << "\n  final_pose (JSON only): first instance's entity transform and every md5 joint's model-space position "
           "and w,x,y,z quaternion, metres.";
    return out.str();
}

} // namespace afb::sim
