// Building a Figure from an `.af` decl and its skeleton: af-format §1.8 (ordering), §2 (placement), §3 (shapes
// and mass), §4 (constraint meaning), §5.3 (containedJoints), §6 (rest, collision). Findings name every silent
// engine fallback and every "behave weird or explode" condition of id's modding guide.
#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <sstream>

#include <Eigen/Eigenvalues>

#include "afb/figure/Collision.h"
#include "afb/figure/DoomMath.h"
#include "afb/figure/Figure.h"
#include "afb/figure/MassProperties.h"
#include "afb/figure/Polytope.h"
#include "afb/text/Lexer.h"

namespace afb::figure {
namespace {

using decl::AfBody;
using decl::AfConstraint;
using decl::AfVector;
using Eigen::Matrix3d;
using Eigen::Vector3d;

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

// The decl's keywords in the figure's words: the one place they are translated.
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

// A body while it is built: Doom units until the final conversion.
struct Work {
    std::size_t declIndex = 0;
    const AfBody* decl = nullptr;
    decl::AfSettingsValues settings; // in force when the body was parsed (§1.8)
    Polytope polytope;               // body-local, COM at the origin, Doom units
    Transform pose;                  // body frame in model space (COM), Doom units
    double volume = 0;
    double mass = 0;
    Matrix3d inertia = Matrix3d::Identity(); // about the COM in the body frame, Doom units
    ShapeType type = ShapeType::Box;
    int sidesUsed = 0;
};

class Builder {
  public:
    Builder(const FigureInput& in, text::Diagnostics& findings)
        : m_decl(*in.decl), m_skel(*in.skeleton), m_units(in.units), m_findings(findings),
          m_figure{.name = in.decl->name,
                   .units = in.units,
                   .skeleton = *in.skeleton,
                   .bodies = {},
                   .constraints = {},
                   .selfCollision = true,
                   .rest = {},
                   .jointBody = {},
                   .totalMassKg = 0} {}

    std::optional<Figure> build() {
        const std::size_t errorsBefore = m_findings.errorCount();
        const decl::AfSettingsValues settings = m_decl.finalSettings();
        m_figure.selfCollision = settings.selfCollision;
        applyRestRules(settings);

        std::vector<std::size_t> order = bodyOrder();
        if (m_findings.errorCount() > errorsBefore) return std::nullopt;
        for (std::size_t k = 0; k < order.size(); ++k) buildBody(order[k], k == 0);
        if (m_findings.errorCount() > errorsBefore) return std::nullopt;
        applyTotalMass(settings.totalMass);
        for (std::size_t k = 0; k < m_work.size(); ++k) m_figure.bodies.push_back(finishBody(k));
        for (std::size_t i = 0; i < m_decl.constraints.size(); ++i) buildConstraint(i);
        if (m_findings.errorCount() > errorsBefore) return std::nullopt;
        mapContainedJoints();
        checkFigure();
        if (m_findings.errorCount() > errorsBefore) return std::nullopt;
        return std::move(m_figure);
    }

  private:
    void error(const text::SourceLocation& at, const std::string& msg) { m_findings.error(at, msg); }
    void warning(const text::SourceLocation& at, const std::string& msg) { m_findings.warning(at, msg); }
    double s() const { return m_units.metresPerUnit; }

    // §1.8: the first body whose joint is exactly "origin" is swapped with body 0.
    std::vector<std::size_t> bodyOrder() {
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

    std::optional<int> joint(const std::string& name, const text::SourceLocation& at, const std::string& what) {
        if (auto j = m_skel.findJoint(name)) return j;
        error(at, what + ": joint \"" + name + "\" not found in the skeleton");
        return std::nullopt;
    }

    // §1.2: a vector expression at the load pose, Doom units, negation applied once.
    Vector3d eval(const AfVector& v, const text::SourceLocation& at, const std::string& what) {
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

    void applyRestRules(const decl::AfSettingsValues& st) {
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

    // --- bodies (§2.2, §3) ---------------------------------------------------------------------------------

    void buildBody(std::size_t declIndex, bool isOriginBody) {
        const AfBody& b = m_decl.bodies[declIndex];
        Work w;
        w.declIndex = declIndex;
        w.decl = &b;
        w.settings = m_decl.settingsForBody(declIndex);
        const std::string what = "body '" + b.name + "'";

        const decl::AfShape shape = b.model.value_or(decl::AfShape{});
        const ShapeType type = shapeTypeOf(shape.kind);
        const Vector3d v1 = eval(shape.v1, b.location, what);
        const Vector3d v2 = eval(shape.v2, b.location, what);
        const Vector3d origin = b.origin ? eval(*b.origin, b.location, what) : Vector3d::Zero();
        Matrix3d axis = Matrix3d::Identity();
        if (b.angles && type != ShapeType::Bone && b.angles->form == AfVector::Form::Literal)
            axis = anglesToRotation(b.angles->literal.x, b.angles->literal.y, b.angles->literal.z);
        if (b.angles && type == ShapeType::Bone)
            warning(b.location, what + ": angles are ignored for a bone (its axis runs from v1 to v2)");

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
                warning(b.location, what + ": " + std::to_string(shape.numSides) + " sides become " +
                                        std::to_string(sb.effectiveSides) + " (the engine's trace-model limits)");
            break;
        }
        case ShapeType::Bone: {
            const double length = (v2 - v1).norm();
            if (!(length > 0.0)) {
                error(b.location, what + ": bone from v1 to v2 has zero length");
                return;
            }
            w.polytope = makeBone(length, shape.width);
            axis = boneFrame(v1, v2);
            break;
        }
        }
        w.type = type;

        // §2.2: mass properties at density 1 give the local COM c; the body origin moves to origin + R·c.
        const MassProperties unit = computeMassProperties(w.polytope, 1.0);
        if (!(unit.volume > 0.0) || !std::isfinite(unit.volume)) {
            error(b.location, what + ": the shape has " + (unit.volume == 0.0 ? "zero" : "negative") +
                                  " volume (" + fmt(unit.volume) +
                                  " cubic units; inverted bounds or a degenerate shape); the engine falls back "
                                  "to mass 1 with identity inertia");
            return;
        }
        for (Vector3d& p : w.polytope.vertices) p -= unit.centerOfMass;
        w.pose.rotation = axis;
        w.pose.position = origin + axis * unit.centerOfMass;
        w.volume = unit.volume;

        // §3.3 SetDensity: mass and inertia scale with density; inertiaScale is a matrix product.
        const double density = b.density.value_or(0.2);
        w.mass = density * unit.volume;
        w.inertia = unit.inertia * density;
        if (!(w.mass > 0.0) || !std::isfinite(w.mass)) {
            error(b.location, what + ": density " + fmt(density) +
                                  " gives an invalid mass (the engine replaces it with mass 1 and identity inertia)");
            return;
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
        if (isOriginBody && b.mod && !text::equalsIgnoreCase(*b.mod, "orientation"))
            warning(b.location, what + " is the origin body: its mod '" + *b.mod +
                                    "' is ignored (the engine always drives orientation)");
        m_work.push_back(std::move(w));
    }

    void applyTotalMass(double totalMass) {
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
    decl::BodyFriction friction(const Work& w) {
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
        warning(w.decl->location, "body '" + w.decl->name + "': friction " + fmt(f.linear) + ", " + fmt(f.angular) +
                                      ", " + fmt(f.contact) + " is out of range (linear and angular in [0, 1], "
                                      "contact >= 0); the engine uses " + fmt(fallback.linear) + ", " +
                                      fmt(fallback.angular) + ", " + fmt(fallback.contact));
        return fallback;
    }

    std::uint32_t contents(const decl::ContentsList& list, const AfBody& b, const char* what) {
        std::optional<std::size_t> unknown;
        const std::uint32_t bits = decl::contentsBits(list, &unknown);
        if (unknown)
            warning(b.location, "body '" + b.name + "': unknown " + what + " name '" + list.names[*unknown] +
                                    "' ends the list; it and every later name are ignored");
        return bits;
    }

    FigureBody finishBody(std::size_t k) {
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
        out.inertiaKgM2 = moments * (s() * s());
        out.loadPose = {poseDoom.rotation, poseDoom.position * s()};
        if (out.joint >= 0) {
            const Transform& j = m_skel.loadPose()[static_cast<std::size_t>(out.joint)];
            out.jointInBody = out.loadPose.inverse() * Transform{j.rotation, j.position * s()};
        }

        const decl::BodyFriction f = friction(w);
        out.linearFrictionPerStep = f.linear;
        out.angularFrictionPerStep = f.angular;
        out.contactFriction = f.contact;
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

    // §5.3: containedJoints ("*origin" when omitted); later bodies win overlaps.
    void mapContainedJoints() {
        const int n = m_skel.jointCount();
        m_figure.jointBody.assign(static_cast<std::size_t>(n), -1);
        for (std::size_t k = 0; k < m_work.size(); ++k) {
            const AfBody& b = *m_work[k].decl;
            std::vector<bool> mine(static_cast<std::size_t>(n), false);
            std::istringstream words(b.containedJoints.value_or("*origin"));
            std::string word;
            while (words >> word) {
                bool remove = false, all = false;
                std::string name = word;
                if (!name.empty() && name[0] == '-') {
                    remove = true;
                    name.erase(0, 1);
                }
                if (!name.empty() && name[0] == '*') {
                    all = true;
                    name.erase(0, 1);
                }
                const std::optional<int> j = m_skel.findJoint(name);
                if (!j) {
                    warning(b.location, "body '" + b.name + "': containedJoints names unknown joint \"" + name +
                                            "\"; the entry is skipped");
                    continue;
                }
                const std::vector<int> joints = all ? m_skel.jointAndDescendants(*j) : std::vector<int>{*j};
                for (int x : joints) mine[static_cast<std::size_t>(x)] = !remove;
            }
            std::map<int, std::string> takenFrom; // previous owner -> joints this body takes over
            for (int j = 0; j < n; ++j) {
                if (!mine[static_cast<std::size_t>(j)]) continue;
                int& owner = m_figure.jointBody[static_cast<std::size_t>(j)];
                if (owner >= 0) {
                    std::string& list = takenFrom[owner];
                    list += (list.empty() ? "" : ", ") + m_skel.name(j);
                }
                owner = static_cast<int>(k);
                m_figure.bodies[k].containedJoints.push_back(j);
            }
            for (const auto& [owner, joints] : takenFrom)
                warning(b.location, "body '" + b.name + "' contains joints that body '" +
                                        m_figure.bodies[static_cast<std::size_t>(owner)].name +
                                        "' contains too (" + joints + "); the later body '" + b.name +
                                        "' takes their impacts");
        }
        for (auto& body : m_figure.bodies) {
            std::sort(body.containedJoints.begin(), body.containedJoints.end());
            body.containedJoints.erase(std::unique(body.containedJoints.begin(), body.containedJoints.end()),
                                       body.containedJoints.end());
        }
        for (FigureBody& body : m_figure.bodies)
            std::erase_if(body.containedJoints, [&](int j) {
                return m_figure.jointBody[static_cast<std::size_t>(j)] != &body - m_figure.bodies.data();
            });
        std::string uncontained;
        int count = 0;
        for (int j = 0; j < n; ++j)
            if (m_figure.jointBody[static_cast<std::size_t>(j)] < 0) {
                if (count < 8) uncontained += (count ? ", " : "") + m_skel.name(j);
                ++count;
            }
        if (count > 0)
            warning(m_decl.location, std::to_string(count) + " joint(s) contained by no body (" + uncontained +
                                         (count > 8 ? ", ..." : "") + "): impacts on them are ignored");
    }

    // --- constraints (§4) ------------------------------------------------------------------------------------

    std::optional<int> bodyIndex(const std::string& name) const {
        for (std::size_t k = 0; k < m_work.size(); ++k)
            if (text::equalsIgnoreCase(m_work[k].decl->name, name)) return static_cast<int>(k);
        return std::nullopt;
    }

    // `frame` (model space, metres) expressed in a body's frame, or kept in model space for the world.
    Transform inBody(int body, const Transform& frame) const {
        if (body < 0) return frame;
        return m_figure.bodies[static_cast<std::size_t>(body)].loadPose.inverse() * frame;
    }
    Vector3d dirInBody(int body, const Vector3d& dirModel) const {
        if (body < 0) return dirModel;
        return m_figure.bodies[static_cast<std::size_t>(body)].loadPose.rotation.transpose() * dirModel;
    }

    // A right-handed frame whose column `axisIndex` is `dir` (unit).
    static Matrix3d frameWithAxis(const Vector3d& dir, int axisIndex) {
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

    void buildConstraint(std::size_t i) {
        const AfConstraint& c = m_decl.constraints[i];
        const std::string what = std::string(decl::keywordOf(c.type)) + " '" + c.name + "'";
        FigureConstraint out;
        out.name = c.name;
        out.location = c.location;
        out.type = jointTypeOf(c.type);

        const std::string name1 = c.body1.value_or(m_decl.defaultBody1(i));
        const std::optional<int> b1 = bodyIndex(name1);
        if (!b1) {
            error(c.location, what + ": body1 \"" + name1 + "\" matches no body (the engine would crash)");
            return;
        }
        out.body1 = *b1;
        const std::string name2 = c.body2.value_or("world");
        if (const std::optional<int> b2 = bodyIndex(name2)) {
            out.body2 = *b2;
        } else {
            out.body2 = -1;
            if (!text::equalsIgnoreCase(name2, "world"))
                warning(c.location, what + ": body2 \"" + name2 +
                                        "\" matches no body, so the constraint attaches to the world");
        }
        if (out.body1 == out.body2) {
            error(c.location, what + ": body1 and body2 are the same body '" + name1 + "'");
            return;
        }
        const FigureBody& body1 = m_figure.bodies[static_cast<std::size_t>(out.body1)];
        const Matrix3d ref = out.body2 >= 0 ? m_figure.bodies[static_cast<std::size_t>(out.body2)].loadPose.rotation
                                            : Matrix3d::Identity();
        auto point = [&](const std::optional<AfVector>& v) -> Vector3d {
            return (v ? eval(*v, c.location, what) : Vector3d::Zero()) * s();
        };
        auto direction = [&](const std::optional<AfVector>& v, const char* key) -> std::optional<Vector3d> {
            const Vector3d d = v ? eval(*v, c.location, what) : Vector3d::Zero();
            if (d.norm() > 0.0 && std::isfinite(d.norm())) return d;
            error(c.location, what + ": " + key + " is a zero vector (the engine needs it; it defaults to 0)");
            return std::nullopt;
        };
        out.friction = out.type == JointType::Fixed ? 0.0 : c.friction.value_or(0.5);
        if ((out.type == JointType::Slider || out.type == JointType::Spring) && c.friction && *c.friction != 0.0)
            warning(c.location, what + ": friction is parsed but never applied by the engine to this type");
        if (out.type == JointType::Slider || out.type == JointType::Spring) out.friction = 0.0;

        Transform frame; // model space, metres; origin = anchor
        switch (out.type) {
        case JointType::Fixed:
            frame = body1.loadPose;
            break;
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
        case JointType::Spring:
            if (!spring(c, out, what)) return;
            out.frameInBody1 = inBody(out.body1, {Matrix3d::Identity(), point(c.anchor)});
            out.frameInBody2 = inBody(out.body2, {Matrix3d::Identity(), point(c.anchor2)});
            out.disablesCollision = false;
            m_figure.constraints.push_back(std::move(out));
            return;
        }
        out.frameInBody1 = inBody(out.body1, frame);
        out.frameInBody2 = inBody(out.body2, frame);
        m_figure.constraints.push_back(std::move(out));
    }

    // Cone and pyramid limits (§4.3, §4.4): the shaft is fixed in body1, the axis or basis in body2.
    std::variant<std::monostate, ConeLimit, PyramidLimit, HingeRange> limit(const AfConstraint& c,
                                                                           const FigureConstraint& out,
                                                                           const std::string& what,
                                                                           std::optional<Vector3d> shaftModel) {
        auto shaftOf = [&](const std::optional<AfVector>& v) -> std::optional<Vector3d> {
            if (shaftModel) return shaftModel;
            const Vector3d d = v ? eval(*v, c.location, what) : Vector3d::Zero();
            if (d.norm() > 0.0) return d.normalized();
            error(c.location, what + ": the limit's shaft is a zero vector");
            return std::nullopt;
        };
        if (const auto* cone = std::get_if<decl::ConeLimit>(&c.limit)) {
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
            const double start = std::acos(std::clamp(a.normalized().dot(*shaft), -1.0, 1.0));
            if (start > l.halfAngleRad + 1e-6)
                warning(c.location, what + ": the shaft starts " + fmt(start / kRadPerDeg) +
                                        " deg from the cone axis, outside the half-angle " +
                                        fmt(cone->angleDeg / 2) + " deg: it is pushed in at once");
            return l;
        }
        if (const auto* pyr = std::get_if<decl::PyramidLimit>(&c.limit)) {
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
            l.basisInBody2 = out.body2 >= 0
                                 ? Matrix3d(m_figure.bodies[static_cast<std::size_t>(out.body2)].loadPose.rotation.transpose() * basis)
                                 : basis;
            l.shaftInBody1 = dirInBody(out.body1, *shaft);
            l.halfAngle1Rad = 0.5 * pyr->angle1Deg * kRadPerDeg;
            l.halfAngle2Rad = 0.5 * pyr->angle2Deg * kRadPerDeg;
            const Vector3d sb = basis.transpose() * *shaft; // shaft in (f, l, u) at the load pose
            const double a1 = std::atan2(sb.y(), sb.x()), a2 = std::atan2(sb.z(), sb.x());
            if (std::abs(a1) > l.halfAngle1Rad + 1e-6 || std::abs(a2) > l.halfAngle2Rad + 1e-6)
                warning(c.location, what + ": the shaft starts outside the pyramid (" + fmt(a1 / kRadPerDeg) + ", " +
                                        fmt(a2 / kRadPerDeg) + " deg from its axis; limits " +
                                        fmt(pyr->angle1Deg / 2) + ", " + fmt(pyr->angle2Deg / 2) +
                                        " deg): it is pushed in at once");
            return l;
        }
        return std::monostate{};
    }

    // §4.5: φ ∈ [g(a2) − g(a0) − a1/2, g(a2) − g(a0) + a1/2], g the engine's non-unit-axis distortion.
    std::variant<std::monostate, ConeLimit, PyramidLimit, HingeRange> hingeRange(const decl::HingeLimit& h, double axisLength,
                                                                                const AfConstraint& c,
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
        if (std::abs(centre) > half + 1e-9)
            warning(c.location, what + ": the limit [" + fmt((centre - half) / kRadPerDeg) + ", " +
                                    fmt((centre + half) / kRadPerDeg) +
                                    "] deg excludes the load pose (0 deg): the joint is pushed into range at once");
        return HingeRange{centre - half, centre + half};
    }

    bool spring(const AfConstraint& c, FigureConstraint& out, const std::string& what) {
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
        return true;
    }

    // --- figure-wide findings (id's "behave weird or explode" list) ------------------------------------------

    void checkFigure() {
        // Names that differ only in case merge at load (§1.8).
        auto caseClash = [&](auto&& items, const char* what) {
            std::map<std::string, std::string> seen;
            for (const auto& it : items) {
                const auto [pos, fresh] = seen.emplace(lower(it.name), it.name);
                if (!fresh && pos->second != it.name)
                    error(it.location, std::string(what) + " '" + it.name + "' differs only in case from '" +
                                           pos->second + "': the engine's lookup merges them");
            }
        };
        caseClash(m_decl.bodies, "body");
        caseClash(m_decl.constraints, "constraint");

        for (const FigureBody& b : m_figure.bodies) {
            if (b.massKg < 1.0 || b.massKg > 100.0)
                warning(b.location, "body '" + b.name + "' has mass " + fmt(b.massKg) +
                                        ", outside [1, 100]: bodies that light or heavy make figures unstable");
            const double hi = b.inertiaKgM2.maxCoeff(), lo = b.inertiaKgM2.minCoeff();
            if (lo > 0 && hi / lo > 10.0)
                warning(b.location, "body '" + b.name + "' has principal moments " + fmt(hi / lo) +
                                        ":1 apart (more than 10:1): thin bodies spin unstably");
        }
        for (const FigureConstraint& c : m_figure.constraints) {
            if (c.body2 < 0) continue;
            const FigureBody& a = m_figure.bodies[static_cast<std::size_t>(c.body1)];
            const FigureBody& b = m_figure.bodies[static_cast<std::size_t>(c.body2)];
            const double ratio = std::max(a.massKg, b.massKg) / std::min(a.massKg, b.massKg);
            if (ratio > 10.0)
                warning(c.location, std::string(toString(c.type)) + " '" + c.name + "' joins masses " +
                                        fmt(a.massKg) + " and " + fmt(b.massKg) +
                                        " (more than 10:1): the solver struggles with such ratios");
        }
        // Self-colliding pairs that overlap or touch at the load pose fight their joints from the first step.
        const auto pairs = selfCollisionPairs(m_figure);
        for (const auto& [i, j] : pairs) {
            const FigureBody& a = m_figure.bodies[static_cast<std::size_t>(i)];
            const FigureBody& b = m_figure.bodies[static_cast<std::size_t>(j)];
            const double gap = separation(a, b);
            if (gap < kTouchToleranceM)
                warning(b.location, "self-colliding bodies '" + a.name + "' and '" + b.name + "' " +
                                        (gap < 0 ? "overlap" : "touch") + " at the load pose (" +
                                        (gap < 0 ? "depth " + fmt(-gap * 1000) : "gap " + fmt(gap * 1000)) +
                                        " mm): their contact will fight the joints");
        }
    }

    const decl::AfDecl& m_decl;
    const Skeleton& m_skel;
    UnitSystem m_units;
    text::Diagnostics& m_findings;
    std::vector<Work> m_work;
    Figure m_figure;
};

} // namespace

std::optional<Figure> buildFigure(const FigureInput& input, text::Diagnostics& findings) {
    if (!input.decl || !input.skeleton) {
        findings.error({}, "buildFigure needs a decl and a skeleton");
        return std::nullopt;
    }
    return Builder(input, findings).build();
}

} // namespace afb::figure
