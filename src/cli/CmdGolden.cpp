// afb golden record|compare: settled poses of drop scenarios, stored as JSON and compared within tolerances.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>

#include "Commands.h"
#include "MethodOptions.h"
#include "Usage.h"
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
    if (!lib || !findEntities(*lib, {entity}, diags)) return run;
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

struct Record {
    std::filesystem::path base = ".", out;
    std::string entity;
    sim::DropOptions drop;
    std::optional<std::uint32_t> seed;
    std::shared_ptr<MethodOptions> method = std::make_shared<MethodOptions>();
    double positionM = 0.02, angleDeg = 3.0;
};

nlohmann::json goldenJson(const Record& rec, const Run& run) {
    const std::filesystem::path goldenDir = std::filesystem::absolute(rec.out).parent_path();
    const sim::DropResult& r = *run.result;
    return {{"entity", rec.entity},
            {"base", std::filesystem::relative(std::filesystem::absolute(rec.base), goldenDir).generic_string()},
            {"inputs", inputHashes(*run.resolved, std::filesystem::absolute(rec.base))},
            {"options", sim::dropOptionsJson(rec.drop)},
            {"bullet", sim::bulletVersion()},
            {"precision", sim::bulletPrecision()},
            {"tolerance", {{"position_m", rec.positionM}, {"angle_deg", rec.angleDeg}}},
            {"settle_time_s", r.settleTimeS ? nlohmann::json(*r.settleTimeS) : nlohmann::json(nullptr)},
            {"state_hash", stateHash(r)},
            {"entity_transform",
             {{"position", {r.entity[0], r.entity[1], r.entity[2]}},
              {"quaternion", {r.entity[3], r.entity[4], r.entity[5], r.entity[6]}}}},
            {"pose", sim::poseJson(r.finalPose)}};
}

void addRecordCommand(CLI::App* golden, int& exitCode) {
    auto rec = std::make_shared<Record>();
    auto* record = golden->add_subcommand("record", "Run a drop and store its scenario, input hashes and settled pose");
    record->add_option("entity", rec->entity, "entityDef to drop")->required();
    record->add_option("--base", rec->base, "Content folder")->capture_default_str();
    record->add_option("--out", rec->out, "Golden file to write (JSON)")->required();
    record->add_option("--height", rec->drop.heightM, "Spawn height, m")->check(nonNegative())->capture_default_str();
    record->add_option("--seconds", rec->drop.seconds, "Simulated time, s")
        ->check(nonNegative())
        ->capture_default_str();
    record->add_option("--hz", rec->drop.hz, "Frame rate")->check(positive())->capture_default_str();
    addMethodOptions(record, rec->method);
    record->add_option("--seed", rec->seed, "Random initial orientation from this seed");
    record->add_option("--position-tolerance", rec->positionM, "Per-joint position tolerance, m")
        ->check(nonNegative())
        ->capture_default_str();
    record->add_option("--angle-tolerance", rec->angleDeg, "Per-joint angle tolerance, degrees")
        ->check(within(0, 180))
        ->capture_default_str();
    record->callback([rec, &exitCode] {
        rec->drop.method = resolveMethod(*rec->method);
        checkStepCount("--seconds", rec->drop.seconds, rec->drop.hz);
        rec->drop.seed = rec->seed;
        text::Diagnostics diags;
        const Run run = runScenario(rec->base, rec->entity, rec->drop, diags);
        printDiagnostics(diags);
        if (!run.result) {
            exitCode = kExitFailure;
            return;
        }
        std::ofstream(rec->out) << goldenJson(*rec, run).dump(2) << "\n";
        std::printf("recorded %s -> %s (%zu joints, state %s)\n", rec->entity.c_str(), rec->out.string().c_str(),
                    run.result->finalPose.size(), stateHash(*run.result).c_str());
    });
}

struct Compare {
    std::vector<std::filesystem::path> files;
    bool exact = false;
    bool ignoreInputs = false;
};

// A golden file's scenario, checked: the record, its content folder and drop options.
struct Golden {
    nlohmann::json g;
    std::filesystem::path base;
    sim::DropOptions options;
};

// Reads a golden file; nullopt (after saying why) when it is not one, an input changed (unless `ignoreInputs`) or
// its method cannot be run as recorded.
std::optional<Golden> readGolden(const std::filesystem::path& file, bool ignoreInputs) {
    text::Diagnostics diags;
    const auto data = text::readFile(file, diags);
    Golden golden;
    if (data) golden.g = nlohmann::json::parse(*data, nullptr, false);
    const nlohmann::json& g = golden.g;
    if (!data || g.is_discarded() || !g.contains("pose")) {
        printDiagnostics(diags);
        std::cerr << file.string() << ": error: not a golden file\n";
        return std::nullopt;
    }
    golden.base = std::filesystem::absolute(file).parent_path() / g.at("base").get<std::string>();
    // An input that changed is reported as such, not as a pose difference.
    bool changed = false;
    const nlohmann::json inputs = g.value("inputs", nlohmann::json::object());
    for (const auto& [rel, hash] : inputs.items())
        if (fileHash(golden.base / rel) != hash.get<std::string>()) {
            std::cerr << file.string() << ": input changed since recording: " << rel << "\n";
            changed = true;
        }
    if (changed && !ignoreInputs) return std::nullopt;
    if (const std::string err = sim::dropOptionsFromJson(g.at("options"), golden.options); !err.empty()) {
        std::cerr << file.string() << ": error: " << err << "\n";
        return std::nullopt;
    }
    // A knob the record does not name would run with today's preset value: a method nobody recorded, whose pose
    // the record says nothing about.
    if (const auto missing = sim::missingKnobs(g.at("options").value("method", nlohmann::json::object()));
        !missing.empty() && g.at("options").contains("method")) {
        std::string names;
        for (const std::string& k : missing) names += (names.empty() ? "" : ", ") + k;
        std::cerr << file.string() << ": error: the recorded method does not name " << names
                  << " (recorded before the knob existed); re-record it with afb golden record\n";
        return std::nullopt;
    }
    return golden;
}

// Prints the comparison of a run with its golden record; true when every joint is within its tolerance (and, with
// `exact`, the state hash is equal).
bool comparePose(const std::filesystem::path& file, const nlohmann::json& g, const sim::DropResult& result,
                 bool exact) {
    const double tolM = g.at("tolerance").at("position_m"), tolDeg = g.at("tolerance").at("angle_deg");
    std::vector<std::string> moved;
    double worstM = 0, worstDeg = 0;
    const auto& joints = g.at("pose");
    // The entity transform (world) first, then every joint (model space).
    std::vector<sim::JointPose> nowPose;
    nowPose.push_back({"(entity)",
                       {result.entity[0], result.entity[1], result.entity[2]},
                       {result.entity[3], result.entity[4], result.entity[5], result.entity[6]}});
    nowPose.insert(nowPose.end(), result.finalPose.begin(), result.finalPose.end());
    nlohmann::json expected = nlohmann::json::array();
    if (g.contains("entity_transform")) expected.push_back(g.at("entity_transform"));
    else expected.push_back({{"position", {0, 0, 0}}, {"quaternion", {1, 0, 0, 0}}});
    for (const auto& j : joints) expected.push_back(j);
    for (std::size_t i = 0; i < expected.size() && i < nowPose.size(); ++i) {
        const sim::JointPose& now = nowPose[i];
        const std::vector<double> p = expected[i]["position"], q = expected[i]["quaternion"];
        const double dm = std::hypot(now.position[0] - p[0], now.position[1] - p[1], now.position[2] - p[2]);
        const double dd = angleDeg(now.quaternion, q.data());
        worstM = std::max(worstM, dm);
        worstDeg = std::max(worstDeg, dd);
        if (dm > tolM || dd > tolDeg) {
            char line[160];
            std::snprintf(line, sizeof line, "  %-20s moved %.4f m, turned %.2f deg", now.name.c_str(), dm, dd);
            moved.emplace_back(line);
        }
    }
    bool fail = !moved.empty() || joints.size() + 1 != nowPose.size();
    const std::string hash = stateHash(result);
    const bool hashEqual = exact && hash == g.at("state_hash").get<std::string>();
    if (exact && !hashEqual) fail = true;
    std::printf("%s %s: worst joint %.4f m / %.2f deg (tolerance %.4f m / %.2f deg)%s%s\n", fail ? "FAIL" : "ok  ",
                file.string().c_str(), worstM, worstDeg, tolM, tolDeg,
                exact ? (hashEqual ? ", state hash equal" : ", state hash differs") : "",
                joints.size() + 1 != nowPose.size() ? ", joint count differs" : "");
    for (const std::string& m : moved) std::printf("%s\n", m.c_str());
    return !fail;
}

// Re-runs one golden file; true when it holds.
bool compareOne(const std::filesystem::path& file, const Compare& cmp) {
    try {
        const auto golden = readGolden(file, cmp.ignoreInputs);
        if (!golden) return false;
        text::Diagnostics diags;
        const Run run = runScenario(golden->base, golden->g.at("entity").get<std::string>(), golden->options, diags);
        printDiagnostics(diags);
        return run.result && comparePose(file, golden->g, *run.result, cmp.exact);
    } catch (const nlohmann::json::exception& e) {
        std::cerr << file.string() << ": error: malformed golden file: " << e.what() << "\n";
        return false;
    }
}

void addCompareCommand(CLI::App* golden, int& exitCode) {
    auto cmp = std::make_shared<Compare>();
    auto* compare = golden->add_subcommand("compare", "Re-run golden scenarios; exit 1 when a joint moved past its "
                                                      "tolerance or an input changed");
    compare->add_option("files", cmp->files, "Golden files")->required();
    compare->add_flag("--exact", cmp->exact, "Also demand the bit-exact state hash (same build, same machine class)");
    compare->add_flag("--ignore-inputs", cmp->ignoreInputs,
                      "Compare poses even when input files changed since recording (they are still listed)");
    compare->callback([cmp, &exitCode] {
        for (const std::filesystem::path& file : cmp->files)
            if (!compareOne(file, *cmp)) exitCode = kExitFailure;
    });
}

} // namespace

void addGoldenCommand(CLI::App& app, int& exitCode) {
    auto* golden = app.add_subcommand("golden", "Record and compare settled poses of drop scenarios");
    golden->require_subcommand(1);
    addRecordCommand(golden, exitCode);
    addCompareCommand(golden, exitCode);
}

} // namespace afb::cli
