#pragma once
// Diagnostics with a source location: every parser reports `file:line:col: error: message`.
#include <cstdint>
#include <string>
#include <vector>

/// The text layer: bounded file reading and the diagnostics every parser reports, as
/// `file:line:col: error|warning: message`.
namespace afb::text {

/// Where something was written: file name, 1-based line and 1-based column (in bytes).
struct SourceLocation {
    std::string file;         ///< the file name as the caller gave it to the parser
    std::uint32_t line = 0;   ///< 1-based line; 0 when unknown
    std::uint32_t column = 0; ///< 1-based column in bytes; 0 when unknown

    /// `file:line:col` (or `file` when the position is unknown).
    std::string str() const;

    /// Locations never take part in value equality: two decls are equal when they say the same thing,
    /// wherever they were written (this is what makes `parse(write(parse(f))) == parse(f)` meaningful).
    friend bool operator==(const SourceLocation&, const SourceLocation&) { return true; }
};

/// How bad a Diagnostic is.
enum class Severity {
    Warning, ///< the input loads, but relies on an engine fallback or something else worth knowing
    Error,   ///< the input does not load
};

/// One message about an input, tied to where it was found.
struct Diagnostic {
    Severity severity = Severity::Error; ///< whether the input still loads
    SourceLocation where;                ///< where in the input it was found
    std::string message;                 ///< one line, without location or severity

    /// `file:line:col: error: message` — the one format every tool prints.
    std::string str() const;
};

/// Collects diagnostics; library code never prints. Bounded, so hostile input cannot grow it without limit.
class Diagnostics {
  public:
    /// At most this many messages are kept; later ones are counted, not stored.
    static constexpr std::size_t kMaxKept = 500;

    /// Reports an error at `where`.
    void error(SourceLocation where, std::string message);
    /// Reports a warning at `where`.
    void warning(SourceLocation where, std::string message);
    /// Reports a message built elsewhere.
    void add(Diagnostic d);
    /// Reports every message of `other` (its counts too, kept or not), after this one's.
    void append(const Diagnostics& other);

    /// True once any error was reported: the input did not load.
    bool hasErrors() const { return m_errorCount > 0; }
    /// Errors reported, including those past kMaxKept.
    std::size_t errorCount() const { return m_errorCount; }
    /// Warnings reported, including those past kMaxKept.
    std::size_t warningCount() const { return m_warningCount; }
    /// The kept messages (at most kMaxKept), in the order they were reported.
    const std::vector<Diagnostic>& items() const { return m_items; }
    /// True when nothing was reported.
    bool empty() const { return m_errorCount + m_warningCount == 0; }

    /// All kept messages, one per line, in the order they were reported.
    std::string str() const;

  private:
    std::vector<Diagnostic> m_items;
    std::size_t m_errorCount = 0;
    std::size_t m_warningCount = 0;
};

} // namespace afb::text
