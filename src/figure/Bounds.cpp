// Hostile numbers (bounds in Bounds.h, docs/format.md "Hostile numbers"): every number of the decl is finite,
// and what reaches the physics engine stays inside bounds it can simulate. Values outside are errors, or
// repaired with a warning that says "repaired" and how (errors under FigureInput::strict).
#include "afb/figure/Bounds.h"

#include <cmath>

#include "FigureBuilder.h"

namespace afb::figure::detail {

void Builder::repair(const text::SourceLocation& at, const std::string& problem, const std::string& how) {
    if (m_strict) error(at, problem + " (strict: not repaired; without --strict it would be " + how + ")");
    else warning(at, problem + "; repaired: " + how);
}

// Every number the decl holds must be finite. The idTech4 lexer never yields inf or nan, but a decl built in
// code can hold them, and they would reach the physics engine unnoticed.
void Builder::checkNumbers() {
    auto check = [&](const text::SourceLocation& at, const std::string& what, double v) {
        if (!std::isfinite(v)) error(at, what + " is " + fmt(v) + ": every number must be finite");
    };
    auto vec = [&](const text::SourceLocation& at, const std::string& what, const std::optional<AfVector>& v) {
        if (!v || v->form != AfVector::Form::Literal) return;
        check(at, what, v->literal.x);
        check(at, what, v->literal.y);
        check(at, what, v->literal.z);
    };
    for (const decl::AfSettings& st : m_decl.settings) {
        const std::string what = "settings";
        if (st.friction) {
            check(st.location, what + " friction", st.friction->linear);
            check(st.location, what + " friction", st.friction->angular);
            check(st.location, what + " friction", st.friction->contact);
            if (st.friction->constraint) check(st.location, what + " friction", *st.friction->constraint);
        }
        if (st.suspendSpeed)
            for (double v : *st.suspendSpeed) check(st.location, what + " suspendSpeed", v);
        for (const auto& [key, v] : {std::pair{"noMoveTime", st.noMoveTime},
                                     {"noMoveTranslation", st.noMoveTranslation},
                                     {"noMoveRotation", st.noMoveRotation},
                                     {"minMoveTime", st.minMoveTime},
                                     {"maxMoveTime", st.maxMoveTime},
                                     {"totalMass", st.totalMass}})
            if (v) check(st.location, what + " " + key, *v);
    }
    for (const AfBody& b : m_decl.bodies) {
        const std::string what = "body '" + b.name + "'";
        if (b.model) {
            vec(b.location, what + " shape bound", b.model->v1);
            vec(b.location, what + " shape bound", b.model->v2);
            check(b.location, what + " bone width", b.model->width);
        }
        vec(b.location, what + " origin", b.origin);
        vec(b.location, what + " angles", b.angles);
        vec(b.location, what + " frictionDirection", b.frictionDirection);
        vec(b.location, what + " contactMotorDirection", b.contactMotorDirection);
        if (b.density) check(b.location, what + " density", *b.density);
        if (b.inertiaScale)
            for (double v : *b.inertiaScale) check(b.location, what + " inertiaScale", v);
        if (b.friction) {
            check(b.location, what + " friction", b.friction->linear);
            check(b.location, what + " friction", b.friction->angular);
            check(b.location, what + " friction", b.friction->contact);
        }
    }
    for (const AfConstraint& c : m_decl.constraints) {
        const std::string what = std::string(decl::keywordOf(c.type)) + " '" + c.name + "'";
        vec(c.location, what + " anchor", c.anchor);
        vec(c.location, what + " anchor2", c.anchor2);
        vec(c.location, what + " axis", c.axis);
        if (c.shafts) {
            vec(c.location, what + " shaft 1", c.shafts->at(0));
            vec(c.location, what + " shaft 2", c.shafts->at(1));
        }
        for (const auto& [key, v] : {std::pair{"friction", c.friction},
                                     {"stretch", c.stretch},
                                     {"compress", c.compress},
                                     {"damping", c.damping},
                                     {"restLength", c.restLength},
                                     {"minLength", c.minLength},
                                     {"maxLength", c.maxLength}})
            if (v) check(c.location, what + " " + key, *v);
        if (const auto* cone = std::get_if<decl::ConeLimit>(&c.limit)) {
            vec(c.location, what + " limit axis", cone->axis);
            vec(c.location, what + " limit shaft", cone->shaft);
            check(c.location, what + " cone angle", cone->angleDeg);
        } else if (const auto* pyr = std::get_if<decl::PyramidLimit>(&c.limit)) {
            vec(c.location, what + " limit axis", pyr->axis);
            vec(c.location, what + " limit shaft", pyr->shaft);
            check(c.location, what + " pyramid angle", pyr->angle1Deg);
            check(c.location, what + " pyramid angle", pyr->angle2Deg);
            check(c.location, what + " pyramid roll", pyr->rollDeg);
        } else if (const auto* h = std::get_if<decl::HingeLimit>(&c.limit)) {
            check(c.location, what + " hinge limit", h->orientationDeg);
            check(c.location, what + " hinge limit", h->widthDeg);
            check(c.location, what + " hinge limit", h->angleDeg);
        }
    }
}

// A positive extent thinner than kMinThicknessM is raised to it; returns the extent to build with, Doom units.
double Builder::thick(double extent, const text::SourceLocation& at, const std::string& what) {
    const double minimum = kMinThicknessM / s();
    if (!(extent > 0.0) || extent >= minimum) return extent;
    repair(at,
           what + " is " + fmt(extent * s() * 1000) + " mm, thinner than the " + fmt(kMinThicknessM * 1000) +
               " mm minimum thickness",
           "raised to " + fmt(kMinThicknessM * 1000) + " mm about its centre");
    return minimum;
}

// A position (model space, Doom units) must lie within kMaxFigureExtentM of the model origin.
bool Builder::withinFigure(const Vector3d& p, const text::SourceLocation& at, const std::string& what) {
    const double distance = p.norm() * s();
    if (distance <= kMaxFigureExtentM) return true;
    error(at, what + " lies " + fmt(distance) + " m from the model origin, beyond the " + fmt(kMaxFigureExtentM) +
                  " m a figure may span");
    return false;
}

// After totalMass: every body's mass and size inside the bounds.
void Builder::checkBodyBounds() {
    for (const Work& w : m_work) {
        const AfBody& b = *w.decl;
        const std::string what = "body '" + b.name + "'";
        if (!(w.mass >= kMinBodyMassKg && w.mass <= kMaxBodyMassKg))
            error(b.location, what + " has mass " + fmt(w.mass) + " kg, outside [" + fmt(kMinBodyMassKg) + ", " +
                                  fmt(kMaxBodyMassKg) + "] kg (density, totalMass): it cannot be simulated");
        double radius = 0;
        for (const Vector3d& p : w.polytope.vertices) radius = std::max(radius, p.norm());
        if (!(2 * radius * s() <= kMaxFigureExtentM))
            error(b.location, what + " is " + fmt(2 * radius * s()) + " m across, more than the " +
                                  fmt(kMaxFigureExtentM) + " m a body may span");
        withinFigure(w.pose.position, b.location, what + "'s centre of mass");
    }
}

// Principal moments (SI) with the inertia floor: a moment <= 0 is an error, one below kMinInertiaRatio of the
// largest is raised to it.
Vector3d Builder::inertiaFloor(Vector3d moments, double massKg, double radiusM, const AfBody& b) {
    const std::string what = "body '" + b.name + "'";
    const double ceiling = kMaxInertiaOverMassRadius2 * massKg * radiusM * radiusM;
    if (!(moments.maxCoeff() <= ceiling)) {
        error(b.location, what + " has a principal moment of inertia " + fmt(moments.maxCoeff()) +
                              " kg m^2, more than " + fmt(kMaxInertiaOverMassRadius2) + " x mass x radius^2 (" +
                              fmt(ceiling) + ", inertiaScale): it cannot be simulated");
        return moments;
    }
    if (!(moments.minCoeff() > 0.0) || !moments.allFinite()) {
        error(b.location, what + " has principal moments of inertia " + fmt(moments.x()) + ", " + fmt(moments.y()) +
                              ", " + fmt(moments.z()) + " kg m^2 (inertiaScale): each must be > 0");
        return moments;
    }
    const double floor = kMinInertiaRatio * moments.maxCoeff();
    if (moments.minCoeff() >= floor) return moments;
    repair(b.location,
           what + " has a principal moment of inertia " + fmt(moments.minCoeff()) + " kg m^2, less than " +
               fmt(kMinInertiaRatio) + " of its largest (" + fmt(moments.maxCoeff()) + ")",
           "raised to " + fmt(floor) + " kg m^2 (an inertia floor)");
    return moments.cwiseMax(floor);
}

// Contact and joint friction above their bounds are clamped.
double Builder::clampFriction(double f, double max, const text::SourceLocation& at, const std::string& what) {
    if (!(f > max)) return f;
    repair(at, what + " " + fmt(f) + " is above " + fmt(max), "clamped to " + fmt(max));
    return max;
}

} // namespace afb::figure::detail
