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
    std::filesystem::path manifest; // only for the hint printed when results are missing
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

// Refuses results that do not belong together: another plan, another build, inputs other than the plan's. Prints
// each and returns false.
bool consistent(const std::map<std::size_t, sim::RunResult>& results, const sim::PlannedRun& first) {
    bool ok = true;
    const std::string self = buildIdentity();
    if (first.build != self) {
        std::cerr << "afb merge: error: the results were made by " << first.build << "; this is " << self
                  << " (merge with the build that ran them)\n";
        return false;
    }
    for (const auto& [index, r] : results) {
        std::string why;
        if (r.line.build != first.build) why = "made by another build: " + r.line.build;
        else if (r.line.command != first.command || r.line.runs != first.runs || r.line.plan != first.plan)
            why = "from another plan";
        else if (r.inputsSeen != r.line.inputs) why = "ran on input files other than the plan's";
        if (why.empty()) continue;
        std::cerr << r.file.string() << ": error: " << why << "\n";
        ok = false;
    }
    return ok;
}

// The line most results share (their plan, build and run count): the one the others are checked against.
const sim::PlannedRun& majorityLine(const std::map<std::size_t, sim::RunResult>& results) {
    std::map<std::string, std::pair<std::size_t, const sim::PlannedRun*>> votes;
    for (const auto& [index, r] : results) {
        auto& vote = votes[r.line.command + "\n" + r.line.build + "\n" + std::to_string(r.line.runs) + "\n" +
                           r.line.plan.dump()];
        if (vote.first++ == 0) vote.second = &r.line;
    }
    const auto best = std::max_element(votes.begin(), votes.end(),
                                       [](const auto& a, const auto& b) { return a.second.first < b.second.first; });
    return *best->second.second;
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
    const sim::PlannedRun& first = majorityLine(results);
    if (first.precision != sim::bulletPrecision()) {
        execOtherPrecision(first.precision, argv, "afb merge");
        return kExitFailure;
    }
    if (!consistent(results, first)) return kExitFailure;
    std::vector<std::size_t> missing;
    for (std::size_t i = 0; i < first.runs; ++i)
        if (!results.count(i)) missing.push_back(i);
    if (!missing.empty()) {
        std::cerr << "afb merge: " << missing.size() << " of " << first.runs << " results missing in "
                  << opt.dir.string() << ": " << ranges(missing) << "\n  run them: afb run --manifest "
                  << (opt.manifest.empty() ? std::string("MANIFEST") : opt.manifest.string()) << " --resume --out "
                  << opt.dir.string() << "\n";
        return kExitFailure;
    }
    std::string error;
    const std::unique_ptr<BatchJob> job = makeBatchJob(first.command, first.plan, false, error);
    if (!job) {
        std::cerr << results.begin()->second.file.string() << ": error: " << error << "\n";
        return kExitFailure;
    }
    std::vector<nlohmann::json> ordered;
    for (const auto& [index, r] : results) ordered.push_back(r.result);
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
                "drop.csv in --out), equal to a one-process run but for timings. Refuses results of another plan, "
                "another build or precision, or other input files; names missing indices on stderr and exits 1 "
                "(afb run --resume runs them).");
    auto opt = std::make_shared<MergeCli>();
    cmd->add_option("dir", opt->dir, "Folder of the result files")->required();
    cmd->add_option("--out", opt->out, "Output folder (default: the command's --out as planned)");
    cmd->add_option("--manifest", opt->manifest, "The manifest, named in the hint for missing results");
    cmd->callback([opt, &exitCode, argv] { exitCode = mergeCommand(*opt, argv); });
}

} // namespace afb::cli
