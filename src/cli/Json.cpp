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

} // namespace afb::cli
