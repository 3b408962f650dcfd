// afb stress: the scenario × method matrix of where ragdolls fail (sim/Stress.h), as a terminal table, stress.md,
// stress.json and a heat map drawn by gnuplot.
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>

#include <unistd.h>

#include "ChartPlot.h"
#include "Commands.h"
#include "MethodOptions.h"
#include "StressCli.h"
#include "Suggest.h"
#include "Usage.h"
#include "afb/figure/Load.h"
#include "afb/sim/Stress.h"

namespace afb::cli {
namespace {

std::string gpQuoted(const std::string& s) {
    std::string out = "\"";
    for (char c : s) {
        if (c == '"' || c == '\\') out += '\\';
        out += c;
    }
    return out + "\"";
}

// stress.dat (one row per cell: method column, scenario row, the fraction of its runs that passed or -1 when
// skipped, label) and stress.gp, which renders stress.png: green cells pass at every yaw, red cells at none (shades
// between), grey cells were skipped; the cell's table text (sim::stressCellText) is written in it.
std::string writeHeatMap(const std::filesystem::path& dir, const std::vector<sim::StressResult>& results,
                         const std::vector<sim::StressMethod>& methods, const std::vector<std::string>& scenarios) {
    std::ostringstream data, gp;
    const int rows = static_cast<int>(scenarios.size()), cols = static_cast<int>(methods.size());
    const std::vector<sim::StressCell> cells = sim::stressCells(results);
    const int yaws = cells.empty() ? 1 : cells.front().total;
    for (const sim::StressCell& c : cells) {
        int col = 0, row = 0;
        for (int m = 0; m < cols; ++m)
            if (methods[static_cast<std::size_t>(m)].label == c.method) col = m;
        for (int s = 0; s < rows; ++s)
            if (scenarios[static_cast<std::size_t>(s)] == c.scenario) row = rows - 1 - s; // first scenario on top
        const double value = c.skipped() ? -1.0 : static_cast<double>(c.passed) / static_cast<double>(c.total);
        data << col << "\t" << row << "\t" << value << "\t" << gpQuoted(sim::stressCellText(c, results)) << "\n";
    }
    // Skipped (-1) is a grey step below the red-to-green scale of the fraction passed (a repeated gray value
    // makes the palette discontinuous there).
    // At least 720 px wide, so the title (centred over the cells) fits over one or two columns.
    gp << "set terminal pngcairo size " << std::max(720, 260 + (yaws > 1 ? 190 : 130) * cols) << "," << 120 + 30 * rows
       << " font \"DejaVu Sans,10\" noenhanced\nset output \"stress.png\"\n"
       << "set title \""
       << (yaws > 1 ? "afb stress: runs passed of " + std::to_string(yaws) + " yaws (green: all rest within the limits)"
                    : std::string("afb stress: first failure per scenario and method (green: rests within the limits)"))
       << "\"\nunset colorbox\nset cbrange [-1:1]\n"
       << "set palette defined (-1 \"#cccccc\", -0.001 \"#cccccc\", 0 \"#e41a1c\", 0.5 \"#fdae61\", 1 \"#4daf4a\")\n"
       << "set xrange [-0.5:" << cols - 0.5 << "]\nset yrange [-0.5:" << rows - 0.5 << "]\nset x2tics (";
    for (int m = 0; m < cols; ++m)
        gp << (m ? ", " : "") << gpQuoted(methods[static_cast<std::size_t>(m)].label) << " " << m;
    gp << ")\nset x2range [-0.5:" << cols - 0.5 << "]\nset ytics (";
    for (int s = 0; s < rows; ++s)
        gp << (s ? ", " : "") << gpQuoted(scenarios[static_cast<std::size_t>(s)]) << " " << rows - 1 - s;
    gp << ")\nset tics scale 0\nunset xtics\nset lmargin 24\n"
       // Filled boxes, not `with image`: an image needs a grid of at least 2 x 2 cells and draws nothing for one
       // method or one scenario.
       << "plot \"stress.dat\" using 1:2:(0.5):(0.5):3 with boxxyerror fillstyle solid noborder lc palette notitle, "
          "\"stress.dat\" using 1:2:4 with labels notitle\n"
       << "set output\n";
    std::ofstream dataFile(dir / "stress.dat");
    dataFile << data.str();
    std::ofstream scriptFile(dir / "stress.gp");
    scriptFile << gp.str();
    if (!dataFile || !scriptFile) return "cannot write " + (dir / "stress.gp").string();
    return {};
}

// A yaw in degrees as the tables write it ("22.5").
std::string fixedYaw(double deg) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.1f", deg);
    return buf;
}

} // namespace

void addStressOptions(CLI::App* cmd, StressCli& opt) {
    cmd->add_option("--base", opt.base, "Content folder with the humanoid (af/, def/, models/)")->capture_default_str();
    cmd->add_option(
           "--methods", opt.methods,
           "Methods, comma-separated: NAME[:KNOB=VALUE]... as afb chart, then mitigations +stabilize, +clamp, +rest")
        ->delimiter(',')
        ->capture_default_str();
    cmd->add_option("--scenarios", opt.scenarios, "Scenarios, comma-separated (default: all; --list names them)")
        ->delimiter(',');
    cmd->add_flag("--ci", opt.ci, "Only the scenarios CI runs as unit tests");
    cmd->add_flag("--list", opt.list, "List the scenarios and exit");
    cmd->add_option("--out", opt.out, "Output folder (created)")->capture_default_str();
    cmd->add_option("--threads", opt.threads, "Worker threads (each run owns its world)")
        ->check(CLI::Range(1, 256))
        ->capture_default_str();
    cmd->add_option("--yaws", opt.yaws,
                    "run each scenario at N orientations about the vertical (yaw k·360°/N); a cell reports how many "
                    "passed")
        ->check(CLI::Range(1, 64))
        ->capture_default_str();
    cmd->add_option("--precision", opt.precision, "Bullet build: float or double (default: this binary's)")
        ->check(CLI::IsMember({"float", "double"}));
}

std::vector<sim::StressMethod> parseStressMethods(const std::vector<std::string>& specs) {
    std::vector<sim::StressMethod> methods;
    for (const std::string& spec : specs) {
        std::string error;
        auto m = sim::parseStressMethod(spec, error);
        if (!m) usageError(error + methodSpecHint(spec));
        for (const sim::StressMethod& other : methods)
            if (other.label == m->label) usageError("method " + spec + " is listed twice");
        methods.push_back(std::move(*m));
    }
    return methods;
}

std::vector<const sim::StressScenario*> pickStressScenarios(const StressCli& opt) {
    std::vector<std::string> names = opt.scenarios;
    if (opt.ci)
        for (std::string_view n : sim::stressCiScenarios()) names.emplace_back(n);
    std::vector<std::string> all;
    for (const sim::StressScenario& s : sim::stressScenarios()) all.push_back(s.name);
    if (names.empty()) names = all;
    std::vector<const sim::StressScenario*> scenarios;
    for (const std::string& n : names) {
        const sim::StressScenario* s = sim::findStressScenario(n);
        if (!s) usageError(unknownName("scenario", n, all) + " (afb stress --list describes them)");
        if (std::find(scenarios.begin(), scenarios.end(), s) == scenarios.end()) scenarios.push_back(s);
    }
    return scenarios;
}

sim::StressContent loadStressContent(const StressCli& opt, const std::vector<const sim::StressScenario*>& scenarios) {
    sim::StressContent content;
    bool needsHumanoid = false;
    for (const sim::StressScenario* s : scenarios) needsHumanoid = needsHumanoid || s->needsHumanoid;
    if (!needsHumanoid) return content;
    text::Diagnostics diags;
    if (auto lib = decl::Library::open(opt.base, diags))
        if (auto loaded = figure::loadEntityFigure(*lib, "humanoid", {}, diags))
            content.humanoid = std::move(loaded->figure);
    if (!content.humanoid) {
        printDiagnostics(diags);
        std::cerr << "afb stress: warning: no humanoid in " << opt.base.string()
                  << ": its scenarios are skipped (--base)\n";
    }
    return content;
}

namespace {

// Each failing cell with its first failing run (the lowest yaw), then the count; every run is in stress.md.
void printFailures(const std::vector<sim::StressResult>& results, int yaws) {
    const std::vector<sim::StressCell> cells = sim::stressCells(results);
    int failedCells = 0, failedRuns = 0;
    for (const sim::StressCell& c : cells) {
        if (c.skipped() || !c.firstFailure) continue;
        ++failedCells;
        failedRuns += c.total - c.passed;
        const sim::StressResult& r = results[*c.firstFailure];
        const std::string yaw = yaws == 1 ? std::string() : " (first at yaw " + fixedYaw(r.yawDeg) + "°)";
        std::printf("  %s / %s%s: %s at %.3f s: %s\n", r.scenario.c_str(), r.method.c_str(), yaw.c_str(),
                    std::string(sim::toString(r.cause)).c_str(), r.failedAtS.value_or(0), r.detail.c_str());
    }
    if (yaws == 1) std::printf("%d of %zu cells failed\n", failedCells, cells.size());
    else
        std::printf("%d of %zu cells failed at one yaw or more (%d of %zu runs)\n", failedCells, cells.size(),
                    failedRuns, results.size());
}

int stressCommand(const StressCli& opt) {
    const std::vector<sim::StressMethod> methods = parseStressMethods(opt.methods);
    const std::vector<const sim::StressScenario*> scenarios = pickStressScenarios(opt);
    if (methods.empty() || scenarios.empty()) usageError("no methods or no scenarios");
    const sim::StressContent content = loadStressContent(opt, scenarios);
    std::error_code ec;
    std::filesystem::create_directories(opt.out, ec);
    if (ec) {
        std::cerr << "afb stress: cannot create " << opt.out.string() << ": " << ec.message() << "\n";
        return kExitFailure;
    }
    std::printf("afb stress: Bullet %s (%s), %zu scenarios x %zu methods x %d yaw%s on %d threads into %s\n",
                sim::bulletVersion().c_str(), sim::bulletPrecision(), scenarios.size(), methods.size(), opt.yaws,
                opt.yaws == 1 ? "" : "s", opt.threads, opt.out.string().c_str());
    std::fflush(stdout);
    const bool tty = ::isatty(STDERR_FILENO) != 0;
    const std::vector<sim::StressResult> results =
        sim::runStressMatrix(scenarios, methods, content, {}, opt.threads, opt.yaws, [&](int done, int total) {
            if (!tty) return;
            std::fprintf(stderr, "\r  %d/%d runs%s", done, total, done == total ? "\n" : "");
            std::fflush(stderr);
        });
    writeStressOutputs(opt.out, results, methods, scenarios, opt.yaws);
    return 0;
}

} // namespace

void addStressCommand(CLI::App& app, int& exitCode, char** argv) {
    auto* cmd = app.add_subcommand("stress", "Where methods fail: stress scenarios x methods, first failure per cell\n"
                                             "Examples:\n  afb stress --list\n"
                                             "  afb stress --base . --ci --methods fast,default --out stress");
    cmd->footer("Writes into --out: stress.md (thresholds, the matrix, every failure and the worst values), "
                "stress.json (the same, with every knob), stress.png (gnuplot heat map; stress.gp and stress.dat "
                "redraw it). Exit code 0 even when cells fail (2 on bad arguments).\n"
                "Scenarios that use the bundled humanoid need --base (the repository root, or any content folder "
                "with entity 'humanoid'); without it they are skipped.");
    auto opt = std::make_shared<StressCli>();
    addStressOptions(cmd, *opt);
    cmd->callback([opt, &exitCode, argv] {
        if (opt->list) {
            for (const sim::StressScenario& s : sim::stressScenarios())
                std::printf("%-26s %s\n", s.name.c_str(), s.description.c_str());
            return;
        }
        if (!opt->precision.empty() && opt->precision != sim::bulletPrecision()) {
            execOtherPrecision(opt->precision, argv, "afb stress");
            exitCode = kExitFailure;
            return;
        }
        exitCode = stressCommand(*opt);
    });
}

void writeStressOutputs(const std::filesystem::path& out, const std::vector<sim::StressResult>& results,
                        const std::vector<sim::StressMethod>& methods,
                        const std::vector<const sim::StressScenario*>& scenarios, int yaws) {
    const sim::StressThresholds thresholds;
    std::ofstream(out / "stress.md") << sim::stressMarkdown(results, methods, thresholds);
    std::ofstream(out / "stress.json") << sim::stressJson(results, methods, thresholds);
    std::vector<std::string> scenarioNames;
    for (const sim::StressScenario* s : scenarios) scenarioNames.push_back(s->name);
    std::string plotError = writeHeatMap(out, results, methods, scenarioNames);
    if (plotError.empty()) plotError = runGnuplot(out, "stress.gp");
    std::printf("\n%s", sim::stressTable(results, methods).c_str());
    printFailures(results, yaws);
    if (!plotError.empty()) std::cerr << "afb stress: warning: no stress.png: " << plotError << "\n";
    std::printf("wrote %s/{stress.md,stress.json,stress.gp,stress.dat%s}\n", out.string().c_str(),
                plotError.empty() ? ",stress.png" : "");
}

} // namespace afb::cli
