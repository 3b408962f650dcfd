#pragma once
// afb stress's options, inputs and outputs, shared by the one-process command and by plan/run/merge (the batch of
// its runs over many processes), so that both read, run and write the matrix by the same code.
#include <filesystem>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "afb/sim/Stress.h"

namespace afb::cli {

/// The options of `afb stress`.
struct StressCli {
    std::filesystem::path base = ".";
    // Every preset, the multibody backend included. Every method is judged on its physics alone; default+rest is
    // the default as the library spawns a ragdoll (SpawnOptions::comeToRest, the engine's rest rules), the verdict
    // a game sees.
    std::vector<std::string> methods = {"raw",     "legacy",       "fast",     "balanced", "iterative",
                                        "default", "default+rest", "accurate", "multibody"};
    std::vector<std::string> scenarios;
    std::filesystem::path out = "stress";
    int threads = 2;
    int yaws = 1;
    std::string precision;
    bool list = false, ci = false;
};

/// Registers afb stress's options on `cmd` (afb stress, afb plan stress).
void addStressOptions(CLI::App* cmd, StressCli& opt);
/// The methods of --methods, each once; a spec that does not parse is a usage error.
std::vector<sim::StressMethod> parseStressMethods(const std::vector<std::string>& specs);
/// The scenarios of --scenarios and --ci (all when neither names one), each once; an unknown name is a usage error.
std::vector<const sim::StressScenario*> pickStressScenarios(const StressCli& opt);
/// The bundled humanoid when a scenario needs it and --base has it (a warning when it does not).
sim::StressContent loadStressContent(const StressCli& opt, const std::vector<const sim::StressScenario*>& scenarios);
/// Writes stress.md, stress.json, the heat map (stress.gp, stress.dat, stress.png) into `out` and prints the table,
/// the failures and what it wrote. `results` in runStressMatrix's order.
void writeStressOutputs(const std::filesystem::path& out, const std::vector<sim::StressResult>& results,
                        const std::vector<sim::StressMethod>& methods,
                        const std::vector<const sim::StressScenario*>& scenarios, int yaws);

} // namespace afb::cli
