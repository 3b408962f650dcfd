// afb run: runs one line (or one shard) of a manifest written by afb plan, one result file per line, each written
// atomically; --resume runs the lines whose result is missing.
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <iostream>
#include <mutex>
#include <set>
#include <thread>

#include "Batch.h"
#include "Commands.h"
#include "Usage.h"
#include "afb/sim/Batch.h"
#include "afb/sim/Drop.h"

namespace afb::cli {
namespace {

struct RunCli {
    std::filesystem::path manifest, out;
    std::optional<std::size_t> index;
    std::string shard; // K/N
    std::optional<std::size_t> shards;
    bool resume = false;
    int threads = 1;
};

// What count() gives for text that is not a count (a count has at most 15 digits, so it is never this).
constexpr std::size_t kNoIndex = static_cast<std::size_t>(-1);

// A non-negative integer from text, or kNoIndex.
std::size_t count(const std::string& text) {
    if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos || text.size() > 15) return kNoIndex;
    return static_cast<std::size_t>(std::stoull(text));
}

// Which lines this process runs: --index, --shard K/N, --shards N with K from SLURM_ARRAY_TASK_ID, every line
// (--resume alone), or the line SLURM_ARRAY_TASK_ID names.
std::function<bool(std::size_t)> selection(const RunCli& opt) {
    const char* env = std::getenv("SLURM_ARRAY_TASK_ID");
    const std::size_t task = env ? count(env) : kNoIndex;
    if (env && task == kNoIndex) usageError(std::string("SLURM_ARRAY_TASK_ID is not an index: '") + env + "'");
    if (opt.index) return [i = *opt.index](std::size_t n) { return n == i; };
    if (!opt.shard.empty()) {
        const std::size_t slash = opt.shard.find('/');
        const std::size_t k = count(opt.shard.substr(0, slash)),
                          n = slash == std::string::npos ? kNoIndex : count(opt.shard.substr(slash + 1));
        if (k == kNoIndex || n == kNoIndex || n == 0 || k >= n)
            usageError("--shard " + opt.shard + ": expected K/N with 0 <= K < N");
        return [k, n](std::size_t i) { return i % n == k; };
    }
    if (opt.shards) {
        if (task == kNoIndex) usageError("--shards needs SLURM_ARRAY_TASK_ID (or give --shard K/N)");
        const std::size_t n = *opt.shards;
        if (task >= n)
            usageError("SLURM_ARRAY_TASK_ID " + std::to_string(task) + " is not below --shards " + std::to_string(n));
        return [task, n](std::size_t i) { return i % n == task; };
    }
    if (opt.resume) return [](std::size_t) { return true; };
    if (task != kNoIndex) return [task](std::size_t n) { return n == task; };
    usageError("give --index I, --shard K/N or --resume (or run as a Slurm array task)");
}

// Runs `lines` on opt.threads threads; each result goes to its file as soon as it is done. Returns the exit code.
// `seen`: the input hashes found before running, by the planned input set (its JSON text).
int runLines(const RunCli& opt, const BatchJob& job, const std::vector<sim::PlannedRun>& lines,
             const std::map<std::string, nlohmann::json>& seen) {
    std::atomic<std::size_t> next{0};
    std::atomic<int> failed{0};
    std::mutex print;
    auto worker = [&] {
        for (std::size_t k = next++; k < lines.size(); k = next++) {
            const sim::PlannedRun& line = lines[k];
            const auto start = std::chrono::steady_clock::now();
            std::string error;
            try {
                const nlohmann::json result = job.runOne(line.run);
                const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
                error = sim::writeAtomically(sim::resultPath(opt.out, line.index),
                                             sim::resultFileText(line, seen.at(line.inputs.dump()), result, wall));
                const std::lock_guard lock(print);
                if (error.empty())
                    std::printf("afb run: %zu/%zu %s in %.2f s -> %s\n", line.index, line.runs, line.run.dump().c_str(),
                                wall, sim::resultPath(opt.out, line.index).string().c_str());
            } catch (const std::exception& e) {
                error = opt.manifest.string() + ":" + std::to_string(line.index + 1) + ":1: error: " + e.what();
            }
            if (error.empty()) continue;
            ++failed;
            const std::lock_guard lock(print);
            std::cerr << "afb run: " << error << "\n";
        }
    };
    std::vector<std::thread> pool;
    for (int t = 1; t < std::min<int>(opt.threads, static_cast<int>(lines.size())); ++t) pool.emplace_back(worker);
    worker();
    for (std::thread& t : pool) t.join();
    std::fflush(stdout);
    return failed ? kExitFailure : 0;
}

// The lines of `manifest` whose result in opt.out is missing or is not this line's.
std::vector<sim::PlannedRun> missingOnly(const RunCli& opt, std::vector<sim::PlannedRun> lines) {
    std::vector<std::string> errors; // unreadable results are re-run
    const std::map<std::size_t, sim::RunResult> done = sim::readResults(opt.out, errors);
    std::erase_if(lines, [&](const sim::PlannedRun& line) {
        const auto r = done.find(line.index);
        return r != done.end() && r->second.line == line.lineHash && r->second.inputsSeen == r->second.inputs;
    });
    return lines;
}

// True when every input file of `lines` has its planned hash; names each that changed. `seen` receives the hashes
// found, by input set.
bool inputsAsPlanned(const std::vector<sim::PlannedRun>& lines, std::map<std::string, nlohmann::json>& seen) {
    std::set<std::string> changed;
    for (const sim::PlannedRun& line : lines) {
        const auto [at, fresh] = seen.emplace(line.inputs.dump(), nlohmann::json());
        if (!fresh) continue;
        const std::filesystem::path base = line.plan.at("base").get<std::string>();
        const nlohmann::json& now = at->second = hashInputs(base, line.inputs);
        for (const auto& [rel, hash] : line.inputs.items())
            if (now.at(rel) != hash) changed.insert((base / rel).string());
    }
    for (const std::string& file : changed) std::cerr << file << ": error: input changed since planning\n";
    return changed.empty();
}

int runCommand(const RunCli& opt, char** argv) {
    std::string error;
    auto manifest = sim::readManifest(opt.manifest, selection(opt), error);
    if (!manifest) {
        std::cerr << error << "\n";
        return kExitFailure;
    }
    if (opt.index && *opt.index >= manifest->runs)
        usageError("--index " + std::to_string(*opt.index) + ": " + opt.manifest.string() + " has " +
                   std::to_string(manifest->runs) + " runs (0.." + std::to_string(manifest->runs - 1) + ")");
    std::vector<sim::PlannedRun> lines = std::move(manifest->lines);
    if (lines.empty()) {
        std::printf("afb run: no line of %s selected\n", opt.manifest.string().c_str());
        return 0;
    }
    const sim::PlannedRun first = lines.front(); // a copy: --resume below changes `lines`
    if (first.precision != sim::bulletPrecision()) {
        execOtherPrecision(first.precision, argv, "afb run");
        return kExitFailure;
    }
    if (first.build != buildIdentity()) {
        std::cerr << opt.manifest.string() << ":" << first.index + 1 << ":1: error: planned by " << first.build
                  << "; this is " << buildIdentity() << " (plan again with this build)\n";
        return kExitFailure;
    }
    std::map<std::string, nlohmann::json> seen;
    if (!inputsAsPlanned(lines, seen)) return kExitFailure;
    std::error_code ec;
    std::filesystem::create_directories(opt.out, ec);
    if (ec) {
        std::cerr << "afb run: cannot create " << opt.out.string() << ": " << ec.message() << "\n";
        return kExitFailure;
    }
    // The plan beside the results, for a merge without the manifest (written once; every process writes the same).
    if (const auto plan = sim::planFilePath(opt.out, sim::planHash(first)); !std::filesystem::exists(plan, ec))
        if (const std::string e = sim::writeAtomically(plan, sim::planFileText(first)); !e.empty()) {
            std::cerr << "afb run: " << e << "\n";
            return kExitFailure;
        }
    if (opt.resume) lines = missingOnly(opt, std::move(lines));
    if (lines.empty()) {
        std::printf("afb run: every selected result is in %s\n", opt.out.string().c_str());
        return 0;
    }
    const std::unique_ptr<BatchJob> job = makeBatchJob(first.command, first.plan, true, error);
    if (!job) {
        std::cerr << opt.manifest.string() << ":" << first.index + 1 << ":1: error: " << error << "\n";
        return kExitFailure;
    }
    return runLines(opt, *job, lines, seen);
}

} // namespace

void addRunCommand(CLI::App& app, int& exitCode, char** argv) {
    auto* cmd = app.add_subcommand("run", "Run lines of a manifest written by afb plan, one result file per line\n"
                                          "Examples:\n"
                                          "  afb run --manifest runs.jsonl --index 3 --out results\n"
                                          "  afb run --manifest runs.jsonl --shard 0/16 --out results\n"
                                          "  afb run --manifest runs.jsonl --resume --threads 2 --out results");
    cmd->footer("Line I's result goes to DIR/run-I.json (six digits), written to a hidden temporary file and renamed: "
                "a run killed midway leaves no result. Without --index, --shard or --shards the line is "
                "SLURM_ARRAY_TASK_ID. The build must be the one that planned (afb --version), and every input file "
                "as planned. Exit code 0 when every selected run wrote its result.");
    auto opt = std::make_shared<RunCli>();
    cmd->add_option("--manifest", opt->manifest, "Manifest written by afb plan")->required();
    cmd->add_option("--out", opt->out, "Folder of the result files (created)")->required();
    cmd->add_option("--index", opt->index, "Run this line (0-based)");
    cmd->add_option("--shard", opt->shard, "Run lines i with i mod N = K (K/N, 0 <= K < N)");
    cmd->add_option("--shards", opt->shards, "Run shard SLURM_ARRAY_TASK_ID of N (lines i mod N = the task id)")
        ->check(CLI::Range(std::size_t{1}, std::size_t{1} << 40));
    cmd->add_flag("--resume", opt->resume, "Run only the selected lines whose result is missing (all lines alone)");
    cmd->add_option("--threads", opt->threads, "Runs at once in this process")
        ->check(CLI::Range(1, 256))
        ->capture_default_str();
    cmd->callback([opt, &exitCode, argv] {
        if (int(opt->index.has_value()) + int(!opt->shard.empty()) + int(opt->shards.has_value()) > 1)
            usageError("give one of --index, --shard and --shards");
        exitCode = runCommand(*opt, argv);
    });
}

} // namespace afb::cli
