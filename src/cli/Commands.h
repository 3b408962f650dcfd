#pragma once
// Subcommands of the `afb` tool. Each registers its options on the CLI11 app and runs when selected.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "afb/decl/Library.h"
#include "afb/text/Diagnostics.h"

namespace afb::cli {

/// Registers `afb parse`; the callback sets the process exit code through `exitCode`.
void addParseCommand(CLI::App& app, int& exitCode);
/// Registers `afb fmt`.
void addFmtCommand(CLI::App& app, int& exitCode);
/// Registers `afb resolve`.
void addResolveCommand(CLI::App& app, int& exitCode);
/// Registers `afb drop`; `argv` is kept to re-run the sibling binary of the other Bullet precision.
void addDropCommand(CLI::App& app, int& exitCode, int argc, char** argv);
/// Registers `afb track`.
void addTrackCommand(CLI::App& app, int& exitCode);
/// Registers `afb golden record|compare`.
void addGoldenCommand(CLI::App& app, int& exitCode);
/// Registers `afb inspect`.
void addInspectCommand(CLI::App& app, int& exitCode);
/// Registers `afb draw`.
void addDrawCommand(CLI::App& app, int& exitCode);
/// Registers `afb chart`; `argv` is kept to re-run the sibling binary of the other Bullet precision.
void addChartCommand(CLI::App& app, int& exitCode, char** argv);
/// Registers `afb stress`; `argv` is kept to re-run the sibling binary of the other Bullet precision.
void addStressCommand(CLI::App& app, int& exitCode, char** argv);

/// Registers `afb methods`.
void addMethodsCommand(CLI::App& app, int& exitCode);

/// Registers `afb gen`.
void addGenCommand(CLI::App& app, int& exitCode);

/// Registers `afb plan`, `afb run` and `afb merge`: a command's runs spread over processes and machines (Batch.h);
/// `argv` is kept to re-run the sibling binary of the other Bullet precision.
void addPlanCommand(CLI::App& app, int& exitCode, char** argv);
void addRunCommand(CLI::App& app, int& exitCode, char** argv);
void addMergeCommand(CLI::App& app, int& exitCode, char** argv);

/// Replaces this process by the sibling binary built against the other Bullet precision ("afb" for float,
/// "afb-double" for double) with the same arguments: the two builds cannot share a process. Returns only when
/// that fails, after printing why (`command` names the caller in the message).
void execOtherPrecision(const std::string& precision, char** argv, const char* command);

/// Checks that every name in `entities` is an entityDef of `library`; each that is not is an error in
/// `diagnostics` naming the closest entityDef there. Commands check their entities with it before they print or
/// run anything.
bool findEntities(const decl::Library& library, const std::vector<std::string>& entities,
                  text::Diagnostics& diagnostics);

/// Writes a report (a JSON or CSV document) to the file `path`, or to stdout for "-" (docs/cli.md: reports on
/// stdout).
void writeReport(const std::string& path, const std::string& text);
/// Prints every diagnostic to stderr as `file:line:col: error: message`.
void printDiagnostics(const text::Diagnostics& diagnostics);
/// Diagnostics as JSON: {"errors": [...], "warnings": [...]} of formatted messages.
nlohmann::json diagnosticsJson(const text::Diagnostics& diagnostics);

} // namespace afb::cli
