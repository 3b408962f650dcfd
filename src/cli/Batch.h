#pragma once
// afb plan, afb run and afb merge: a command's runs spread over processes and machines. Each batchable command
// (stress, chart, drop, golden compare) has a BatchJob that runs one manifest line and merges the results with the same
// code the one-process command uses; sim/Batch.h holds the manifest and result files.
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "afb/decl/Library.h"
#include "afb/sim/Batch.h"
#include "afb/text/Diagnostics.h"

namespace afb::cli {

/// This binary's identity, recorded in every manifest line and checked before a run and a merge: its version,
/// Bullet version, precision, build type and compiler. Results are exact only between equal identities.
std::string buildIdentity();

/// One command's side of a batch, made from a plan (the options recorded in the manifest).
class BatchJob {
  public:
    virtual ~BatchJob() = default;
    /// Runs one manifest line (its "run" object) and returns the result as exact JSON. Safe to call from several
    /// threads at once. Throws nlohmann::json::exception or std::runtime_error on a malformed line.
    virtual nlohmann::json runOne(const nlohmann::json& run) const = 0;
    /// Writes what the one-process command writes, from every result (runOne's JSON as text) in index order; `out`
    /// replaces the output folder the plan names when not empty. Returns the command's exit code. Throws
    /// nlohmann::json::exception or std::runtime_error on a malformed result.
    virtual int merge(const std::vector<std::string_view>& results, const std::filesystem::path& out) = 0;
};

/// The job of a plan's command; nullptr with `error` set when the plan does not make sense. With `forRunning`, the
/// content is loaded too (a merge needs none).
std::unique_ptr<BatchJob> makeBatchJob(const std::string& command, const nlohmann::json& plan, bool forRunning,
                                       std::string& error);
std::unique_ptr<BatchJob> makeStressJob(const nlohmann::json& plan, bool forRunning, std::string& error);
std::unique_ptr<BatchJob> makeChartJob(const nlohmann::json& plan, bool forRunning, std::string& error);
std::unique_ptr<BatchJob> makeDropJob(const nlohmann::json& plan, bool forRunning, std::string& error);
std::unique_ptr<BatchJob> makeGoldenJob(const nlohmann::json& plan, std::string& error);

/// What `afb plan COMMAND` produces: the plan (options), the input sets and the runs.
struct PlanOutput {
    std::string command;
    sim::PlanLines lines;
};
/// Registers `afb plan stress|chart|drop|golden compare`: each takes its command's options (and --manifest); `emit`
/// writes the manifest and returns the exit code.
using PlanEmitter = std::function<int(const PlanOutput&)>;
void addPlanStress(CLI::App* plan, int& exitCode, char** argv, const std::shared_ptr<std::string>& manifest,
                   const PlanEmitter& emit);
void addPlanChart(CLI::App* plan, int& exitCode, char** argv, const std::shared_ptr<std::string>& manifest,
                  const PlanEmitter& emit);
void addPlanDrop(CLI::App* plan, int& exitCode, char** argv, const std::shared_ptr<std::string>& manifest,
                 const PlanEmitter& emit);
void addPlanGolden(CLI::App* plan, int& exitCode, const std::shared_ptr<std::string>& manifest,
                   const PlanEmitter& emit);

/// Every input file of `entity` (figure, mesh, af_pose animation, the entityDef's and the model decl's files),
/// relative to `base`, with its hash, added to `inputs`. False (diagnostics set) when it does not resolve.
bool addEntityInputs(const decl::Library& library, const std::string& entity, const std::filesystem::path& base,
                     nlohmann::json& inputs, text::Diagnostics& diagnostics);
/// The hashes now of `inputs` (paths relative to `base` → hash), in the same form.
nlohmann::json hashInputs(const std::filesystem::path& base, const nlohmann::json& inputs);

} // namespace afb::cli
