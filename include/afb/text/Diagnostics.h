#pragma once
// Diagnostics with a source location: every parser reports `file:line:col: error: message`.
#include <cstdint>
#include <string>
#include <vector>

namespace afb::text {

/// Where something was written: file name, 1-based line and 1-based column (in bytes).
struct SourceLocation {
    std::string file;
    std::uint32_t line = 0;
    std::uint32_t column = 0;

    /// `file:line:col` (or `file` when the position is unknown).
    std::string str() const;

    /// Locations never take part in value equality: two decls are equal when they say the same thing,
    /// wherever they were written (this is what makes `parse(write(parse(f))) == parse(f)` meaningful).
    friend bool operator==(const SourceLocation&, const SourceLocation&) { return true; }
};

enum class Severity { Warning, Error };

/// One message about an input, tied to where it was found.
struct Diagnostic {
    Severity severity = Severity::Error;
    SourceLocation where;
    std::string message;

    /// `file:line:col: error: message` — the one format every tool prints.
    std::string str() const;
};

/// Collects diagnostics; library code never prints. Bounded, so hostile input cannot grow it without limit.
class Diagnostics {
  public:
    /// At most this many messages are kept; later ones are counted, not stored.
    static constexpr std::size_t kMaxKept = 500;

    void error(SourceLocation where, std::string message);
    void warning(SourceLocation where, std::string message);
    void add(Diagnostic d);
    void append(const Diagnostics& other);

    bool hasErrors() const { return m_errorCount > 0; }
    std::size_t errorCount() const { return m_errorCount; }
    std::size_t warningCount() const { return m_warningCount; }
    const std::vector<Diagnostic>& items() const { return m_items; }
    bool empty() const { return m_errorCount + m_warningCount == 0; }

    /// All kept messages, one per line, in the order they were reported.
    std::string str() const;

  private:
    std::vector<Diagnostic> m_items;
    std::size_t m_errorCount = 0;
    std::size_t m_warningCount = 0;
};

} // namespace afb::text
