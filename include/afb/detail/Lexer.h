#pragma once
// The one idTech4 lexer (docs/format.md §1.1) shared by .af, .def, .md5mesh and .md5anim.
#include <cstdint>
#include <deque>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "afb/text/Diagnostics.h"

namespace afb::text {

enum class TokenKind : std::uint8_t {
    End,     ///< end of input
    Name,    ///< [A-Za-z_] then [A-Za-z0-9_] plus the path characters / \ : .
    String,  ///< "double quoted", no escapes; `text` is the contents (see setBackslashStringConcatenation)
    Literal, ///< 'single quoted' (multi-character allowed); not a string for the decl parsers
    Number,  ///< unsigned number; a minus sign is always its own Punct token
    Punct,   ///< one punctuation character
};

/// One token. `text` points into the lexer's source (or, for a string joined by a backslash continuation, into the
/// lexer's own storage); the lexer and its source must outlive the token.
struct Token {
    TokenKind kind = TokenKind::End;
    std::string_view text;     ///< as written (String/Literal: without the quotes)
    std::uint32_t line = 0;    ///< 1-based
    std::uint32_t column = 0;  ///< 1-based, in bytes
    double value = 0.0;        ///< Number: its value
    std::uint64_t integer = 0; ///< Number written as an integer: its exact value
    bool isInteger = false;    ///< no '.', exponent or float suffix (decimal, octal, hex or binary)

    bool isPunct(char c) const { return kind == TokenKind::Punct && text.size() == 1 && text[0] == c; }
    /// A Name equal to `s`, case-sensitively.
    bool isName(std::string_view s) const { return kind == TokenKind::Name && text == s; }
    /// A Name equal to `s`, ignoring ASCII case (idStr::Icmp).
    bool isNameI(std::string_view s) const;
    /// How the token reads in a message: `'text'`, `"text"` or `end of file`.
    std::string describe() const;
};

/// ASCII case-insensitive equality (idStr::Icmp == 0).
bool equalsIgnoreCase(std::string_view a, std::string_view b);
/// `s` with A–Z lowered (ASCII only, as the engine compares names).
std::string lowerAscii(std::string_view s);

/// Thrown by the lexer and by parsers built on it; caught at each parser's entry point and turned into a
/// Diagnostic. Never escapes the library.
struct ParseError : std::runtime_error {
    SourceLocation where;
    ParseError(SourceLocation w, const std::string& message) : std::runtime_error(message), where(std::move(w)) {}
};

/// Tokenizer with one token of lookahead plus the engine's number/string helpers (ParseFloat, ParseInt, …).
/// Lexical errors throw ParseError; warnings (octal numbers) go to the Diagnostics given.
class Lexer {
  public:
    Lexer(std::string_view source, std::string fileName, Diagnostics& diagnostics);

    /// The next token, consuming it.
    Token next();
    /// The next token, without consuming it.
    const Token& peek();
    bool atEnd() { return peek().kind == TokenKind::End; }

    /// Decl files (.af, .def) join `"a" \\ "b"` into one string (the engine's LEXFL_ALLOWBACKSLASHSTRINGCONCAT,
    /// part of its decl lexer flags); md5 files do not. Off by default.
    void setBackslashStringConcatenation(bool on) { m_backslashConcat = on; }

    const std::string& fileName() const { return m_file; }
    SourceLocation locationOf(const Token& t) const { return {m_file, t.line, t.column}; }
    Diagnostics& diagnostics() { return m_diags; }

    /// Throws a ParseError located at `t`.
    [[noreturn]] void fail(const Token& t, const std::string& message) const;
    void warn(const Token& t, std::string message) { m_diags.warning(locationOf(t), std::move(message)); }

    // --- helpers with the engine's meaning, each throwing a located error on mismatch ----------------
    /// Consumes punctuation `c` or fails with "expected 'c' <context>".
    void expectPunct(char c, std::string_view context = {});
    /// Consumes punctuation `c` if it is next.
    bool acceptPunct(char c);
    /// A "double quoted" string (TT_STRING), e.g. body and joint names.
    std::string expectString(std::string_view what);
    /// A bare name (TT_NAME), e.g. a shape keyword.
    Token expectName(std::string_view what);
    /// Any token but end of input (ReadToken), returned by value.
    Token expectToken(std::string_view what);
    /// idParser::ParseFloat: an optional '-' then a number.
    double parseFloat(std::string_view what);
    /// idParser::ParseInt: an optional '-' then an integer number (a float is an error here).
    std::int64_t parseInt(std::string_view what);
    /// A non-negative integer no larger than `max`, e.g. an md5 count or index.
    std::uint64_t parseCount(std::string_view what, std::uint64_t max);
    /// idParser::ParseBool: a number, true when its integer value is not 0 (`true` is an error).
    bool parseBool(std::string_view what);
    /// Skips a `{ ... }` section whose `{` is next; nesting is counted, not recursed.
    void skipBracedSection();

  private:
    Token lex();
    void skipWhitespaceAndComments();
    Token lexNumber(Token t);
    Token lexQuoted(Token t, char quote);
    Token lexQuotedPart(Token t);
    void concatenateContinuations(Token& t);
    [[noreturn]] void failAt(std::uint32_t line, std::uint32_t column, const std::string& message) const;
    char cur() const { return m_pos < m_src.size() ? m_src[m_pos] : '\0'; }
    char at(std::size_t offset) const { return m_pos + offset < m_src.size() ? m_src[m_pos + offset] : '\0'; }
    void advance();

    std::string_view m_src;
    std::string m_file;
    Diagnostics& m_diags;
    std::size_t m_pos = 0;
    std::uint32_t m_line = 1;
    std::uint32_t m_column = 1;
    std::optional<Token> m_peeked;
    bool m_backslashConcat = false;
    std::deque<std::string>
        m_joinedStrings; ///< storage of strings joined by backslash continuations (stable addresses)
};

} // namespace afb::text
