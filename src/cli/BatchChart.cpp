// afb chart as a batch: one manifest line per (figure, method, height, rate, repeat), in runChart's order, so the
// merged runs are the chart the one-process command runs and are written by the same writeChartOutputs.
#include <iostream>
#include <stdexcept>

#include "Batch.h"
#include "ChartCli.h"
#include "Commands.h"
#include "Usage.h"
#include "afb/sim/Batch.h"

namespace afb::cli {
namespace {

using nlohmann::json;

json optionalJson(const std::optional<double>& v) { return v ? json(*v) : json(nullptr); }
std::optional<double> optionalFrom(const json& v) {
    if (v.is_null()) return std::nullopt;
    return v.get<double>();
}

json chartPlanJson(const ChartCli& opt, const std::vector<std::string>& names) {
    const sim::ChartOptions& c = opt.chart;
    return {{"base", opt.base.generic_string()},
            {"entities", opt.entities},
            {"figures", names},
            {"methods", opt.methods},
            {"heights_m", c.heightsM},
            {"hz", c.hz},
            {"repeats", c.repeats},
            {"count", c.count},
            {"seconds", c.seconds},
            {"threads", c.threads},
            {"no_sleep", opt.noSleep},
            {"out", opt.out.generic_string()},
            {"max",
             {optionalJson(opt.maxAnchor), optionalJson(opt.maxLimit), optionalJson(opt.maxPenetration),
              optionalJson(opt.maxSettle)}}};
}

ChartCli chartCliFromPlan(const json& plan) {
    ChartCli opt;
    opt.base = plan.at("base").get<std::string>();
    opt.entities = plan.at("entities").get<std::vector<std::string>>();
    opt.methods = plan.at("methods").get<std::vector<std::string>>();
    opt.chart.heightsM = plan.at("heights_m").get<std::vector<double>>();
    opt.chart.hz = plan.at("hz").get<std::vector<double>>();
    opt.chart.repeats = plan.at("repeats").get<int>();
    opt.chart.count = plan.at("count").get<int>();
    opt.chart.seconds = plan.at("seconds").get<double>();
    opt.chart.threads = plan.at("threads").get<int>();
    opt.noSleep = plan.at("no_sleep").get<bool>();
    opt.out = plan.at("out").get<std::string>();
    const json& max = plan.at("max");
    opt.maxAnchor = optionalFrom(max.at(0));
    opt.maxLimit = optionalFrom(max.at(1));
    opt.maxPenetration = optionalFrom(max.at(2));
    opt.maxSettle = optionalFrom(max.at(3));
    resolveChartOptions(opt);
    return opt;
}

class ChartJob : public BatchJob {
  public:
    ChartJob(const json& plan, bool forRunning) : m_opt(chartCliFromPlan(plan)) {
        m_names = plan.at("figures").get<std::vector<std::string>>();
        if (m_names.size() != m_opt.entities.size()) throw std::runtime_error("one figure name per entity");
        std::vector<std::string> loadedNames;
        if (forRunning && (!loadChartFigures(m_opt, m_figures, loadedNames) || loadedNames != m_names))
            throw std::runtime_error("the figures of " + m_opt.base.string() + " are not the planned ones");
    }

    json runOne(const json& run) const override {
        sim::ChartRun r{run.at("method").get<std::string>(), run.at("figure").get<std::size_t>(),
                        run.at("height_m").get<double>(),    run.at("hz").get<double>(),
                        run.at("repeat").get<int>(),         {}};
        const sim::ChartMethod* method = nullptr;
        for (const sim::ChartMethod& m : m_opt.chart.methods)
            if (m.label == r.label) method = &m;
        if (!method || r.figure >= m_figures.size()) throw std::runtime_error("not a run of this plan: " + run.dump());
        sim::DropResult result =
            sim::runDrop(m_figures[r.figure], sim::chartDropOptions(m_opt.chart, r, method->method));
        // A chart reports no pose: the result file keeps the numbers it writes. The method is the plan's (the
        // merge puts it back): a result file holds the measurements, not the method's every knob again.
        result.finalPose.clear();
        result.firstBodies.clear();
        json exact = sim::dropResultExact(result);
        exact.erase("method");
        return exact;
    }

    int merge(const std::vector<std::string_view>& results, const std::filesystem::path& out) override {
        std::vector<sim::ChartRun> runs = sim::chartRuns(m_names.size(), m_opt.chart);
        if (runs.size() != results.size()) throw std::runtime_error("the results are not the plan's runs");
        std::map<std::string, const bullet::Method*> methods;
        for (const sim::ChartMethod& m : m_opt.chart.methods) methods.emplace(m.label, &m.method);
        sim::forEachIndex(runs.size(), [&](std::size_t i) {
            runs[i].result = sim::dropResultFromExact(json::parse(results[i]));
            runs[i].result.method = *methods.at(runs[i].label);
        });
        ChartCli opt = m_opt;
        if (!out.empty()) opt.out = out;
        std::error_code ec;
        std::filesystem::create_directories(opt.out, ec);
        if (ec) {
            std::cerr << "afb merge: cannot create " << opt.out.string() << ": " << ec.message() << "\n";
            return kExitFailure;
        }
        std::printf("afb chart: Bullet %s (%s), %zu runs merged into %s\n", sim::bulletVersion().c_str(),
                    sim::bulletPrecision(), runs.size(), opt.out.string().c_str());
        writeChartOutputs(opt, runs, m_names);
        return 0;
    }

  private:
    ChartCli m_opt;
    std::vector<std::string> m_names;
    std::vector<figure::Figure> m_figures;
};

int planChart(ChartCli& opt, const PlanEmitter& emit) {
    resolveChartOptions(opt);
    std::vector<figure::Figure> figures;
    std::vector<std::string> names;
    if (!loadChartFigures(opt, figures, names)) return kExitFailure;
    PlanOutput out{"chart", {chartPlanJson(opt, names), {}, {}}};
    text::Diagnostics diags;
    auto lib = decl::Library::open(opt.base, diags);
    for (const std::string& e : opt.entities) {
        json inputs = json::object();
        if (!lib || !addEntityInputs(*lib, e, opt.base, inputs, diags)) {
            printDiagnostics(diags);
            return kExitFailure;
        }
        out.lines.inputSets.push_back(std::move(inputs));
    }
    for (const sim::ChartRun& r : sim::chartRuns(figures.size(), opt.chart))
        out.lines.runs.emplace_back(r.figure, json{{"entity", opt.entities[r.figure]},
                                                   {"figure", r.figure},
                                                   {"method", r.label},
                                                   {"height_m", r.heightM},
                                                   {"hz", r.hz},
                                                   {"repeat", r.repeat}});
    return emit(out);
}

} // namespace

std::unique_ptr<BatchJob> makeChartJob(const json& plan, bool forRunning, std::string& error) {
    try {
        return std::make_unique<ChartJob>(plan, forRunning);
    } catch (const std::exception& e) {
        error = std::string("chart plan: ") + e.what();
    }
    return nullptr;
}

void addPlanChart(CLI::App* plan, int& exitCode, char** argv, const std::shared_ptr<std::string>& manifest,
                  const PlanEmitter& emit) {
    auto* cmd = plan->add_subcommand("chart", "Plan afb chart: one line per figure, method, height, rate and repeat\n"
                                              "Examples:\n"
                                              "  afb plan chart --base . humanoid --repeats 5 --manifest runs.jsonl");
    auto opt = std::make_shared<ChartCli>();
    addChartOptions(cmd, *opt);
    cmd->add_option("--manifest", *manifest, "Manifest to write, JSON lines ('-': stdout)")->capture_default_str();
    cmd->callback([opt, &exitCode, argv, emit] {
        if (!opt->precision.empty() && opt->precision != sim::bulletPrecision()) {
            execOtherPrecision(opt->precision, argv, "afb plan chart");
            exitCode = kExitFailure;
            return;
        }
        exitCode = planChart(*opt, emit);
    });
}

} // namespace afb::cli
