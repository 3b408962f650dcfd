#pragma once
// afb drop's options, inputs and outputs, shared by the one-process command and by plan/run/merge (the batch of its
// drops over many processes), so that both read, run and report the drops by the same code.
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "MethodOptions.h"
#include "afb/figure/Load.h"
#include "afb/sim/Drop.h"

namespace afb::cli {

/// The options of `afb drop`.
struct DropCli {
    std::filesystem::path base = ".";
    std::vector<std::string> entities;
    sim::DropOptions drop;
    std::optional<std::uint32_t> seed;
    std::shared_ptr<MethodOptions> method = std::make_shared<MethodOptions>();
    std::optional<int> steps;
    std::string precision;
    std::string json, csv;
    std::filesystem::path gltf;
    double gravity = 9.81;
    bool doomGravity = false, noSleep = false, strict = false, verbose = false;
    std::optional<int> worlds;
    std::optional<double> motorHz, motorDamping; ///< --motor-hz, --motor-damping
};

/// Registers afb drop's options on `cmd` (afb drop, afb plan drop).
void addDropOptions(CLI::App* cmd, DropCli& opt);
/// Refuses options that do not go together (a usage error).
void checkDropOptions(const DropCli& opt, const bullet::Method& method);
/// Completes opt.drop from the options (the method, seed, steps, sleeping, worlds) and returns the units (gravity).
figure::UnitSystem resolveDropOptions(DropCli& opt, const bullet::Method& method);
/// Every entity's figure, or nullopt when one cannot be loaded (the diagnostics say why).
std::optional<std::vector<figure::LoadedFigure>> loadDropFigures(const DropCli& opt, const figure::UnitSystem& units,
                                                                 text::Diagnostics& diags);
/// Where the text goes: stderr when a report goes to stdout, else stdout.
std::FILE* dropTextStream(const DropCli& opt);
/// Prints the run's header: Bullet, rate, sleeping, gravity, the method.
void printDropHeader(const DropCli& opt, const figure::UnitSystem& units);
/// One entity's drop as afb drop runs it (the entity's rest key applied).
sim::DropResult dropOne(const DropCli& opt, const figure::LoadedFigure& loaded, const sim::DropObserver& observer = {});
/// Prints the table (and `notes` after it) and writes --json and --csv. Returns the exit code: 1 when a figure
/// exploded.
int reportDrops(const DropCli& opt, const std::vector<sim::DropResult>& results, const std::vector<std::string>& notes,
                double gravityMps2);

} // namespace afb::cli
