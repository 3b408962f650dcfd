// afb drop: drop figures onto a ground plane and report speed, accuracy and stability.
#include <algorithm>
#include <cctype>
#include <cstdio>
#include <fstream>
#include <iostream>

#include <unistd.h>

#include "Commands.h"
#include "MethodOptions.h"
#include "afb/figure/Load.h"
#include "afb/sim/Drop.h"
#include "afb/sim/GltfReplay.h"
#include "afb/sim/RawRagdoll.h"
#include "afb/sim/Report.h"

namespace afb::cli {

void addDropCommand(CLI::App& app, int& exitCode, int argc, char** argv) {
    auto* cmd = app.add_subcommand("drop", "Drop figures onto a ground plane and report speed, accuracy and stability");
    cmd->footer(sim::dropFieldsHelp());
    struct Options {
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
        bool doomGravity = false, noSleep = false, strict = false;
        std::optional<int> worlds;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("entities", opt->entities, "entityDefs to drop")->required();
    cmd->add_option("--base", opt->base, "Content folder (af/, def/, models/)")->capture_default_str();
    cmd->add_option("--height", opt->drop.heightM, "Height of each figure's lowest point at spawn, m")
        ->capture_default_str();
    cmd->add_option("--count", opt->drop.count, "Instances per figure, on a grid in one world")->capture_default_str();
    cmd->add_option("--threads", opt->drop.threads,
                    "Run the worlds on this many threads (default 1; alone, also splits into that many worlds)")
        ->check(CLI::Range(1, 1024));
    cmd->add_option("--worlds", opt->worlds,
                    "Split the instances over this many independent worlds (default: --threads); the results "
                    "do not depend on --threads")
        ->check(CLI::Range(1, 1 << 20));
    cmd->add_option("--seed", opt->seed,
                    "Random initial orientations (yaw and tilt) from this seed; default: yaw 37°·i");
    cmd->add_option("--lod", opt->drop.lod,
                    "Level of detail: switch every instance at spawn to N rigid bodies, the lightest body merged into "
                    "its lightest jointed neighbour until N remain (fixed joints always merged; rigid backend only). "
                    "bodies, us/body and awake still count the figure's bodies, so the numbers compare with a run "
                    "without --lod")
        ->check(CLI::Range(1, 1 << 20));
    cmd->add_option("--seconds", opt->drop.seconds, "Simulated time, s")->capture_default_str();
    cmd->add_option("--steps", opt->steps, "Exact number of steps (overrides --seconds); 0 reports the spawn pose");
    cmd->add_option("--hz", opt->drop.hz, "Fixed frame rate")->capture_default_str();
    addMethodOptions(cmd, opt->method);
    cmd->add_option("--precision", opt->precision, "Bullet build: float or double (default: this binary's)")
        ->check(CLI::IsMember({"float", "double"}));
    cmd->add_flag("--strict", opt->strict, "Refuse values the builder would repair (README: hostile numbers)");
    cmd->add_flag("--no-sleep", opt->noSleep, "Never put figures to rest (the rest rules are off)");
    cmd->add_flag("--stop-at-rest", opt->drop.stopAtRest, "End a run when every instance is at rest");
    cmd->add_flag("--doom-gravity", opt->doomGravity, "Doom's gravity, 1066 units/s² (27.1 m/s²), instead of 9.81");
    cmd->add_option("--json", opt->json, "Write the results as JSON to this file ('-': stdout)");
    cmd->add_option("--csv", opt->csv, "Write the results (without final_pose) as CSV to this file");
    cmd->add_option("--gltf", opt->gltf,
                    "Record the first instance as a glTF 2.0 binary (FILE.glb, one entity): the skinned md5 mesh, "
                    "its skeleton, the body hulls, the ground and one animation at the step rate; metres, Y up");
    cmd->callback([opt, &exitCode, argc, argv] {
        if (!opt->precision.empty() && opt->precision != sim::bulletPrecision()) {
            execOtherPrecision(opt->precision, argv, "afb drop");
            exitCode = 1;
            return;
        }
        (void)argc;
        std::string error;
        const auto method = resolveMethod(*opt->method, error);
        if (!method) {
            std::cerr << "afb drop: " << error << "\n";
            exitCode = 1;
            return;
        }
        if (opt->drop.lod && (sim::isRaw(*method) || method->backend != bullet::Backend::Rigid)) {
            std::cerr << "afb drop: --lod needs the rigid backend (not the raw method or the multibody backend)\n";
            exitCode = 1;
            return;
        }
        if (!opt->gltf.empty()) {
            std::string ext = opt->gltf.extension().string();
            for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
            const char* problem = ext != ".glb"               ? "--gltf must name a .glb file"
                                  : opt->entities.size() != 1 ? "--gltf records one entity: give exactly one"
                                                              : nullptr;
            if (problem) {
                std::cerr << "afb drop: " << problem << "\n";
                exitCode = 1;
                return;
            }
        }
        opt->drop.method = *method;
        opt->drop.seed = opt->seed;
        opt->drop.steps = opt->steps;
        opt->drop.sleeping = !opt->noSleep;
        opt->drop.worlds = opt->worlds.value_or(std::max(1, opt->drop.threads)); // --threads N alone: N worlds
        figure::UnitSystem units;
        units.gravityMps2 = opt->doomGravity ? units.doomGravityMps2() : opt->gravity;
        text::Diagnostics diags;
        auto lib = decl::Library::open(opt->base, diags);
        std::vector<sim::DropResult> results;
        // The table names each row by its entity, and by the figure too where they differ: entities that share a
        // figure (humanoid, humanoid_prop, humanoid_sleeping) would otherwise print alike.
        std::vector<std::string> labels;
        std::vector<std::string> replays; // what --gltf wrote, printed after the table
        std::printf("afb drop: Bullet %s (%s), %g Hz, sleeping %s, gravity %.3f m/s²\n  method %s\n",
                    sim::bulletVersion().c_str(), sim::bulletPrecision(), opt->drop.hz,
                    opt->drop.sleeping ? "on" : "off", units.gravityMps2, bullet::describe(opt->drop.method).c_str());
        if (opt->drop.lod)
            std::printf("  level of detail: --lod %d (automatic merge; each figure's rigid bodies below)\n",
                        *opt->drop.lod);
        for (const std::string& e : opt->entities) {
            std::optional<figure::LoadedFigure> loaded;
            if (lib) loaded = figure::loadEntityFigure(*lib, e, units, diags, opt->strict);
            if (!loaded) {
                exitCode = 1;
                continue;
            }
            if (::isatty(STDERR_FILENO)) std::fprintf(stderr, "  dropping %s x %d ...\r", e.c_str(), opt->drop.count);
            sim::DropOptions drop = opt->drop;
            drop.startAtRest = loaded->startAtRest; // "nodrop"/"sleep" entities hang until touched
            sim::DropRecording recording;
            sim::DropObserver observer;
            if (!opt->gltf.empty()) observer = sim::recordInto(recording, drop.hz);
            results.push_back(sim::runDrop(loaded->figure, drop, observer));
            labels.push_back(results.back().figure == e ? e : e + " (" + results.back().figure + ")");
            if (!opt->gltf.empty()) {
                const sim::GltfReplayResult written =
                    sim::writeGltfReplay(loaded->figure, loaded->mesh, recording, opt->gltf);
                if (written.error) {
                    std::cerr << "afb drop: --gltf: " << *written.error << "\n";
                    exitCode = 1;
                    continue;
                }
                char line[512];
                std::snprintf(line, sizeof line,
                              "afb drop: replay of %s (first instance: %d frames at %g Hz, %d joints, %d bodies) -> %s",
                              e.c_str(), written.frames, drop.hz, written.joints, written.bodies, opt->gltf.c_str());
                replays.push_back(line);
                if (written.framesDropped > 0)
                    replays.push_back("afb drop: warning: the replay stops where the pose stopped being finite (" +
                                      std::to_string(written.framesDropped) + " frames left out)");
            }
        }
        std::fflush(stdout);
        printDiagnostics(diags);
        std::printf("\n%-32s %6s %7s %9s %9s %10s %9s %9s %9s %9s %9s %8s %8s\n", "entity", "bodies", "steps",
                    "us/step", "us/body", "awake", "anchor m", "limit deg", "pen. m", "rest m", "gain J", "exploded",
                    "settle s");
        for (std::size_t i = 0; i < results.size(); ++i) {
            const sim::DropResult& r = results[i];
            std::printf("%-32s %6d %7d %9.1f %9.2f %10lld %9.4f %9.2f %9.4f %9.4f %9.3f %8s %8s\n", labels[i].c_str(),
                        r.bodies, r.steps, r.usPerStep, r.usPerBodyStep, r.awakeBodySteps, r.maxAnchorErrorM,
                        r.maxLimitViolationDeg, r.maxPenetrationM, r.restPenetrationM, r.maxEnergyGainJ,
                        r.nonFinite  ? "NaN"
                        : r.exploded ? "YES"
                                     : "no",
                        r.settleTimeS ? std::to_string(*r.settleTimeS).substr(0, 6).c_str() : "-");
            if (r.exploded) exitCode = 1;
        }
        for (std::size_t i = 0; i < results.size(); ++i)
            if (const sim::DropResult& r = results[i]; !r.worstAnchorJoint.empty() || !r.worstLimitJoint.empty())
                std::printf("  %s: worst anchor at %s, worst limit at %s, deepest contact %s\n", labels[i].c_str(),
                            r.worstAnchorJoint.empty() ? "-" : r.worstAnchorJoint.c_str(),
                            r.worstLimitJoint.empty() ? "-" : r.worstLimitJoint.c_str(),
                            r.worstContact.empty() ? "-" : r.worstContact.c_str());
        for (std::size_t i = 0; i < results.size(); ++i)
            if (const sim::DropResult& r = results[i]; r.lodBodies)
                std::printf("  %s: level of detail, %d rigid bodies for %d bodies per instance\n", labels[i].c_str(),
                            *r.lodBodies, r.bodies / std::max(1, opt->drop.count));
        for (const std::string& line : replays) std::printf("%s\n", line.c_str());
        nlohmann::json all = {{"bullet", sim::bulletVersion()},
                              {"precision", sim::bulletPrecision()},
                              {"gravity_mps2", units.gravityMps2},
                              {"threads", opt->drop.threads > 0 ? opt->drop.threads : 1},
                              {"worlds", opt->drop.worlds},
                              {"scenario", sim::dropOptionsJson(opt->drop)},
                              {"runs", nlohmann::json::array()}};
        for (const sim::DropResult& r : results) all["runs"].push_back(sim::dropResultJson(r));
        if (opt->json == "-") std::cout << all.dump(2) << "\n";
        else if (!opt->json.empty()) std::ofstream(opt->json) << all.dump(2) << "\n";
        if (!opt->csv.empty()) {
            std::ofstream csv(opt->csv);
            csv << sim::dropCsvHeader() << "\n";
            for (const sim::DropResult& r : results) csv << sim::dropCsvRow(r) << "\n";
        }
        if (diags.hasErrors()) exitCode = 1;
    });
}

void execOtherPrecision(const std::string& precision, char** argv, const char* command) {
    const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe");
    const std::filesystem::path other = self.parent_path() / (precision == "double" ? "afb-double" : "afb");
    ::execv(other.c_str(), argv);
    std::cerr << command << ": cannot run " << other.string() << " for --precision " << precision << "\n";
}

} // namespace afb::cli
