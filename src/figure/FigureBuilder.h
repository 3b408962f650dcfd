#pragma once
// The figure builder's internals, shared by the files that implement it, one concept each:
//   FigureBuilder.cpp   — the build order, body order, vector expressions, rest rules, decl → figure words
//   BuildBodies.cpp     — shapes, mass properties, friction, contents (docs/format.md §2.2, §3)
//   BuildConstraints.cpp — constraint frames, limits and springs (§4)
//   ContainedJoints.cpp — which body takes each joint's impacts (§5.3)
//   Bounds.cpp          — hostile numbers: non-finite values, sizes, masses, inertia and friction bounds
//   Findings.cpp        — findings on the built figure: limits and spring lengths the load pose exceeds, id's
//                         "behave weird or explode" list
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "afb/figure/Figure.h"
#include "afb/figure/MassProperties.h"
#include "afb/figure/Polytope.h"

namespace afb::figure::detail {

using decl::AfBody;
using decl::AfConstraint;
using decl::AfVector;
using Eigen::Matrix3d;
using Eigen::Vector3d;

/// `v` with 4 significant digits, for findings.
std::string fmt(double v);
/// `s` with ASCII letters lower-cased.
std::string lower(std::string s);

/// The decl's shape keyword in the figure's words (the one place it is translated).
ShapeType shapeTypeOf(decl::ShapeKind kind);
/// The decl's constraint keyword in the figure's words (the one place it is translated).
JointType jointTypeOf(decl::ConstraintType type);

/// A right-handed frame whose column `axisIndex` is `dir` normalized.
Matrix3d frameWithAxis(const Vector3d& dir, int axisIndex);

/// A body while it is built: Doom units until the final conversion.
struct Work {
    std::size_t declIndex = 0;
    const AfBody* decl = nullptr;
    decl::AfSettingsValues settings; ///< in force when the body was parsed (§1.8)
    Polytope polytope;               ///< body-local, COM at the origin, Doom units
    Transform pose;                  ///< body frame in model space (COM), Doom units
    double volume = 0;
    double mass = 0;
    Matrix3d inertia = Matrix3d::Identity(); ///< about the COM in the body frame, Doom units
    ShapeType type = ShapeType::Box;
    int sidesUsed = 0;
};

using Limit = decltype(FigureConstraint::limit);

/// Builds one Figure from one decl and skeleton, collecting findings as it goes.
class Builder {
  public:
    Builder(const FigureInput& in, text::Diagnostics& findings);

    /// The figure, or nullopt when any error was found.
    std::optional<Figure> build();

  private:
    void error(const text::SourceLocation& at, const std::string& msg) { m_findings.error(at, msg); }
    void warning(const text::SourceLocation& at, const std::string& msg) { m_findings.warning(at, msg); }
    double s() const { return m_units.metresPerUnit; }

    // FigureBuilder.cpp
    std::vector<std::size_t> bodyOrder();
    std::optional<int> joint(const std::string& name, const text::SourceLocation& at, const std::string& what);
    Vector3d eval(const AfVector& v, const text::SourceLocation& at, const std::string& what);
    void applyRestRules(const decl::AfSettingsValues& st);

    // BuildBodies.cpp
    void buildBody(std::size_t declIndex, bool isOriginBody);
    void thickenBounds(ShapeType type, Vector3d& v1, Vector3d& v2, const text::SourceLocation& at,
                       const std::string& what);
    bool bodyShape(const decl::AfShape& shape, ShapeType type, const Vector3d& v1, const Vector3d& v2,
                   const text::SourceLocation& at, const std::string& what, Work& w, Matrix3d& axis);
    bool bodyMass(const AfBody& b, const std::string& what, const MassProperties& unit, Work& w);
    void applyTotalMass(double totalMass);
    decl::BodyFriction friction(const Work& w);
    std::uint32_t contents(const decl::ContentsList& list, const AfBody& b, const char* what);
    FigureBody finishBody(std::size_t k);

    // ContainedJoints.cpp
    void mapContainedJoints();

    // BuildConstraints.cpp
    std::optional<int> bodyIndex(const std::string& name) const;
    Transform inBody(int body, const Transform& frame) const;
    Vector3d dirInBody(int body, const Vector3d& dirModel) const;
    void buildConstraint(std::size_t i);
    bool constraintBodies(std::size_t i, FigureConstraint& out, const std::string& what);
    bool jointFriction(const AfConstraint& c, FigureConstraint& out, const std::string& what);
    Limit limit(const AfConstraint& c, const FigureConstraint& out, const std::string& what,
                std::optional<Vector3d> shaftModel);
    Limit hingeRange(const decl::HingeLimit& h, double axisLength, const AfConstraint& c, const std::string& what);
    bool spring(const AfConstraint& c, FigureConstraint& out, const std::string& what);

    // Bounds.cpp
    void repair(const text::SourceLocation& at, const std::string& problem, const std::string& how);
    void checkNumbers();
    double thick(double extent, const text::SourceLocation& at, const std::string& what);
    bool withinFigure(const Vector3d& p, const text::SourceLocation& at, const std::string& what);
    void checkBodyBounds();
    Vector3d inertiaFloor(Vector3d moments, double massKg, double radiusM, const AfBody& b);
    double clampFriction(double f, double max, const text::SourceLocation& at, const std::string& what);

    // Findings.cpp
    void lintLimitAtLoadPose(const FigureConstraint& c, const std::string& what);
    void lintSpringAtLoadPose(const FigureConstraint& c, double lengthM, const std::string& what);
    void checkFigure();

    const decl::AfDecl& m_decl;
    const Skeleton& m_skel;
    UnitSystem m_units;
    bool m_strict = false;
    text::Diagnostics& m_findings;
    std::vector<Work> m_work;
    Figure m_figure;
};

} // namespace afb::figure::detail
