// Shared output of the commands: diagnostics to stderr or as JSON, and reports to a file or stdout.
#include <fstream>
#include <iostream>

#include "Commands.h"

namespace afb::cli {

void printDiagnostics(const text::Diagnostics& diagnostics) { std::cerr << diagnostics.str(); }

nlohmann::json diagnosticsJson(const text::Diagnostics& diagnostics) {
    nlohmann::json errors = nlohmann::json::array(), warnings = nlohmann::json::array();
    for (const text::Diagnostic& d : diagnostics.items())
        (d.severity == text::Severity::Error ? errors : warnings).push_back(d.str());
    return {{"errors", errors}, {"warnings", warnings}};
}

void writeReport(const std::string& path, const std::string& text) {
    if (path == "-") std::cout << text;
    else std::ofstream(path) << text;
}

} // namespace afb::cli
