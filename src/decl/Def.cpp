#include "afb/decl/Def.h"

#include <array>
#include <map>
#include <set>

#include "DeclFile.h"
#include "afb/detail/Lexer.h"
#include "afb/text/Files.h"

namespace afb::decl {
namespace {

using text::Token;
using text::TokenKind;

bool isDigit(char c) { return c >= '0' && c <= '9'; }

// idDeclModelDef::ParseAnim: scan back from the last character while digits, but never onto the first
// character; the index where the scan stops is the last character of the alias (0 means invalid).
std::size_t aliasEnd(std::string_view name) {
    if (name.empty()) return 0;
    std::size_t i = name.size() - 1;
    while (i > 0 && isDigit(name[i])) --i;
    return i;
}

// The statements a model decl accepts (docs/format.md §7.1), for the unknown-keyword message.
constexpr const char* kModelKeywords = "inherit, skin, mesh, offset, channel, anim, remove";

// One `.def` file: the decl scan is DeclFile's; this reads the bodies of entityDef and model decls.
class DefParser {
  public:
    DefParser(std::string_view source, const std::string& fileName, text::Diagnostics& diagnostics)
        : m_src(source), m_lex(source, fileName, diagnostics) {
        m_lex.setBackslashStringConcatenation(true); // DECL_LEXER_FLAGS, e.g. monster_default.def's editor_var
    }

    DefFile parse() {
        DefFile file;
        detail::forEachDecl(m_lex, "entityDef", [&](const detail::DeclHeader& header) {
            if (header.type == "entityDef") {
                file.entityDefs.push_back(parseEntityDef(header));
                return true;
            }
            if (header.type == "model") {
                file.models.push_back(parseModel(header));
                return true;
            }
            return false; // export, skin, table, material, …: not ours
        });
        return file;
    }

  private:
    // A value token (ReadToken in the engine); punctuation is rejected so a missing value cannot swallow the
    // braces that delimit the decl.
    struct Value {
        Token token;      ///< where it was written
        std::string text; ///< its text (strings joined over '\\' by the lexer)
    };
    Value expectValue(const std::string& what) {
        const Token t = m_lex.next();
        if (t.kind == TokenKind::End) m_lex.fail(t, "unexpected end of file: expected " + what);
        if (t.kind == TokenKind::Punct) m_lex.fail(t, "expected " + what + ", found " + t.describe());
        return {t, std::string(t.text)};
    }

    // idDeclEntityDef::Parse: quoted key, then any value token, until '}' (docs/format.md §7.2).
    EntityDef parseEntityDef(const detail::DeclHeader& header) {
        EntityDef def;
        def.name = header.name;
        def.location = m_lex.locationOf(header.typeToken);
        const std::string where = "entityDef '" + def.name + "'";
        m_lex.expectPunct('{', "to open " + where);
        std::map<std::string, std::uint32_t, std::less<>> lineOfKey; // lower-cased key → line first written
        while (true) {
            const Token key = m_lex.next();
            if (key.kind == TokenKind::End) m_lex.fail(key, "unexpected end of file in " + where + " (missing '}')");
            if (key.isPunct('}')) break;
            if (key.kind != TokenKind::String)
                m_lex.fail(key, "expected a \"quoted\" key or '}' in " + where + ", found " + key.describe());
            std::string keyText(key.text);
            const Token value = m_lex.next();
            if (value.kind == TokenKind::End)
                m_lex.fail(value, "unexpected end of file: key \"" + keyText + "\" of " + where + " has no value");
            if (value.isPunct('{') || value.isPunct('}'))
                m_lex.fail(value,
                           "key \"" + keyText + "\" of " + where + " has no value (found " + value.describe() + ")");
            const auto [it, inserted] = lineOfKey.try_emplace(text::lowerAscii(keyText), key.line);
            if (!inserted)
                m_lex.warn(key, "'" + keyText + "' already defined in " + where + " (line " +
                                    std::to_string(it->second) + "); the later value wins");
            def.keyValues.emplace_back(std::move(keyText), std::string(value.text));
        }
        return def;
    }

    // idDeclModelDef::Parse (docs/format.md §7.1). Keywords are case-sensitive and may be quoted.
    ModelDef parseModel(const detail::DeclHeader& header) {
        ModelDef model;
        model.name = header.name;
        model.location = m_lex.locationOf(header.typeToken);
        const std::string where = "model '" + model.name + "'";
        m_lex.expectPunct('{', "to open " + where);
        bool anyStatement = false;
        OwnAnims own; // sets, so that huge decls stay O(n log n)
        while (true) {
            const Token keyword = m_lex.next();
            if (keyword.kind == TokenKind::End)
                m_lex.fail(keyword, "unexpected end of file in " + where + " (missing '}')");
            if (keyword.isPunct('}')) break;
            const std::string_view word = keyword.kind == TokenKind::Punct ? std::string_view{} : keyword.text;
            if (word == "inherit") {
                const Value parent = expectValue("a model decl name after 'inherit'");
                if (anyStatement) {
                    // CopyDecl frees everything parsed so far before copying the parent.
                    m_lex.warn(keyword, "'inherit' after other statements in " + where + ": the engine's copy of '" +
                                            parent.text + "' replaces them, so they are dropped");
                    ModelDef reset;
                    reset.name = std::move(model.name);
                    reset.location = std::move(model.location);
                    model = std::move(reset);
                    own = {};
                }
                model.inherit = parent.text;
            } else if (word == "skin") {
                model.skin = expectValue("a skin name after 'skin'").text;
            } else if (word == "mesh") {
                const Value mesh = expectValue("an .md5mesh path after 'mesh'");
                const auto dot = mesh.text.rfind('.');
                // The engine compares the extension case-sensitively (MD5_MESH_EXT).
                if (dot == std::string::npos || mesh.text.substr(dot + 1) != "md5mesh")
                    m_lex.fail(mesh.token, "mesh '" + mesh.text + "' of " + where +
                                               " is not an .md5mesh file (the engine requires that extension)");
                model.mesh = mesh.text;
            } else if (word == "offset") {
                model.offset = parseOffset(where);
            } else if (word == "channel") {
                model.channels.push_back(parseChannel(keyword, model, where));
            } else if (word == "anim") {
                model.anims.push_back(parseAnim(keyword, model, own, where));
            } else if (word == "remove") {
                model.removes.push_back(parseRemove(model, own, where));
            } else {
                m_lex.fail(keyword, "unknown keyword " + keyword.describe() + " in " + where +
                                        " (model keywords are case-sensitive: " + kModelKeywords + ")");
            }
            anyStatement = true;
        }
        return model;
    }

    // Parse1DMatrix(3): '(' x y z ')' with no commas.
    Vec3 parseOffset(const std::string& where) {
        m_lex.expectPunct('(', "after 'offset' in " + where);
        std::array<double, 3> v{};
        for (double& x : v) {
            if (m_lex.peek().isPunct(','))
                m_lex.fail(m_lex.peek(), "offset takes three numbers without commas: ( x y z )");
            x = m_lex.parseFloat("offset");
        }
        m_lex.expectPunct(')', "after the three numbers of 'offset'");
        return {v[0], v[1], v[2]};
    }

    void requireMesh(const Token& keyword, const ModelDef& model, const std::string& where) {
        if (!model.mesh && !model.inherit)
            m_lex.fail(keyword, "'" + std::string(keyword.text) + "' before 'mesh' in " + where +
                                    ": the mesh must be given (or inherited) first");
    }

    ModelChannel parseChannel(const Token& keyword, const ModelDef& model, const std::string& where) {
        requireMesh(keyword, model, where);
        ModelChannel channel;
        channel.location = m_lex.locationOf(keyword);
        const Value name = expectValue("a channel name after 'channel'");
        channel.name = name.text;
        m_lex.expectPunct('(', "after channel '" + channel.name + "'");
        if (!isModelChannelName(channel.name))
            m_lex.fail(name.token, "unknown channel '" + channel.name + "' in " + where +
                                       " (torso, legs, head or eyelids; 'all' holds every joint already)");
        // The engine appends each token and a space, except after '*' and '-', which bind to the next name.
        while (true) {
            const Token t = m_lex.next();
            if (t.kind == TokenKind::End)
                m_lex.fail(t, "unexpected end of file in the joint list of channel '" + channel.name + "'");
            if (t.isPunct(')')) break;
            if (t.isPunct('{') || t.isPunct('}'))
                m_lex.fail(t, "expected ')' to close the joint list of channel '" + channel.name + "', found " +
                                  t.describe());
            channel.joints += t.text;
            if (t.text != "*" && t.text != "-") channel.joints += ' ';
        }
        while (!channel.joints.empty() && channel.joints.back() == ' ') channel.joints.pop_back();
        return channel;
    }

    // Names and aliases of the anims a model decl defined itself.
    struct OwnAnims {
        std::map<std::string, std::string, std::less<>> nameOfAlias; // alias → first anim name with it
        std::set<std::string, std::less<>> names;
    };

    ModelAnim parseAnim(const Token& keyword, const ModelDef& model, OwnAnims& own, const std::string& where) {
        requireMesh(keyword, model, where);
        ModelAnim anim;
        anim.location = m_lex.locationOf(keyword);
        const Value name = expectValue("an anim name after 'anim'");
        anim.name = name.text;
        if (!isValidAnimName(anim.name))
            m_lex.fail(name.token, "invalid animation name '" + anim.name +
                                       "' (the engine needs a non-digit after the first character)");
        // Without inherit nothing can be overridden, so a second anim of the same name is the engine's
        // "Duplicate anim"; with inherit it may be an override, which the Library decides.
        if (!model.inherit && own.names.count(anim.name))
            m_lex.fail(name.token, "duplicate anim '" + anim.name + "' in " + where);
        own.names.insert(anim.name);
        own.nameOfAlias.try_emplace(anim.alias(), anim.name);
        do {
            Value file = expectValue("an .md5anim file for anim '" + anim.name + "'");
            if (anim.files.size() == 3)
                m_lex.fail(file.token, "anim '" + anim.name + "' has more than 3 synced files (ANIM_MaxSyncedAnims)");
            anim.files.push_back(std::move(file.text));
        } while (m_lex.acceptPunct(','));
        if (m_lex.peek().isPunct('{')) anim.block = readBlock(anim.name);
        return anim;
    }

    // The frame-command block, kept verbatim; nesting is counted, not recursed.
    std::string readBlock(const std::string& animName) {
        const Token open = m_lex.next();
        const std::size_t begin = offsetOf(open) + 1;
        std::size_t depth = 1;
        while (true) {
            const Token t = m_lex.next();
            if (t.kind == TokenKind::End)
                m_lex.fail(open, "unterminated { } block of anim '" + animName + "' (missing '}')");
            if (t.isPunct('{')) ++depth;
            if (t.isPunct('}') && --depth == 0) return std::string(m_src.substr(begin, offsetOf(t) - begin));
        }
    }

    std::string parseRemove(const ModelDef& model, const OwnAnims& own, const std::string& where) {
        const Value name = expectValue("an anim name after 'remove'");
        const std::string& target = name.text;
        // The engine removes by name or alias; removing one of this decl's own anims is its "not inherited"
        // error.
        std::string ownAnim;
        if (own.names.count(target)) ownAnim = target;
        else if (const auto it = own.nameOfAlias.find(target); it != own.nameOfAlias.end()) ownAnim = it->second;
        if (!ownAnim.empty())
            m_lex.fail(name.token, "'remove " + target + "' in " + where + " comes after this decl's own anim '" +
                                       ownAnim + "': the engine only removes inherited anims (drop the anim instead)");
        if (!model.inherit)
            m_lex.fail(name.token, "'remove " + target + "' in " + where +
                                       ", which inherits nothing: there is no inherited anim to remove");
        return target;
    }

    std::size_t offsetOf(const Token& t) const { return static_cast<std::size_t>(t.text.data() - m_src.data()); }

    std::string_view m_src;
    text::Lexer m_lex;
};

} // namespace

std::optional<std::string> EntityDef::get(std::string_view key) const {
    for (auto it = keyValues.rbegin(); it != keyValues.rend(); ++it)
        if (text::equalsIgnoreCase(it->first, key)) return it->second;
    return std::nullopt;
}

std::string ModelAnim::alias() const {
    const std::size_t end = aliasEnd(name);
    return end == 0 ? name : name.substr(0, end + 1);
}

const ModelAnim* ModelDef::findAnim(std::string_view animName) const {
    for (const ModelAnim& a : anims)
        if (a.name == animName) return &a;
    return nullptr;
}

bool isModelChannelName(std::string_view name) {
    for (std::string_view c : {"torso", "legs", "head", "eyelids"})
        if (text::equalsIgnoreCase(c, name)) return true;
    return false;
}

bool isValidAnimName(std::string_view name) { return aliasEnd(name) > 0; }

std::optional<DefFile> parseDef(std::string_view text, const std::string& fileName, text::Diagnostics& diagnostics) {
    try {
        DefParser parser(text, fileName, diagnostics);
        return parser.parse();
    } catch (const text::ParseError& e) {
        diagnostics.error(e.where, e.what());
        return std::nullopt;
    }
}

std::optional<DefFile> loadDef(const std::filesystem::path& path, text::Diagnostics& diagnostics) {
    const std::optional<std::string> text = text::readFile(path, diagnostics);
    if (!text) return std::nullopt;
    return parseDef(*text, path.string(), diagnostics);
}

} // namespace afb::decl
