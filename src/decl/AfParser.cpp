// `.af` parser: docs/format.md §1. Keys and block keywords are case-insensitive; vector keywords are not.
#include "afb/decl/AfParser.h"

#include <map>

#include "DeclFile.h"
#include "afb/detail/Lexer.h"
#include "afb/text/Files.h"

namespace afb::decl {
namespace {

using text::Lexer;
using text::Token;
using text::TokenKind;

class AfParser {
  public:
    explicit AfParser(Lexer& lex) : m_lex(lex) {}

    AfDecl parseDecl(const detail::DeclHeader& header) {
        AfDecl decl;
        decl.name = header.name;
        decl.location = m_lex.locationOf(header.typeToken);
        m_lex.expectPunct('{', "to open the figure");
        while (true) {
            const Token t = m_lex.next();
            if (t.isPunct('}')) break;
            if (t.kind == TokenKind::End)
                m_lex.fail(t, "unexpected end of file in articulatedFigure '" + decl.name + "'");
            if (t.isNameI("settings")) {
                decl.order.push_back({AfBlockRef::Kind::Settings, decl.settings.size()});
                decl.settings.push_back(parseSettings(t));
            } else if (t.isNameI("body")) {
                decl.order.push_back({AfBlockRef::Kind::Body, decl.bodies.size()});
                decl.bodies.push_back(parseBody(t));
            } else if (auto type = constraintTypeOf(t)) {
                decl.order.push_back({AfBlockRef::Kind::Constraint, decl.constraints.size()});
                decl.constraints.push_back(parseConstraint(t, *type));
            } else {
                m_lex.fail(t, "unknown block " + t.describe() + " in articulatedFigure '" + decl.name +
                                  "' (expected settings, body, fixed, ballAndSocketJoint, universalJoint, hinge, "
                                  "slider or spring)");
            }
        }
        checkNames(decl);
        return decl;
    }

  private:
    static std::optional<ConstraintType> constraintTypeOf(const Token& t) {
        if (t.isNameI("fixed")) return ConstraintType::Fixed;
        if (t.isNameI("ballAndSocketJoint")) return ConstraintType::BallAndSocket;
        if (t.isNameI("universalJoint")) return ConstraintType::Universal;
        if (t.isNameI("hinge")) return ConstraintType::Hinge;
        if (t.isNameI("slider")) return ConstraintType::Slider;
        if (t.isNameI("spring")) return ConstraintType::Spring;
        return std::nullopt;
    }

    // --- values ---------------------------------------------------------------------------------------

    Vec3 parseTriple(std::string_view what) {
        Vec3 v;
        v.x = m_lex.parseFloat(what);
        m_lex.expectPunct(',', "between vector components (the commas in ( x, y, z ) are required)");
        v.y = m_lex.parseFloat(what);
        m_lex.expectPunct(',', "between vector components (the commas in ( x, y, z ) are required)");
        v.z = m_lex.parseFloat(what);
        return v;
    }

    std::string parseJointName() {
        const Token t = m_lex.expectToken("a joint name");
        if (t.kind != TokenKind::String && t.kind != TokenKind::Name)
            m_lex.fail(t, "expected a joint name, found " + t.describe());
        return std::string(t.text);
    }

    // idAFVector::Parse (docs/format.md §1.2).
    AfVector parseVector(std::string_view what) {
        AfVector v;
        Token t = m_lex.expectToken(what);
        if (t.isPunct('-')) {
            v.negated = true;
            t = m_lex.expectToken(what);
        }
        if (t.isPunct('(')) {
            v.form = AfVector::Form::Literal;
            v.literal = parseTriple(what);
            m_lex.expectPunct(')', "to close the vector");
        } else if (t.isName("joint")) {
            v.form = AfVector::Form::Joint;
            m_lex.expectPunct('(', "after joint");
            v.joint1 = parseJointName();
            m_lex.expectPunct(')', "to close joint( )");
        } else if (t.isName("bonecenter") || t.isName("bonedir")) {
            v.form = t.isName("bonecenter") ? AfVector::Form::BoneCenter : AfVector::Form::BoneDir;
            m_lex.expectPunct('(', "after " + std::string(t.text));
            v.joint1 = parseJointName();
            m_lex.expectPunct(',', "between the two joints");
            v.joint2 = parseJointName();
            m_lex.expectPunct(')', "to close " + std::string(t.text) + "( )");
        } else {
            std::string hint;
            if (t.isNameI("joint") || t.isNameI("bonecenter") || t.isNameI("bonedir"))
                hint = " (the keywords joint, bonecenter and bonedir are case-sensitive)";
            m_lex.fail(t, "unknown token " + t.describe() + " in vector for " + std::string(what) + hint);
        }
        return v;
    }

    ContentsList parseContents(std::string_view what) {
        ContentsList list;
        do {
            const Token t = m_lex.expectToken("a contents name");
            if (t.kind != TokenKind::Name && t.kind != TokenKind::String)
                m_lex.fail(t, "expected a contents name for " + std::string(what) + ", found " + t.describe());
            list.names.emplace_back(t.text);
            if (!contentsBitsOfName(t.text) && list.names.size() < 64)
                m_lex.warn(t, "unknown contents name '" + std::string(t.text) + "' in " + std::string(what) +
                                  ": the engine silently drops it and every name after it (known: none, solid, "
                                  "playerclip, monsterclip, body, corpse)");
        } while (m_lex.acceptPunct(','));
        return list;
    }

    std::string parseQuoted(std::string_view what) { return m_lex.expectString(what); }

    // --- settings (docs/format.md §1.3) -----------------------------------------------------------------------

    AfSettings parseSettings(const Token& keyword) {
        AfSettings s;
        s.location = m_lex.locationOf(keyword);
        m_lex.expectPunct('{', "after settings");
        while (true) {
            const Token t = m_lex.next();
            if (t.isPunct('}')) break;
            if (t.isNameI("model")) s.model = parseQuoted("settings model");
            else if (t.isNameI("skin")) s.skin = parseQuoted("settings skin");
            else if (t.isNameI("mesh")) s.mesh = parseQuoted("settings mesh");
            else if (t.isNameI("anim")) s.anim = parseQuoted("settings anim");
            else if (t.isNameI("friction")) {
                SettingsFriction f;
                f.linear = m_lex.parseFloat("linear friction");
                m_lex.expectPunct(',', "in friction");
                f.angular = m_lex.parseFloat("angular friction");
                m_lex.expectPunct(',', "in friction");
                f.contact = m_lex.parseFloat("contact friction");
                if (m_lex.acceptPunct(',')) f.constraint = m_lex.parseFloat("constraint friction");
                s.friction = f;
            } else if (t.isNameI("suspendSpeed")) {
                std::array<double, 4> v{};
                for (std::size_t i = 0; i < 4; ++i) {
                    if (i > 0) m_lex.expectPunct(',', "in suspendSpeed");
                    v[i] = m_lex.parseFloat("suspendSpeed");
                }
                s.suspendSpeed = v;
            } else if (t.isNameI("noMoveTime")) s.noMoveTime = m_lex.parseFloat("noMoveTime");
            else if (t.isNameI("noMoveTranslation")) s.noMoveTranslation = m_lex.parseFloat("noMoveTranslation");
            else if (t.isNameI("noMoveRotation")) s.noMoveRotation = m_lex.parseFloat("noMoveRotation");
            else if (t.isNameI("minMoveTime")) s.minMoveTime = m_lex.parseFloat("minMoveTime");
            else if (t.isNameI("maxMoveTime")) s.maxMoveTime = m_lex.parseFloat("maxMoveTime");
            else if (t.isNameI("totalMass")) s.totalMass = m_lex.parseFloat("totalMass");
            else if (t.isNameI("contents")) s.contents = parseContents("settings contents");
            else if (t.isNameI("clipMask")) s.clipMask = parseContents("settings clipMask");
            else if (t.isNameI("selfCollision")) s.selfCollision = m_lex.parseBool("selfCollision");
            else if (t.kind == TokenKind::End) m_lex.fail(t, "unexpected end of file in settings");
            else m_lex.fail(t, "unknown token " + t.describe() + " in settings");
        }
        return s;
    }

    // --- bodies (docs/format.md §1.4, §1.5) ---------------------------------------------------------------------

    AfShape parseShape() {
        AfShape shape;
        const Token kind = m_lex.expectName("a shape (box, octahedron, dodecahedron, cylinder, cone or bone)");
        if (kind.isNameI("box")) shape.kind = ShapeKind::Box;
        else if (kind.isNameI("octahedron")) shape.kind = ShapeKind::Octahedron;
        else if (kind.isNameI("dodecahedron")) shape.kind = ShapeKind::Dodecahedron;
        else if (kind.isNameI("cylinder")) shape.kind = ShapeKind::Cylinder;
        else if (kind.isNameI("cone")) shape.kind = ShapeKind::Cone;
        else if (kind.isNameI("bone")) shape.kind = ShapeKind::Bone;
        else if (kind.isNameI("custom")) m_lex.fail(kind, "custom models are not implemented (nor in the engine)");
        else m_lex.fail(kind, "unknown model type " + kind.describe());
        m_lex.expectPunct('(', "after the shape name");
        shape.v1 = parseVector("shape bounds");
        m_lex.expectPunct(',', "between the shape's vectors");
        shape.v2 = parseVector("shape bounds");
        if (shape.kind == ShapeKind::Cylinder || shape.kind == ShapeKind::Cone) {
            m_lex.expectPunct(',', "before the number of sides");
            shape.numSides = m_lex.parseInt("numSides");
        } else if (shape.kind == ShapeKind::Bone) {
            m_lex.expectPunct(',', "before the bone width");
            shape.width = m_lex.parseFloat("bone width");
        }
        m_lex.expectPunct(')', "to close the shape");
        return shape;
    }

    AfBody parseBody(const Token& keyword) {
        AfBody b;
        b.location = m_lex.locationOf(keyword);
        const Token nameToken = m_lex.peek();
        b.name = m_lex.expectString("a body name");
        if (text::equalsIgnoreCase(b.name, "origin") || text::equalsIgnoreCase(b.name, "world"))
            m_lex.fail(nameToken, "a body may not be named '" + b.name + "' (origin and world are reserved)");
        m_lex.expectPunct('{', "after the body name");
        bool hasJoint = false;
        while (true) {
            const Token t = m_lex.next();
            if (t.isPunct('}')) break;
            if (t.isNameI("joint")) {
                b.joint = parseQuoted("the body's joint");
                hasJoint = true;
            } else if (t.isNameI("mod")) {
                const Token m = m_lex.expectToken("a joint mod");
                b.mod = std::string(m.text);
                const auto is = [&](std::string_view v) { return text::equalsIgnoreCase(m.text, v); };
                if (m.kind == TokenKind::Punct || !(is("orientation") || is("position") || is("both")))
                    m_lex.warn(m, "unknown mod " + m.describe() + " in body '" + b.name +
                                      "': the engine treats it as orientation");
            } else if (t.isNameI("model")) b.model = parseShape();
            else if (t.isNameI("origin")) b.origin = parseVector("origin");
            else if (t.isNameI("angles")) {
                const Token at = m_lex.peek();
                b.angles = parseVector("angles");
                if (b.angles->negated || b.angles->form != AfVector::Form::Literal)
                    m_lex.warn(at, "angles of body '" + b.name +
                                       "' use a '-' or a joint form, which the engine ignores (angles are read as "
                                       "literal pitch, yaw, roll; joint forms give 0)");
            } else if (t.isNameI("density")) b.density = m_lex.parseFloat("density");
            else if (t.isNameI("inertiaScale")) {
                std::array<double, 9> m{};
                m_lex.expectPunct('(', "to open inertiaScale (nine numbers without commas)");
                for (double& x : m) {
                    if (m_lex.peek().isPunct(','))
                        m_lex.fail(m_lex.peek(), "inertiaScale takes nine numbers without commas");
                    x = m_lex.parseFloat("inertiaScale");
                }
                m_lex.expectPunct(')', "to close inertiaScale (exactly nine numbers)");
                b.inertiaScale = m;
            } else if (t.isNameI("friction")) {
                BodyFriction f;
                f.linear = m_lex.parseFloat("linear friction");
                m_lex.expectPunct(',', "in friction");
                f.angular = m_lex.parseFloat("angular friction");
                m_lex.expectPunct(',', "in friction");
                f.contact = m_lex.parseFloat("contact friction");
                b.friction = f;
            } else if (t.isNameI("contents")) b.contents = parseContents("body contents");
            else if (t.isNameI("clipMask")) b.clipMask = parseContents("body clipMask");
            else if (t.isNameI("selfCollision")) b.selfCollision = m_lex.parseBool("selfCollision");
            else if (t.isNameI("containedJoints")) b.containedJoints = parseQuoted("containedJoints");
            else if (t.isNameI("frictionDirection")) b.frictionDirection = parseVector("frictionDirection");
            else if (t.isNameI("contactMotorDirection")) b.contactMotorDirection = parseVector("contactMotorDirection");
            else if (t.kind == TokenKind::End) m_lex.fail(t, "unexpected end of file in body '" + b.name + "'");
            else m_lex.fail(t, "unknown token " + t.describe() + " in body '" + b.name + "'");
        }
        if (!hasJoint) m_lex.fail(keyword, "no joint set for body '" + b.name + "' (the joint key is mandatory)");
        return b;
    }

    // --- constraints (docs/format.md §1.7) ------------------------------------------------------------------------

    AfConstraint parseConstraint(const Token& keyword, ConstraintType type) {
        AfConstraint c;
        c.type = type;
        c.location = m_lex.locationOf(keyword);
        c.name = m_lex.expectString(std::string("a ") + keywordOf(type) + " name");
        m_lex.expectPunct('{', "after the constraint name");
        const std::string where = std::string(keywordOf(type)) + " '" + c.name + "'";
        const bool ball = type == ConstraintType::BallAndSocket;
        const bool universal = type == ConstraintType::Universal;
        const bool hinge = type == ConstraintType::Hinge;
        const bool spring = type == ConstraintType::Spring;
        while (true) {
            const Token t = m_lex.next();
            if (t.isPunct('}')) break;
            if (t.kind == TokenKind::End) m_lex.fail(t, "unexpected end of file in " + where);
            if (t.isNameI("body1") || t.isNameI("body2")) {
                const Token at = m_lex.peek();
                std::string name = parseQuoted(std::string(t.text) + " name");
                if (name.empty()) m_lex.fail(at, std::string(t.text) + " of " + where + " is an empty name");
                (t.isNameI("body1") ? c.body1 : c.body2) = std::move(name);
            } else if (type == ConstraintType::Fixed) {
                failUnknown(t, where);
            } else if (t.isNameI("friction")) {
                c.friction = m_lex.parseFloat("friction");
            } else if ((ball || universal || hinge) && t.isNameI("anchor")) {
                c.anchor = parseVector("anchor");
            } else if (spring && t.isNameI("anchor1")) {
                c.anchor = parseVector("anchor1");
            } else if (spring && t.isNameI("anchor2")) {
                c.anchor2 = parseVector("anchor2");
            } else if (universal && t.isNameI("shafts")) {
                std::array<AfVector, 2> s;
                s[0] = parseVector("shaft 1");
                m_lex.expectPunct(',', "between the two shafts");
                s[1] = parseVector("shaft 2");
                c.shafts = s;
            } else if ((hinge || type == ConstraintType::Slider) && t.isNameI("axis")) {
                c.axis = parseVector("axis");
            } else if ((ball || universal) && t.isNameI("coneLimit")) {
                ConeLimit l;
                l.axis = parseVector("cone limit axis");
                m_lex.expectPunct(',', "in coneLimit");
                l.angleDeg = m_lex.parseFloat("cone limit angle");
                if (ball) {
                    m_lex.expectPunct(',', "in coneLimit");
                    l.shaft = parseVector("cone limit shaft");
                }
                c.limit = l;
            } else if ((ball || universal) && t.isNameI("pyramidLimit")) {
                PyramidLimit l;
                l.axis = parseVector("pyramid limit axis");
                m_lex.expectPunct(',', "in pyramidLimit");
                l.angle1Deg = m_lex.parseFloat("pyramid limit angle 1");
                m_lex.expectPunct(',', "in pyramidLimit");
                l.angle2Deg = m_lex.parseFloat("pyramid limit angle 2");
                m_lex.expectPunct(',', "in pyramidLimit");
                l.rollDeg = m_lex.parseFloat("pyramid limit roll");
                if (ball) {
                    m_lex.expectPunct(',', "in pyramidLimit");
                    l.shaft = parseVector("pyramid limit shaft");
                }
                c.limit = l;
            } else if (hinge && t.isNameI("limit")) {
                HingeLimit l;
                l.orientationDeg = m_lex.parseFloat("hinge limit orientation");
                m_lex.expectPunct(',', "in limit");
                l.widthDeg = m_lex.parseFloat("hinge limit width");
                m_lex.expectPunct(',', "in limit");
                l.angleDeg = m_lex.parseFloat("hinge limit angle");
                c.limit = l;
            } else if (spring && t.isNameI("stretch")) c.stretch = m_lex.parseFloat("stretch");
            else if (spring && t.isNameI("compress")) c.compress = m_lex.parseFloat("compress");
            else if (spring && t.isNameI("damping")) c.damping = m_lex.parseFloat("damping");
            else if (spring && t.isNameI("restLength")) c.restLength = m_lex.parseFloat("restLength");
            else if (spring && t.isNameI("minLength")) c.minLength = m_lex.parseFloat("minLength");
            else if (spring && t.isNameI("maxLength")) c.maxLength = m_lex.parseFloat("maxLength");
            else failUnknown(t, where);
        }
        return c;
    }

    [[noreturn]] void failUnknown(const Token& t, const std::string& where) {
        std::string hint;
        if (t.isNameI("anchor") && where.rfind("spring", 0) == 0) hint = " (a spring uses anchor1 and anchor2)";
        if (t.isNameI("limit")) hint = " (limit is accepted only inside a hinge)";
        m_lex.fail(t, "unknown token " + t.describe() + " in " + where + hint);
    }

    // docs/format.md §1.8: duplicate names. Exact duplicates are errors (the engine logs one); names that differ only
    // in case are warnings here, because the engine's case-insensitive lookups merge them at load.
    void checkNames(const AfDecl& decl) {
        auto check = [&](const auto& items, const char* what) {
            std::map<std::string, std::size_t> seen;
            for (std::size_t i = 0; i < items.size(); ++i) {
                std::string key = items[i].name;
                for (char& ch : key) ch = static_cast<char>((ch >= 'A' && ch <= 'Z') ? ch - 'A' + 'a' : ch);
                const auto [it, fresh] = seen.emplace(key, i);
                if (fresh) continue;
                const auto& first = items[it->second];
                const text::SourceLocation& loc = items[i].location;
                if (first.name == items[i].name) {
                    throw text::ParseError(loc, std::string("duplicate ") + what + " name '" + items[i].name +
                                                    "' (first at " + first.location.str() + ")");
                }
                m_lex.diagnostics().warning(loc, std::string(what) + " name '" + items[i].name +
                                                     "' differs only in case from '" + first.name + "' at " +
                                                     first.location.str() +
                                                     ": the engine's case-insensitive lookup merges them");
            }
        };
        check(decl.bodies, "body");
        check(decl.constraints, "constraint");
    }

    Lexer& m_lex;
};

} // namespace

std::optional<AfFile> parseAf(std::string_view text, const std::string& fileName, text::Diagnostics& diagnostics) {
    text::Diagnostics local;
    Lexer lex(text, fileName, local);
    lex.setBackslashStringConcatenation(true);
    AfFile file;
    try {
        AfParser parser(lex);
        detail::forEachDecl(lex, "articulatedFigure", [&](const detail::DeclHeader& header) {
            if (header.type != "articulatedFigure") {
                lex.warn(header.typeToken, "skipping " + header.type + " '" + header.name + "' in an .af file");
                return false;
            }
            file.decls.push_back(parser.parseDecl(header));
            return true;
        });
    } catch (const text::ParseError& e) {
        local.error(e.where, e.what());
    }
    diagnostics.append(local);
    if (local.hasErrors()) return std::nullopt;
    return file;
}

std::optional<AfFile> loadAf(const std::filesystem::path& path, text::Diagnostics& diagnostics) {
    const std::optional<std::string> data = text::readFile(path, diagnostics);
    if (!data) return std::nullopt;
    return parseAf(*data, path.string(), diagnostics);
}

} // namespace afb::decl
