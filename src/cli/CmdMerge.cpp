// afb merge: the result files of afb run, checked (one plan, this build, unchanged inputs, none missing) and written
// out as the one-process command writes them.
#include <algorithm>
#include <iostream>
#include <stdexcept>

#include "Batch.h"
#include "Commands.h"
#include "Usage.h"
#include "afb/sim/Batch.h"
#include "afb/sim/Drop.h"

namespace afb::cli {
namespace {

struct MergeCli {
    std::filesystem::path dir, out;
    std::filesystem::path manifest; // every result checked against its line; named in the hint for missing ones
};

// "3, 7, 12-15": the indices, consecutive ones as ranges.
std::string ranges(const std::vector<std::size_t>& indices) {
    std::string out;
    for (std::size_t i = 0; i < indices.size();) {
        std::size_t j = i;
        while (j + 1 < indices.size() && indices[j + 1] == indices[j] + 1) ++j;
        out += (out.empty() ? "" : ", ") + std::to_string(indices[i]);
        if (j > i) out += "-" + std::to_string(indices[j]);
        i = j + 1;
    }
    return out;
}

// The plan most results name: the one the others are checked against.
std::uint64_t majorityPlan(const std::map<std::size_t, sim::RunResult>& results) {
    std::map<std::uint64_t, std::size_t> votes;
    for (const auto& [index, r] : results) ++votes[r.plan];
    return std::max_element(votes.begin(), votes.end(),
                            [](const auto& a, const auto& b) { return a.second < b.second; })
        ->first;
}

// The plan named `hash` (a line without index, inputs and run): the manifest's first line with --manifest, which
// also gives every line's hash in `lineHashes`, else the plan file afb run left beside the results.
std::optional<sim::PlannedRun> loadPlan(const MergeCli& opt, std::uint64_t hash,
                                        std::vector<std::uint64_t>& lineHashes) {
    std::string error;
    if (opt.manifest.empty()) {
        auto plan = sim::readPlanFile(sim::planFilePath(opt.dir, hash), hash, error);
        if (!plan) std::cerr << error << "\n  (afb run writes it; or give --manifest)\n";
        return plan;
    }
    auto m = sim::readManifest(
        opt.manifest, [](std::size_t i) { return i == 0; }, error, true);
    if (!m || m->lines.empty()) {
        std::cerr << (m ? opt.manifest.string() + ": error: no lines" : error) << "\n";
        return std::nullopt;
    }
    if (sim::planHash(m->lines.front()) != hash) {
        std::cerr << opt.manifest.string() << ": error: the results in " << opt.dir.string()
                  << " are not of this manifest's plan\n";
        return std::nullopt;
    }
    lineHashes = std::move(m->lineHashes);
    return std::move(m->lines.front());
}

// Refuses results that do not belong together: another build, another plan, another line than the manifest's,
// inputs other than the plan's. Prints each and returns false.
bool consistent(const std::map<std::size_t, sim::RunResult>& results, const sim::PlannedRun& plan,
                const std::vector<std::uint64_t>& lineHashes, const MergeCli& opt) {
    bool ok = true;
    const std::uint64_t hash = sim::planHash(plan);
    for (const auto& [index, r] : results) {
        std::string why;
        if (r.build != plan.build) why = "made by another build: " + r.build;
        else if (r.plan != hash || r.command != plan.command || r.runs != plan.runs) why = "from another plan";
        else if (!lineHashes.empty() && (index >= lineHashes.size() || r.line != lineHashes[index]))
            why = "not the result of line " + std::to_string(index + 1) + " of " + opt.manifest.string();
        else if (r.inputsSeen != r.inputs) why = "ran on input files other than the plan's";
        if (why.empty()) continue;
        std::cerr << r.file.string() << ": error: " << why << "\n";
        ok = false;
    }
    return ok;
}

// Names the missing indices on stderr; true when none is missing.
bool complete(const std::map<std::size_t, sim::RunResult>& results, std::size_t runs, const MergeCli& opt) {
    std::vector<std::size_t> missing;
    for (std::size_t i = 0; i < runs; ++i)
        if (!results.count(i)) missing.push_back(i);
    if (missing.empty()) return true;
    std::cerr << "afb merge: " << missing.size() << " of " << runs << " results missing in " << opt.dir.string() << ": "
              << ranges(missing) << "\n  run them: afb run --manifest "
              << (opt.manifest.empty() ? std::string("MANIFEST") : opt.manifest.string()) << " --resume --out "
              << opt.dir.string() << "\n";
    return false;
}

int mergeCommand(const MergeCli& opt, char** argv) {
    std::vector<std::string> errors;
    const std::map<std::size_t, sim::RunResult> results = sim::readResults(opt.dir, errors);
    for (const std::string& e : errors) std::cerr << e << "\n";
    if (!errors.empty()) return kExitFailure;
    if (results.empty()) {
        std::cerr << opt.dir.string() << ": error: no result files (run-*.json) of afb run\n";
        return kExitFailure;
    }
    const std::uint64_t hash = majorityPlan(results);
    for (const auto& [index, r] : results)
        if (r.plan == hash && r.precision != sim::bulletPrecision()) {
            execOtherPrecision(r.precision, argv, "afb merge");
            return kExitFailure;
        }
    std::vector<std::uint64_t> lineHashes;
    const std::optional<sim::PlannedRun> plan = loadPlan(opt, hash, lineHashes);
    if (!plan) return kExitFailure;
    if (const std::string self = buildIdentity(); plan->build != self) {
        std::cerr << "afb merge: error: the results were made by " << plan->build << "; this is " << self
                  << " (merge with the build that ran them)\n";
        return kExitFailure;
    }
    if (!consistent(results, *plan, lineHashes, opt) || !complete(results, plan->runs, opt)) return kExitFailure;
    std::string error;
    const std::unique_ptr<BatchJob> job = makeBatchJob(plan->command, plan->plan, false, error);
    if (!job) {
        std::cerr << results.begin()->second.file.string() << ": error: " << error << "\n";
        return kExitFailure;
    }
    std::vector<std::string_view> ordered;
    ordered.reserve(results.size());
    for (const auto& [index, r] : results) ordered.emplace_back(r.result);
    try {
        return job->merge(ordered, opt.out);
    } catch (const std::exception& e) {
        std::cerr << opt.dir.string() << ": error: malformed result: " << e.what() << "\n";
        return kExitFailure;
    }
}

} // namespace

void addMergeCommand(CLI::App& app, int& exitCode, char** argv) {
    auto* cmd = app.add_subcommand("merge", "Merge the result files of afb run into the command's own outputs\n"
                                            "Examples:\n"
                                            "  afb merge results --out stress\n"
                                            "  afb merge results --out chart --manifest runs.jsonl");
    cmd->footer("Writes what the planned command writes (stress: stress.md, stress.json, the heat map; chart: "
                "runs.csv, summary.md, front.*; drop: the table, and --json/--csv as planned, or drop.json and "
                "drop.csv in --out; golden compare: its lines, the --junit file and the --report folder as "
                "planned, or OUT/junit.xml and OUT as the report, exit 1 when a golden failed), equal to a "
                "one-process run but for timings. Refuses results of another plan, another build or precision, or "
                "other input files; names missing indices on stderr and exits 1 (afb run --resume runs them).");
    auto opt = std::make_shared<MergeCli>();
    cmd->add_option("dir", opt->dir, "Folder of the result files")->required();
    cmd->add_option("--out", opt->out, "Output folder (default: the command's --out as planned)");
    cmd->add_option("--manifest", opt->manifest,
                    "The manifest: the plan read from it and every result checked against its line (default: the "
                    "plan file afb run writes beside the results)");
    cmd->callback([opt, &exitCode, argv] { exitCode = mergeCommand(*opt, argv); });
}

} // namespace afb::cli
