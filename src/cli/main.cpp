// afb: the afbullet command-line tool.
#include <string>

#include <LinearMath/btScalar.h>

#include "Commands.h"
#include "Usage.h"
#include "afb/Version.h"

#ifndef AFB_BUILD_TYPE
#define AFB_BUILD_TYPE ""
#endif

namespace {

/// `afb 0.1.0 (Bullet 3.24, float, Release)`: this binary's version, the Bullet it runs on and its precision (both
/// as compiled in: btGetVersion() is inline), and the build type it was configured with.
std::string versionLine() {
    const int bullet = btGetVersion();
    const std::string buildType = *AFB_BUILD_TYPE ? AFB_BUILD_TYPE : "no build type";
#ifdef BT_USE_DOUBLE_PRECISION
    const char* precision = "double";
#else
    const char* precision = "float";
#endif
    return "afb " AFB_VERSION_STRING " (Bullet " + std::to_string(bullet / 100) + "." + std::to_string(bullet % 100) +
           ", " + precision + ", " + buildType + ")";
}

} // namespace

int main(int argc, char** argv) {
    CLI::App app{"afb — Doom 3 articulated figures (.af) on Bullet: parse, format, resolve, inspect, drop, "
                 "track, golden, draw, chart, stress, gen, methods; plan, run, merge.\n"
                 "Diagnostics go to stderr as file:line:col: error: message. Exit code 0 on success, 1 on a failed "
                 "check or bad input, 2 on a command line that makes no sense. A report written to '-' goes to "
                 "stdout alone; the human text goes to stderr then."};
    app.formatter(afb::cli::helpFormatter()); // before the commands: they take it
    app.require_subcommand(1);
    app.set_version_flag("--version", versionLine());
    int exitCode = 0;
    afb::cli::addParseCommand(app, exitCode);
    afb::cli::addFmtCommand(app, exitCode);
    afb::cli::addResolveCommand(app, exitCode);
    afb::cli::addInspectCommand(app, exitCode);
    afb::cli::addDropCommand(app, exitCode, argc, argv);
    afb::cli::addTrackCommand(app, exitCode);
    afb::cli::addGoldenCommand(app, exitCode);
    afb::cli::addDrawCommand(app, exitCode);
    afb::cli::addChartCommand(app, exitCode, argv);
    afb::cli::addStressCommand(app, exitCode, argv);
    afb::cli::addGenCommand(app, exitCode);
    afb::cli::addMethodsCommand(app, exitCode);
    afb::cli::addPlanCommand(app, exitCode, argv);
    afb::cli::addRunCommand(app, exitCode, argv);
    afb::cli::addMergeCommand(app, exitCode, argv);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return afb::cli::reportParseError(app, e);
    }
    return exitCode;
}
