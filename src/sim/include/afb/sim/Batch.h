#pragma once
// Batches beyond one process (`afb plan`, `afb run`, `afb merge`): a run manifest of JSON lines, one line per
// independent run, and one result file per line, written atomically, read back and checked before a merge.
// Results carry every number exactly (doubles round-trip; NaN and infinities as text), so a merge of results made
// in many processes equals the one-process command's output but for the timings.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "afb/sim/Drop.h"
#include "afb/sim/Stress.h"

namespace afb::sim {

/// FNV-1a, 64 bit: a stable content hash for change detection (not for security).
std::uint64_t fnv1a(std::string_view data, std::uint64_t hash = 1469598103934665603ull);
/// `value` as 16 lowercase hex digits.
std::string hashHex(std::uint64_t value);
/// The FNV-1a hash of a file's bytes as hex, or "missing" when it cannot be read.
std::string fileHash(const std::filesystem::path& path);

/// One line of a run manifest: one independent run of a command, with everything needed to run it alone and to
/// check its result against the others'.
struct PlannedRun {
    std::size_t index = 0;      ///< the line's position, 0-based (a Slurm array task id)
    std::size_t runs = 0;       ///< lines in the manifest
    std::string command;        ///< "stress", "chart", "drop"
    std::string build;          ///< the planning binary (its `afb --version` line and compiler)
    std::string precision;      ///< "float" or "double": the afb binary that runs the line
    nlohmann::json plan;        ///< the command's options, the same on every line
    nlohmann::json inputs;      ///< this run's input files: path relative to the content folder → fileHash
    nlohmann::json run;         ///< this run's own values (entity, method, height, rate, yaw, repeat, …)
    std::uint64_t lineHash = 0; ///< fnv1a of the line's text as read (0 for a run not read from a manifest)
};

/// The text every line of a plan shares: `"runs":N,"command":…,"build":…,"precision":…,"plan":{…}`.
std::string manifestHead(std::size_t runs, const std::string& command, const std::string& build,
                         const std::string& precision, const nlohmann::json& plan);
/// fnv1a of manifestHead(): what a result names its plan by (build and precision included).
std::uint64_t planHash(const PlannedRun& run);

/// What a plan writes: the options common to every run, the sets of input files the runs read, and the runs, each
/// with the index of its input set.
struct PlanLines {
    nlohmann::json plan;
    std::vector<nlohmann::json> inputSets; ///< each {path relative to the content folder: fileHash}
    std::vector<std::pair<std::size_t, nlohmann::json>> runs;
};
/// Writes a manifest: one line per run, index = position. The plan and each input set are serialised once.
void writeManifest(std::ostream& out, const std::string& command, const std::string& build,
                   const std::string& precision, const PlanLines& lines);

/// A manifest read back: its line count and the lines selected.
struct Manifest {
    std::size_t runs = 0;
    std::vector<PlannedRun> lines;         ///< in index order
    std::vector<std::uint64_t> lineHashes; ///< fnv1a of every line's text, with `hashEvery` only
};
/// Reads the lines of `path` for which `want(index)` is true (every line is counted, only those are parsed; with
/// `hashEvery` every line's text is hashed too). On a malformed line returns nullopt with `error` as
/// "FILE:LINE:COL: error: …".
std::optional<Manifest> readManifest(const std::filesystem::path& path, const std::function<bool(std::size_t)>& want,
                                     std::string& error, bool hashEvery = false);
/// Parses one manifest line (`where` prefixes the error: "FILE:LINE").
std::optional<PlannedRun> parseManifestLine(std::string_view line, const std::string& where, std::string& error);
/// A planned run as its manifest line (no newline), as writeManifest writes it.
nlohmann::json manifestLineJson(const PlannedRun& run);

/// Where the result of line `index` goes: DIR/run-000042.json (six digits or more).
std::filesystem::path resultPath(const std::filesystem::path& dir, std::size_t index);
/// Writes `text` to `path` atomically: a temporary file in the same folder, flushed, then renamed over `path`. A
/// process killed before the rename leaves no file at `path` (only a hidden `.run-*.tmp.*` file, ignored by
/// readResults). Returns an error message, or an empty string.
std::string writeAtomically(const std::filesystem::path& path, const std::string& text);

/// One result file read back: a header naming its line by hashes, and the command's result as text (parsed by
/// the merge, one at a time). The line itself (plan, inputs, run) is the manifest's, or the plan file's.
struct RunResult {
    std::size_t index = 0, runs = 0;          ///< the line it ran, and the manifest's line count
    std::string command, build, precision;    ///< as the line says
    std::uint64_t plan = 0;                   ///< planHash() of the line
    std::uint64_t line = 0;                   ///< fnv1a of the manifest line's text
    std::uint64_t inputs = 0, inputsSeen = 0; ///< fnv1a of the planned input set's JSON text, and of the one found
    std::string result;                       ///< the command's result (exact JSON text)
    std::filesystem::path file;               ///< where it was read from
};
/// A result file's text: a header line (index, run count, command, build, precision, the hashes of the plan, the
/// line, the planned and the found input sets; host and wall time) and the result on a line of its own.
std::string resultFileText(const PlannedRun& line, const nlohmann::json& inputsSeen, const nlohmann::json& result,
                           double wallSeconds);
/// Every result file of `dir` (run-*.json), by index. Files that do not parse are errors ("FILE: error: …").
std::map<std::size_t, RunResult> readResults(const std::filesystem::path& dir, std::vector<std::string>& errors);

/// Calls fn(0) … fn(n - 1) on up to 8 threads (the machine's cores), each index once, in no set order; rethrows the
/// first exception thrown (the indices not yet started are then skipped).
void forEachIndex(std::size_t n, const std::function<void(std::size_t)>& fn);

/// Where the plan of results is kept for a merge without the manifest: DIR/plan-HASH.json (HASH: planHash()).
std::filesystem::path planFilePath(const std::filesystem::path& dir, std::uint64_t planHash);
/// The plan file's text: manifestHead() as one JSON object.
std::string planFileText(const PlannedRun& line);
/// Reads a plan file back as a line without index, inputs or run; nullopt with `error` when it is unreadable or
/// its text is not the plan `planHash` names.
std::optional<PlannedRun> readPlanFile(const std::filesystem::path& path, std::uint64_t planHash, std::string& error);

/// A number written exactly: finite doubles as JSON numbers (shortest round-trip form), NaN and infinities as the
/// strings "nan", "inf", "-inf" (JSON has no such numbers).
nlohmann::json exactNumber(double value);
/// Reads exactNumber's output; throws nlohmann::json::exception on anything else.
double fromExactNumber(const nlohmann::json& value);

/// A stress run, exactly (every field).
nlohmann::json stressResultExact(const StressResult& result);
StressResult stressResultFromExact(const nlohmann::json& json);
/// A drop result, exactly (every field, the method by its knobs, the final pose and body frames).
nlohmann::json dropResultExact(const DropResult& result);
/// Reads dropResultExact's output; throws nlohmann::json::exception (or std::runtime_error for a bad method). A
/// result without "method" (a chart's: its plan names the method) keeps the default-constructed one.
DropResult dropResultFromExact(const nlohmann::json& json);

} // namespace afb::sim
