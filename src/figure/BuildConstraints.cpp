// A figure's constraints (docs/format.md §4): bodies, frames in both bodies, limits, friction and springs.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "FigureBuilder.h"
#include "afb/detail/DoomMath.h"
#include "afb/detail/Lexer.h"
#include "afb/figure/Bounds.h"

namespace afb::figure::detail {

// A right-handed frame whose column `axisIndex` is `dir` normalized.
Matrix3d frameWithAxis(const Vector3d& dir, int axisIndex) {
    const Vector3d a = dir.normalized();
    const Vector3d helper = std::abs(a.x()) < 0.9 ? Vector3d::UnitX() : Vector3d::UnitY();
    const Vector3d b = a.cross(helper).normalized();
    const Vector3d c = a.cross(b);
    Matrix3d m;
    m.col(axisIndex) = a;
    m.col((axisIndex + 1) % 3) = b;
    m.col((axisIndex + 2) % 3) = c;
    return m;
}

std::optional<int> Builder::bodyIndex(const std::string& name) const {
    for (std::size_t k = 0; k < m_work.size(); ++k)
        if (text::equalsIgnoreCase(m_work[k].decl->name, name)) return static_cast<int>(k);
    return std::nullopt;
}

// `frame` (model space, metres) expressed in a body's frame, or kept in model space for the world.
Transform Builder::inBody(int body, const Transform& frame) const {
    if (body < 0) return frame;
    return m_figure.bodies[static_cast<std::size_t>(body)].loadPose.inverse() * frame;
}

Vector3d Builder::dirInBody(int body, const Vector3d& dirModel) const {
    if (body < 0) return dirModel;
    return m_figure.bodies[static_cast<std::size_t>(body)].loadPose.rotation.transpose() * dirModel;
}

// The constraint's two bodies (body2 absent or unknown: the world). False, with an error, when body1 matches no
// body or both are the same.
bool Builder::constraintBodies(std::size_t i, FigureConstraint& out, const std::string& what) {
    const AfConstraint& c = m_decl.constraints[i];
    const std::string name1 = c.body1.value_or(m_decl.defaultBody1(i));
    const std::optional<int> b1 = bodyIndex(name1);
    if (!b1) {
        error(c.location, what + ": body1 \"" + name1 + "\" matches no body (the engine would crash)");
        return false;
    }
    out.body1 = *b1;
    const std::string name2 = c.body2.value_or("world");
    if (const std::optional<int> b2 = bodyIndex(name2)) {
        out.body2 = *b2;
    } else {
        out.body2 = -1;
        if (!text::equalsIgnoreCase(name2, "world"))
            warning(c.location,
                    what + ": body2 \"" + name2 + "\" matches no body, so the constraint attaches to the world");
    }
    if (out.body1 == out.body2) {
        error(c.location, what + ": body1 and body2 are the same body '" + name1 + "'");
        return false;
    }
    return true;
}

// The joint's friction (§4.8): 0.5 unless given, none for fixed joints; parsed but never applied to sliders and
// springs; bounded by kMaxJointFriction. False, with an error, when negative.
bool Builder::jointFriction(const AfConstraint& c, FigureConstraint& out, const std::string& what) {
    out.friction = out.type == JointType::Fixed ? 0.0 : c.friction.value_or(0.5);
    if (out.friction < 0.0) {
        error(c.location, what + ": friction " + fmt(out.friction) + " is negative (it bounds a resisting force)");
        return false;
    }
    if ((out.type == JointType::Slider || out.type == JointType::Spring) && c.friction && *c.friction != 0.0)
        warning(c.location, what + ": friction is parsed but never applied by the engine to this type");
    if (out.type == JointType::Slider || out.type == JointType::Spring) out.friction = 0.0;
    out.friction = clampFriction(out.friction, kMaxJointFriction, c.location, what + ": joint friction");
    return true;
}

void Builder::buildConstraint(std::size_t i) {
    const AfConstraint& c = m_decl.constraints[i];
    const std::string what = std::string(decl::keywordOf(c.type)) + " '" + c.name + "'";
    FigureConstraint out;
    out.name = c.name;
    out.location = c.location;
    out.type = jointTypeOf(c.type);
    if (!constraintBodies(i, out, what) || !jointFriction(c, out, what)) return;
    const FigureBody& body1 = m_figure.bodies[static_cast<std::size_t>(out.body1)];
    const Matrix3d ref =
        out.body2 >= 0 ? m_figure.bodies[static_cast<std::size_t>(out.body2)].loadPose.rotation : Matrix3d::Identity();
    bool farAway = false;
    auto point = [&](const std::optional<AfVector>& v) -> Vector3d {
        const Vector3d p = v ? eval(*v, c.location, what) : Vector3d::Zero();
        if (!withinFigure(p, c.location, what + " anchor")) farAway = true;
        return p * s();
    };
    auto direction = [&](const std::optional<AfVector>& v, const char* key) -> std::optional<Vector3d> {
        const Vector3d d = v ? eval(*v, c.location, what) : Vector3d::Zero();
        if (d.norm() > 0.0 && std::isfinite(d.norm())) return d;
        error(c.location, what + ": " + key + " is a zero vector (the engine needs it; it defaults to 0)");
        return std::nullopt;
    };
    Transform frame; // model space, metres; origin = anchor
    switch (out.type) {
    case JointType::Fixed: frame = body1.loadPose; break;
    case JointType::BallAndSocket:
        frame = {ref, point(c.anchor)};
        out.limit = limit(c, out, what, std::nullopt);
        break;
    case JointType::Universal: {
        if (!c.shafts) {
            error(c.location, what + ": no shafts (both default to zero vectors in the engine)");
            return;
        }
        const auto s1 = direction(c.shafts->at(0), "shaft 1");
        const auto s2 = direction(c.shafts->at(1), "shaft 2");
        if (!s1 || !s2) return;
        if (s1->normalized().dot(s2->normalized()) > -1.0 + 1e-6)
            warning(c.location, what + ": shafts are not opposite; mapped as no relative spin about shaft 1 "
                                       "(exact for the usual opposite shafts, §4.4)");
        frame = {frameWithAxis(*s1, 0), point(c.anchor)};
        out.limit = limit(c, out, what, s1->normalized());
        break;
    }
    case JointType::Hinge: {
        const auto axis = direction(c.axis, "axis");
        if (!axis) return;
        frame = {frameWithAxis(*axis, 2), point(c.anchor)};
        if (const auto* h = std::get_if<decl::HingeLimit>(&c.limit)) out.limit = hingeRange(*h, axis->norm(), c, what);
        break;
    }
    case JointType::Slider: {
        const Vector3d raw = c.axis ? eval(*c.axis, c.location, what) : Vector3d::UnitX();
        if (!(raw.norm() > 0.0)) {
            error(c.location, what + ": axis is a zero vector");
            return;
        }
        frame = {frameWithAxis(raw, 0), body1.loadPose.position};
        break;
    }
    case JointType::Spring: {
        if (!spring(c, out, what)) return;
        // §4.7 defaults: a missing anchor is the model origin, usually far from its body (anchor1 written twice
        // leaves anchor2 there), and the spring then pulls on a long lever.
        for (const auto& [anchor, key] : {std::pair{&c.anchor, "anchor1"}, {&c.anchor2, "anchor2"}})
            if (!*anchor)
                warning(c.location, what + ": no " + key + "; the engine places it at the model origin (0, 0, 0)");
        const Vector3d anchor1 = point(c.anchor), anchor2 = point(c.anchor2);
        out.frameInBody1 = inBody(out.body1, {Matrix3d::Identity(), anchor1});
        out.frameInBody2 = inBody(out.body2, {Matrix3d::Identity(), anchor2});
        if (farAway) return;
        lintSpringAtLoadPose(out, (anchor2 - anchor1).norm(), what);
        out.disablesCollision = false;
        m_figure.constraints.push_back(std::move(out));
        return;
    }
    }
    if (farAway) return;
    out.frameInBody1 = inBody(out.body1, frame);
    out.frameInBody2 = inBody(out.body2, frame);
    lintLimitAtLoadPose(out, what);
    m_figure.constraints.push_back(std::move(out));
}

// Cone and pyramid limits (§4.3, §4.4): the shaft is fixed in body1, the axis or basis in body2.
Limit Builder::limit(const AfConstraint& c, const FigureConstraint& out, const std::string& what,
                     std::optional<Vector3d> shaftModel) {
    auto shaftOf = [&](const std::optional<AfVector>& v) -> std::optional<Vector3d> {
        if (shaftModel) return shaftModel;
        const Vector3d d = v ? eval(*v, c.location, what) : Vector3d::Zero();
        if (d.norm() > 0.0) return d.normalized();
        error(c.location, what + ": the limit's shaft is a zero vector");
        return std::nullopt;
    };
    // Apex angles are full angles of a cone or pyramid: [0, 360] degrees (§4.3); outside is no cone at all.
    auto apexAngle = [&](double deg, const char* name) {
        if (deg >= 0.0 && deg <= 360.0) return true;
        error(c.location, what + ": " + name + " " + fmt(deg) + " deg is outside [0, 360] deg");
        return false;
    };
    if (const auto* cone = std::get_if<decl::ConeLimit>(&c.limit)) {
        if (!apexAngle(cone->angleDeg, "the cone angle")) return std::monostate{};
        const Vector3d a = eval(cone->axis, c.location, what);
        const auto shaft = shaftOf(cone->shaft);
        if (!(a.norm() > 0.0) || !shaft) {
            if (!(a.norm() > 0.0)) error(c.location, what + ": the cone limit's axis is a zero vector");
            return std::monostate{};
        }
        ConeLimit l;
        l.axisInBody2 = dirInBody(out.body2, a.normalized());
        l.shaftInBody1 = dirInBody(out.body1, *shaft);
        l.halfAngleRad = 0.5 * cone->angleDeg * kRadPerDeg;
        return l;
    }
    if (const auto* pyr = std::get_if<decl::PyramidLimit>(&c.limit)) {
        if (!apexAngle(pyr->angle1Deg, "the pyramid's first angle") ||
            !apexAngle(pyr->angle2Deg, "the pyramid's second angle"))
            return std::monostate{};
        const Vector3d a = eval(pyr->axis, c.location, what);
        const auto shaft = shaftOf(pyr->shaft);
        if (!(a.norm() > 0.0) || !shaft) {
            if (!(a.norm() > 0.0)) error(c.location, what + ": the pyramid limit's axis is a zero vector");
            return std::monostate{};
        }
        // §4.3: basis from A.ToAngles() with roll; columns forward f, left l, up f×l.
        const PitchYaw py = toAngles(a);
        const Matrix3d basis = anglesToRotation(py.pitchDeg, py.yawDeg, pyr->rollDeg);
        PyramidLimit l;
        l.basisInBody2 = basis;
        if (out.body2 >= 0)
            l.basisInBody2 = m_figure.bodies[static_cast<std::size_t>(out.body2)].loadPose.rotation.transpose() * basis;
        l.shaftInBody1 = dirInBody(out.body1, *shaft);
        l.halfAngle1Rad = 0.5 * pyr->angle1Deg * kRadPerDeg;
        l.halfAngle2Rad = 0.5 * pyr->angle2Deg * kRadPerDeg;
        return l;
    }
    return std::monostate{};
}

// §4.5: φ ∈ [g(a2) − g(a0) − a1/2, g(a2) − g(a0) + a1/2], g the engine's non-unit-axis distortion.
Limit Builder::hingeRange(const decl::HingeLimit& h, double axisLength, const AfConstraint& c,
                          const std::string& what) {
    if (h.widthDeg >= 360.0) return std::monostate{};
    const double a0 = h.orientationDeg * kRadPerDeg, a2 = h.angleDeg * kRadPerDeg;
    double centre = nonUnitAxisAngle(a2, axisLength) - nonUnitAxisAngle(a0, axisLength);
    if (std::abs(axisLength - 1.0) > 1e-6 && h.orientationDeg != h.angleDeg) {
        const double plain = std::remainder(a2 - a0, 2 * std::numbers::pi);
        const double distorted = std::remainder(centre, 2 * std::numbers::pi);
        if (std::abs(plain - distorted) > 1e-9)
            warning(c.location, what + ": the axis has length " + fmt(axisLength) +
                                    " (not 1), which distorts the limit in the engine: its centre is " +
                                    fmt(distorted / kRadPerDeg) + " deg instead of " + fmt(plain / kRadPerDeg) +
                                    " deg; the engine's value is used");
    }
    centre = std::remainder(centre, 2 * std::numbers::pi);
    const double half = 0.5 * std::max(0.0, h.widthDeg) * kRadPerDeg;
    return HingeRange{centre - half, centre + half};
}

bool Builder::spring(const AfConstraint& c, FigureConstraint& out, const std::string& what) {
    bool ok = true;
    auto need = [&](const std::optional<double>& v, const char* key) {
        if (v) return *v;
        error(c.location, what + ": no " + key + " (the engine leaves it uninitialised)");
        ok = false;
        return 0.0;
    };
    const double stretch = need(c.stretch, "stretch"), compress = need(c.compress, "compress");
    const double damping = need(c.damping, "damping"), rest = need(c.restLength, "restLength");
    const double minL = c.minLength.value_or(0.0), maxL = c.maxLength.value_or(0.0);
    if (!ok) return false;
    if (stretch < 0 || compress < 0 || damping < 0 || rest < 0 || minL < 0 || maxL < 0 || (maxL > 0 && maxL < minL)) {
        error(c.location, what + ": spring values must be >= 0 and maxLength >= minLength (engine asserts)");
        return false;
    }
    // F = k·ΔL² in Doom units scales to SI as k/s; the damping term D = damping·v/L scales with s (§4.7).
    out.spring = {stretch / s(), compress / s(), damping * s(), rest * s(), minL * s(), maxL * s()};
    const SpringParams& sp = out.spring;
    if (sp.stretchNPerM2 > kMaxSpringStiffness || sp.compressNPerM2 > kMaxSpringStiffness ||
        sp.dampingNs > kMaxSpringDamping) {
        error(c.location, what + ": stiffness above " + fmt(kMaxSpringStiffness) + " N/m^2 or damping above " +
                              fmt(kMaxSpringDamping) + " N s/m (stretch " + fmt(sp.stretchNPerM2) + ", compress " +
                              fmt(sp.compressNPerM2) + ", damping " + fmt(sp.dampingNs) +
                              "): so stiff a spring gains energy every step");
        return false;
    }
    if (std::max({sp.restLengthM, sp.minLengthM, sp.maxLengthM}) > kMaxFigureExtentM) {
        error(c.location, what + ": a spring length is above the " + fmt(kMaxFigureExtentM) + " m a figure may span");
        return false;
    }
    return true;
}

} // namespace afb::figure::detail
