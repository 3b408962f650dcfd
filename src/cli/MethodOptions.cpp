#include "MethodOptions.h"

#include "afb/sim/RawRagdoll.h"

namespace afb::cli {

void addMethodOptions(CLI::App* cmd, const std::shared_ptr<MethodOptions>& options) {
    std::string presets;
    for (std::string_view p : sim::methodNames()) presets += (presets.empty() ? "" : ", ") + std::string(p);
    cmd->add_option("--method", options->preset,
                    "How figures are simulated: " + presets + " (docs/methods.md; raw: plain Bullet, the reference)")
        ->capture_default_str();
    const auto knobs = bullet::methodKnobs();
    options->overrides.assign(knobs.size(), std::string());
    const bullet::Method base;
    for (std::size_t i = 0; i < knobs.size(); ++i)
        cmd->add_option("--" + std::string(knobs[i].name), options->overrides[i],
                        std::string(knobs[i].help) +
                            " (overrides the method's; default method: " + bullet::knobValue(base, knobs[i]) + ")")
            ->group("Method knobs");
}

std::optional<bullet::Method> resolveMethod(const MethodOptions& options, std::string& error) {
    auto method = sim::methodByName(options.preset);
    if (!method) {
        error = "--method " + options.preset + ": unknown method (";
        for (std::string_view p : sim::methodNames()) error += " " + std::string(p);
        error += " )";
        return std::nullopt;
    }
    const auto knobs = bullet::methodKnobs();
    for (std::size_t i = 0; i < knobs.size() && i < options.overrides.size(); ++i) {
        if (options.overrides[i].empty()) continue;
        error = bullet::setKnob(*method, knobs[i], options.overrides[i]);
        if (!error.empty()) return std::nullopt;
    }
    error = sim::rawMethodError(*method);
    if (!error.empty()) return std::nullopt;
    return method;
}

} // namespace afb::cli
