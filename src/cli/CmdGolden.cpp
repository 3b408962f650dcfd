// afb golden record|compare: settled poses of drop scenarios, stored as JSON and compared within tolerances.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>

#include "Commands.h"
#include "MethodOptions.h"
#include "afb/figure/Load.h"
#include "afb/sim/Drop.h"
#include "afb/sim/Report.h"
#include "afb/text/Files.h"

namespace afb::cli {
namespace {

// FNV-1a, 64 bit: a stable content hash for change detection (not for security).
std::uint64_t fnv1a(std::string_view data, std::uint64_t h = 1469598103934665603ull) {
    for (unsigned char c : data) {
        h ^= c;
        h *= 1099511628211ull;
    }
    return h;
}
std::string hex(std::uint64_t v) {
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
    return buf;
}

std::string fileHash(const std::filesystem::path& p) {
    text::Diagnostics d;
    const auto data = text::readFile(p, d);
    return data ? hex(fnv1a(*data)) : "missing";
}

// Every input file of an entity, relative to the content folder, with its hash.
nlohmann::json inputHashes(const decl::ResolvedEntity& r, const std::filesystem::path& base) {
    nlohmann::json out = nlohmann::json::object();
    for (const std::filesystem::path& p :
         {r.figureFile, r.meshPath, r.afPosePath, std::filesystem::path(r.entityLocation.file),
          std::filesystem::path(r.modelLocation.file)})
        out[std::filesystem::relative(p, base).generic_string()] = fileHash(p);
    return out;
}

// The bit-exact state of a run: every value of the final pose.
std::string stateHash(const sim::DropResult& r) {
    std::uint64_t h = fnv1a(std::string_view(reinterpret_cast<const char*>(r.entity), sizeof r.entity));
    for (const sim::JointPose& j : r.finalPose) {
        h = fnv1a(std::string_view(reinterpret_cast<const char*>(j.position), sizeof j.position), h);
        h = fnv1a(std::string_view(reinterpret_cast<const char*>(j.quaternion), sizeof j.quaternion), h);
    }
    return hex(h);
}

struct Run {
    std::optional<decl::ResolvedEntity> resolved;
    std::optional<sim::DropResult> result;
};

Run runScenario(const std::filesystem::path& base, const std::string& entity, const sim::DropOptions& o,
                text::Diagnostics& diags) {
    Run run;
    auto lib = decl::Library::open(base, diags);
    if (!lib) return run;
    run.resolved = lib->resolveEntity(entity, diags);
    auto loaded = figure::loadEntityFigure(*lib, entity, {}, diags);
    if (run.resolved && loaded) {
        sim::DropOptions drop = o;
        drop.startAtRest = loaded->startAtRest;
        run.result = sim::runDrop(loaded->figure, drop);
    }
    return run;
}

double angleDeg(const double* a, const double* b) {
    const double dot = std::abs(a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]);
    return 2.0 * std::acos(std::min(1.0, dot)) * 180.0 / 3.14159265358979323846;
}

} // namespace

void addGoldenCommand(CLI::App& app, int& exitCode) {
    auto* golden = app.add_subcommand("golden", "Record and compare settled poses of drop scenarios");
    golden->require_subcommand(1);

    struct Record {
        std::filesystem::path base = ".", out;
        std::string entity;
        sim::DropOptions drop;
        std::optional<std::uint32_t> seed;
        std::shared_ptr<MethodOptions> method = std::make_shared<MethodOptions>();
        double positionM = 0.02, angleDeg = 3.0;
    };
    auto rec = std::make_shared<Record>();
    auto* record = golden->add_subcommand("record", "Run a drop and store its scenario, input hashes and settled pose");
    record->add_option("entity", rec->entity, "entityDef to drop")->required();
    record->add_option("--base", rec->base, "Content folder")->capture_default_str();
    record->add_option("--out", rec->out, "Golden file to write (JSON)")->required();
    record->add_option("--height", rec->drop.heightM, "Spawn height, m")->capture_default_str();
    record->add_option("--seconds", rec->drop.seconds, "Simulated time, s")->capture_default_str();
    record->add_option("--hz", rec->drop.hz, "Frame rate")->capture_default_str();
    addMethodOptions(record, rec->method);
    record->add_option("--seed", rec->seed, "Random initial orientation from this seed");
    record->add_option("--position-tolerance", rec->positionM, "Per-joint position tolerance, m")
        ->capture_default_str();
    record->add_option("--angle-tolerance", rec->angleDeg, "Per-joint angle tolerance, degrees")->capture_default_str();
    record->callback([rec, &exitCode] {
        std::string error;
        const auto method = resolveMethod(*rec->method, error);
        if (!method) {
            std::cerr << "afb golden record: " << error << "\n";
            exitCode = 1;
            return;
        }
        rec->drop.method = *method;
        rec->drop.seed = rec->seed;
        text::Diagnostics diags;
        const Run run = runScenario(rec->base, rec->entity, rec->drop, diags);
        printDiagnostics(diags);
        if (!run.result) {
            exitCode = 1;
            return;
        }
        const std::filesystem::path goldenDir = std::filesystem::absolute(rec->out).parent_path();
        const nlohmann::json g = {
            {"entity", rec->entity},
            {"base", std::filesystem::relative(std::filesystem::absolute(rec->base), goldenDir).generic_string()},
            {"inputs", inputHashes(*run.resolved, std::filesystem::absolute(rec->base))},
            {"options", sim::dropOptionsJson(rec->drop)},
            {"bullet", sim::bulletVersion()},
            {"precision", sim::bulletPrecision()},
            {"tolerance", {{"position_m", rec->positionM}, {"angle_deg", rec->angleDeg}}},
            {"settle_time_s",
             run.result->settleTimeS ? nlohmann::json(*run.result->settleTimeS) : nlohmann::json(nullptr)},
            {"state_hash", stateHash(*run.result)},
            {"entity_transform",
             {{"position", {run.result->entity[0], run.result->entity[1], run.result->entity[2]}},
              {"quaternion",
               {run.result->entity[3], run.result->entity[4], run.result->entity[5], run.result->entity[6]}}}},
            {"pose", sim::poseJson(run.result->finalPose)}};
        std::ofstream(rec->out) << g.dump(2) << "\n";
        std::printf("recorded %s -> %s (%zu joints, state %s)\n", rec->entity.c_str(), rec->out.string().c_str(),
                    run.result->finalPose.size(), stateHash(*run.result).c_str());
    });

    struct Compare {
        std::vector<std::filesystem::path> files;
        bool exact = false;
        bool ignoreInputs = false;
    };
    auto cmp = std::make_shared<Compare>();
    auto* compare = golden->add_subcommand("compare", "Re-run golden scenarios; exit 1 when a joint moved past its "
                                                      "tolerance or an input changed");
    compare->add_option("files", cmp->files, "Golden files")->required();
    compare->add_flag("--exact", cmp->exact, "Also demand the bit-exact state hash (same build, same machine class)");
    compare->add_flag("--ignore-inputs", cmp->ignoreInputs,
                      "Compare poses even when input files changed since recording (they are still listed)");
    compare->callback([cmp, &exitCode] {
        for (const std::filesystem::path& file : cmp->files) try {
                text::Diagnostics diags;
                const auto data = text::readFile(file, diags);
                nlohmann::json g;
                if (data) g = nlohmann::json::parse(*data, nullptr, false);
                if (!data || g.is_discarded() || !g.contains("pose")) {
                    printDiagnostics(diags);
                    std::cerr << file.string() << ": error: not a golden file\n";
                    exitCode = 1;
                    continue;
                }
                const std::filesystem::path base =
                    std::filesystem::absolute(file).parent_path() / g["base"].get<std::string>();
                const std::string entity = g["entity"];
                // An input that changed is reported as such, not as a pose difference.
                bool changed = false;
                for (const auto& [rel, hash] : g["inputs"].items())
                    if (fileHash(base / rel) != hash.get<std::string>()) {
                        std::cerr << file.string() << ": input changed since recording: " << rel << "\n";
                        changed = true;
                    }
                if (changed && !cmp->ignoreInputs) {
                    exitCode = 1;
                    continue;
                }
                sim::DropOptions options;
                if (const std::string err = sim::dropOptionsFromJson(g["options"], options); !err.empty()) {
                    std::cerr << file.string() << ": error: " << err << "\n";
                    exitCode = 1;
                    continue;
                }
                // A knob the record does not name would run with today's preset value: a method nobody recorded,
                // whose pose the record says nothing about.
                if (const auto missing = sim::missingKnobs(g["options"].value("method", nlohmann::json::object()));
                    !missing.empty() && g["options"].contains("method")) {
                    std::string names;
                    for (const std::string& k : missing) names += (names.empty() ? "" : ", ") + k;
                    std::cerr << file.string() << ": error: the recorded method does not name " << names
                              << " (recorded before the knob existed); re-record it with afb golden record\n";
                    exitCode = 1;
                    continue;
                }
                const Run run = runScenario(base, entity, options, diags);
                printDiagnostics(diags);
                if (!run.result) {
                    exitCode = 1;
                    continue;
                }
                const double tolM = g["tolerance"]["position_m"], tolDeg = g["tolerance"]["angle_deg"];
                std::vector<std::string> moved;
                double worstM = 0, worstDeg = 0;
                const auto& joints = g.at("pose");
                // The entity transform (world) first, then every joint (model space).
                std::vector<sim::JointPose> nowPose;
                nowPose.push_back(
                    {"(entity)",
                     {run.result->entity[0], run.result->entity[1], run.result->entity[2]},
                     {run.result->entity[3], run.result->entity[4], run.result->entity[5], run.result->entity[6]}});
                nowPose.insert(nowPose.end(), run.result->finalPose.begin(), run.result->finalPose.end());
                nlohmann::json expected = nlohmann::json::array();
                if (g.contains("entity_transform")) expected.push_back(g["entity_transform"]);
                else expected.push_back({{"position", {0, 0, 0}}, {"quaternion", {1, 0, 0, 0}}});
                for (const auto& j : joints) expected.push_back(j);
                for (std::size_t i = 0; i < expected.size() && i < nowPose.size(); ++i) {
                    const sim::JointPose& now = nowPose[i];
                    const std::vector<double> p = expected[i]["position"], q = expected[i]["quaternion"];
                    const double dm =
                        std::hypot(now.position[0] - p[0], now.position[1] - p[1], now.position[2] - p[2]);
                    const double dd = angleDeg(now.quaternion, q.data());
                    worstM = std::max(worstM, dm);
                    worstDeg = std::max(worstDeg, dd);
                    if (dm > tolM || dd > tolDeg) {
                        char line[160];
                        std::snprintf(line, sizeof line, "  %-20s moved %.4f m, turned %.2f deg", now.name.c_str(), dm,
                                      dd);
                        moved.emplace_back(line);
                    }
                }
                bool fail = !moved.empty() || joints.size() + 1 != nowPose.size();
                const std::string hash = stateHash(*run.result);
                if (cmp->exact && hash != g["state_hash"].get<std::string>()) fail = true;
                std::printf("%s %s: worst joint %.4f m / %.2f deg (tolerance %.4f m / %.2f deg)%s%s\n",
                            fail ? "FAIL" : "ok  ", file.string().c_str(), worstM, worstDeg, tolM, tolDeg,
                            cmp->exact ? (hash == g["state_hash"].get<std::string>() ? ", state hash equal"
                                                                                     : ", state hash differs")
                                       : "",
                            joints.size() + 1 != nowPose.size() ? ", joint count differs" : "");
                for (const std::string& m : moved) std::printf("%s\n", m.c_str());
                if (fail) exitCode = 1;
            } catch (const nlohmann::json::exception& e) {
                std::cerr << file.string() << ": error: malformed golden file: " << e.what() << "\n";
                exitCode = 1;
            }
    });
}

} // namespace afb::cli
