// Building a Figure from an `.af` decl and its skeleton: docs/format.md §1.8 (ordering), §2 (placement), §3
// (shapes and mass), §4 (constraint meaning), §5.3 (containedJoints), §6 (rest, collision). Findings name
// every silent engine fallback and every "behave weird or explode" condition of id's modding guide. This file
// holds the build order and what every part shares; FigureBuilder.h says where the rest lives.
#include "FigureBuilder.h"

#include <sstream>

#include "afb/detail/DoomMath.h"
#include "afb/detail/Lexer.h"

namespace afb::figure {
namespace detail {

std::string fmt(double v) {
    std::ostringstream s;
    s.precision(4);
    s << v;
    return s.str();
}

std::string lower(std::string s) {
    for (char& c : s) c = static_cast<char>((c >= 'A' && c <= 'Z') ? c - 'A' + 'a' : c);
    return s;
}

ShapeType shapeTypeOf(decl::ShapeKind kind) {
    switch (kind) {
    case decl::ShapeKind::Box: return ShapeType::Box;
    case decl::ShapeKind::Octahedron: return ShapeType::Octahedron;
    case decl::ShapeKind::Dodecahedron: return ShapeType::Dodecahedron;
    case decl::ShapeKind::Cylinder: return ShapeType::Cylinder;
    case decl::ShapeKind::Cone: return ShapeType::Cone;
    case decl::ShapeKind::Bone: return ShapeType::Bone;
    }
    return ShapeType::Box;
}

JointType jointTypeOf(decl::ConstraintType type) {
    switch (type) {
    case decl::ConstraintType::Fixed: return JointType::Fixed;
    case decl::ConstraintType::BallAndSocket: return JointType::BallAndSocket;
    case decl::ConstraintType::Universal: return JointType::Universal;
    case decl::ConstraintType::Hinge: return JointType::Hinge;
    case decl::ConstraintType::Slider: return JointType::Slider;
    case decl::ConstraintType::Spring: return JointType::Spring;
    }
    return JointType::Fixed;
}

// decl::contentsBits yields the engine's bits, which FigureBody stores as they are.
static_assert(kContentsSolid == decl::kContentsSolid && kContentsPlayerClip == decl::kContentsPlayerClip &&
              kContentsMonsterClip == decl::kContentsMonsterClip &&
              kContentsMoveableClip == decl::kContentsMoveableClip && kContentsBody == decl::kContentsBody &&
              kContentsCorpse == decl::kContentsCorpse);

Builder::Builder(const FigureInput& in, text::Diagnostics& findings)
    : m_decl(*in.decl), m_skel(*in.skeleton), m_units(in.units), m_strict(in.strict),
      m_findings(findings), m_figure{.name = in.decl->name,
                                     .units = in.units,
                                     .skeleton = *in.skeleton,
                                     .bodies = {},
                                     .constraints = {},
                                     .selfCollision = true,
                                     .rest = {},
                                     .jointBody = {},
                                     .totalMassKg = 0} {}

std::optional<Figure> Builder::build() {
    const std::size_t errorsBefore = m_findings.errorCount();
    const decl::AfSettingsValues settings = m_decl.finalSettings();
    m_figure.selfCollision = settings.selfCollision;
    applyRestRules(settings);
    checkNumbers();
    if (m_findings.errorCount() > errorsBefore) return std::nullopt;

    std::vector<std::size_t> order = bodyOrder();
    if (m_findings.errorCount() > errorsBefore) return std::nullopt;
    for (std::size_t k = 0; k < order.size(); ++k) buildBody(order[k], k == 0);
    if (m_findings.errorCount() > errorsBefore) return std::nullopt;
    applyTotalMass(settings.totalMass);
    checkBodyBounds();
    if (m_findings.errorCount() > errorsBefore) return std::nullopt;
    for (std::size_t k = 0; k < m_work.size(); ++k) m_figure.bodies.push_back(finishBody(k));
    for (std::size_t i = 0; i < m_decl.constraints.size(); ++i) buildConstraint(i);
    if (m_findings.errorCount() > errorsBefore) return std::nullopt;
    mapContainedJoints();
    checkFigure();
    if (m_findings.errorCount() > errorsBefore) return std::nullopt;
    return std::move(m_figure);
}

// §1.8: the first body whose joint is exactly "origin" is swapped with body 0.
std::vector<std::size_t> Builder::bodyOrder() {
    std::vector<std::size_t> order(m_decl.bodies.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    if (order.empty()) {
        error(m_decl.location, "articulatedFigure '" + m_decl.name + "' has no bodies");
        return order;
    }
    std::optional<std::size_t> origin;
    for (std::size_t i = 0; i < order.size(); ++i) {
        const AfBody& b = m_decl.bodies[i];
        if (b.joint != "origin") {
            if (text::equalsIgnoreCase(b.joint, "origin"))
                warning(b.location, "body '" + b.name + "' uses joint \"" + b.joint +
                                        "\": only the exact lowercase \"origin\" makes the origin body");
            continue;
        }
        if (!origin) origin = i;
        else
            error(b.location, "body '" + b.name + "' is a second body on joint \"origin\" (first: '" +
                                  m_decl.bodies[*origin].name + "'); the engine would clobber the base");
    }
    if (!origin) {
        error(m_decl.location, "no body uses joint \"origin\": the engine refuses the figure (idAF::Load)");
        return order;
    }
    std::swap(order[0], order[*origin]);
    return order;
}

std::optional<int> Builder::joint(const std::string& name, const text::SourceLocation& at, const std::string& what) {
    if (auto j = m_skel.findJoint(name)) return j;
    error(at, what + ": joint \"" + name + "\" not found in the skeleton");
    return std::nullopt;
}

// §1.2: a vector expression at the load pose, Doom units, negation applied once.
Vector3d Builder::eval(const AfVector& v, const text::SourceLocation& at, const std::string& what) {
    Vector3d r = Vector3d::Zero();
    const auto& pose = m_skel.loadPose();
    auto pos = [&](const std::string& name) -> Vector3d {
        const auto j = joint(name, at, what);
        return j ? pose[static_cast<std::size_t>(*j)].position : Vector3d::Zero();
    };
    switch (v.form) {
    case AfVector::Form::Literal: r = {v.literal.x, v.literal.y, v.literal.z}; break;
    case AfVector::Form::Joint: r = pos(v.joint1); break;
    case AfVector::Form::BoneCenter: r = 0.5 * (pos(v.joint1) + pos(v.joint2)); break;
    case AfVector::Form::BoneDir: r = pos(v.joint2) - pos(v.joint1); break;
    }
    return v.negated ? Vector3d(-r) : r;
}

void Builder::applyRestRules(const decl::AfSettingsValues& st) {
    RestRules& r = m_figure.rest;
    r.linearSpeedMps = st.suspendSpeed[0] * s();
    r.angularSpeedRadps = st.suspendSpeed[1];
    r.linearAccelMps2 = st.suspendSpeed[2] * s();
    r.angularAccelRadps2 = st.suspendSpeed[3];
    r.noMoveTimeS = st.noMoveTime;
    r.noMoveTranslationM = st.noMoveTranslation * s();
    r.noMoveRotationRad = st.noMoveRotation * kRadPerDeg;
    r.minMoveTimeS = st.minMoveTime;
    r.maxMoveTimeS = st.maxMoveTime;
}

} // namespace detail

std::optional<Figure> buildFigure(const FigureInput& input, text::Diagnostics& findings) {
    if (!input.decl || !input.skeleton) {
        findings.error({}, "buildFigure needs a decl and a skeleton");
        return std::nullopt;
    }
    return detail::Builder(input, findings).build();
}

} // namespace afb::figure
