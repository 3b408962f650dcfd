// Canonical `.af` text: the inverse of parseAf for every value it can produce.
#include <charconv>
#include <cmath>

#include "afb/decl/AfParser.h"

namespace afb::decl {
namespace {

// Shortest text that reads back as exactly this double; a negative value is written as '-' then the number,
// which the lexer reads back as two tokens, as the engine does.
std::string afNumber(double v) {
    if (v == 0) v = 0; // -0 and 0 read back equal; write "0"
    char buf[64];
    auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
    const std::string_view text(buf, static_cast<std::size_t>(end - buf));
    // A large integral value prints without '.' or exponent; the lexer would read it as an integer, which must
    // fit 64 bits. The exponent form reads back as the same double.
    if (text.find_first_of(".e") == std::string_view::npos && std::abs(v) >= 1e15)
        end = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::scientific).ptr;
    return std::string(buf, end);
}

bool isBareName(std::string_view s) {
    if (s.empty()) return false;
    const char c0 = s[0];
    if (!((c0 >= 'a' && c0 <= 'z') || (c0 >= 'A' && c0 <= 'Z') || c0 == '_')) return false;
    for (char c : s)
        if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '/' ||
              c == '\\' || c == ':' || c == '.'))
            return false;
    return true;
}

std::string inQuotes(std::string_view s) { return "\"" + std::string(s) + "\""; }
std::string nameOrQuoted(std::string_view s) { return isBareName(s) ? std::string(s) : inQuotes(s); }

std::string vec(const AfVector& v) {
    std::string out = v.negated ? "-" : "";
    switch (v.form) {
    case AfVector::Form::Literal:
        return out + "( " + afNumber(v.literal.x) + ", " + afNumber(v.literal.y) + ", " + afNumber(v.literal.z) + " )";
    case AfVector::Form::Joint: return out + "joint( " + inQuotes(v.joint1) + " )";
    case AfVector::Form::BoneCenter:
        return out + "bonecenter( " + inQuotes(v.joint1) + ", " + inQuotes(v.joint2) + " )";
    case AfVector::Form::BoneDir: return out + "bonedir( " + inQuotes(v.joint1) + ", " + inQuotes(v.joint2) + " )";
    }
    return out;
}

std::string contents(const ContentsList& list) {
    std::string out;
    for (std::size_t i = 0; i < list.names.size(); ++i) out += (i ? ", " : "") + nameOrQuoted(list.names[i]);
    return out;
}

const char* shapeName(ShapeKind k) {
    switch (k) {
    case ShapeKind::Box: return "box";
    case ShapeKind::Octahedron: return "octahedron";
    case ShapeKind::Dodecahedron: return "dodecahedron";
    case ShapeKind::Cylinder: return "cylinder";
    case ShapeKind::Cone: return "cone";
    case ShapeKind::Bone: return "bone";
    }
    return "box";
}

std::string shape(const AfShape& s) {
    std::string out = std::string(shapeName(s.kind)) + "( " + vec(s.v1) + ", " + vec(s.v2);
    if (s.kind == ShapeKind::Cylinder || s.kind == ShapeKind::Cone) out += ", " + std::to_string(s.numSides);
    if (s.kind == ShapeKind::Bone) out += ", " + afNumber(s.width);
    return out + " )";
}

class Writer {
  public:
    std::string out;

    void line(const std::string& key, const std::string& value) { out += "\t\t" + key + " " + value + "\n"; }
    template <class T, class F>
    void opt(const std::string& key, const std::optional<T>& v, F&& format) {
        if (v) line(key, format(*v));
    }
    void optNum(const std::string& key, const std::optional<double>& v) { opt(key, v, afNumber); }
    void optStr(const std::string& key, const std::optional<std::string>& v) { opt(key, v, inQuotes); }
    void optVec(const std::string& key, const std::optional<AfVector>& v) { opt(key, v, vec); }
    void optBool(const std::string& key, const std::optional<bool>& v) {
        opt(key, v, [](bool b) { return std::string(b ? "1" : "0"); });
    }

    void settings(const AfSettings& s) {
        out += "\tsettings {\n";
        optStr("model", s.model);
        optStr("skin", s.skin);
        optStr("mesh", s.mesh);
        optStr("anim", s.anim);
        opt("friction", s.friction, [](const SettingsFriction& f) {
            return afNumber(f.linear) + ", " + afNumber(f.angular) + ", " + afNumber(f.contact) +
                   (f.constraint ? ", " + afNumber(*f.constraint) : "");
        });
        opt("suspendSpeed", s.suspendSpeed, [](const std::array<double, 4>& v) {
            return afNumber(v[0]) + ", " + afNumber(v[1]) + ", " + afNumber(v[2]) + ", " + afNumber(v[3]);
        });
        optNum("noMoveTime", s.noMoveTime);
        optNum("noMoveTranslation", s.noMoveTranslation);
        optNum("noMoveRotation", s.noMoveRotation);
        optNum("minMoveTime", s.minMoveTime);
        optNum("maxMoveTime", s.maxMoveTime);
        optNum("totalMass", s.totalMass);
        opt("contents", s.contents, contents);
        opt("clipMask", s.clipMask, contents);
        optBool("selfCollision", s.selfCollision);
        out += "\t}\n";
    }

    void body(const AfBody& b) {
        out += "\tbody " + inQuotes(b.name) + " {\n";
        line("joint", inQuotes(b.joint));
        opt("mod", b.mod, nameOrQuoted);
        opt("model", b.model, shape);
        optVec("origin", b.origin);
        optVec("angles", b.angles);
        optNum("density", b.density);
        opt("inertiaScale", b.inertiaScale, [](const std::array<double, 9>& m) {
            std::string s = "(";
            for (double x : m) s += " " + afNumber(x);
            return s + " )";
        });
        opt("friction", b.friction, [](const BodyFriction& f) {
            return afNumber(f.linear) + ", " + afNumber(f.angular) + ", " + afNumber(f.contact);
        });
        opt("contents", b.contents, contents);
        opt("clipMask", b.clipMask, contents);
        optBool("selfCollision", b.selfCollision);
        optStr("containedJoints", b.containedJoints);
        optVec("frictionDirection", b.frictionDirection);
        optVec("contactMotorDirection", b.contactMotorDirection);
        out += "\t}\n";
    }

    void constraint(const AfConstraint& c) {
        out += "\t" + std::string(keywordOf(c.type)) + " " + inQuotes(c.name) + " {\n";
        optStr("body1", c.body1);
        optStr("body2", c.body2);
        optVec(c.type == ConstraintType::Spring ? "anchor1" : "anchor", c.anchor);
        optVec("anchor2", c.anchor2);
        opt("shafts", c.shafts, [](const std::array<AfVector, 2>& s) { return vec(s[0]) + ", " + vec(s[1]); });
        optVec("axis", c.axis);
        optNum("friction", c.friction);
        if (const auto* cone = std::get_if<ConeLimit>(&c.limit))
            line("coneLimit",
                 vec(cone->axis) + ", " + afNumber(cone->angleDeg) + (cone->shaft ? ", " + vec(*cone->shaft) : ""));
        if (const auto* pyr = std::get_if<PyramidLimit>(&c.limit))
            line("pyramidLimit", vec(pyr->axis) + ", " + afNumber(pyr->angle1Deg) + ", " + afNumber(pyr->angle2Deg) +
                                     ", " + afNumber(pyr->rollDeg) + (pyr->shaft ? ", " + vec(*pyr->shaft) : ""));
        if (const auto* h = std::get_if<HingeLimit>(&c.limit))
            line("limit", afNumber(h->orientationDeg) + ", " + afNumber(h->widthDeg) + ", " + afNumber(h->angleDeg));
        optNum("stretch", c.stretch);
        optNum("compress", c.compress);
        optNum("damping", c.damping);
        optNum("restLength", c.restLength);
        optNum("minLength", c.minLength);
        optNum("maxLength", c.maxLength);
        out += "\t}\n";
    }
};

} // namespace

std::string writeAf(const AfDecl& decl) {
    Writer w;
    w.out = "articulatedFigure " + nameOrQuoted(decl.name) + " {\n";
    for (std::size_t i = 0; i < decl.order.size(); ++i) {
        if (i > 0) w.out += "\n";
        const AfBlockRef& ref = decl.order[i];
        switch (ref.kind) {
        case AfBlockRef::Kind::Settings: w.settings(decl.settings[ref.index]); break;
        case AfBlockRef::Kind::Body: w.body(decl.bodies[ref.index]); break;
        case AfBlockRef::Kind::Constraint: w.constraint(decl.constraints[ref.index]); break;
        }
    }
    w.out += "}\n";
    return w.out;
}

std::string writeAf(const AfFile& file) {
    std::string out;
    for (std::size_t i = 0; i < file.decls.size(); ++i) out += (i ? "\n" : "") + writeAf(file.decls[i]);
    return out;
}

} // namespace afb::decl
