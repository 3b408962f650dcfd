#include "MethodOptions.h"

#include <algorithm>
#include <type_traits>

#include "Suggest.h"
#include "Usage.h"
#include "afb/sim/RawRagdoll.h"

namespace afb::cli {
namespace {

std::vector<std::string> presetNames() {
    std::vector<std::string> names;
    for (std::string_view p : sim::methodNames()) names.emplace_back(p);
    return names;
}

std::vector<std::string> knobNames() {
    std::vector<std::string> names;
    for (const bullet::MethodKnob& k : bullet::methodKnobs()) names.emplace_back(k.name);
    return names;
}

// Refuses at parse time a value the knob does not take (setKnob's own check, on a scratch method).
CLI::Validator knobCheck(const bullet::MethodKnob* knob) {
    return CLI::Validator(
        [knob](std::string& value) -> std::string {
            bullet::Method scratch;
            std::string error = bullet::setKnob(scratch, *knob, value);
            // setKnob's message starts with "--KNOB VALUE: "; CLI11 names the option itself.
            const std::string prefix = "--" + std::string(knob->name) + " " + value + ": ";
            if (error.starts_with(prefix)) error = "Value " + value + ": " + error.substr(prefix.size());
            return error;
        },
        "");
}

CLI::Validator presetCheck() {
    return CLI::Validator(
        [](std::string& name) -> std::string {
            return sim::methodByName(name) ? std::string() : unknownName("method", name, presetNames());
        },
        "");
}

} // namespace

std::string knobType(const bullet::MethodKnob& knob) {
    return std::visit(
        [](auto field) -> std::string {
            using Field = decltype(field);
            if constexpr (std::is_same_v<Field, int bullet::Method::*>) return "INT";
            else if constexpr (std::is_same_v<Field, double bullet::Method::*>) return "FLOAT";
            else if constexpr (std::is_same_v<Field, bool bullet::Method::*>) return "on|off";
            else if constexpr (std::is_same_v<Field, bullet::CcdPolicy bullet::Method::*>) return "off|fast-bodies";
            else return "rigid|multibody";
        },
        knob.field);
}

void addMethodOptions(CLI::App* cmd, const std::shared_ptr<MethodOptions>& options) {
    std::string presets;
    for (std::string_view p : sim::methodNames()) presets += (presets.empty() ? "" : ", ") + std::string(p);
    cmd->add_option("--method", options->preset,
                    "How figures are simulated: " + presets +
                        " (raw: plain Bullet, the reference). --KNOB VALUE overrides one knob of it: `afb methods` "
                        "lists the methods and every knob")
        ->type_name("NAME")
        ->check(presetCheck())
        ->capture_default_str();
    const auto knobs = bullet::methodKnobs();
    options->overrides.assign(knobs.size(), std::string());
    const bullet::Method base;
    for (std::size_t i = 0; i < knobs.size(); ++i)
        cmd->add_option("--" + std::string(knobs[i].name), options->overrides[i],
                        std::string(knobs[i].help) +
                            " (overrides the method's; default method: " + bullet::knobValue(base, knobs[i]) + ")")
            ->type_name(knobType(knobs[i]))
            ->check(knobCheck(&knobs[i]))
            ->group("Method knobs (afb methods: values, defaults, meaning)");
}

std::string methodSpec(const bullet::Method& m) {
    std::string spec = m.name;
    const auto preset = sim::methodByName(m.name);
    if (!preset) return bullet::describe(m);
    for (const bullet::MethodKnob& k : bullet::methodKnobs())
        if (const std::string v = bullet::knobValue(m, k); v != bullet::knobValue(*preset, k))
            spec += ":" + std::string(k.name) + "=" + v;
    return spec;
}

bullet::Method resolveMethod(const MethodOptions& options) {
    auto method = sim::methodByName(options.preset);
    if (!method) usageError("--method: " + unknownName("method", options.preset, presetNames()));
    const auto knobs = bullet::methodKnobs();
    for (std::size_t i = 0; i < knobs.size() && i < options.overrides.size(); ++i) {
        if (options.overrides[i].empty()) continue;
        if (const std::string error = bullet::setKnob(*method, knobs[i], options.overrides[i]); !error.empty())
            usageError(error);
    }
    if (const std::string error = sim::rawMethodError(*method); !error.empty()) usageError(error);
    return *method;
}

std::string methodSpecHint(std::string_view spec) {
    const std::size_t end = spec.find_first_of(":+");
    const std::string name(spec.substr(0, end));
    if (!sim::methodByName(name)) return didYouMean(name, presetNames());
    std::string_view rest = end == std::string_view::npos ? std::string_view() : spec.substr(end);
    while (!rest.empty()) {
        const char kind = rest[0];
        rest.remove_prefix(1);
        const std::size_t next = rest.find_first_of(":+");
        const std::string_view item = rest.substr(0, next);
        rest = next == std::string_view::npos ? std::string_view() : rest.substr(next);
        const std::string word(kind == ':' ? item.substr(0, item.find('=')) : item);
        const std::vector<std::string> valid =
            kind == ':' ? knobNames() : std::vector<std::string>{"stabilize", "clamp", "rest"};
        if (std::find(valid.begin(), valid.end(), word) == valid.end()) return didYouMean(word, valid);
    }
    return {};
}

} // namespace afb::cli
