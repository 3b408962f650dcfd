#pragma once
// What the md5mesh and md5anim parsers share (docs/format.md §7.3, §7.4): keywords, `( x y z )` triples, and header
// counts checked against the input size before anything is allocated for them.
#include <algorithm>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <string_view>

#include "afb/decl/Af.h"
#include "afb/detail/Lexer.h"

namespace afb::decl::detail {

/// A count is only known to fit the input; reserve at most this many entries up front, so that memory follows
/// the entries actually read rather than the claim.
inline constexpr std::size_t kMaxReserve = 4096;

/// The only `MD5Version` the engine reads.
inline constexpr std::int64_t kMd5Version = 10;
inline std::size_t reserveFor(int count) { return std::min(static_cast<std::size_t>(count), kMaxReserve); }

inline std::string quotedName(std::string_view s) { return "\"" + std::string(s.substr(0, 60)) + "\""; }

/// Base of the two md5 parsers: the source, its lexer and the helpers both grammars use.
class Md5ParserBase {
  protected:
    Md5ParserBase(std::string_view source, const std::string& fileName, text::Diagnostics& diagnostics)
        : m_src(source), m_lex(source, fileName, diagnostics) {}

    void expectKeyword(std::string_view keyword, std::string_view context) {
        const text::Token t = m_lex.next();
        if (!t.isName(keyword))
            m_lex.fail(t,
                       "expected '" + std::string(keyword) + "' " + std::string(context) + ", found " + t.describe());
    }

    /// Bytes of input after `t`, a number token (its text lies in the source).
    std::size_t bytesAfter(const text::Token& t) const {
        const std::less<const char*> before;
        if (t.kind != text::TokenKind::Number || before(t.text.data(), m_src.data()) ||
            before(m_src.data() + m_src.size(), t.text.data()))
            return m_src.size();
        const auto start = static_cast<std::size_t>(t.text.data() - m_src.data());
        return m_src.size() - std::min(m_src.size(), start + t.text.size());
    }

    /// A header count, checked against what the rest of the input could hold before anyone allocates for it:
    /// a file claiming two billion joints gets an error, not an allocation.
    int parseSizedCount(std::string_view what, std::size_t minBytesPerEntry) {
        const text::Token t = m_lex.peek();
        const std::uint64_t n = m_lex.parseCount(what, static_cast<std::uint64_t>(std::numeric_limits<int>::max()));
        const std::size_t room = bytesAfter(t) / minBytesPerEntry;
        if (n > room)
            m_lex.fail(t, std::string(what) + " " + std::string(t.text) +
                              " is more than the file can hold (the rest of the file has room for at most " +
                              std::to_string(room) + ")");
        return static_cast<int>(n);
    }

    /// `( x y z )` without commas.
    Vec3 parseVec3(std::string_view what) {
        const std::string context = "around " + std::string(what);
        Vec3 v;
        m_lex.expectPunct('(', context);
        v.x = m_lex.parseFloat(what);
        v.y = m_lex.parseFloat(what);
        v.z = m_lex.parseFloat(what);
        m_lex.expectPunct(')', context);
        return v;
    }

    std::string_view m_src;
    text::Lexer m_lex;
};

} // namespace afb::decl::detail
