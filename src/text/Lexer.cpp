#include "afb/detail/Lexer.h"

#include <charconv>
#include <cmath>
#include <limits>

namespace afb::text {
namespace {

bool isAlpha(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_'; }
bool isDigit(char c) { return c >= '0' && c <= '9'; }
// With LEXFL_ALLOWPATHNAMES a name may also hold these (docs/format.md §1.1).
bool isPathChar(char c) { return c == '/' || c == '\\' || c == ':' || c == '.'; }
bool isNameChar(char c) { return isAlpha(c) || isDigit(c) || isPathChar(c); }
char lower(char c) { return (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c; }

std::string hexByte(unsigned char c) {
    static const char* digits = "0123456789abcdef";
    return std::string("0x") + digits[c >> 4] + digits[c & 15];
}

} // namespace

bool equalsIgnoreCase(std::string_view a, std::string_view b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i)
        if (lower(a[i]) != lower(b[i])) return false;
    return true;
}

std::string lowerAscii(std::string_view s) {
    std::string out(s);
    for (char& c : out) c = lower(c);
    return out;
}

bool Token::isNameI(std::string_view s) const { return kind == TokenKind::Name && equalsIgnoreCase(text, s); }

std::string Token::describe() const {
    switch (kind) {
    case TokenKind::End: return "end of file";
    case TokenKind::String: return "\"" + std::string(text.substr(0, 60)) + "\"";
    case TokenKind::Literal: return "'" + std::string(text.substr(0, 60)) + "' (single-quoted)";
    default: return "'" + std::string(text.substr(0, 60)) + "'";
    }
}

Lexer::Lexer(std::string_view source, std::string fileName, Diagnostics& diagnostics)
    : m_src(source), m_file(std::move(fileName)), m_diags(diagnostics) {}

void Lexer::failAt(std::uint32_t line, std::uint32_t column, const std::string& message) const {
    throw ParseError({m_file, line, column}, message);
}

void Lexer::fail(const Token& t, const std::string& message) const { failAt(t.line, t.column, message); }

void Lexer::advance() {
    if (m_src[m_pos] == '\n') {
        ++m_line;
        m_column = 1;
    } else {
        ++m_column;
    }
    ++m_pos;
}

void Lexer::skipWhitespaceAndComments() {
    while (m_pos < m_src.size()) {
        const char c = cur();
        if (c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f') {
            advance();
        } else if (c == '/' && at(1) == '/') {
            while (m_pos < m_src.size() && cur() != '\n') {
                if (cur() == '\0') failAt(m_line, m_column, "NUL byte in a text file (binary data?)");
                advance();
            }
        } else if (c == '/' && at(1) == '*') {
            const std::uint32_t line = m_line, column = m_column;
            advance();
            advance();
            while (!(cur() == '*' && at(1) == '/')) {
                if (m_pos >= m_src.size()) failAt(line, column, "unterminated /* comment");
                if (cur() == '\0') failAt(m_line, m_column, "NUL byte in a text file (binary data?)");
                advance();
            }
            advance();
            advance();
        } else {
            return;
        }
    }
}

const Token& Lexer::peek() {
    if (!m_peeked) m_peeked = lex();
    return *m_peeked;
}

Token Lexer::next() {
    if (m_peeked) {
        Token t = *m_peeked;
        m_peeked.reset();
        return t;
    }
    return lex();
}

Token Lexer::lex() {
    skipWhitespaceAndComments();
    Token t;
    t.line = m_line;
    t.column = m_column;
    if (m_pos >= m_src.size()) return t;

    const std::size_t start = m_pos;
    const char c = cur();
    if (isDigit(c) || (c == '.' && isDigit(at(1)))) return lexNumber(t);
    if (c == '"' || c == '\'') return lexQuoted(t, c);
    if (isAlpha(c) || isPathChar(c)) {
        while (m_pos < m_src.size() && isNameChar(cur())) advance();
        t.kind = TokenKind::Name;
        t.text = m_src.substr(start, m_pos - start);
        return t;
    }
    const auto u = static_cast<unsigned char>(c);
    if (u == 0) failAt(m_line, m_column, "NUL byte in a text file (binary data?)");
    if (u < 0x20 || u >= 0x7f)
        failAt(m_line, m_column, "unexpected byte " + hexByte(u) + " outside a string or comment (binary data?)");
    advance();
    t.kind = TokenKind::Punct;
    t.text = m_src.substr(start, 1);
    return t;
}

Token Lexer::lexQuotedPart(Token t) {
    advance();
    const std::size_t start = m_pos;
    while (cur() != '"') {
        if (m_pos >= m_src.size()) failAt(t.line, t.column, "unterminated string");
        if (cur() == '\n') failAt(m_line, m_column, "newline inside a quoted string");
        if (cur() == '\0') failAt(m_line, m_column, "NUL byte in a text file (binary data?)");
        advance();
    }
    t.text = m_src.substr(start, m_pos - start);
    advance();
    return t;
}

Token Lexer::lexQuoted(Token t, char quote) {
    advance();
    const std::size_t start = m_pos;
    while (true) {
        if (m_pos >= m_src.size())
            failAt(t.line, t.column, quote == '"' ? "unterminated string" : "unterminated literal");
        const char c = cur();
        if (c == quote) break;
        if (c == '\n') failAt(m_line, m_column, "newline inside a quoted string");
        if (c == '\0') failAt(m_line, m_column, "NUL byte in a text file (binary data?)");
        advance();
    }
    t.kind = quote == '"' ? TokenKind::String : TokenKind::Literal;
    t.text = m_src.substr(start, m_pos - start);
    advance();
    if (quote == '"' && m_backslashConcat) concatenateContinuations(t);
    return t;
}

// LEXFL_ALLOWBACKSLASHSTRINGCONCAT (part of the engine's decl lexer flags): "a" \ "b" — a string, a backslash
// and another string, separated by white space — is one string "ab". Real .def files use it for long texts.
void Lexer::concatenateContinuations(Token& t) {
    std::string* joined = nullptr;
    while (true) {
        const std::size_t savePos = m_pos;
        const std::uint32_t saveLine = m_line, saveColumn = m_column;
        skipWhitespaceAndComments();
        if (cur() != '\\') {
            m_pos = savePos;
            m_line = saveLine;
            m_column = saveColumn;
            return;
        }
        const std::uint32_t slashLine = m_line, slashColumn = m_column;
        advance();
        skipWhitespaceAndComments();
        if (cur() != '"') failAt(slashLine, slashColumn, "expected a string after '\\' that continues a string");
        Token next;
        next.line = m_line;
        next.column = m_column;
        next = lexQuotedPart(next);
        if (!joined) {
            m_joinedStrings.emplace_back(t.text);
            joined = &m_joinedStrings.back();
        }
        joined->append(next.text);
        t.text = *joined;
    }
}

// idLexer::ReadNumber semantics (docs/format.md §1.1): decimal with '.', exponent and f/l suffix; 0x hex; 0b binary;
// a leading 0 not followed by '.' is octal. We reject what the engine would silently split or mangle.
Token Lexer::lexNumber(Token t) {
    const std::size_t start = m_pos;
    t.kind = TokenKind::Number;
    auto finishText = [&] { t.text = m_src.substr(start, m_pos - start); };
    auto failNumber = [&](const std::string& why) {
        while (m_pos < m_src.size() && (isNameChar(cur()) || cur() == '#')) advance();
        finishText();
        failAt(t.line, t.column, "malformed number '" + std::string(t.text.substr(0, 60)) + "': " + why);
    };

    const char c0 = cur();
    const char c1 = lower(at(1));
    if (c0 == '0' && (c1 == 'x' || c1 == 'b')) {
        const int base = c1 == 'x' ? 16 : 2;
        advance();
        advance();
        const std::size_t digitsStart = m_pos;
        while (m_pos < m_src.size() && (isDigit(cur()) || isAlpha(cur()))) advance();
        const std::string_view digits = m_src.substr(digitsStart, m_pos - digitsStart);
        std::uint64_t v = 0;
        const auto [ptr, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), v, base);
        if (digits.empty() || ptr != digits.data() + digits.size())
            failNumber(base == 16 ? "expected hexadecimal digits" : "expected binary digits");
        if (ec == std::errc::result_out_of_range) failNumber("out of range");
        finishText();
        t.isInteger = true;
        t.integer = v;
        t.value = static_cast<double>(v);
        return t;
    }
    if (c0 == '0' && isDigit(at(1))) {
        // Octal, as in the engine: 010 is 8. 08 and 09 would be split by the engine into two tokens.
        while (m_pos < m_src.size() && isDigit(cur())) advance();
        if (cur() == '.' || lower(cur()) == 'e') failNumber("a leading 0 makes an octal integer in idTech4 files");
        const std::string_view digits = m_src.substr(start, m_pos - start);
        std::uint64_t v = 0;
        const auto [ptr, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), v, 8);
        if (ptr != digits.data() + digits.size())
            failNumber("a leading 0 makes an octal number, and 8 and 9 are not octal digits");
        if (ec == std::errc::result_out_of_range) failNumber("out of range");
        finishText();
        t.isInteger = true;
        t.integer = v;
        t.value = static_cast<double>(v);
        m_diags.warning(locationOf(t), "number '" + std::string(t.text) + "' has a leading 0 and is read as octal (" +
                                           std::to_string(v) + "), as the engine does");
        return t;
    }

    bool isFloat = false;
    while (isDigit(cur())) advance();
    if (cur() == '.') {
        isFloat = true;
        advance();
        if (cur() == '#') failNumber("special float values such as 1.#INF are not numbers");
        while (isDigit(cur())) advance();
    }
    if (lower(cur()) == 'e' && (isDigit(at(1)) || ((at(1) == '-' || at(1) == '+') && isDigit(at(2))))) {
        isFloat = true;
        advance();
        if (cur() == '-' || cur() == '+') advance();
        while (isDigit(cur())) advance();
    }
    const std::size_t end = m_pos;
    // Suffixes: f/l make a float, u/l an integer (idLexer accepts them and ignores them).
    if (lower(cur()) == 'f') {
        isFloat = true;
        advance();
    } else {
        while (lower(cur()) == 'u' || lower(cur()) == 'l') advance();
    }
    if (isAlpha(cur()) || isDigit(cur())) failNumber("unexpected character after the number");
    finishText();
    const std::string_view digits = m_src.substr(start, end - start);
    if (!isFloat) {
        std::uint64_t v = 0;
        const auto [ptr, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), v);
        if (ec == std::errc::result_out_of_range) failNumber("out of range");
        t.isInteger = true;
        t.integer = v;
        t.value = static_cast<double>(v);
        return t;
    }
    double v = 0;
    const auto [ptr, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), v);
    if (ptr != digits.data() + digits.size()) failNumber("not a number");
    if (ec == std::errc::result_out_of_range || !std::isfinite(v)) {
        // from_chars also reports underflow as out of range; a tiny value is 0 for every purpose here.
        bool tiny = true;
        for (char ch : digits) {
            if (lower(ch) == 'e') break;
            if (ch >= '1' && ch <= '9') {
                tiny = false;
                break;
            }
        }
        const auto ePos = digits.find_first_of("eE");
        if (ePos != std::string_view::npos && ePos + 1 < digits.size() && digits[ePos + 1] == '-') tiny = true;
        if (!tiny) failNumber("out of range");
        v = 0.0;
    }
    t.value = v;
    return t;
}

// --- parse helpers ------------------------------------------------------------------------------------

void Lexer::expectPunct(char c, std::string_view context) {
    const Token t = next();
    if (!t.isPunct(c)) {
        std::string msg = std::string("expected '") + c + "'";
        if (!context.empty()) msg += " " + std::string(context);
        fail(t, msg + ", found " + t.describe());
    }
}

bool Lexer::acceptPunct(char c) {
    if (!peek().isPunct(c)) return false;
    next();
    return true;
}

std::string Lexer::expectString(std::string_view what) {
    const Token t = next();
    if (t.kind != TokenKind::String)
        fail(t, "expected " + std::string(what) + " as a \"quoted string\", found " + t.describe());
    return std::string(t.text);
}

Token Lexer::expectName(std::string_view what) {
    Token t = next();
    if (t.kind != TokenKind::Name) fail(t, "expected " + std::string(what) + ", found " + t.describe());
    return t;
}

Token Lexer::expectToken(std::string_view what) {
    Token t = next();
    if (t.kind == TokenKind::End) fail(t, "expected " + std::string(what) + ", found end of file");
    return t;
}

double Lexer::parseFloat(std::string_view what) {
    Token t = next();
    bool negative = false;
    if (t.isPunct('-')) {
        negative = true;
        t = next();
    }
    if (t.kind != TokenKind::Number) fail(t, "expected a number for " + std::string(what) + ", found " + t.describe());
    return negative ? -t.value : t.value;
}

std::int64_t Lexer::parseInt(std::string_view what) {
    Token t = next();
    bool negative = false;
    if (t.isPunct('-')) {
        negative = true;
        t = next();
    }
    if (t.kind != TokenKind::Number)
        fail(t, "expected an integer for " + std::string(what) + ", found " + t.describe());
    if (!t.isInteger) fail(t, "expected an integer for " + std::string(what) + ", found " + t.describe());
    if (t.integer > static_cast<std::uint64_t>(std::numeric_limits<std::int32_t>::max()))
        fail(t, "integer " + std::string(t.text) + " for " + std::string(what) + " is out of range");
    const auto v = static_cast<std::int64_t>(t.integer);
    return negative ? -v : v;
}

std::uint64_t Lexer::parseCount(std::string_view what, std::uint64_t max) {
    const Token t = next();
    if (t.kind != TokenKind::Number || !t.isInteger)
        fail(t, "expected a non-negative integer for " + std::string(what) + ", found " + t.describe());
    if (t.integer > max)
        fail(t,
             std::string(what) + " " + std::string(t.text) + " is out of range (at most " + std::to_string(max) + ")");
    return t.integer;
}

bool Lexer::parseBool(std::string_view what) {
    Token t = next();
    bool negative = false;
    if (t.isPunct('-')) {
        negative = true;
        t = next();
    }
    if (t.kind != TokenKind::Number)
        fail(t, "expected 0 or 1 for " + std::string(what) + ", found " + t.describe() +
                    " (the engine reads a non-number as false)");
    (void)negative; // -1 is as true as 1
    // idParser::ParseBool compares the integer value with 0: 1.0 is true, 0.5 is false.
    return t.value >= 1.0;
}

void Lexer::skipBracedSection() {
    expectPunct('{');
    std::size_t depth = 1;
    while (depth > 0) {
        const Token t = next();
        if (t.kind == TokenKind::End) fail(t, "unexpected end of file inside a { } section");
        if (t.isPunct('{')) ++depth;
        if (t.isPunct('}')) --depth;
    }
}

} // namespace afb::text
