// afb golden record|compare: settled poses of drop scenarios, stored as JSON and compared within tolerances.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>

#include "Commands.h"
#include "GoldenCli.h"
#include "GoldenReport.h"
#include "MethodOptions.h"
#include "Usage.h"
#include "afb/figure/Load.h"
#include "afb/sim/Batch.h"
#include "afb/sim/Drop.h"
#include "afb/sim/Report.h"
#include "afb/text/Files.h"

namespace afb::cli {
namespace {

// Content hashes shared with the batch manifests (afb/sim/Batch.h).
using sim::fileHash;
using sim::fnv1a;

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
    return sim::hashHex(h);
}

struct Run {
    std::optional<decl::ResolvedEntity> resolved;
    std::optional<figure::Figure> figure;
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
        run.figure = std::move(loaded->figure);
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
    return {{"schema", sim::schemaJson(sim::kGoldenSchema)},
            {"entity", rec.entity},
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
    auto* record = golden->add_subcommand("record", "Run a drop and store its scenario, input hashes and settled pose\n"
                                                    "Examples:\n  afb golden record --base . chain --out chain.json\n"
                                                    "  afb golden record --base . humanoid --out humanoid.json "
                                                    "--height 2 --seconds 5");
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

// A golden file's scenario, checked: the record, its content folder and drop options.
struct Golden {
    nlohmann::json g;
    std::filesystem::path base;
    sim::DropOptions options;
};

// Reads a golden file; nullopt when it is not one, an input changed (unless `ignoreInputs`) or its method cannot
// be run as recorded: the case's errors say why. A changed input compared anyway is a line on stderr.
std::optional<Golden> readGolden(const std::filesystem::path& file, bool ignoreInputs, GoldenCase& out) {
    text::Diagnostics diags;
    const auto data = text::readFile(file, diags);
    Golden golden;
    if (data) golden.g = nlohmann::json::parse(*data, nullptr, false);
    const nlohmann::json& g = golden.g;
    if (!data || g.is_discarded() || !g.contains("pose")) {
        for (const text::Diagnostic& d : diags.items()) out.errors.push_back(d.str());
        out.errors.push_back(file.string() + ": error: not a golden file");
        return std::nullopt;
    }
    if (const std::string wrong = sim::checkSchema(g, sim::kGoldenSchema); !wrong.empty()) {
        out.errors.push_back(file.string() + ": error: " + wrong);
        return std::nullopt;
    }
    out.entity = g.at("entity").get<std::string>();
    golden.base = std::filesystem::absolute(file).parent_path() / g.at("base").get<std::string>();
    // An input that changed is reported as such, not as a pose difference.
    std::vector<std::string> changed;
    const nlohmann::json inputs = g.value("inputs", nlohmann::json::object());
    for (const auto& [rel, hash] : inputs.items())
        if (fileHash(golden.base / rel) != hash.get<std::string>())
            changed.push_back(file.string() + ": input changed since recording: " + rel);
    if (!changed.empty() && !ignoreInputs) {
        out.errors = changed;
        return std::nullopt;
    }
    for (const std::string& c : changed) out.warnings += c + "\n";
    if (const std::string err = sim::dropOptionsFromJson(g.at("options"), golden.options); !err.empty()) {
        out.errors.push_back(file.string() + ": error: " + err);
        return std::nullopt;
    }
    // A knob the record does not name would run with today's preset value: a method nobody recorded, whose pose
    // the record says nothing about.
    if (const auto missing = sim::missingKnobs(g.at("options").value("method", nlohmann::json::object()));
        !missing.empty() && g.at("options").contains("method")) {
        std::string names;
        for (const std::string& k : missing) names += (names.empty() ? "" : ", ") + k;
        out.errors.push_back(file.string() + ": error: the recorded method does not name " + names +
                             " (recorded before the knob existed); re-record it with afb golden record");
        return std::nullopt;
    }
    return golden;
}

// The recorded pose: the entity transform (world; identity in records made before it was kept) and every joint.
PoseRecord recordedPose(const nlohmann::json& g) {
    const auto transform = [](const nlohmann::json& j) {
        const std::vector<double> p = j.at("position"), q = j.at("quaternion");
        if (p.size() != 3 || q.size() != 4) throw std::invalid_argument("a position or quaternion of a wrong size");
        return figure::Transform{Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix(),
                                 Eigen::Vector3d(p[0], p[1], p[2])};
    };
    PoseRecord pose;
    if (g.contains("entity_transform")) pose.entity = transform(g.at("entity_transform"));
    for (const auto& j : g.at("pose")) pose.jointsModel.push_back(transform(j));
    return pose;
}

PoseRecord settledPose(const sim::DropResult& r) {
    const auto transform = [](const double* p, const double* q) {
        return figure::Transform{Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix(),
                                 Eigen::Vector3d(p[0], p[1], p[2])};
    };
    PoseRecord pose;
    pose.entity = transform(r.entity, r.entity + 3);
    for (const sim::JointPose& j : r.finalPose) pose.jointsModel.push_back(transform(j.position, j.quaternion));
    return pose;
}

// Compares a run with its golden record: every joint within its tolerance (and, with `exact`, the state hash
// equal) passes.
void comparePose(const nlohmann::json& g, const sim::DropResult& result, bool exact, GoldenCase& out) {
    out.toleranceM = g.at("tolerance").at("position_m");
    out.toleranceDeg = g.at("tolerance").at("angle_deg");
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
        out.worstM = std::max(out.worstM, dm);
        out.worstDeg = std::max(out.worstDeg, dd);
        if (dm > out.toleranceM || dd > out.toleranceDeg) out.missed.push_back({now.name, dm, dd});
    }
    if (exact)
        out.notes.push_back(stateHash(result) == g.at("state_hash").get<std::string>() ? "state hash equal"
                                                                                       : "state hash differs");
    if (joints.size() + 1 != nowPose.size()) out.notes.push_back("joint count differs");
    out.passed = out.missed.empty() && joints.size() + 1 == nowPose.size() &&
                 (!exact || out.notes.front() == "state hash equal");
}

// Draws a failing golden's settled pose over its recorded one into the report folder.
void drawFailure(const GoldenCompareCli& cmp, const Golden& golden, const Run& run, GoldenCase& c,
                 std::vector<std::filesystem::path>& taken) {
    const PoseRecord recorded = recordedPose(golden.g);
    if (recorded.jointsModel.size() != static_cast<std::size_t>(run.figure->skeleton.jointCount()))
        return; // a record of another skeleton: nothing to overlay
    const std::filesystem::path name = goldenPictureName(c, taken);
    char subtitle[160];
    std::snprintf(subtitle, sizeof subtitle, "%zu joints past tolerance; worst %.4f m / %.2f deg", c.missed.size(),
                  c.worstM, c.worstDeg);
    if (const auto error = drawGoldenPicture(*run.figure, recorded, settledPose(*run.result), c.file.generic_string(),
                                             subtitle, cmp.report / name))
        std::cerr << "afb golden compare: --report: " << *error << "\n";
    else c.picture = name;
}

} // namespace

GoldenCase compareGolden(const std::filesystem::path& file, const GoldenCompareCli& cmp,
                         std::vector<std::filesystem::path>& pictures) {
    GoldenCase c;
    c.file = file;
    const auto t0 = std::chrono::steady_clock::now();
    try {
        const auto golden = readGolden(file, cmp.ignoreInputs, c);
        if (!golden) return c;
        text::Diagnostics diags;
        const Run run = runScenario(golden->base, c.entity, golden->options, diags);
        c.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (!run.result) {
            for (const text::Diagnostic& d : diags.items()) c.errors.push_back(d.str());
            if (c.errors.empty()) c.errors.push_back(file.string() + ": error: the scenario did not run");
            return c;
        }
        c.warnings += diags.str(); // warnings
        comparePose(golden->g, *run.result, cmp.exact, c);
        if (!c.passed && !c.missed.empty() && !cmp.report.empty()) drawFailure(cmp, *golden, run, c, pictures);
    } catch (const std::exception& e) {
        c.passed = false;
        c.errors.push_back(file.string() + ": error: malformed golden file: " + e.what());
    }
    return c;
}

std::filesystem::path goldenPictureName(const GoldenCase& c, std::vector<std::filesystem::path>& taken) {
    const std::string stem = c.file.stem().string().empty() ? "golden" : c.file.stem().string();
    std::filesystem::path name = stem + ".png";
    for (int k = 2; std::find(taken.begin(), taken.end(), name) != taken.end(); ++k)
        name = stem + "-" + std::to_string(k) + ".png";
    taken.push_back(name);
    return name;
}

std::FILE* goldenTextStream(const GoldenCompareCli& opt) { return opt.junit == "-" ? stderr : stdout; }

void printGoldenCase(const GoldenCase& c, std::FILE* text) {
    std::fputs(c.warnings.c_str(), stderr);
    for (const std::string& e : c.errors) std::fprintf(stderr, "%s\n", e.c_str());
    if (c.errors.empty()) std::fprintf(text, "%s\n", caseLine(c).c_str());
    for (const JointMiss& m : c.missed)
        std::fprintf(text, "  %-20s moved %.4f m, turned %.2f deg\n", m.joint.c_str(), m.movedM, m.turnedDeg);
    std::fflush(text);
}

int finishGoldenCompare(const GoldenCompareCli& opt, const std::vector<GoldenCase>& cases, std::size_t pictures) {
    int exitCode = 0;
    for (const GoldenCase& c : cases)
        if (!c.passed) exitCode = kExitFailure;
    std::optional<std::string> error;
    if (!opt.junit.empty()) error = writeJUnit(cases, opt.junit);
    if (!error && !opt.report.empty()) error = writeMarkdown(cases, opt.report);
    if (error) {
        std::cerr << "afb golden compare: " << *error << "\n";
        return kExitFailure;
    }
    std::FILE* text = goldenTextStream(opt);
    if (!opt.junit.empty() && opt.junit != "-")
        std::fprintf(text, "afb golden compare: JUnit report -> %s\n", opt.junit.c_str());
    if (!opt.report.empty())
        std::fprintf(text, "afb golden compare: report -> %s (%zu pictures)\n", (opt.report / "summary.md").c_str(),
                     pictures);
    return exitCode;
}

void addGoldenCompareOptions(CLI::App* compare, GoldenCompareCli& cmp) {
    compare->add_option("files", cmp.files, "Golden files")->required();
    compare->add_flag("--exact", cmp.exact, "Also demand the bit-exact state hash (same build, same machine class)");
    compare->add_flag("--ignore-inputs", cmp.ignoreInputs,
                      "Compare poses even when input files changed since recording (they are still listed)");
    compare->add_option("--junit", cmp.junit,
                        "Write a JUnit XML report (one test case per golden; '-': stdout, which then holds only it)");
    compare->add_option("--report", cmp.report,
                        "Write DIR/summary.md and, per failing golden, DIR/NAME.png: the settled pose (orange) over "
                        "the golden pose (blue)");
}

nlohmann::json goldenInputs(const std::filesystem::path& file, const std::filesystem::path& base) {
    const std::filesystem::path root = std::filesystem::absolute(base);
    const auto rel = [&](const std::filesystem::path& p) {
        return std::filesystem::relative(std::filesystem::absolute(p), root).generic_string();
    };
    nlohmann::json inputs = nlohmann::json::object();
    inputs[rel(file)] = fileHash(file);
    text::Diagnostics diags;
    const auto data = text::readFile(file, diags);
    const nlohmann::json g = data ? nlohmann::json::parse(*data, nullptr, false) : nlohmann::json();
    if (!g.is_object() || !g.contains("base") || !g.at("base").is_string() || !g.contains("inputs") ||
        !g.at("inputs").is_object())
        return inputs;
    const std::filesystem::path goldenBase =
        std::filesystem::absolute(file).parent_path() / g.at("base").get<std::string>();
    for (const auto& [path, hash] : g.at("inputs").items())
        inputs[rel(goldenBase / path)] = fileHash(goldenBase / path);
    return inputs;
}

namespace {

void addCompareCommand(CLI::App* golden, int& exitCode) {
    auto cmp = std::make_shared<GoldenCompareCli>();
    auto* compare = golden->add_subcommand("compare", "Re-run golden scenarios; exit 1 when a joint moved past its "
                                                      "tolerance or an input changed\n"
                                                      "Examples:\n  afb golden compare tests/golden/*.json\n"
                                                      "  afb golden compare --junit goldens.xml --report golden-report "
                                                      "tests/golden/*.json");
    addGoldenCompareOptions(compare, *cmp);
    compare->callback([cmp, &exitCode] {
        if (!cmp->report.empty()) {
            std::error_code ec;
            std::filesystem::create_directories(cmp->report, ec);
            if (ec) {
                std::cerr << "afb golden compare: --report " << cmp->report.string() << ": " << ec.message() << "\n";
                exitCode = kExitFailure;
                return;
            }
        }
        std::vector<GoldenCase> cases;
        std::vector<std::filesystem::path> pictures;
        for (const std::filesystem::path& file : cmp->files) {
            cases.push_back(compareGolden(file, *cmp, pictures));
            printGoldenCase(cases.back(), goldenTextStream(*cmp));
        }
        exitCode = finishGoldenCompare(*cmp, cases, pictures.size());
    });
}

} // namespace

void addGoldenCommand(CLI::App& app, int& exitCode) {
    auto* golden = app.add_subcommand("golden", "Record and compare settled poses of drop scenarios\n"
                                                "Examples:\n  afb golden record --base . chain --out chain.json\n"
                                                "  afb golden compare --junit goldens.xml chain.json");
    golden->require_subcommand(1);
    addRecordCommand(golden, exitCode);
    addCompareCommand(golden, exitCode);
}

} // namespace afb::cli
