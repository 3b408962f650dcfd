#include "afb/text/Diagnostics.h"

namespace afb::text {

std::string SourceLocation::str() const {
    if (line == 0) return file;
    return file + ":" + std::to_string(line) + ":" + std::to_string(column);
}

std::string Diagnostic::str() const {
    return where.str() + (severity == Severity::Error ? ": error: " : ": warning: ") + message;
}

void Diagnostics::add(Diagnostic d) {
    (d.severity == Severity::Error ? m_errorCount : m_warningCount)++;
    if (m_items.size() < kMaxKept) m_items.push_back(std::move(d));
}

void Diagnostics::error(SourceLocation where, std::string message) {
    add({Severity::Error, std::move(where), std::move(message)});
}

void Diagnostics::warning(SourceLocation where, std::string message) {
    add({Severity::Warning, std::move(where), std::move(message)});
}

void Diagnostics::append(const Diagnostics& other) {
    std::size_t keptErrors = 0, keptWarnings = 0;
    for (const Diagnostic& d : other.m_items) {
        (d.severity == Severity::Error ? keptErrors : keptWarnings)++;
        add(d);
    }
    // Messages the other collection counted but did not keep still count here.
    m_errorCount += other.m_errorCount - keptErrors;
    m_warningCount += other.m_warningCount - keptWarnings;
}

std::string Diagnostics::str() const {
    std::string out;
    for (const Diagnostic& d : m_items) out += d.str() + "\n";
    const std::size_t dropped = m_errorCount + m_warningCount - m_items.size();
    if (dropped > 0) out += "(" + std::to_string(dropped) + " more messages not shown)\n";
    return out;
}

} // namespace afb::text
