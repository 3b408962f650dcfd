// afb drop as a batch: one manifest line per entity (each entity's drop is one world, or worlds split as
// --worlds says), reported by the same table and reports as the one-process command.
#include <iostream>
#include <stdexcept>

#include "Batch.h"
#include "Commands.h"
#include "DropCli.h"
#include "Usage.h"
#include "afb/sim/Batch.h"
#include "afb/sim/Report.h"

namespace afb::cli {
namespace {

using nlohmann::json;

// Everything afb drop's output depends on; the method as its knobs (exact).
json dropPlanJson(const DropCli& opt) {
    const sim::DropOptions& d = opt.drop;
    return {{"base", opt.base.generic_string()},
            {"entities", opt.entities},
            {"height_m", d.heightM},
            {"count", d.count},
            {"threads", d.threads},
            {"worlds", opt.worlds ? json(*opt.worlds) : json(nullptr)},
            {"seed", opt.seed ? json(*opt.seed) : json(nullptr)},
            {"lod", d.lod ? json(*d.lod) : json(nullptr)},
            {"motors", d.motors ? json({d.motors->frequencyHz, d.motors->dampingRatio}) : json(nullptr)},
            {"seconds", d.seconds},
            {"steps", opt.steps ? json(*opt.steps) : json(nullptr)},
            {"hz", d.hz},
            {"method", sim::methodJson(d.method)},
            {"gravity", opt.gravity},
            {"flags", {opt.doomGravity, opt.noSleep, opt.strict, opt.verbose, d.stopAtRest}},
            {"json", opt.json},
            {"csv", opt.csv}};
}

// The options of a plan, resolved as afb drop resolves its command line.
DropCli dropCliFromPlan(const json& plan, figure::UnitSystem& units) {
    DropCli opt;
    opt.base = plan.at("base").get<std::string>();
    opt.entities = plan.at("entities").get<std::vector<std::string>>();
    opt.drop.heightM = plan.at("height_m").get<double>();
    opt.drop.count = plan.at("count").get<int>();
    opt.drop.threads = plan.at("threads").get<int>();
    if (!plan.at("worlds").is_null()) opt.worlds = plan.at("worlds").get<int>();
    if (!plan.at("seed").is_null()) opt.seed = plan.at("seed").get<std::uint32_t>();
    if (!plan.at("lod").is_null()) opt.drop.lod = plan.at("lod").get<int>();
    if (const json motors = plan.value("motors", json(nullptr)); !motors.is_null())
        opt.drop.motors = bullet::MotorGains{motors.at(0).get<double>(), motors.at(1).get<double>()};
    opt.drop.seconds = plan.at("seconds").get<double>();
    if (!plan.at("steps").is_null()) opt.steps = plan.at("steps").get<int>();
    opt.drop.hz = plan.at("hz").get<double>();
    opt.gravity = plan.at("gravity").get<double>();
    const json& flags = plan.at("flags");
    opt.doomGravity = flags.at(0).get<bool>();
    opt.noSleep = flags.at(1).get<bool>();
    opt.strict = flags.at(2).get<bool>();
    opt.verbose = flags.at(3).get<bool>();
    opt.drop.stopAtRest = flags.at(4).get<bool>();
    opt.json = plan.at("json").get<std::string>();
    opt.csv = plan.at("csv").get<std::string>();
    bullet::Method method;
    if (std::string e = sim::methodFromJson(plan.at("method"), method); !e.empty()) throw std::runtime_error(e);
    units = resolveDropOptions(opt, method);
    return opt;
}

class DropJob : public BatchJob {
  public:
    DropJob(const json& plan, bool forRunning) : m_opt(dropCliFromPlan(plan, m_units)) {
        if (!forRunning) return;
        text::Diagnostics diags;
        auto figures = loadDropFigures(m_opt, m_units, diags);
        printDiagnostics(diags);
        if (!figures) throw std::runtime_error("cannot load the planned entities from " + m_opt.base.string());
        m_figures = std::move(*figures);
    }

    json runOne(const json& run) const override {
        const auto i = run.at("entity_index").get<std::size_t>();
        if (i >= m_figures.size() || run.at("entity").get<std::string>() != m_opt.entities[i])
            throw std::runtime_error("not a run of this plan: " + run.dump());
        return sim::dropResultExact(dropOne(m_opt, m_figures[i]));
    }

    int merge(const std::vector<std::string_view>& results, const std::filesystem::path& out) override {
        std::vector<sim::DropResult> drops;
        for (const std::string_view r : results) drops.push_back(sim::dropResultFromExact(json::parse(r)));
        if (drops.size() != m_opt.entities.size()) throw std::runtime_error("the results are not the plan's runs");
        DropCli opt = m_opt;
        if (!out.empty()) {
            std::error_code ec;
            std::filesystem::create_directories(out, ec);
            if (ec) {
                std::cerr << "afb merge: cannot create " << out.string() << ": " << ec.message() << "\n";
                return kExitFailure;
            }
            opt.json = (out / "drop.json").string();
            opt.csv = (out / "drop.csv").string();
        }
        printDropHeader(opt, m_units);
        return reportDrops(opt, drops, {}, m_units.gravityMps2);
    }

  private:
    figure::UnitSystem m_units;
    DropCli m_opt;
    std::vector<figure::LoadedFigure> m_figures;
};

int planDrop(DropCli& opt, const bullet::Method& method, const PlanEmitter& emit) {
    const figure::UnitSystem units = resolveDropOptions(opt, method);
    text::Diagnostics diags;
    auto figures = loadDropFigures(opt, units, diags);
    auto lib = figures ? decl::Library::open(opt.base, diags) : std::nullopt;
    PlanOutput out{"drop", {dropPlanJson(opt), {}, {}}};
    bool ok = lib.has_value();
    for (std::size_t i = 0; ok && i < opt.entities.size(); ++i) {
        json inputs = json::object();
        ok = addEntityInputs(*lib, opt.entities[i], opt.base, inputs, diags);
        out.lines.inputSets.push_back(std::move(inputs));
        out.lines.runs.emplace_back(i, json{{"entity", opt.entities[i]}, {"entity_index", i}});
    }
    printDiagnostics(diags);
    if (!ok) return kExitFailure;
    return emit(out);
}

} // namespace

std::unique_ptr<BatchJob> makeDropJob(const json& plan, bool forRunning, std::string& error) {
    try {
        return std::make_unique<DropJob>(plan, forRunning);
    } catch (const std::exception& e) {
        error = std::string("drop plan: ") + e.what();
    }
    return nullptr;
}

void addPlanDrop(CLI::App* plan, int& exitCode, char** argv, const std::shared_ptr<std::string>& manifest,
                 const PlanEmitter& emit) {
    auto* cmd =
        plan->add_subcommand("drop", "Plan afb drop: one line per entity\n"
                                     "Examples:\n"
                                     "  afb plan drop --base . humanoid lamp --height 10 --manifest runs.jsonl");
    auto opt = std::make_shared<DropCli>();
    addDropOptions(cmd, *opt);
    cmd->add_option("--manifest", *manifest, "Manifest to write, JSON lines ('-': stdout)")->capture_default_str();
    cmd->callback([opt, &exitCode, argv, emit] {
        const bullet::Method method = resolveMethod(*opt->method);
        checkDropOptions(*opt, method);
        if (!opt->gltf.empty()) usageError("--gltf records one drop in one process: use afb drop");
        if (!opt->precision.empty() && opt->precision != sim::bulletPrecision()) {
            execOtherPrecision(opt->precision, argv, "afb plan drop");
            exitCode = kExitFailure;
            return;
        }
        exitCode = planDrop(*opt, method, emit);
    });
}

} // namespace afb::cli
