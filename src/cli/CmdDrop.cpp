// afb drop: drop figures onto a ground plane and report speed, accuracy and stability.
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <iostream>

#include "Commands.h"
#include "afb/figure/Load.h"
#include "afb/sim/Drop.h"

namespace afb::cli {
namespace {

nlohmann::json resultJson(const sim::DropResult& r) {
    nlohmann::json pose = nlohmann::json::array();
    for (const sim::JointPose& j : r.finalPose)
        pose.push_back({{"joint", j.name},
                        {"position", {j.position[0], j.position[1], j.position[2]}},
                        {"quaternion", {j.quaternion[0], j.quaternion[1], j.quaternion[2], j.quaternion[3]}}});
    auto opt = [](const std::optional<double>& v) { return v ? nlohmann::json(*v) : nlohmann::json(nullptr); };
    return {{"figure", r.figure},
            {"precision", r.precision},
            {"bodies", r.bodies},
            {"constraints", r.constraints},
            {"steps", r.steps},
            {"wall_ms", r.wallMs},
            {"us_per_step", r.usPerStep},
            {"us_per_body_step", r.usPerBodyStep},
            {"awake_body_steps", r.awakeBodySteps},
            {"max_anchor_error_m", r.maxAnchorErrorM},
            {"max_limit_violation_deg", r.maxLimitViolationDeg},
            {"max_penetration_m", r.maxPenetrationM},
            {"max_energy_gain_j", r.maxEnergyGainJ},
            {"max_speed_mps", r.maxSpeedMps},
            {"exploded", r.exploded},
            {"exploded_at_s", opt(r.explodedAtS)},
            {"settle_time_s", opt(r.settleTimeS)},
            {"final_pose", {{"entity", {{"position", {r.entity[0], r.entity[1], r.entity[2]}},
                                        {"quaternion", {r.entity[3], r.entity[4], r.entity[5], r.entity[6]}}}},
                            {"joints", pose}}}};
}

const char* kFields =
    "Fields (JSON and CSV): figure, precision, bodies, constraints, steps; speed: wall_ms, us_per_step (stepping only, "
    "the slowest world), us_per_body_step, awake_body_steps (body-steps not asleep); accuracy: max_anchor_error_m "
    "(largest separation of a constraint's two anchor copies; sliders: off-axis only), max_limit_violation_deg (cone, "
    "pyramid and hinge limits), max_penetration_m (deepest contact: ground and between bodies), max_energy_gain_j "
    "(kinetic + potential above the start); stability: max_speed_mps, exploded (NaN, a speed over 100 m/s or an anchor "
    "error over 0.1 m), exploded_at_s; outcome: settle_time_s (every instance at rest by its figure's rules, else "
    "null), final_pose (first instance: entity transform and every md5 joint's model-space position and w,x,y,z "
    "quaternion, metres).";

} // namespace

void addDropCommand(CLI::App& app, int& exitCode, int argc, char** argv) {
    auto* cmd = app.add_subcommand("drop", "Drop figures onto a ground plane and report speed, accuracy and stability");
    cmd->footer(kFields);
    struct Options {
        std::filesystem::path base = ".";
        std::vector<std::string> entities;
        sim::DropOptions drop;
        std::optional<std::uint32_t> seed;
        std::optional<int> steps;
        std::string precision;
        std::string json, csv;
        double gravity = 9.81;
        bool doomGravity = false, noSleep = false;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("entities", opt->entities, "entityDefs to drop")->required();
    cmd->add_option("--base", opt->base, "Content folder (af/, def/, models/)")->capture_default_str();
    cmd->add_option("--height", opt->drop.heightM, "Height of each figure's lowest point at spawn, m")->capture_default_str();
    cmd->add_option("--count", opt->drop.count, "Instances per figure, on a grid in one world")->capture_default_str();
    cmd->add_option("--threads", opt->drop.worlds, "Split the instances over this many worlds, one thread each")
        ->capture_default_str();
    cmd->add_option("--seed", opt->seed, "Random initial orientations (yaw and tilt) from this seed; default: yaw 37°·i");
    cmd->add_option("--seconds", opt->drop.seconds, "Simulated time, s")->capture_default_str();
    cmd->add_option("--steps", opt->steps, "Exact number of steps (overrides --seconds); 0 reports the spawn pose");
    cmd->add_option("--hz", opt->drop.hz, "Fixed step rate")->capture_default_str();
    cmd->add_option("--substeps", opt->drop.substeps, "Bullet substeps per step")->capture_default_str();
    cmd->add_option("--iterations", opt->drop.iterations, "Solver iterations")->capture_default_str();
    cmd->add_option("--joint-iterations", opt->drop.constraintIterations,
                    "Solver iterations of the figure's joints and limits (0: the world's)")
        ->capture_default_str();
    cmd->add_option("--precision", opt->precision, "Bullet build: float or double (default: this binary's)")
        ->check(CLI::IsMember({"float", "double"}));
    cmd->add_flag("--no-sleep", opt->noSleep, "Never put figures to rest (the rest rules are off)");
    cmd->add_flag("--stop-at-rest", opt->drop.stopAtRest, "End a run when every instance is at rest");
    cmd->add_flag("--doom-gravity", opt->doomGravity, "Doom's gravity, 1066 units/s² (27.1 m/s²), instead of 9.81");
    cmd->add_option("--json", opt->json, "Write the results as JSON to this file ('-': stdout)");
    cmd->add_option("--csv", opt->csv, "Write the results (without final_pose) as CSV to this file");
    cmd->callback([opt, &exitCode, argc, argv] {
        if (!opt->precision.empty() && opt->precision != sim::bulletPrecision()) {
            // The two Bullet builds cannot share a process: run the sibling binary built against the other one.
            const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe");
            const std::filesystem::path other = self.parent_path() / (opt->precision == "double" ? "afb-double" : "afb");
            ::execv(other.c_str(), argv);
            std::cerr << "afb drop: cannot run " << other.string() << " for --precision " << opt->precision << "\n";
            exitCode = 1;
            return;
        }
        (void)argc;
        opt->drop.seed = opt->seed;
        opt->drop.steps = opt->steps;
        opt->drop.sleeping = !opt->noSleep;
        figure::UnitSystem units;
        units.gravityMps2 = opt->doomGravity ? units.doomGravityMps2() : opt->gravity;
        text::Diagnostics diags;
        auto lib = decl::Library::open(opt->base, diags);
        std::vector<sim::DropResult> results;
        std::printf("afb drop: Bullet %s (%s), %g Hz x %d substeps, %d iterations (joints %d), sleeping %s, gravity %.3f m/s²\n",
                    sim::bulletVersion().c_str(), sim::bulletPrecision(), opt->drop.hz, opt->drop.substeps,
                    opt->drop.iterations, opt->drop.constraintIterations, opt->drop.sleeping ? "on" : "off",
                    units.gravityMps2);
        for (const std::string& e : opt->entities) {
            std::optional<figure::LoadedFigure> loaded;
            if (lib) loaded = figure::loadEntityFigure(*lib, e, units, diags);
            if (!loaded) {
                exitCode = 1;
                continue;
            }
            if (::isatty(STDERR_FILENO)) std::fprintf(stderr, "  dropping %s x %d ...\r", e.c_str(), opt->drop.count);
            sim::DropOptions drop = opt->drop;
            drop.startAtRest = loaded->startAtRest; // "nodrop"/"sleep" entities hang until touched
            results.push_back(sim::runDrop(loaded->figure, drop));
        }
        std::fflush(stdout);
        printDiagnostics(diags);
        std::printf("\n%-32s %6s %7s %9s %9s %10s %9s %9s %9s %9s %8s %8s\n", "figure", "bodies", "steps", "us/step",
                    "us/body", "awake", "anchor m", "limit deg", "pen. m", "gain J", "exploded", "settle s");
        for (const sim::DropResult& r : results) {
            std::printf("%-32s %6d %7d %9.1f %9.2f %10lld %9.4f %9.2f %9.4f %9.3f %8s %8s\n", r.figure.c_str(), r.bodies,
                        r.steps, r.usPerStep, r.usPerBodyStep, r.awakeBodySteps, r.maxAnchorErrorM,
                        r.maxLimitViolationDeg, r.maxPenetrationM, r.maxEnergyGainJ, r.exploded ? "YES" : "no",
                        r.settleTimeS ? std::to_string(*r.settleTimeS).substr(0, 6).c_str() : "-");
            if (r.exploded) exitCode = 1;
        }
        nlohmann::json all = {{"bullet", sim::bulletVersion()},
                              {"precision", sim::bulletPrecision()},
                              {"hz", opt->drop.hz},
                              {"substeps", opt->drop.substeps},
                              {"iterations", opt->drop.iterations},
                              {"joint_iterations", opt->drop.constraintIterations},
                              {"sleeping", opt->drop.sleeping},
                              {"gravity_mps2", units.gravityMps2},
                              {"count", opt->drop.count},
                              {"threads", opt->drop.worlds},
                              {"height_m", opt->drop.heightM},
                              {"seed", opt->seed ? nlohmann::json(*opt->seed) : nlohmann::json(nullptr)},
                              {"runs", nlohmann::json::array()}};
        for (const sim::DropResult& r : results) all["runs"].push_back(resultJson(r));
        if (opt->json == "-") std::cout << all.dump(2) << "\n";
        else if (!opt->json.empty()) std::ofstream(opt->json) << all.dump(2) << "\n";
        if (!opt->csv.empty()) {
            std::ofstream csv(opt->csv);
            csv << "figure,precision,bodies,constraints,steps,wall_ms,us_per_step,us_per_body_step,awake_body_steps,"
                   "max_anchor_error_m,max_limit_violation_deg,max_penetration_m,max_energy_gain_j,max_speed_mps,"
                   "exploded,exploded_at_s,settle_time_s\n";
            for (const sim::DropResult& r : results)
                csv << r.figure << ',' << r.precision << ',' << r.bodies << ',' << r.constraints << ',' << r.steps << ','
                    << r.wallMs << ',' << r.usPerStep << ',' << r.usPerBodyStep << ',' << r.awakeBodySteps << ','
                    << r.maxAnchorErrorM << ',' << r.maxLimitViolationDeg << ',' << r.maxPenetrationM << ','
                    << r.maxEnergyGainJ << ',' << r.maxSpeedMps << ',' << (r.exploded ? 1 : 0) << ','
                    << (r.explodedAtS ? std::to_string(*r.explodedAtS) : "") << ','
                    << (r.settleTimeS ? std::to_string(*r.settleTimeS) : "") << "\n";
        }
        if (diags.hasErrors()) exitCode = 1;
    });
}

} // namespace afb::cli
