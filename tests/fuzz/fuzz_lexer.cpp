// libFuzzer target: tokenize arbitrary bytes until End or a ParseError. Any crash, sanitizer report, hang or
// runaway allocation is a bug; a ParseError is the expected outcome for most inputs.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "afb/detail/Lexer.h"
#include "afb/text/Diagnostics.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view src(reinterpret_cast<const char*>(data), size);
    afb::text::Diagnostics diags;
    try {
        afb::text::Lexer lexer(src, "fuzz", diags);
        std::size_t tokens = 0;
        std::uint32_t lastLine = 0;
        for (;;) {
            const afb::text::Token t = lexer.next();
            if (t.kind == afb::text::TokenKind::End) break;
            // Each token consumes at least one byte; more tokens than bytes means the lexer is not advancing.
            if (++tokens > size) std::abort();
            // Token text lies inside the source it was lexed from — except strings joined by a backslash
            // continuation ("a" \ "b"), which the lexer stores itself; those still never contain a quote.
            const bool inside =
                t.text.empty() || (t.text.data() >= src.data() && t.text.data() + t.text.size() <= src.data() + size);
            if (!inside && t.kind != afb::text::TokenKind::String) std::abort();
            if (t.kind == afb::text::TokenKind::String && t.text.find('"') != std::string_view::npos) std::abort();
            if (t.line < lastLine || t.line == 0 || t.column == 0) std::abort();
            lastLine = t.line;
        }
        // Once at End, the lexer stays there.
        if (lexer.next().kind != afb::text::TokenKind::End) std::abort();
    } catch (const afb::text::ParseError&) {
    }
    return 0;
}
