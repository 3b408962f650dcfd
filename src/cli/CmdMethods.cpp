// afb methods: the presets and the knobs of bullet::Method, with what each means (docs/methods.md has the why and
// the measured numbers).
#include <cstdio>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "Commands.h"
#include "MethodOptions.h"
#include "Suggest.h"
#include "Usage.h"
#include "afb/bullet/Method.h"
#include "afb/sim/RawRagdoll.h"
#include "afb/sim/Report.h"

namespace afb::cli {
namespace {

// One line per method name that --method takes.
std::string_view presetSummary(std::string_view name) {
    if (name == "fast")
        return "the default's direct joint solve in block mode: 2 iterations, 2 position sweeps, an anchor tree "
               "step; the cheap one";
    if (name == "balanced")
        return "the default in block mode: 3 iterations; about the default's accuracy for three quarters of its cost";
    if (name == "iterative")
        return "the default without the direct joint solve (what a world without a RagdollSolver runs)";
    if (name == "default")
        return "joints solved exactly each iteration, position pass with tree steps; the accurate one";
    if (name == "exact") return "the same method as default";
    if (name == "accurate") return "the iterative solve in 2 substeps (the substep rung of the chart)";
    if (name == "legacy") return "afbullet 0.1: Bullet's solver, none of the techniques (a reference)";
    if (name == "multibody") return "the reduced-coordinate backend (btMultiBody trees)";
    if (name == "raw") return "plain Bullet as a user writes it: Bullet's defaults and constraints (the reference)";
    return "";
}

std::vector<std::string> methodNameList() {
    std::vector<std::string> names;
    for (std::string_view n : sim::methodNames()) names.emplace_back(n);
    return names;
}

void printOverview() {
    const bullet::Method base;
    std::printf("Methods (--method NAME; afb methods NAME lists one's knobs; docs/methods.md explains them):\n");
    for (std::string_view n : sim::methodNames())
        std::printf("  %-10s %s\n", std::string(n).c_str(), std::string(presetSummary(n)).c_str());
    std::printf("\nKnobs (afb drop and golden record: --KNOB VALUE; chart and stress: NAME:KNOB=VALUE):\n");
    std::printf("  %-28s %-17s %-10s %s\n", "knob", "values", "default", "meaning");
    for (const bullet::MethodKnob& k : bullet::methodKnobs())
        std::printf("  %-28s %-17s %-10s %s\n", std::string(k.name).c_str(), knobType(k).c_str(),
                    bullet::knobValue(base, k).c_str(), std::string(k.help).c_str());
}

// One method's knobs, those that differ from the default marked.
void printMethod(const bullet::Method& m, std::string_view name) {
    const bullet::Method base;
    std::printf("%s: %s\n", std::string(name).c_str(), std::string(presetSummary(name)).c_str());
    for (const bullet::MethodKnob& k : bullet::methodKnobs()) {
        const std::string value = bullet::knobValue(m, k), usual = bullet::knobValue(base, k);
        if (value == usual) std::printf("  %-28s %s\n", std::string(k.name).c_str(), value.c_str());
        else std::printf("  %-28s %-12s (default: %s)\n", std::string(k.name).c_str(), value.c_str(), usual.c_str());
    }
}

nlohmann::json knobsJson(const bullet::Method& m) {
    nlohmann::json out = nlohmann::json::object();
    for (const bullet::MethodKnob& k : bullet::methodKnobs()) out[std::string(k.name)] = bullet::knobValue(m, k);
    return out;
}

nlohmann::json overviewJson() {
    nlohmann::json methods = nlohmann::json::array(), knobs = nlohmann::json::array();
    for (std::string_view n : sim::methodNames())
        methods.push_back({{"name", n}, {"summary", presetSummary(n)}, {"knobs", knobsJson(*sim::methodByName(n))}});
    const bullet::Method base;
    for (const bullet::MethodKnob& k : bullet::methodKnobs())
        knobs.push_back(
            {{"name", k.name}, {"values", knobType(k)}, {"default", bullet::knobValue(base, k)}, {"help", k.help}});
    return {{"methods", methods}, {"knobs", knobs}};
}

} // namespace

void addMethodsCommand(CLI::App& app, int& exitCode) {
    auto* cmd = app.add_subcommand("methods", "The methods (presets) and the knobs that tune them, with their meaning\n"
                                              "Examples:\n  afb methods\n  afb methods fast");
    auto name = std::make_shared<std::string>();
    auto json = std::make_shared<bool>(false);
    cmd->add_option("name", *name, "One method: its value of every knob");
    cmd->add_flag("--json", *json, "As JSON on stdout");
    cmd->callback([name, json, &exitCode] {
        if (name->empty()) {
            if (*json) {
                nlohmann::json j = overviewJson();
                j["schema"] = sim::schemaJson(sim::kMethodsSchema);
                std::printf("%s\n", j.dump(2).c_str());
            } else printOverview();
            exitCode = 0;
            return;
        }
        const auto method = sim::methodByName(*name);
        if (!method) usageError(unknownName("method", *name, methodNameList()));
        if (*json)
            std::printf("%s\n", nlohmann::json{{"schema", sim::schemaJson(sim::kMethodSchema)},
                                               {"name", *name},
                                               {"summary", presetSummary(*name)},
                                               {"knobs", knobsJson(*method)}}
                                    .dump(2)
                                    .c_str());
        else printMethod(*method, *name);
        exitCode = 0;
    });
}

} // namespace afb::cli
