// afb drop: drop figures onto a ground plane and report speed, accuracy and stability.
#include <algorithm>
#include <cctype>
#include <cstdio>
#include <fstream>
#include <iostream>

#include <unistd.h>

#include "Commands.h"
#include "DropCli.h"
#include "MethodOptions.h"
#include "Usage.h"
#include "afb/figure/Load.h"
#include "afb/sim/Drop.h"
#include "afb/sim/GltfReplay.h"
#include "afb/sim/RawRagdoll.h"
#include "afb/sim/Report.h"

namespace afb::cli {

void addDropOptions(CLI::App* cmd, DropCli& opt) {
    cmd->add_option("entities", opt.entities, "entityDefs to drop")->required();
    cmd->add_option("--base", opt.base, "Content folder (af/, def/, models/)")->capture_default_str();
    cmd->add_option("--height", opt.drop.heightM, "Height of each figure's lowest point at spawn, m")
        ->check(nonNegative())
        ->capture_default_str();
    cmd->add_option("--count", opt.drop.count, "Instances per figure, on a grid in one world")
        ->check(CLI::Range(1, 1 << 20))
        ->capture_default_str();
    cmd->add_option("--threads", opt.drop.threads,
                    "Run the worlds on this many threads (default 1; alone, also splits into that many worlds)")
        ->check(CLI::Range(1, 1024));
    cmd->add_option("--worlds", opt.worlds,
                    "Split the instances over this many independent worlds (default: --threads); the results "
                    "do not depend on --threads")
        ->check(CLI::Range(1, 1 << 20));
    cmd->add_option("--seed", opt.seed,
                    "Random initial orientations (yaw and tilt) from this seed; default: yaw 37°·i");
    cmd->add_option("--lod", opt.drop.lod,
                    "Level of detail: switch every instance at spawn to N rigid bodies, the lightest body merged into "
                    "its lightest jointed neighbour until N remain (fixed joints always merged; rigid backend only). "
                    "bodies, us/body and awake still count the figure's bodies, so the numbers compare with a run "
                    "without --lod")
        ->check(CLI::Range(1, 1 << 20));
    cmd->add_option("--motor-hz", opt.motorHz,
                    "Joint motors: every instance holds its load pose with motors of this frequency, Hz (held to a "
                    "quarter of --hz; docs/motors.md); rigid backend only")
        ->check(positive());
    cmd->add_option("--motor-damping", opt.motorDamping, "The motors' damping ratio (default 1: critically damped)")
        ->check(CLI::NonNegativeNumber);
    cmd->add_option("--seconds", opt.drop.seconds, "Simulated time, s")->check(nonNegative())->capture_default_str();
    cmd->add_option("--steps", opt.steps, "Exact number of steps (overrides --seconds); 0 reports the spawn pose")
        ->check(CLI::NonNegativeNumber);
    cmd->add_option("--hz", opt.drop.hz, "Fixed frame rate")->check(positive())->capture_default_str();
    addMethodOptions(cmd, opt.method);
    cmd->add_option("--precision", opt.precision, "Bullet build: float or double (default: this binary's)")
        ->check(CLI::IsMember({"float", "double"}));
    cmd->add_flag("--strict", opt.strict, "Refuse values the builder would repair (docs/format.md: hostile numbers)");
    cmd->add_flag("--no-sleep", opt.noSleep, "Never put figures to rest (the rest rules are off)");
    cmd->add_flag("--verbose", opt.verbose, "Print every knob of the method (JSON and CSV reports always have them)");
    cmd->add_flag("--stop-at-rest", opt.drop.stopAtRest, "End a run when every instance is at rest");
    cmd->add_flag("--doom-gravity", opt.doomGravity, "Doom's gravity, 1066 units/s² (27.1 m/s²), instead of 9.81");
    cmd->add_option("--json", opt.json,
                    "Write the results as JSON to this file ('-': stdout, which then holds only the JSON)");
    cmd->add_option("--csv", opt.csv,
                    "Write the results (without final_pose) as CSV to this file ('-': stdout, which then holds only "
                    "the CSV)");
    cmd->add_option("--gltf", opt.gltf,
                    "Record the first instance as a glTF 2.0 binary (FILE.glb, one entity): the skinned md5 mesh, "
                    "its skeleton, the body hulls, the ground and one animation at the step rate; metres, Y up");
}

void checkDropOptions(const DropCli& opt, const bullet::Method& method) {
    if (!opt.steps) checkStepCount("--seconds", opt.drop.seconds, opt.drop.hz);
    if (opt.json == "-" && opt.csv == "-") usageError("--json - and --csv - both ask for stdout; give one a file");
    if (opt.drop.lod && (sim::isRaw(method) || method.backend != bullet::Backend::Rigid))
        usageError("--lod needs the rigid backend (not the raw method or the multibody backend)");
    if (opt.motorHz && (sim::isRaw(method) || method.backend != bullet::Backend::Rigid))
        usageError("--motor-hz needs the rigid backend (not the raw method or the multibody backend)");
    if (opt.motorDamping && !opt.motorHz) usageError("--motor-damping needs --motor-hz");
    if (opt.gltf.empty()) return;
    std::string ext = opt.gltf.extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (ext != ".glb") usageError("--gltf must name a .glb file");
    if (opt.entities.size() != 1) usageError("--gltf records one entity: give exactly one");
}

std::optional<std::vector<figure::LoadedFigure>> loadDropFigures(const DropCli& opt, const figure::UnitSystem& units,
                                                                 text::Diagnostics& diags) {
    auto lib = decl::Library::open(opt.base, diags);
    if (!lib || !findEntities(*lib, opt.entities, diags)) return std::nullopt;
    std::vector<figure::LoadedFigure> figures;
    bool all = true; // every entity is loaded, so that every error is reported
    for (const std::string& e : opt.entities) {
        if (auto loaded = figure::loadEntityFigure(*lib, e, units, diags, opt.strict))
            figures.push_back(std::move(*loaded));
        else all = false;
    }
    if (!all) return std::nullopt;
    return figures;
}

namespace {

void printTable(std::FILE* out, const std::vector<sim::DropResult>& results, const std::vector<std::string>& labels,
                int count) {
    std::fprintf(out, "\n%-32s %6s %7s %9s %9s %10s %9s %9s %9s %9s %9s %8s %8s\n", "entity", "bodies", "steps",
                 "us/step", "us/body", "awake", "anchor m", "limit deg", "pen. m", "rest m", "gain J", "exploded",
                 "settle s");
    for (std::size_t i = 0; i < results.size(); ++i) {
        const sim::DropResult& r = results[i];
        std::fprintf(out, "%-32s %6d %7d %9.1f %9.2f %10lld %9.4f %9.2f %9.4f %9.4f %9.3f %8s %8s\n", labels[i].c_str(),
                     r.bodies / std::max(1, count), r.steps, r.usPerStep, r.usPerBodyStep, r.awakeBodySteps,
                     r.maxAnchorErrorM, r.maxLimitViolationDeg, r.maxPenetrationM, r.restPenetrationM, r.maxEnergyGainJ,
                     r.nonFinite  ? "NaN"
                     : r.exploded ? "YES"
                                  : "no",
                     r.settleTimeS
                         ? (std::to_string(*r.settleTimeS).substr(0, 6) + (r.frozenBeforeContact ? "*" : "")).c_str()
                         : "-");
    }
    for (std::size_t i = 0; i < results.size(); ++i)
        if (const sim::DropResult& r = results[i]; !r.worstAnchorJoint.empty() || !r.worstLimitJoint.empty())
            std::fprintf(out, "  %s: worst anchor at %s, worst limit at %s, deepest contact %s\n", labels[i].c_str(),
                         r.worstAnchorJoint.empty() ? "-" : r.worstAnchorJoint.c_str(),
                         r.worstLimitJoint.empty() ? "-" : r.worstLimitJoint.c_str(),
                         r.worstContact.empty() ? "-" : r.worstContact.c_str());
    std::fprintf(out, "  (bodies: per instance; us/step, us/body: CPU µs per step and per awake body-step; awake: "
                      "body-steps awake;\n   anchor m, limit deg, pen. m: worst joint gap, limit overshoot, contact "
                      "depth; rest m: deepest contact\n   in the last second; gain J: largest energy gain; settle s: "
                      "all instances at rest; every field: --help)\n");
    for (std::size_t i = 0; i < results.size(); ++i)
        if (const sim::DropResult& r = results[i]; r.frozenBeforeContact > 0)
            std::fprintf(out,
                         "  %s: * %d of %d instances came to rest before touching anything: frozen in the air by "
                         "the figure's rest rules (its maxMoveTime), not settled\n",
                         labels[i].c_str(), r.frozenBeforeContact, count);
    for (std::size_t i = 0; i < results.size(); ++i)
        if (const sim::DropResult& r = results[i]; r.lodBodies)
            std::fprintf(out, "  %s: level of detail, %d rigid bodies for %d bodies per instance\n", labels[i].c_str(),
                         *r.lodBodies, r.bodies / std::max(1, count));
}

// --json and --csv: to their files, or to stdout for '-'.
void writeReports(const DropCli& opt, const std::vector<sim::DropResult>& results, double gravityMps2) {
    nlohmann::json all = {{"schema", sim::schemaJson(sim::kDropSchema)},
                          {"bullet", sim::bulletVersion()},
                          {"precision", sim::bulletPrecision()},
                          {"gravity_mps2", gravityMps2},
                          {"threads", opt.drop.threads > 0 ? opt.drop.threads : 1},
                          {"worlds", opt.drop.worlds},
                          {"scenario", sim::dropOptionsJson(opt.drop)},
                          {"runs", nlohmann::json::array()}};
    for (const sim::DropResult& r : results) all["runs"].push_back(sim::dropResultJson(r));
    if (!opt.json.empty()) writeReport(opt.json, all.dump(2) + "\n");
    if (opt.csv.empty()) return;
    std::string csv = sim::dropCsvHeader() + "\n";
    for (const sim::DropResult& r : results) csv += sim::dropCsvRow(r) + "\n";
    writeReport(opt.csv, csv);
}

// Writes --gltf's replay of one drop; returns the lines to print after the table, or nullopt when it failed.
std::optional<std::vector<std::string>> writeReplay(const DropCli& opt, const std::string& entity,
                                                    const figure::LoadedFigure& loaded,
                                                    const sim::DropRecording& recording, double hz) {
    const sim::GltfReplayResult written = sim::writeGltfReplay(loaded.figure, loaded.mesh, recording, opt.gltf);
    if (written.error) {
        std::cerr << "afb drop: --gltf: " << *written.error << "\n";
        return std::nullopt;
    }
    char line[512];
    std::snprintf(line, sizeof line,
                  "afb drop: replay of %s (first instance: %d frames at %g Hz, %d joints, %d bodies) -> %s",
                  entity.c_str(), written.frames, hz, written.joints, written.bodies, opt.gltf.c_str());
    std::vector<std::string> lines{line};
    if (written.framesDropped > 0)
        lines.push_back("afb drop: warning: the replay stops where the pose stopped being finite (" +
                        std::to_string(written.framesDropped) + " frames left out)");
    return lines;
}

int runDrops(DropCli& opt, const bullet::Method& method) {
    const figure::UnitSystem units = resolveDropOptions(opt, method);
    text::Diagnostics diags;
    auto figures = loadDropFigures(opt, units, diags);
    printDiagnostics(diags);
    if (!figures) return kExitFailure;
    printDropHeader(opt, units);
    int exitCode = 0;
    std::vector<sim::DropResult> results;
    std::vector<std::string> replays; // what --gltf wrote, printed after the table
    for (std::size_t i = 0; i < figures->size(); ++i) {
        const std::string& e = opt.entities[i];
        const figure::LoadedFigure& loaded = (*figures)[i];
        if (::isatty(STDERR_FILENO)) std::fprintf(stderr, "  dropping %s x %d ...\r", e.c_str(), opt.drop.count);
        sim::DropRecording recording;
        sim::DropObserver observer;
        if (!opt.gltf.empty()) observer = sim::recordInto(recording, opt.drop.hz);
        results.push_back(dropOne(opt, loaded, observer));
        if (opt.gltf.empty()) continue;
        if (auto lines = writeReplay(opt, e, loaded, recording, opt.drop.hz))
            replays.insert(replays.end(), lines->begin(), lines->end());
        else exitCode = kExitFailure;
    }
    return std::max(exitCode, reportDrops(opt, results, replays, units.gravityMps2));
}

} // namespace

void addDropCommand(CLI::App& app, int& exitCode, int argc, char** argv) {
    auto* cmd =
        app.add_subcommand("drop", "Drop figures onto a ground plane and report speed, accuracy and stability\n"
                                   "Examples:\n  afb drop --base . humanoid\n"
                                   "  afb drop --base . humanoid --method fast --count 4 --height 10 --json -\n"
                                   "  afb drop --base . humanoid --motor-hz 6   # holding its pose with motors");
    cmd->footer(sim::dropFieldsHelp());
    auto opt = std::make_shared<DropCli>();
    addDropOptions(cmd, *opt);
    cmd->callback([opt, &exitCode, argc, argv] {
        (void)argc;
        const bullet::Method method = resolveMethod(*opt->method);
        checkDropOptions(*opt, method);
        if (!opt->precision.empty() && opt->precision != sim::bulletPrecision()) {
            execOtherPrecision(opt->precision, argv, "afb drop");
            exitCode = kExitFailure;
            return;
        }
        exitCode = runDrops(*opt, method);
    });
}

void execOtherPrecision(const std::string& precision, char** argv, const char* command) {
    const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe");
    const std::filesystem::path other = self.parent_path() / (precision == "double" ? "afb-double" : "afb");
    ::execv(other.c_str(), argv);
    std::cerr << command << ": cannot run " << other.string() << " for --precision " << precision << "\n";
}

figure::UnitSystem resolveDropOptions(DropCli& opt, const bullet::Method& method) {
    opt.drop.method = method;
    opt.drop.seed = opt.seed;
    opt.drop.steps = opt.steps;
    opt.drop.sleeping = !opt.noSleep;
    opt.drop.worlds = opt.worlds.value_or(std::max(1, opt.drop.threads)); // --threads N alone: N worlds
    if (opt.motorHz) opt.drop.motors = bullet::MotorGains{*opt.motorHz, opt.motorDamping.value_or(1.0)};
    figure::UnitSystem units;
    units.gravityMps2 = opt.doomGravity ? units.doomGravityMps2() : opt.gravity;
    return units;
}

std::FILE* dropTextStream(const DropCli& opt) {
    // With a report on stdout, stdout holds only that report.
    return opt.json == "-" || opt.csv == "-" ? stderr : stdout;
}

void printDropHeader(const DropCli& opt, const figure::UnitSystem& units) {
    std::FILE* text = dropTextStream(opt);
    // The method as chart and stress spell it (the preset and the knobs set on it); every knob with --verbose.
    const std::string methodLine =
        opt.verbose
            ? bullet::describe(opt.drop.method)
            : methodSpec(opt.drop.method) + " (every knob: --verbose, or afb methods " + opt.drop.method.name + ")";
    std::fprintf(text, "afb drop: Bullet %s (%s), %g Hz, sleeping %s, gravity %.3f m/s²\n  method %s\n",
                 sim::bulletVersion().c_str(), sim::bulletPrecision(), opt.drop.hz, opt.drop.sleeping ? "on" : "off",
                 units.gravityMps2, methodLine.c_str());
    if (opt.drop.lod)
        std::fprintf(text, "  level of detail: --lod %d (automatic merge; each figure's rigid bodies below)\n",
                     *opt.drop.lod);
    if (const auto& m = opt.drop.motors)
        std::fprintf(text, "  joint motors: %g Hz, damping ratio %g, holding the load pose\n", m->frequencyHz,
                     m->dampingRatio);
    std::fflush(text);
}

sim::DropResult dropOne(const DropCli& opt, const figure::LoadedFigure& loaded, const sim::DropObserver& observer) {
    sim::DropOptions drop = opt.drop;
    drop.startAtRest = loaded.startAtRest; // "nodrop"/"sleep" entities hang until touched
    return sim::runDrop(loaded.figure, drop, observer);
}

int reportDrops(const DropCli& opt, const std::vector<sim::DropResult>& results, const std::vector<std::string>& notes,
                double gravityMps2) {
    // The table names each row by its entity, and by the figure too where they differ: entities that share a
    // figure (humanoid, humanoid_prop, humanoid_sleeping) would otherwise print alike.
    std::vector<std::string> labels;
    int exitCode = 0;
    for (std::size_t i = 0; i < results.size(); ++i) {
        const std::string& e = opt.entities[i];
        labels.push_back(results[i].figure == e ? e : e + " (" + results[i].figure + ")");
        if (results[i].exploded) exitCode = kExitFailure;
    }
    std::FILE* text = dropTextStream(opt);
    printTable(text, results, labels, opt.drop.count);
    for (const std::string& line : notes) std::fprintf(text, "%s\n", line.c_str());
    std::fflush(text);
    writeReports(opt, results, gravityMps2);
    return exitCode;
}

} // namespace afb::cli
