#pragma once
// The decl-file level shared by `.af` and `.def` files (idDeclManager's file scan): `type name { ... }`
// blocks, with a default type for untyped ones, and braced sections of other types skipped.
#include <string_view>

#include "afb/detail/Lexer.h"

namespace afb::decl::detail {

/// True for the decl type keywords of idTech4 and the Doom 3 game (case-insensitive).
bool isDeclTypeName(std::string_view word);

/// The header of one decl: its type keyword (or the file's default type) and its name.
struct DeclHeader {
    std::string type;      ///< canonical spelling, e.g. "articulatedFigure", "entityDef", "model"
    text::Token typeToken; ///< where the decl starts
    std::string name;
};

/// Calls `onDecl(header)` for every decl in the file; the callback must consume the `{ ... }` that follows
/// and returns true, or returns false to have it skipped (another decl type).
template <class OnDecl>
void forEachDecl(text::Lexer& lex, std::string_view defaultType, OnDecl&& onDecl);

std::string canonicalDeclType(std::string_view word);

template <class OnDecl>
void forEachDecl(text::Lexer& lex, std::string_view defaultType, OnDecl&& onDecl) {
    while (!lex.atEnd()) {
        const text::Token first = lex.next();
        DeclHeader header;
        header.typeToken = first;
        if (first.kind == text::TokenKind::Name && isDeclTypeName(first.text)) {
            header.type = canonicalDeclType(first.text);
            const text::Token name = lex.expectToken("a decl name after '" + std::string(first.text) + "'");
            if (name.kind == text::TokenKind::Punct) lex.fail(name, "expected a decl name, found " + name.describe());
            header.name = std::string(name.text);
        } else if (first.kind == text::TokenKind::Name || first.kind == text::TokenKind::String) {
            header.type = std::string(defaultType);
            header.name = std::string(first.text);
        } else {
            lex.fail(first, "expected a decl type or name, found " + first.describe());
        }
        if (!lex.peek().isPunct('{'))
            lex.fail(lex.peek(),
                     "expected '{' after " + header.type + " '" + header.name + "', found " + lex.peek().describe());
        if (!onDecl(header)) lex.skipBracedSection();
    }
}

} // namespace afb::decl::detail
