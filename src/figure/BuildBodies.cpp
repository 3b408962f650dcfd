// A figure's bodies (docs/format.md §2.2, §3): shape, mass properties, principal frame, friction, contents.
#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>

#include "FigureBuilder.h"
#include "afb/detail/DoomMath.h"
#include "afb/detail/Lexer.h"
#include "afb/figure/Bounds.h"
#include "afb/figure/MassProperties.h"

namespace afb::figure::detail {

// Bounds.h: positive extents thinner than the minimum thickness grow about their centre (a cone's height is
// v2.z − v1.z, §3.1).
void Builder::thickenBounds(ShapeType type, Vector3d& v1, Vector3d& v2, const text::SourceLocation& at,
                            const std::string& what) {
    for (int i = 0; i < 3; ++i) {
        const char* axisName[] = {"x", "y", "z"};
        const double extent = v2[i] - v1[i];
        const double grown = thick(extent, at, what + " " + axisName[i] + " extent");
        if (grown == extent) continue;
        if (type == ShapeType::Cone && i == 2) {
            v1[i] = v2[i] - grown;
        } else {
            const double centre = 0.5 * (v1[i] + v2[i]);
            v1[i] = centre - 0.5 * grown;
            v2[i] = centre + 0.5 * grown;
        }
    }
}

// The body's polytope (§3.1) from its bounds; a bone's frame into `axis`. False, with an error, for a bone of zero
// length or width.
bool Builder::bodyShape(const decl::AfShape& shape, ShapeType type, const Vector3d& v1, const Vector3d& v2,
                        const text::SourceLocation& at, const std::string& what, Work& w, Matrix3d& axis) {
    const int sides = static_cast<int>(std::clamp<std::int64_t>(shape.numSides, -1000, 1000));
    switch (type) {
    case ShapeType::Box: w.polytope = makeBox(v1, v2); break;
    case ShapeType::Octahedron: w.polytope = makeOctahedron(v1, v2); break;
    case ShapeType::Dodecahedron: w.polytope = makeDodecahedron(v1, v2); break;
    case ShapeType::Cylinder:
    case ShapeType::Cone: {
        const ShapeBuild sb = type == ShapeType::Cylinder ? makeCylinder(v1, v2, sides) : makeCone(v1, v2, sides);
        w.polytope = sb.polytope;
        w.sidesUsed = sb.effectiveSides;
        if (sb.clamped)
            warning(at, what + ": " + std::to_string(shape.numSides) + " sides become " +
                            std::to_string(sb.effectiveSides) + " (the engine's trace-model limits)");
        break;
    }
    case ShapeType::Bone: {
        const double length = (v2 - v1).norm();
        if (!(length > 0.0)) {
            error(at, what + ": bone from v1 to v2 has zero length");
            return false;
        }
        if (!(shape.width > 0.0)) {
            error(at, what + ": bone width " + fmt(shape.width) + " must be > 0");
            return false;
        }
        w.polytope = makeBone(thick(length, at, what + " bone length"), thick(shape.width, at, what + " bone width"));
        axis = boneFrame(v1, v2);
        break;
    }
    }
    return true;
}

// §3.3 SetDensity: mass and inertia scale with density; inertiaScale is a matrix product. False, with an error,
// when the density gives no valid mass.
bool Builder::bodyMass(const AfBody& b, const std::string& what, const MassProperties& unit, Work& w) {
    const double density = b.density.value_or(0.2);
    w.mass = density * unit.volume;
    w.inertia = unit.inertia * density;
    if (!(w.mass > 0.0) || !std::isfinite(w.mass)) {
        error(b.location, what + ": density " + fmt(density) +
                              " gives an invalid mass (the engine replaces it with mass 1 and identity inertia)");
        return false;
    }
    if (b.inertiaScale) {
        Matrix3d scale;
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) scale(r, c) = (*b.inertiaScale)[static_cast<std::size_t>(3 * r + c)];
        w.inertia = w.inertia * scale;
        const double asym = (w.inertia - w.inertia.transpose()).norm();
        if (asym > 1e-9 * w.inertia.norm())
            warning(b.location, what + ": inertiaScale makes the inertia tensor asymmetric; its symmetric part "
                                       "is used");
        w.inertia = 0.5 * (w.inertia + w.inertia.transpose());
    }
    return true;
}

void Builder::buildBody(std::size_t declIndex, bool isOriginBody) {
    const AfBody& b = m_decl.bodies[declIndex];
    Work w;
    w.declIndex = declIndex;
    w.decl = &b;
    w.settings = m_decl.settingsForBody(declIndex);
    const std::string what = "body '" + b.name + "'";

    const decl::AfShape shape = b.model.value_or(decl::AfShape{});
    const ShapeType type = shapeTypeOf(shape.kind);
    Vector3d v1 = eval(shape.v1, b.location, what);
    Vector3d v2 = eval(shape.v2, b.location, what);
    const Vector3d origin = b.origin ? eval(*b.origin, b.location, what) : Vector3d::Zero();
    if (!withinFigure(v1, b.location, what + " shape bound") || !withinFigure(v2, b.location, what + " shape bound") ||
        !withinFigure(origin, b.location, what + " origin"))
        return;
    if (type != ShapeType::Bone) thickenBounds(type, v1, v2, b.location, what);
    Matrix3d axis = Matrix3d::Identity();
    if (b.angles && type != ShapeType::Bone && b.angles->form == AfVector::Form::Literal)
        axis = anglesToRotation(b.angles->literal.x, b.angles->literal.y, b.angles->literal.z);
    if (b.angles && type == ShapeType::Bone)
        warning(b.location, what + ": angles are ignored for a bone (its axis runs from v1 to v2)");

    if (!bodyShape(shape, type, v1, v2, b.location, what, w, axis)) return;
    w.type = type;

    // §2.2: mass properties at density 1 give the local COM c; the body origin moves to origin + R·c.
    const MassProperties unit = computeMassProperties(w.polytope, 1.0);
    if (!(unit.volume > 0.0) || !std::isfinite(unit.volume)) {
        error(b.location, what + ": the shape has " + (unit.volume == 0.0 ? "zero" : "negative") + " volume (" +
                              fmt(unit.volume) +
                              " cubic units; inverted bounds or a degenerate shape); the engine falls back "
                              "to mass 1 with identity inertia");
        return;
    }
    for (Vector3d& p : w.polytope.vertices) p -= unit.centerOfMass;
    w.pose.rotation = axis;
    w.pose.position = origin + axis * unit.centerOfMass;
    w.volume = unit.volume;

    if (!bodyMass(b, what, unit, w)) return;
    if (isOriginBody && b.mod && !text::equalsIgnoreCase(*b.mod, "orientation"))
        warning(b.location, what + " is the origin body: its mod '" + *b.mod +
                                "' is ignored (the engine always drives orientation)");
    m_work.push_back(std::move(w));
}

void Builder::applyTotalMass(double totalMass) {
    double sum = 0;
    for (const Work& w : m_work) sum += w.mass;
    m_figure.totalMassKg = sum;
    if (!(totalMass > 0.0)) return;
    const double factor = totalMass / sum; // §3.3: density ratios kept, inertiaScale applied before
    for (Work& w : m_work) {
        w.mass *= factor;
        w.inertia *= factor;
    }
    m_figure.totalMassKg = totalMass;
}

// §3.4 friction with its range checks and fallbacks.
// A rejected body falls back to the physics defaults, which idAF::Load sets from the decl's final settings
// (SetDefaultFriction), not from the settings in force when the body was parsed.
decl::BodyFriction Builder::friction(const Work& w) {
    const decl::AfSettingsValues& st = w.settings;
    auto valid = [](const decl::BodyFriction& f, bool contactAtMostOne) {
        return f.linear >= 0 && f.linear <= 1 && f.angular >= 0 && f.angular <= 1 && f.contact >= 0 &&
               (!contactAtMostOne || f.contact <= 1);
    };
    const decl::BodyFriction physicsDefault = m_decl.finalSettings().friction;
    const decl::BodyFriction fallback =
        valid(physicsDefault, true) ? physicsDefault : decl::BodyFriction{0.005, 0.005, 0.8};
    const decl::BodyFriction f = w.decl->friction.value_or(st.friction);
    if (valid(f, false)) return f;
    warning(w.decl->location, "body '" + w.decl->name + "': friction " + fmt(f.linear) + ", " + fmt(f.angular) + ", " +
                                  fmt(f.contact) +
                                  " is out of range (linear and angular in [0, 1], "
                                  "contact >= 0); the engine uses " +
                                  fmt(fallback.linear) + ", " + fmt(fallback.angular) + ", " + fmt(fallback.contact));
    return fallback;
}

std::uint32_t Builder::contents(const decl::ContentsList& list, const AfBody& b, const char* what) {
    std::optional<std::size_t> unknown;
    const std::uint32_t bits = decl::contentsBits(list, &unknown);
    if (unknown)
        warning(b.location, "body '" + b.name + "': unknown " + what + " name '" + list.names[*unknown] +
                                "' ends the list; it and every later name are ignored");
    return bits;
}

FigureBody Builder::finishBody(std::size_t k) {
    Work& w = m_work[k];
    const AfBody& b = *w.decl;
    FigureBody out;
    out.name = b.name;
    out.location = b.location;
    out.jointName = b.joint;
    if (k == 0) {
        // §2.4: the origin body drives the first child of the joint named "origin" (joint 0 if none).
        const std::optional<int> originJoint = m_skel.findJoint("origin");
        out.joint = m_skel.firstChild(originJoint.value_or(-1));
        out.mod = JointMod::Orientation;
    } else {
        out.joint = joint(b.joint, b.location, "body '" + b.name + "'").value_or(-1);
        const std::string mod = b.mod.value_or("orientation");
        out.mod = text::equalsIgnoreCase(mod, "position") ? JointMod::Position
                  : text::equalsIgnoreCase(mod, "both")   ? JointMod::Both
                                                          : JointMod::Orientation;
    }

    // Principal axes: built-in shapes are already diagonal; inertiaScale may not be (§3.2).
    Matrix3d q = Matrix3d::Identity();
    Vector3d moments = w.inertia.diagonal();
    const double offDiagonal = std::abs(w.inertia(0, 1)) + std::abs(w.inertia(0, 2)) + std::abs(w.inertia(1, 2));
    if (offDiagonal > 1e-12 * w.inertia.diagonal().cwiseAbs().maxCoeff()) {
        Eigen::SelfAdjointEigenSolver<Matrix3d> eig(w.inertia);
        q = eig.eigenvectors();
        if (q.determinant() < 0) q.col(2) = -q.col(2);
        moments = eig.eigenvalues();
    }
    const Transform poseDoom{w.pose.rotation * q, w.pose.position};

    out.shape.kind = w.type;
    out.shape.sidesUsed = w.sidesUsed;
    out.shape.faces = w.polytope.faces;
    for (const Vector3d& p : w.polytope.vertices) out.shape.vertices.push_back(q.transpose() * p * s());
    if (w.type == ShapeType::Box && q.isIdentity(0.0)) {
        Vector3d half = Vector3d::Zero();
        for (const Vector3d& p : out.shape.vertices) half = half.cwiseMax(p.cwiseAbs());
        out.shape.boxHalfExtents = half;
    }
    out.volumeM3 = w.volume * s() * s() * s();
    out.massKg = w.mass;
    double radius = 0;
    for (const Vector3d& p : out.shape.vertices) radius = std::max(radius, p.norm());
    out.inertiaKgM2 = inertiaFloor(moments * (s() * s()), w.mass, radius, b);
    out.loadPose = {poseDoom.rotation, poseDoom.position * s()};
    if (out.joint >= 0) {
        const Transform& j = m_skel.loadPose()[static_cast<std::size_t>(out.joint)];
        out.jointInBody = out.loadPose.inverse() * Transform{j.rotation, j.position * s()};
    }

    const decl::BodyFriction f = friction(w);
    out.linearFrictionPerStep = f.linear;
    out.angularFrictionPerStep = f.angular;
    out.contactFriction =
        clampFriction(f.contact, kMaxContactFriction, b.location, "body '" + b.name + "': contact friction");
    const double stepsPerSecond = 1.0 / m_units.engineStepSeconds;
    out.linearDamping = 1.0 - std::pow(1.0 - f.linear, stepsPerSecond);
    out.angularDamping = 1.0 - std::pow(1.0 - f.angular, stepsPerSecond);
    out.selfCollision = b.selfCollision.value_or(w.settings.selfCollision);
    out.contents = contents(b.contents.value_or(w.settings.contents), b, "contents");
    out.clipMask = contents(b.clipMask.value_or(w.settings.clipMask), b, "clipMask") | kContentsMoveableClip;
    auto direction = [&](const std::optional<AfVector>& v, const char* what) -> std::optional<Vector3d> {
        if (!v) return std::nullopt;
        const Vector3d d = eval(*v, b.location, "body '" + b.name + "' " + what);
        if (d.norm() == 0.0) return std::nullopt;
        return out.loadPose.rotation.transpose() * d.normalized();
    };
    out.frictionDirection = direction(b.frictionDirection, "frictionDirection");
    out.contactMotorDirection = direction(b.contactMotorDirection, "contactMotorDirection");
    return out;
}

} // namespace afb::figure::detail
