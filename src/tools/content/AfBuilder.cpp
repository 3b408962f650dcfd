#include "AfBuilder.h"

#include "Common.h"
#include "afb/figure/MassProperties.h"
#include "afb/figure/Polytope.h"

namespace afb::gen {

using namespace afb::decl;
using Eigen::Vector3d;

namespace {

Vector3d literal(const AfVector& v) { return {v.literal.x, v.literal.y, v.literal.z}; }

/// Volume of the shape as the engine builds it (figure layer polytopes, exact integration, docs/format.md §3.2);
/// a bone's length comes from the skeleton.
double volumeOf(const AfShape& s, const Skeleton& sk) {
    const int sides = static_cast<int>(s.numSides);
    figure::Polytope p;
    switch (s.kind) {
    case ShapeKind::Box: p = figure::makeBox(literal(s.v1), literal(s.v2)); break;
    case ShapeKind::Octahedron: p = figure::makeOctahedron(literal(s.v1), literal(s.v2)); break;
    case ShapeKind::Dodecahedron: p = figure::makeDodecahedron(literal(s.v1), literal(s.v2)); break;
    case ShapeKind::Cylinder: p = figure::makeCylinder(literal(s.v1), literal(s.v2), sides).polytope; break;
    case ShapeKind::Cone: p = figure::makeCone(literal(s.v1), literal(s.v2), sides).polytope; break;
    case ShapeKind::Bone: p = figure::makeBone((sk.pos(s.v2.joint1) - sk.pos(s.v1.joint1)).norm(), s.width); break;
    }
    return figure::computeMassProperties(p, 1.0).volume;
}

} // namespace

AfVector lit(double x, double y, double z) { return AfVector::fromLiteral({rnd(x, 6), rnd(y, 6), rnd(z, 6)}); }
AfVector lit(const Vector3d& v) { return lit(v.x(), v.y(), v.z()); }
AfVector jointV(const std::string& j) { return AfVector::fromJoint(j); }
AfVector boneCenter(const std::string& a, const std::string& b) { return AfVector::fromBoneCenter(a, b); }
AfVector boneDir(const std::string& a, const std::string& b, bool negated) {
    return AfVector::fromBoneDir(a, b, negated);
}

AfShape shape(ShapeKind kind, Vector3d lo, Vector3d hi, std::int64_t sides) {
    AfShape s;
    s.kind = kind;
    s.v1 = lit(lo);
    s.v2 = lit(hi);
    s.numSides = sides;
    return s;
}

AfShape boneShape(const std::string& a, const std::string& b, double width) {
    AfShape s;
    s.kind = ShapeKind::Bone;
    s.v1 = jointV(a);
    s.v2 = jointV(b);
    s.width = rnd(width);
    return s;
}

AfBuilder::AfBuilder(const std::string& name, const Skeleton& skel) : sk(skel) { decl.name = name; }

void AfBuilder::settings(const std::string& model, double totalMass) {
    AfSettings s;
    s.model = model;
    s.friction = SettingsFriction{0.01, 0.01, 0.8, std::nullopt};
    s.suspendSpeed = std::array<double, 4>{20, 30, 40, 60};
    s.noMoveTime = 1;
    s.noMoveTranslation = 10;
    s.noMoveRotation = 10;
    s.minMoveTime = -1;
    s.maxMoveTime = -1;
    s.totalMass = totalMass;
    s.contents = ContentsList{{"corpse"}};
    s.clipMask = ContentsList{{"solid", "corpse"}};
    s.selfCollision = true;
    decl.order.push_back({AfBlockRef::Kind::Settings, decl.settings.size()});
    decl.settings.push_back(s);
}

AfBody& AfBuilder::body(const std::string& name, const std::string& joint, AfShape model, AfVector origin, double mass,
                        const std::string& contained, bool selfCollision) {
    AfBody b;
    b.name = name;
    b.joint = joint;
    b.mod = "orientation";
    b.density = rnd(mass / volumeOf(model, sk), 6);
    b.model = model;
    b.origin = origin;
    b.selfCollision = selfCollision;
    b.containedJoints = contained;
    decl.order.push_back({AfBlockRef::Kind::Body, decl.bodies.size()});
    decl.bodies.push_back(b);
    return decl.bodies.back();
}

AfConstraint& AfBuilder::constraint(ConstraintType type, const std::string& name, const std::string& body1,
                                    const std::string& body2) {
    AfConstraint c;
    c.type = type;
    c.name = name;
    c.body1 = body1;
    c.body2 = body2;
    decl.order.push_back({AfBlockRef::Kind::Constraint, decl.constraints.size()});
    decl.constraints.push_back(c);
    return decl.constraints.back();
}

AfConstraint& AfBuilder::spring(const std::string& name, const std::string& body1, const std::string& body2,
                                AfVector a1, AfVector a2, double rest, double minL, double maxL) {
    AfConstraint& c = constraint(ConstraintType::Spring, name, body1, body2);
    c.anchor = a1;
    c.anchor2 = a2;
    c.stretch = 20;
    c.compress = 10;
    c.damping = 50;
    c.restLength = rnd(rest);
    c.minLength = rnd(minL);
    c.maxLength = rnd(maxL);
    return c;
}

} // namespace afb::gen
