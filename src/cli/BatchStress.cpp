// afb stress as a batch: one manifest line per (scenario, method, yaw), in runStressMatrix's order, so the merged
// results are the matrix the one-process command runs and are written by the same writeStressOutputs.
#include <iostream>
#include <stdexcept>

#include "Batch.h"
#include "Commands.h"
#include "StressCli.h"
#include "Usage.h"
#include "afb/sim/Batch.h"

namespace afb::cli {
namespace {

using nlohmann::json;

json stressPlanJson(const StressCli& opt, const std::vector<const sim::StressScenario*>& scenarios, bool humanoid) {
    json names = json::array();
    for (const sim::StressScenario* s : scenarios) names.push_back(s->name);
    return {{"base", opt.base.generic_string()},
            {"methods", opt.methods},
            {"scenarios", names},
            {"yaws", opt.yaws},
            {"threads", opt.threads},
            {"out", opt.out.generic_string()},
            {"humanoid", humanoid}};
}

StressCli stressCliFromPlan(const json& plan) {
    StressCli opt;
    opt.base = plan.at("base").get<std::string>();
    opt.methods = plan.at("methods").get<std::vector<std::string>>();
    opt.scenarios = plan.at("scenarios").get<std::vector<std::string>>();
    opt.yaws = plan.at("yaws").get<int>();
    opt.threads = plan.at("threads").get<int>();
    opt.out = plan.at("out").get<std::string>();
    if (opt.yaws < 1 || opt.methods.empty() || opt.scenarios.empty())
        throw std::runtime_error("a stress plan needs methods, scenarios and a yaw count of 1 or more");
    return opt;
}

class StressJob : public BatchJob {
  public:
    StressJob(const json& plan, bool forRunning) : m_opt(stressCliFromPlan(plan)) {
        m_methods = parseStressMethods(m_opt.methods);
        m_scenarios = pickStressScenarios(m_opt);
        if (forRunning && plan.at("humanoid").get<bool>()) {
            m_content = loadStressContent(m_opt, m_scenarios);
            if (!m_content.humanoid) throw std::runtime_error("no humanoid in " + m_opt.base.string());
        }
    }

    json runOne(const json& run) const override {
        const sim::StressScenario* scenario = sim::findStressScenario(run.at("scenario").get<std::string>());
        const std::string label = run.at("method").get<std::string>();
        const sim::StressMethod* method = nullptr;
        for (const sim::StressMethod& m : m_methods)
            if (m.label == label) method = &m;
        const auto k = run.at("yaw").get<std::size_t>();
        if (!scenario || !method || k >= static_cast<std::size_t>(m_opt.yaws))
            throw std::runtime_error("not a run of this plan: " + run.dump());
        const double yawDeg = sim::stressYawDeg(k, static_cast<std::size_t>(m_opt.yaws));
        const std::optional<sim::StressSetup> built = scenario->build(m_content);
        const std::optional<sim::StressSetup> yawed =
            built ? std::optional(sim::yawedSetup(*built, yawDeg)) : std::nullopt;
        return sim::stressResultExact(sim::runStressRun(yawed, scenario->name, *method, {}, yawDeg));
    }

    int merge(const std::vector<std::string_view>& results, const std::filesystem::path& out) override {
        std::vector<sim::StressResult> runs;
        for (const std::string_view r : results) runs.push_back(sim::stressResultFromExact(json::parse(r)));
        const std::filesystem::path dir = out.empty() ? m_opt.out : out;
        std::error_code ec;
        std::filesystem::create_directories(dir, ec);
        if (ec) {
            std::cerr << "afb merge: cannot create " << dir.string() << ": " << ec.message() << "\n";
            return kExitFailure;
        }
        std::printf("afb stress: Bullet %s (%s), %zu scenarios x %zu methods x %d yaw%s, merged into %s\n",
                    sim::bulletVersion().c_str(), sim::bulletPrecision(), m_scenarios.size(), m_methods.size(),
                    m_opt.yaws, m_opt.yaws == 1 ? "" : "s", dir.string().c_str());
        writeStressOutputs(dir, runs, m_methods, m_scenarios, m_opt.yaws);
        return 0;
    }

  private:
    StressCli m_opt;
    std::vector<sim::StressMethod> m_methods;
    std::vector<const sim::StressScenario*> m_scenarios;
    sim::StressContent m_content;
};

// The plan of `afb plan stress`: the options, the humanoid's input files when a scenario needs it, one run per
// (scenario, method, yaw).
int planStress(const StressCli& opt, const PlanEmitter& emit) {
    const std::vector<sim::StressMethod> methods = parseStressMethods(opt.methods);
    const std::vector<const sim::StressScenario*> scenarios = pickStressScenarios(opt);
    if (methods.empty() || scenarios.empty()) usageError("no methods or no scenarios");
    bool needsHumanoid = false;
    for (const sim::StressScenario* s : scenarios) needsHumanoid = needsHumanoid || s->needsHumanoid;
    PlanOutput out{"stress", {}};
    json inputs = json::object();
    bool humanoid = false;
    if (needsHumanoid) {
        humanoid = loadStressContent(opt, scenarios).humanoid.has_value();
        text::Diagnostics diags;
        if (auto lib = humanoid ? decl::Library::open(opt.base, diags) : std::nullopt)
            humanoid = addEntityInputs(*lib, "humanoid", opt.base, inputs, diags);
    }
    out.lines.plan = stressPlanJson(opt, scenarios, humanoid);
    out.lines.inputSets.push_back(inputs);
    for (const sim::StressScenario* s : scenarios)
        for (const sim::StressMethod& m : methods)
            for (int k = 0; k < opt.yaws; ++k)
                out.lines.runs.emplace_back(0,
                                            json{{"scenario", s->name},
                                                 {"method", m.label},
                                                 {"yaw", k},
                                                 {"yaw_deg", sim::stressYawDeg(static_cast<std::size_t>(k),
                                                                               static_cast<std::size_t>(opt.yaws))}});
    return emit(out);
}

} // namespace

std::unique_ptr<BatchJob> makeStressJob(const json& plan, bool forRunning, std::string& error) {
    try {
        return std::make_unique<StressJob>(plan, forRunning);
    } catch (const std::exception& e) {
        error = std::string("stress plan: ") + e.what();
    }
    return nullptr;
}

void addPlanStress(CLI::App* plan, int& exitCode, char** argv, const std::shared_ptr<std::string>& manifest,
                   const PlanEmitter& emit) {
    auto* cmd =
        plan->add_subcommand("stress",
                             "Plan afb stress: one line per scenario, method and yaw\n"
                             "Examples:\n"
                             "  afb plan stress --base . --yaws 8 --manifest runs.jsonl\n"
                             "  afb plan stress --base . --methods fast,default --scenarios chain-mass-1 --manifest -");
    auto opt = std::make_shared<StressCli>();
    addStressOptions(cmd, *opt);
    cmd->add_option("--manifest", *manifest, "Manifest to write, JSON lines ('-': stdout)")->capture_default_str();
    cmd->callback([opt, &exitCode, argv, emit] {
        if (!opt->precision.empty() && opt->precision != sim::bulletPrecision()) {
            execOtherPrecision(opt->precision, argv, "afb plan stress");
            exitCode = kExitFailure;
            return;
        }
        if (opt->list) usageError("--list has nothing to plan (afb stress --list)");
        exitCode = planStress(*opt, emit);
    });
}

} // namespace afb::cli
