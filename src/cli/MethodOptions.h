#pragma once
// `--method NAME` and one override flag per knob of bullet::Method (the knob table names them), shared by every
// command that runs a simulation.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "afb/bullet/Method.h"

namespace afb::cli {

/// What the command line said about the method.
struct MethodOptions {
    std::string preset = "default";
    std::vector<std::string> overrides; ///< per knob (methodKnobs() order); empty: not given
};

/// Registers --method and the knob flags on `cmd`; `options` must outlive the parse.
void addMethodOptions(CLI::App* cmd, const std::shared_ptr<MethodOptions>& options);

/// The preset with the overrides applied, or nullopt with `error` set.
std::optional<bullet::Method> resolveMethod(const MethodOptions& options, std::string& error);

} // namespace afb::cli
