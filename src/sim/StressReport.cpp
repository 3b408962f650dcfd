// The stress matrix's cells and its reports (Stress.h): the table, the Markdown page and the JSON document.
#include <algorithm>
#include <cstdio>
#include <optional>

#include <nlohmann/json.hpp>

#include "StressText.h"
#include "afb/sim/Report.h"
#include "afb/sim/Stress.h"

namespace afb::sim {
using detail::fixed;

std::vector<StressCell> stressCells(const std::vector<StressResult>& results) {
    std::vector<StressCell> cells;
    for (std::size_t i = 0; i < results.size(); ++i) {
        const StressResult& r = results[i];
        auto c = std::find_if(cells.begin(), cells.end(),
                              [&](const StressCell& x) { return x.scenario == r.scenario && x.method == r.method; });
        if (c == cells.end()) c = cells.insert(cells.end(), StressCell{r.scenario, r.method, 0, 0, {}, {}});
        ++c->total;
        if (r.passed()) {
            ++c->passed;
            continue;
        }
        auto cause =
            std::find_if(c->causes.begin(), c->causes.end(), [&](const auto& x) { return x.first == r.cause; });
        if (cause == c->causes.end()) c->causes.emplace_back(r.cause, 1);
        else ++cause->second;
        if (!c->firstFailure || r.yawDeg < results[*c->firstFailure].yawDeg) c->firstFailure = i;
    }
    for (StressCell& c : cells)
        std::stable_sort(c.causes.begin(), c.causes.end(), [](const auto& a, const auto& b) {
            return a.second != b.second ? a.second > b.second : a.first < b.first;
        });
    return cells;
}

std::string stressCellText(const StressCell& c, const std::vector<StressResult>& results) {
    if (c.total == 1) {
        if (!c.firstFailure) return "ok";
        const StressResult& r = results[*c.firstFailure];
        if (r.cause == StressCause::Skipped) return "-";
        return std::string(toString(r.cause)) + " " + (r.failedAtS ? fixed(*r.failedAtS, 2) + "s" : "");
    }
    if (c.skipped()) return "-";
    std::string out = std::to_string(c.passed) + "/" + std::to_string(c.total);
    for (std::size_t i = 0; i < c.causes.size(); ++i)
        out += (i == 0 ? " (" : ", ") + std::string(toString(c.causes[i].first)) + " " +
               std::to_string(c.causes[i].second) + (i + 1 == c.causes.size() ? ")" : "");
    return out;
}

namespace {

std::vector<std::string> scenarioOrder(const std::vector<StressResult>& results) {
    std::vector<std::string> names;
    for (const StressResult& r : results)
        if (std::find(names.begin(), names.end(), r.scenario) == names.end()) names.push_back(r.scenario);
    return names;
}

const StressCell* cellOf(const std::vector<StressCell>& cells, const std::string& scenario, const std::string& method) {
    for (const StressCell& c : cells)
        if (c.scenario == scenario && c.method == method) return &c;
    return nullptr;
}

// The runs per cell (1 for a matrix without yaws).
int yawCount(const std::vector<StressCell>& cells) { return cells.empty() ? 1 : cells.front().total; }

// A time that may not have come: its value, or null.
nlohmann::ordered_json orNull(const std::optional<double>& seconds) {
    return seconds ? nlohmann::ordered_json(*seconds) : nlohmann::ordered_json(nullptr);
}

} // namespace

std::string stressTable(const std::vector<StressResult>& results, const std::vector<StressMethod>& methods) {
    const std::vector<StressCell> cells = stressCells(results);
    const std::vector<std::string> scenarios = scenarioOrder(results);
    std::size_t first = 8;
    for (const std::string& s : scenarios) first = std::max(first, s.size());
    std::vector<std::size_t> widths;
    for (const StressMethod& m : methods) {
        std::size_t w = std::max<std::size_t>(m.label.size(), 4);
        for (const StressCell& c : cells)
            if (c.method == m.label) w = std::max(w, stressCellText(c, results).size());
        widths.push_back(w);
    }
    auto pad = [](std::string s, std::size_t w) {
        s.resize(std::max(s.size(), w), ' ');
        return s;
    };
    std::string out = pad("scenario", first);
    for (std::size_t m = 0; m < methods.size(); ++m) out += "  " + pad(methods[m].label, widths[m]);
    out += "\n";
    for (const std::string& s : scenarios) {
        out += pad(s, first);
        for (std::size_t m = 0; m < methods.size(); ++m) {
            const StressCell* c = cellOf(cells, s, methods[m].label);
            out += "  " + pad(c ? stressCellText(*c, results) : "", widths[m]);
        }
        out += "\n";
    }
    return out;
}

std::string stressMarkdown(const std::vector<StressResult>& results, const std::vector<StressMethod>& methods,
                           const StressThresholds& th) {
    std::string out = "# afb stress\n\nBullet " + bulletVersion() + " (" + bulletPrecision() +
                      "). A cell passes when the run comes to rest (no body moves more than " +
                      fixed(th.restMoveM * 1000, 0) + " mm nor turns more than " + fixed(th.restTurnDeg, 0) +
                      "° over " + fixed(th.restWindowS, 1) + " s, and none reports a spin over " +
                      fixed(th.maxResidualSpinRadps, 0) + " rad/s meanwhile) within " + fixed(th.restWithinS, 0) +
                      " s without a failure; otherwise it shows the first failure and its time. Failures: nan "
                      "(non-finite state), speed (over " +
                      fixed(th.maxSpeedMps, 0) + " m/s), anchor (over " + fixed(th.maxAnchorErrorM * 1000, 0) +
                      " mm), limit (over " + fixed(th.maxLimitOvershootDeg, 0) + "°), penetration (over " +
                      fixed(th.maxPenetrationM * 100, 0) + " cm after " + fixed(th.penetrationAfterS, 0) +
                      " s), energy (a gain over " + fixed(th.maxEnergyGainJ, 0) +
                      " J beyond external work), jitter (a body reporting over " + fixed(th.maxResidualSpinRadps, 0) +
                      " rad/s in the second half of the rest window, or in the last second of a run that never rests), "
                      "no-rest.\n\n";
    const std::vector<StressCell> cells = stressCells(results);
    const int yaws = yawCount(cells);
    if (yaws > 1)
        out += "Each scenario is run at " + std::to_string(yaws) + " yaws about the vertical (run k turned by k·" +
               fixed(360.0 / yaws, 1) +
               "°): a cell shows how many of its runs passed and the causes of the others.\n\n";
    out += "| scenario |";
    for (const StressMethod& m : methods) out += " `" + m.label + "` |";
    out += "\n|---|";
    for (std::size_t m = 0; m < methods.size(); ++m) out += "---|";
    out += "\n";
    const std::vector<std::string> scenarios = scenarioOrder(results);
    for (const std::string& s : scenarios) {
        out += "| " + s + " |";
        for (const StressMethod& m : methods) {
            const StressCell* c = cellOf(cells, s, m.label);
            if (!c) out += " |";
            else if (c->passed < c->total) out += " **" + stressCellText(*c, results) + "** |";
            else if (c->total > 1) out += " " + stressCellText(*c, results) + " |";
            else {
                const StressResult* r = &*std::find_if(results.begin(), results.end(), [&](const StressResult& x) {
                    return x.scenario == s && x.method == m.label;
                });
                out += " ok (rest " + fixed(r->restAtS.value_or(0), 1) + " s) |";
            }
        }
        out += "\n";
    }
    out += "\n## Scenarios\n\n";
    for (const std::string& s : scenarios)
        if (const StressScenario* sc = findStressScenario(s)) out += "- `" + s + "`: " + sc->description + "\n";
    // With yaws, every run's row says its yaw (a column after the method).
    const std::string yawHead = yaws > 1 ? " yaw ° |" : "", yawRule = yaws > 1 ? "---|" : "";
    auto yawOf = [yaws](const StressResult& r) { return yaws > 1 ? " " + fixed(r.yawDeg, 1) + " |" : ""; };
    out += "\n## Failures\n\n| scenario | method |" + yawHead + " cause | at | what |\n|---|---|" + yawRule +
           "---|---|---|\n";
    for (const StressResult& r : results)
        if (!r.passed() && r.cause != StressCause::Skipped)
            out += "| " + r.scenario + " | `" + r.method + "` |" + yawOf(r) + " " + std::string(toString(r.cause)) +
                   " | " + (r.failedAtS ? fixed(*r.failedAtS, 3) + " s" : "") + " | " + r.detail + " |\n";
    out += "\n## Worst values (up to the first failure)\n\n| scenario | method |" + yawHead +
           " speed m/s | anchor mm | limit ° | penetration mm | energy gain J | rest at s | CPU ms |\n|---|---|" +
           yawRule + "---|---|---|---|---|---|---|\n";
    for (const StressResult& r : results)
        if (r.cause != StressCause::Skipped)
            out += "| " + r.scenario + " | `" + r.method + "` |" + yawOf(r) + " " + fixed(r.maxSpeedMps, 1) + " | " +
                   fixed(r.maxAnchorErrorM * 1000, 1) + " | " + fixed(r.maxLimitOvershootDeg, 1) + " | " +
                   fixed(r.maxPenetrationM * 1000, 1) + " | " + fixed(r.maxEnergyGainJ, 2) + " | " +
                   (r.restAtS ? fixed(*r.restAtS, 2) : "-") + " | " + fixed(r.cpuMs, 0) + " |\n";
    return out;
}

std::string stressJson(const std::vector<StressResult>& results, const std::vector<StressMethod>& methods,
                       const StressThresholds& th) {
    const std::vector<StressCell> cells = stressCells(results);
    nlohmann::ordered_json j;
    j["schema"] = schemaJson(kStressSchema);
    j["bullet"] = bulletVersion();
    j["precision"] = bulletPrecision();
    j["yaws"] = yawCount(cells);
    j["thresholds"] = {{"max_speed_mps", th.maxSpeedMps},
                       {"max_anchor_error_m", th.maxAnchorErrorM},
                       {"max_limit_overshoot_deg", th.maxLimitOvershootDeg},
                       {"max_penetration_m", th.maxPenetrationM},
                       {"penetration_after_s", th.penetrationAfterS},
                       {"max_residual_spin_radps", th.maxResidualSpinRadps},
                       {"max_energy_gain_j", th.maxEnergyGainJ},
                       {"rest_within_s", th.restWithinS},
                       {"rest_move_m", th.restMoveM},
                       {"rest_turn_deg", th.restTurnDeg},
                       {"rest_window_s", th.restWindowS}};
    nlohmann::ordered_json ms = nlohmann::ordered_json::array();
    for (const StressMethod& m : methods) {
        nlohmann::ordered_json knobs;
        for (const bullet::MethodKnob& k : bullet::methodKnobs()) knobs[std::string(k.name)] = knobValue(m.method, k);
        ms.push_back({{"label", m.label},
                      {"name", m.method.name},
                      {"knobs", knobs},
                      {"stabilize", m.stabilize},
                      {"rest_rules", m.restRules},
                      {"clamp_linear_mps", m.clamp.maxLinearMps},
                      {"clamp_angular_radps", m.clamp.maxAngularRadps}});
    }
    j["methods"] = ms;
    nlohmann::ordered_json cellsJson = nlohmann::ordered_json::array();
    for (const StressCell& c : cells) {
        nlohmann::ordered_json causes = nlohmann::ordered_json::object();
        for (const auto& [cause, count] : c.causes) causes[std::string(toString(cause))] = count;
        nlohmann::ordered_json first = nullptr;
        if (c.firstFailure) {
            const StressResult& r = results[*c.firstFailure];
            first = {{"yaw_deg", r.yawDeg},
                     {"cause", std::string(toString(r.cause))},
                     {"failed_at_s", orNull(r.failedAtS)},
                     {"detail", r.detail}};
        }
        cellsJson.push_back({{"scenario", c.scenario},
                             {"method", c.method},
                             {"passed", c.passed},
                             {"total", c.total},
                             {"causes", causes},
                             {"first_failure", first}});
    }
    j["cells"] = cellsJson;
    nlohmann::ordered_json runs = nlohmann::ordered_json::array();
    for (const StressResult& r : results) {
        nlohmann::ordered_json c = {{"scenario", r.scenario},
                                    {"method", r.method},
                                    {"yaw_deg", r.yawDeg},
                                    {"passed", r.passed()},
                                    {"cause", std::string(toString(r.cause))},
                                    {"failed_at_s", orNull(r.failedAtS)},
                                    {"detail", r.detail},
                                    {"simulated_s", r.simulatedS},
                                    {"rest_at_s", orNull(r.restAtS)},
                                    {"bodies", r.bodies},
                                    {"max_speed_mps", r.maxSpeedMps},
                                    {"max_anchor_error_m", r.maxAnchorErrorM},
                                    {"max_limit_overshoot_deg", r.maxLimitOvershootDeg},
                                    {"max_penetration_m", r.maxPenetrationM},
                                    {"max_energy_gain_j", r.maxEnergyGainJ},
                                    {"cpu_ms", r.cpuMs}};
        runs.push_back(c);
    }
    j["runs"] = runs;
    return j.dump(2) + "\n";
}

} // namespace afb::sim
