// afb: the afbullet command-line tool.
#include "Commands.h"

int main(int argc, char** argv) {
    CLI::App app{"afb — Doom 3 articulated figures (.af) on Bullet: parse, format, resolve, inspect, drop, "
                 "golden, draw, chart, stress, gen.\n"
                 "Diagnostics go to stderr as file:line:col: error: message; exit code 1 on any error."};
    app.require_subcommand(1);
    app.set_version_flag("--version", "afb " AFB_VERSION);
    int exitCode = 0;
    afb::cli::addParseCommand(app, exitCode);
    afb::cli::addFmtCommand(app, exitCode);
    afb::cli::addResolveCommand(app, exitCode);
    afb::cli::addInspectCommand(app, exitCode);
    afb::cli::addDropCommand(app, exitCode, argc, argv);
    afb::cli::addGoldenCommand(app, exitCode);
    afb::cli::addDrawCommand(app, exitCode);
    afb::cli::addChartCommand(app, exitCode, argv);
    afb::cli::addStressCommand(app, exitCode, argv);
    afb::cli::addGenCommand(app, exitCode);
    CLI11_PARSE(app, argc, argv);
    return exitCode;
}
