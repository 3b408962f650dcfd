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

/// Registers --method and the knob flags on `cmd`; `options` must outlive the parse. An unknown method and a knob
/// value the knob does not take are refused by the parse.
void addMethodOptions(CLI::App* cmd, const std::shared_ptr<MethodOptions>& options);

/// The values a knob takes, as help and `afb methods` show them: INT, FLOAT, on|off, or the names of an enum.
std::string knobType(const bullet::MethodKnob& knob);

/// `m` as afb chart and afb stress spell a method: its preset's name, then `:KNOB=VALUE` for each knob whose value
/// differs from the preset's ("fast:iterations=8").
std::string methodSpec(const bullet::Method& m);

/// The preset with the overrides applied; a combination the method cannot run (a knob the raw method lacks) is a
/// usage error (usageError).
bullet::Method resolveMethod(const MethodOptions& options);

/// For a method spec of afb chart and afb stress (NAME[:KNOB=VALUE]...[+MITIGATION]...) that did not parse: "; did
/// you mean 'X'?" for its first misspelt name, method, knob or mitigation, or an empty string.
std::string methodSpecHint(std::string_view spec);

} // namespace afb::cli
