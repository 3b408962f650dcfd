// afb plan: a command's runs as a manifest of JSON lines, one per independent run, to spread over processes and
// machines (afb run) and merge back (afb merge).
#include <fstream>
#include <iostream>

#include "Batch.h"
#include "Commands.h"
#include "Usage.h"
#include "afb/sim/Batch.h"
#include "afb/sim/Drop.h"

namespace afb::cli {
namespace {

// Writes the manifest to `path` ('-': stdout) and says on stderr how to run it.
int emitManifest(const PlanOutput& out, const std::string& path) {
    std::ofstream file;
    if (path != "-") {
        file.open(path, std::ios::binary);
        if (!file) {
            std::cerr << "afb plan: cannot write " << path << "\n";
            return kExitFailure;
        }
    }
    std::ostream& stream = path == "-" ? std::cout : file;
    sim::writeManifest(stream, out.command, buildIdentity(), sim::bulletPrecision(), out.lines);
    stream.flush();
    if (!stream) {
        std::cerr << "afb plan: cannot write " << path << "\n";
        return kExitFailure;
    }
    const std::string name = path == "-" ? "MANIFEST" : path;
    const std::size_t runs = out.lines.runs.size();
    std::cerr << "afb plan: " << runs << " runs of afb " << out.command << " -> " << (path == "-" ? "stdout" : path)
              << "\n  run each: afb run --manifest " << name << " --index I --out DIR   (I = 0.."
              << (runs == 0 ? 0 : runs - 1) << "; or --shard K/N)\n  then:     afb merge DIR --out OUT\n";
    return 0;
}

} // namespace

void addPlanCommand(CLI::App& app, int& exitCode, char** argv) {
    auto* plan = app.add_subcommand("plan", "Write a command's runs as a manifest (JSON lines) for afb run and merge\n"
                                            "Examples:\n"
                                            "  afb plan stress --base . --yaws 4 --manifest runs.jsonl\n"
                                            "  afb plan chart --base . humanoid --repeats 5 --manifest runs.jsonl\n"
                                            "  afb plan golden compare --junit goldens.xml tests/golden/*.json "
                                            "--manifest runs.jsonl");
    plan->footer("Each line is one independent run: its command, its own values (entity, method, height, rate, "
                 "yaw, repeat), the command's options, the hashes of every input file, and the build (version, "
                 "Bullet, precision, build type, compiler) that must run it. afb run --manifest FILE --index I runs "
                 "line I; afb merge writes what the command itself writes. docs/cluster.md: Slurm, GNU parallel, "
                 "CI matrices.");
    plan->require_subcommand(1);
    auto manifest = std::make_shared<std::string>("-");
    const PlanEmitter emit = [manifest](const PlanOutput& out) { return emitManifest(out, *manifest); };
    addPlanStress(plan, exitCode, argv, manifest, emit);
    addPlanChart(plan, exitCode, argv, manifest, emit);
    addPlanDrop(plan, exitCode, argv, manifest, emit);
    addPlanGolden(plan, exitCode, manifest, emit);
}

} // namespace afb::cli
