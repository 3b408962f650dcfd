// Spec-driven tests of the idTech4 lexer (docs/format.md §1.1, §8 item 12, and the project's error policy).
#include <catch2/catch.hpp>

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "afb/detail/Lexer.h"
#include "afb/text/Diagnostics.h"

using afb::text::Diagnostics;
using afb::text::Lexer;
using afb::text::ParseError;
using afb::text::Severity;
using afb::text::Token;
using afb::text::TokenKind;

namespace {

/// A token copied out of the lexer (so the test does not depend on the source's lifetime).
struct Tok {
    TokenKind kind = TokenKind::End;
    std::string text;
    std::uint32_t line = 0, column = 0;
    double value = 0;
    std::uint64_t integer = 0;
    bool isInteger = false;
};

Tok copyOf(const Token& t) { return {t.kind, std::string(t.text), t.line, t.column, t.value, t.integer, t.isInteger}; }

/// Every token up to and excluding End; fails the test if the lexer throws.
std::vector<Tok> lexAll(std::string_view src, Diagnostics& diags) {
    Lexer lex(src, "lexer.txt", diags);
    std::vector<Tok> out;
    for (int guard = 0; guard < 10000; ++guard) {
        const Token t = lex.next();
        if (t.kind == TokenKind::End) return out;
        out.push_back(copyOf(t));
    }
    FAIL("lexer did not reach the end");
    return out;
}

std::vector<Tok> lexAll(std::string_view src) {
    Diagnostics d;
    auto toks = lexAll(src, d);
    INFO(d.str());
    CHECK(d.errorCount() == 0);
    return toks;
}

struct LexFailure {
    bool failed = false;
    std::uint32_t line = 0, column = 0;
    std::string message;
};

/// Lexes everything; reports the first ParseError thrown.
LexFailure lexError(std::string_view src) {
    Diagnostics d;
    Lexer lex(src, "lexer.txt", d);
    try {
        for (int guard = 0; guard < 10000; ++guard)
            if (lex.next().kind == TokenKind::End) return {};
    } catch (const ParseError& e) {
        return {true, e.where.line, e.where.column, e.what()};
    }
    return {};
}

/// One number token with nothing after it.
Tok singleNumber(std::string_view src, Diagnostics& d) {
    const auto toks = lexAll(src, d);
    REQUIRE(toks.size() == 1);
    REQUIRE(toks[0].kind == TokenKind::Number);
    return toks[0];
}

} // namespace

TEST_CASE("lexer: token kinds", "[lexer]") {
    const std::string src = "settings { body \"pelvis\" 'lit' 12 - } ,";
    const auto t = lexAll(src);
    REQUIRE(t.size() == 9);
    CHECK(t[0].kind == TokenKind::Name);
    CHECK(t[0].text == "settings");
    CHECK(t[1].kind == TokenKind::Punct);
    CHECK(t[1].text == "{");
    CHECK(t[2].kind == TokenKind::Name);
    CHECK(t[2].text == "body");
    CHECK(t[3].kind == TokenKind::String);
    CHECK(t[3].text == "pelvis"); // without the quotes
    CHECK(t[4].kind == TokenKind::Literal);
    CHECK(t[4].text == "lit");
    CHECK(t[5].kind == TokenKind::Number);
    CHECK(t[5].value == 12.0);
    CHECK(t[6].kind == TokenKind::Punct);
    CHECK(t[6].text == "-");
    CHECK(t[7].kind == TokenKind::Punct);
    CHECK(t[7].text == "}");
    CHECK(t[8].kind == TokenKind::Punct);
    CHECK(t[8].text == ",");
}

TEST_CASE("lexer: empty and blank input give End", "[lexer]") {
    for (const char* src : {"", "   \t\r\n\n  ", "// only a comment", "/* only */", "/* a */ // b\n"}) {
        INFO("source: " << src);
        Diagnostics d;
        Lexer lex(src, "e.txt", d);
        CHECK(lex.atEnd());
        CHECK(lex.peek().kind == TokenKind::End);
        CHECK(lex.next().kind == TokenKind::End);
        CHECK(lex.next().kind == TokenKind::End); // End is sticky
        CHECK(d.empty());
    }
}

TEST_CASE("lexer: peek does not consume", "[lexer]") {
    Diagnostics d;
    const std::string src = "a b";
    Lexer lex(src, "p.txt", d);
    CHECK(lex.peek().text == "a");
    CHECK(lex.peek().text == "a");
    CHECK(lex.next().text == "a");
    CHECK(lex.peek().text == "b");
    CHECK(lex.next().text == "b");
    CHECK(lex.atEnd());
}

TEST_CASE("lexer: comments", "[lexer]") {
    SECTION("line and block comments are skipped") {
        const std::string src = "a // comment } {\nb /* block\n \"not a string\" */ c /**/ d /***/ e";
        const auto t = lexAll(src);
        REQUIRE(t.size() == 5);
        CHECK(t[0].text == "a");
        CHECK(t[1].text == "b");
        CHECK(t[1].line == 2);
        CHECK(t[2].text == "c");
        CHECK(t[2].line == 3);
        CHECK(t[3].text == "d");
        CHECK(t[4].text == "e");
    }
    SECTION("a line comment at end of input without a newline") {
        const auto t = lexAll("x // trailing");
        REQUIRE(t.size() == 1);
        CHECK(t[0].text == "x");
    }
    SECTION("a comment between punctuation and numbers separates them") {
        const auto t = lexAll("(/**/1/**/)");
        REQUIRE(t.size() == 3);
        CHECK(t[0].text == "(");
        CHECK(t[1].value == 1.0);
        CHECK(t[2].text == ")");
    }
    SECTION("'/' is a name character, so a name runs into a comment marker written without a space") {
        // docs/format.md §1.1: with path names allowed, names are [A-Za-z0-9_] plus / \\ : .
        const auto t = lexAll("models/x//y");
        REQUIRE(t.size() == 1);
        CHECK(t[0].kind == TokenKind::Name);
        CHECK(t[0].text == "models/x//y");
    }
    SECTION("comment markers inside a string are part of the string") {
        const auto t = lexAll("\"a // b /* c */\" d");
        REQUIRE(t.size() == 2);
        CHECK(t[0].kind == TokenKind::String);
        CHECK(t[0].text == "a // b /* c */");
        CHECK(t[1].text == "d");
    }
    SECTION("an unterminated block comment is an error at the comment's start") {
        const auto e = lexError("a\n  /* never closed\n\nmore text");
        CHECK(e.failed);
        CHECK(e.line == 2);
        CHECK(e.column == 3);
    }
    SECTION("'/*/' does not close itself") {
        const auto e = lexError("/*/ x");
        CHECK(e.failed);
        CHECK(e.line == 1);
        CHECK(e.column == 1);
    }
}

TEST_CASE("lexer: double-quoted strings", "[lexer]") {
    SECTION("no escape characters") {
        const std::string src = "\"C:\\dir\\\" next";
        const auto t = lexAll(src);
        REQUIRE(t.size() == 2);
        CHECK(t[0].kind == TokenKind::String);
        CHECK(t[0].text == "C:\\dir\\"); // the backslash does not escape the closing quote
        CHECK(t[1].kind == TokenKind::Name);
        CHECK(t[1].text == "next");
    }
    SECTION("empty string and strings with spaces and punctuation") {
        const auto t = lexAll("\"\" \"*origin -*Waist\" \"a{b},c\"");
        REQUIRE(t.size() == 3);
        CHECK(t[0].kind == TokenKind::String);
        CHECK(t[0].text.empty());
        CHECK(t[1].text == "*origin -*Waist");
        CHECK(t[2].text == "a{b},c");
    }
    SECTION("no concatenation of adjacent strings") {
        const auto t = lexAll("\"a\" \"b\"");
        REQUIRE(t.size() == 2);
        CHECK(t[0].text == "a");
        CHECK(t[1].text == "b");
    }
    SECTION("a newline inside a string is an error") {
        const auto e = lexError("x \"abc\ndef\"");
        CHECK(e.failed);
        CHECK(e.line == 1);
    }
    SECTION("an unterminated string is an error") {
        const auto e = lexError("x\ny \"abc");
        CHECK(e.failed);
        CHECK(e.line == 2);
    }
    SECTION("bytes >= 0x80 are allowed inside a string") {
        const std::string src = "\"caf\xC3\xA9\"";
        const auto t = lexAll(src);
        REQUIRE(t.size() == 1);
        CHECK(t[0].kind == TokenKind::String);
        CHECK(t[0].text == "caf\xC3\xA9");
    }
}

TEST_CASE("lexer: single-quoted tokens are literals, not strings", "[lexer]") {
    const auto t = lexAll("'abc' 'two words' \"s\"");
    REQUIRE(t.size() == 3);
    CHECK(t[0].kind == TokenKind::Literal);
    CHECK(t[0].text == "abc");
    CHECK(t[1].kind == TokenKind::Literal); // multi-character literals are allowed
    CHECK(t[1].text == "two words");
    CHECK(t[2].kind == TokenKind::String);

    SECTION("expectString rejects a literal") {
        Diagnostics d;
        const std::string src = "'origin'";
        Lexer lex(src, "l.txt", d);
        CHECK_THROWS_AS(lex.expectString("a body name"), ParseError);
    }
    SECTION("an unterminated literal is an error") { CHECK(lexError("'abc").failed); }
}

TEST_CASE("lexer: names, with path characters", "[lexer]") {
    SECTION("a path is one Name token") {
        const auto t = lexAll("models/md5/x.md5mesh");
        REQUIRE(t.size() == 1);
        CHECK(t[0].kind == TokenKind::Name);
        CHECK(t[0].text == "models/md5/x.md5mesh");
    }
    SECTION("backslashes, colons and dots") {
        const auto t = lexAll("C:\\base\\af\\x.af _under_9 a.b:c");
        REQUIRE(t.size() == 3);
        CHECK(t[0].kind == TokenKind::Name);
        CHECK(t[0].text == "C:\\base\\af\\x.af");
        CHECK(t[1].kind == TokenKind::Name);
        CHECK(t[1].text == "_under_9");
        CHECK(t[2].kind == TokenKind::Name);
        CHECK(t[2].text == "a.b:c");
    }
    SECTION("a minus sign is not a name character") {
        const auto t = lexAll("a-b");
        REQUIRE(t.size() == 3);
        CHECK(t[0].text == "a");
        CHECK(t[1].kind == TokenKind::Punct);
        CHECK(t[1].text == "-");
        CHECK(t[2].text == "b");
    }
    SECTION("punctuation ends a name") {
        const auto t = lexAll("joint(\"x\")");
        REQUIRE(t.size() == 4);
        CHECK(t[0].kind == TokenKind::Name);
        CHECK(t[0].text == "joint");
        CHECK(t[1].text == "(");
        CHECK(t[2].kind == TokenKind::String);
        CHECK(t[3].text == ")");
    }
    SECTION("isName is case-sensitive, isNameI is not") {
        Diagnostics d;
        const std::string src = "ContainedJoints";
        Lexer lex(src, "n.txt", d);
        const Token t = lex.next();
        CHECK(t.isNameI("containedjoints"));
        CHECK(t.isNameI("CONTAINEDJOINTS"));
        CHECK_FALSE(t.isName("containedjoints"));
        CHECK(t.isName("ContainedJoints"));
        CHECK(afb::text::equalsIgnoreCase("BallAndSocketJoint", "ballandsocketjoint"));
        CHECK_FALSE(afb::text::equalsIgnoreCase("hinge", "hinges"));
    }
}

TEST_CASE("lexer: decimal numbers", "[lexer][number]") {
    struct Case {
        const char* src;
        double value;
        bool isInteger;
    };
    const Case cases[] = {
        {"0", 0.0, true},
        {"42", 42.0, true},
        {"3.25", 3.25, false},
        {"1e-5", 1e-5, false},
        {"1E3", 1000.0, false},
        {"2.5e+2", 250.0, false},
        {"1.5f", 1.5, false},
        {".5", 0.5, false},
        {"0.5", 0.5, false},
        {"10.", 10.0, false},
        {"0.0099999998", 0.0099999998, false},
    };
    for (const Case& c : cases) {
        INFO("source: " << c.src);
        Diagnostics d;
        const Tok t = singleNumber(c.src, d);
        CHECK(t.value == Approx(c.value).epsilon(1e-12));
        CHECK(t.isInteger == c.isInteger);
        CHECK(d.empty()); // no octal warning for 0, 0.5, ...
    }
    SECTION("integer values are exact") {
        Diagnostics d;
        const Tok t = singleNumber("123456789", d);
        CHECK(t.integer == 123456789u);
    }
}

TEST_CASE("lexer: hex, binary and octal numbers", "[lexer][number]") {
    SECTION("hex") {
        Diagnostics d;
        const Tok t = singleNumber("0x1F", d);
        CHECK(t.isInteger);
        CHECK(t.integer == 31u);
        CHECK(t.value == 31.0);
        CHECK(d.empty());
    }
    SECTION("binary") {
        Diagnostics d;
        const Tok t = singleNumber("0b101", d);
        CHECK(t.isInteger);
        CHECK(t.integer == 5u);
        CHECK(t.value == 5.0);
        CHECK(d.empty());
    }
    SECTION("a leading zero is octal, with a warning that says so") {
        Diagnostics d;
        const std::string src = "a\n  010";
        const auto toks = lexAll(src, d);
        REQUIRE(toks.size() == 2);
        CHECK(toks[1].kind == TokenKind::Number);
        CHECK(toks[1].isInteger);
        CHECK(toks[1].integer == 8u);
        CHECK(toks[1].value == 8.0);
        CHECK(d.errorCount() == 0);
        REQUIRE(d.warningCount() == 1);
        REQUIRE(d.items().size() == 1);
        const auto& w = d.items()[0];
        CHECK(w.severity == Severity::Warning);
        CHECK(w.message.find("octal") != std::string::npos);
        CHECK(w.where.line == 2);
        CHECK(w.where.column == 3);
        CHECK(w.where.file == "lexer.txt");
    }
    SECTION("09 and 08 are errors, not two tokens") {
        for (const char* src : {"09", "08", "x 019"}) {
            INFO("source: " << src);
            CHECK(lexError(src).failed);
        }
        const auto e = lexError("a  09");
        CHECK(e.line == 1);
        CHECK(e.column == 4);
    }
}

TEST_CASE("lexer: malformed and out-of-range numbers are errors", "[lexer][number]") {
    SECTION("1.#INF-style tokens") {
        for (const char* src : {"1.#INF", "x -1.#IND", "1.#QNAN"}) {
            INFO("source: " << src);
            CHECK(lexError(src).failed);
        }
        const auto e = lexError("\n\t1.#INF");
        CHECK(e.line == 2);
        CHECK(e.column == 2);
    }
    SECTION("a float that overflows") {
        const auto e = lexError("ok 1e999");
        CHECK(e.failed);
        CHECK(e.line == 1);
        CHECK(e.column == 4);
    }
    SECTION("an integer too large to represent") {
        const auto e = lexError("1 99999999999999999999999999");
        CHECK(e.failed);
        CHECK(e.column == 3);
    }
}

TEST_CASE("lexer: a minus sign is always a separate token", "[lexer][number]") {
    const auto t = lexAll("-5 - 2.5 5-3 1e-5");
    REQUIRE(t.size() == 8);
    CHECK(t[0].kind == TokenKind::Punct);
    CHECK(t[0].text == "-");
    CHECK(t[1].kind == TokenKind::Number);
    CHECK(t[1].value == 5.0);
    CHECK(t[2].text == "-");
    CHECK(t[3].value == 2.5);
    CHECK(t[4].value == 5.0);
    CHECK(t[5].kind == TokenKind::Punct);
    CHECK(t[6].value == 3.0);
    CHECK(t[7].kind == TokenKind::Number); // the exponent sign belongs to the number
    CHECK(t[7].value == Approx(1e-5));
}

TEST_CASE("lexer: line and column are 1-based, in bytes", "[lexer]") {
    const std::string src = "ab  cd\n\tx 12\r\n  \"s\" 'l'\n\n(";
    const auto t = lexAll(src);
    REQUIRE(t.size() == 7);
    CHECK((t[0].line == 1 && t[0].column == 1));
    CHECK((t[1].line == 1 && t[1].column == 5));
    CHECK((t[2].line == 2 && t[2].column == 2)); // a tab is one byte
    CHECK((t[3].line == 2 && t[3].column == 4));
    CHECK((t[4].line == 3 && t[4].column == 3)); // CRLF is one line break
    CHECK((t[5].line == 3 && t[5].column == 7));
    CHECK((t[6].line == 5 && t[6].column == 1));
}

TEST_CASE("lexer: binary data is rejected", "[lexer]") {
    SECTION("NUL byte between tokens") {
        const std::string src("ab\0cd", 5);
        const auto e = lexError(src);
        CHECK(e.failed);
        CHECK(e.line == 1);
        CHECK(e.column == 3);
    }
    SECTION("NUL byte inside a string") {
        const std::string src("\"a\0b\"", 5);
        CHECK(lexError(src).failed);
    }
    SECTION("NUL byte inside a comment") {
        const std::string src("// a\0b\nx", 8);
        CHECK(lexError(src).failed);
        const std::string block("/* a\0b */ x", 11);
        CHECK(lexError(block).failed);
    }
    SECTION("a byte >= 0x80 outside a string") {
        for (const char* src : {"\xC3\xA9", "abc \xFF", "x\n \x80"}) {
            INFO("source bytes: " << src);
            CHECK(lexError(src).failed);
        }
        const auto e = lexError("x\n \x80");
        CHECK(e.line == 2);
        CHECK(e.column == 2);
    }
}

TEST_CASE("lexer: parseFloat, parseInt and parseBool", "[lexer][helpers]") {
    auto withLexer = [](const std::string& src, auto&& fn) {
        Diagnostics d;
        Lexer lex(src, "h.txt", d);
        return fn(lex);
    };

    SECTION("parseFloat accepts a separate minus sign") {
        CHECK(withLexer("2.5", [](Lexer& l) { return l.parseFloat("x"); }) == 2.5);
        CHECK(withLexer("-2.5", [](Lexer& l) { return l.parseFloat("x"); }) == -2.5);
        CHECK(withLexer("- 7", [](Lexer& l) { return l.parseFloat("x"); }) == -7.0);
        CHECK(withLexer("1e-5", [](Lexer& l) { return l.parseFloat("x"); }) == Approx(1e-5));
        CHECK(withLexer("0x10", [](Lexer& l) { return l.parseFloat("x"); }) == 16.0);
    }
    SECTION("parseFloat of a non-number is an error at that token") {
        for (const char* src : {"abc", "\"1\"", "'1'", ",", "", "- x"}) {
            INFO("source: " << src);
            CHECK_THROWS_AS(withLexer(src, [](Lexer& l) { return l.parseFloat("x"); }), ParseError);
        }
        try {
            withLexer("\n   abc", [](Lexer& l) { return l.parseFloat("x"); });
            FAIL("no error");
        } catch (const ParseError& e) {
            CHECK(e.where.line == 2);
            CHECK(e.where.column == 4);
            CHECK(e.where.file == "h.txt");
        }
    }
    SECTION("parseFloat consumes exactly the number") {
        Diagnostics d;
        const std::string src = "- 3 , 4";
        Lexer lex(src, "h.txt", d);
        CHECK(lex.parseFloat("x") == -3.0);
        CHECK(lex.next().text == ",");
        CHECK(lex.parseFloat("x") == 4.0);
        CHECK(lex.atEnd());
    }
    SECTION("parseInt") {
        CHECK(withLexer("7", [](Lexer& l) { return l.parseInt("n"); }) == 7);
        CHECK(withLexer("-7", [](Lexer& l) { return l.parseInt("n"); }) == -7);
        CHECK(withLexer("0x10", [](Lexer& l) { return l.parseInt("n"); }) == 16);
        CHECK_THROWS_AS(withLexer("abc", [](Lexer& l) { return l.parseInt("n"); }), ParseError);
        CHECK_THROWS_AS(withLexer("1.5", [](Lexer& l) { return l.parseInt("n"); }), ParseError);
    }
    SECTION("parseBool takes a number: 1, 0 and 1.0 work; the integer value decides") {
        CHECK(withLexer("1", [](Lexer& l) { return l.parseBool("selfCollision"); }));
        CHECK_FALSE(withLexer("0", [](Lexer& l) { return l.parseBool("selfCollision"); }));
        CHECK(withLexer("1.0", [](Lexer& l) { return l.parseBool("selfCollision"); }));
        CHECK_FALSE(withLexer("0.5", [](Lexer& l) { return l.parseBool("selfCollision"); }));
        CHECK(withLexer("2", [](Lexer& l) { return l.parseBool("selfCollision"); }));
    }
    SECTION("parseBool of 'true' is an error (the engine silently reads false)") {
        CHECK_THROWS_AS(withLexer("true", [](Lexer& l) { return l.parseBool("selfCollision"); }), ParseError);
        CHECK_THROWS_AS(withLexer("\"1\"", [](Lexer& l) { return l.parseBool("selfCollision"); }), ParseError);
        try {
            withLexer("  true", [](Lexer& l) { return l.parseBool("selfCollision"); });
            FAIL("no error");
        } catch (const ParseError& e) {
            CHECK(e.where.line == 1);
            CHECK(e.where.column == 3);
        }
    }
}

TEST_CASE("lexer: expect helpers", "[lexer][helpers]") {
    Diagnostics d;
    const std::string src = "( \"s\" name , )";
    Lexer lex(src, "x.txt", d);
    lex.expectPunct('(');
    CHECK(lex.expectString("s") == "s");
    CHECK(lex.expectName("n").text == "name");
    CHECK_FALSE(lex.acceptPunct(')'));
    CHECK(lex.acceptPunct(','));
    CHECK_THROWS_AS(lex.expectPunct(','), ParseError);
    CHECK(lex.atEnd());
    CHECK_THROWS_AS(lex.expectToken("anything"), ParseError);
}

TEST_CASE("lexer: skipBracedSection counts nesting", "[lexer][helpers]") {
    Diagnostics d;
    const std::string src = "{ a { b } { { c } } } after";
    Lexer lex(src, "s.txt", d);
    lex.skipBracedSection();
    CHECK(lex.next().text == "after");

    const std::string bad = "{ a { b }";
    Lexer lex2(bad, "s.txt", d);
    CHECK_THROWS_AS(lex2.skipBracedSection(), ParseError);
}
