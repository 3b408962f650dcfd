// The position pass: per joint, limits first, then locked axes, then the anchor (so a sweep ends with the
// anchors closed), then the contacts (each manifold point, then each body's deepest point below a static plane when
// no manifold point knows it, then static friction: the points the velocity solve held by it go back to where the
// pass found them along the contact plane). Each projection moves the two bodies by the mass-weighted split of the
// correction (the effective mass of the constraint's rows, as a velocity row would use it), so the centre of
// mass and the momentum of an isolated pair are unchanged. References: Müller et al., "Position Based
// Dynamics" (2007) and Jolt's position steps for the nonlinear Gauss–Seidel scheme; Cline & Pai,
// "Post-Stabilization for Rigid Body Simulation with Contact and Constraints" (2003) for leaving velocities be;
// Guendelman, Bridson & Fedkiw, "Nonconvex Rigid Bodies with Stacking" (2003) for shock propagation (the tree
// step's heavier grounded bodies); Müller et al., "Detailed Rigid Body Simulation with Extended Position Based
// Dynamics" (2020) for static friction as a positional correction.
#include "PositionPass.h"

#include <algorithm>
#include <numeric>
#include <vector>

#include "BlockTree.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/detail/Constraints.h"
#include "afb/detail/Convert.h"

namespace afb::bullet::detail {
namespace {

// Contacts: correct only what is deeper than the slop, and that a fraction at a time, so that resting contacts
// are not pushed apart and re-made every substep (which would feed jitter into the velocity solve).
constexpr btScalar kContactSlopM = btScalar(0.002);
constexpr btScalar kContactFraction = btScalar(0.5);
// A body's deepest point below a plane is left to the manifolds when one of their points is within this of it.
constexpr btScalar kKnownPointM = btScalar(0.001);
// A contact point sticks in the pass when the velocity solve pressed it (a normal impulse), its friction used
// less than this fraction of the Coulomb bound μ·N in each direction (held by static friction with room to spare)
// and it moves slower than kStickSpeedMps after the solve. The speed bound keeps the rule to figures settling
// or at rest: in an impact the pass must be free to put limits back (sticking there too, the humanoid's knee went
// 2° further past its stop at 1 m). Measured on the stress matrix's humanoid rows at 24 yaws (192 runs), with
// `default`: no sticking 105 runs pass, fraction 0.9 133, 0.5 136, 0.5 below 0.1 m/s 139 (0.05 m/s: 132).
constexpr btScalar kStickFrictionFraction = btScalar(0.5);
constexpr btScalar kStickSpeedMps = btScalar(0.1);
// In the tree step of Method::positionTree 2, a body touching anything outside the ragdoll (a manifold point
// within the speculative reach) counts this many times heavier: the step then closes the joints and limits by
// moving the bodies above it (shock propagation), not by turning a foot into the ground.
constexpr btScalar kGroundedTreeMassFactor = btScalar(100);
// Errors below these are left alone (and a sweep that finds none ends the pass): a tenth of a millimetre and
// a hundredth of a degree, well below what any metric reports, so a figure at rest or in free fall costs the
// pass almost nothing.
constexpr btScalar kAnchorToleranceM = btScalar(1e-4);
constexpr btScalar kAngleToleranceRad = btScalar(2e-4);

// One body as the pass sees it: immovable (world, static geometry, another figure's or a game's body) or a body
// of this ragdoll, whose pose the pass works on locally and writes back once, at the end of the pass.
struct Side {
    btRigidBody* body = nullptr; ///< null: immovable
    btVector3 x{0, 0, 0};        ///< centre of mass, world
    btQuaternion q = btQuaternion::getIdentity();
    btMatrix3x3 r = btMatrix3x3::getIdentity(); ///< rotation of q
    btVector3 invInertiaLocal{0, 0, 0};
    btScalar invMass = 0;
    btMatrix3x3 invInertia{0, 0, 0, 0, 0, 0, 0, 0, 0}; ///< world
    bool moved = false;
    btVector3 x0{0, 0, 0}; ///< the pose the pass started from
    btQuaternion q0 = btQuaternion::getIdentity();

    btTransform transform() const { return btTransform(r, x); }
    void updateRotation() {
        r.setRotation(q);
        invInertia = r.scaled(invInertiaLocal) * r.transpose();
    }
};

Side sideOf(btRigidBody* body) {
    Side s;
    if (body == nullptr || body->getInvMass() == 0) return s;
    s.body = body;
    const btTransform& t = body->getCenterOfMassTransform();
    s.x = t.getOrigin();
    t.getBasis().getRotation(s.q);
    s.invMass = body->getInvMass();
    s.x0 = s.x;
    s.q0 = s.q;
    s.invInertiaLocal = body->getInvInertiaDiagLocal();
    s.updateRotation();
    return s;
}

// Scales a body's inverse mass and inertia (the pass's own copy; Bullet's body is untouched).
void scaleMass(Side& s, btScalar inverseFactor) {
    s.invMass *= inverseFactor;
    s.invInertiaLocal *= inverseFactor;
    s.updateRotation();
}

btMatrix3x3 skew(const btVector3& r) { return {0, -r.z(), r.y(), r.z(), 0, -r.x(), -r.y(), r.x(), 0}; }

// Moves a body by `dx` and turns it by the rotation vector `dtheta` (first order, renormalised).
void move(Side& s, const btVector3& dx, const btVector3& dtheta) {
    if (s.body == nullptr) return;
    s.x += dx;
    const btQuaternion dq(dtheta.x(), dtheta.y(), dtheta.z(), 0);
    s.q += (dq * s.q) * btScalar(0.5);
    s.q.normalize();
    s.updateRotation();
    s.moved = true;
}

// Inverse effective mass of a point fixed in a body at offset r: Δ(point) = K·P for an impulse P at the point.
btMatrix3x3 pointInvMass(const Side& s, const btVector3& r) {
    if (s.body == nullptr) return {0, 0, 0, 0, 0, 0, 0, 0, 0};
    const btMatrix3x3 rx = skew(r);
    return btMatrix3x3::getIdentity() * s.invMass - rx * s.invInertia * rx;
}

// Applies the positional impulse P at rA on A and −P at rB on B.
void applyLinear(Side& a, Side& b, const btVector3& p, const btVector3& ra, const btVector3& rb) {
    move(a, p * a.invMass, a.invInertia * ra.cross(p));
    move(b, -p * b.invMass, -(b.invInertia * rb.cross(p)));
}

// Applies the angular positional impulse L: A turns by IA⁻¹L, B by −IB⁻¹L.
void applyAngular(Side& a, Side& b, const btVector3& l) {
    move(a, btVector3(0, 0, 0), a.invInertia * l);
    move(b, btVector3(0, 0, 0), -(b.invInertia * l));
}

// Solves the 2×2 system [n1 n2]ᵀ K [n1 n2] λ = rhs and returns [n1 n2] λ (zero when singular).
btVector3 solveTwoRows(const btMatrix3x3& k, const btVector3& n1, const btVector3& n2, btScalar r1, btScalar r2) {
    const btScalar k11 = n1.dot(k * n1), k12 = n1.dot(k * n2), k22 = n2.dot(k * n2);
    const btScalar det = k11 * k22 - k12 * k12;
    if (det <= SIMD_EPSILON * (k11 * k22 + SIMD_EPSILON)) return {0, 0, 0};
    const btScalar l1 = (k22 * r1 - k12 * r2) / det, l2 = (k11 * r2 - k12 * r1) / det;
    return n1 * l1 + n2 * l2;
}

// The rotation vector that turns unit `from` onto unit `to`.
btVector3 turnOnto(const btVector3& from, const btVector3& to) {
    const btVector3 c = from.cross(to);
    const btScalar s = c.length();
    if (s < SIMD_EPSILON) return {0, 0, 0};
    return c * (btAtan2(s, from.dot(to)) / s);
}

// A constraint's two frames in the world, from the pass's working poses.
struct Frames {
    btTransform a, b;
};
Frames framesOf(const Side& a, const Side& b, const std::pair<btTransform, btTransform>& local) {
    return {a.transform() * local.first, b.body ? b.transform() * local.second : local.second};
}

// Anchor: the two anchor copies meet (sliders: only across the axis).
bool projectAnchor(Side& a, Side& b, const Frames& f, bool slider) {
    const btVector3 ra = f.a.getOrigin() - a.x;
    const btVector3 rb = b.body ? f.b.getOrigin() - b.x : btVector3(0, 0, 0);
    const btVector3 c = f.b.getOrigin() - f.a.getOrigin();
    if (c.length2() < kAnchorToleranceM * kAnchorToleranceM) return false;
    const btMatrix3x3 k = pointInvMass(a, ra) + pointInvMass(b, rb);
    btVector3 p;
    if (slider) {
        const btVector3 axis = f.b.getBasis().getColumn(0);
        btVector3 n1, n2;
        btPlaneSpace1(axis, n1, n2);
        p = solveTwoRows(k, n1, n2, c.dot(n1), c.dot(n2));
    } else {
        if (btFabs(k.determinant()) < SIMD_EPSILON) return false;
        p = k.inverse() * c;
    }
    applyLinear(a, b, p, ra, rb);
    return true;
}

// Full orientation lock (fixed, slider): frame A's rotation onto frame B's.
bool projectOrientation(Side& a, Side& b, const Frames& f) {
    btQuaternion q;
    (f.b.getBasis() * f.a.getBasis().transpose()).getRotation(q);
    if (q.w() < 0) q = -q;
    const btScalar angle = q.getAngle();
    if (angle < kAngleToleranceRad) return false;
    const btVector3 delta = q.getAxis() * angle;
    const btMatrix3x3 k = a.invInertia + b.invInertia;
    if (btFabs(k.determinant()) < SIMD_EPSILON) return false;
    applyAngular(a, b, k.inverse() * delta);
    return true;
}

// Hinge axes: frame A's Z onto frame B's Z, leaving the rotation about the axis free.
bool projectHingeAxis(Side& a, Side& b, const Frames& f) {
    const btVector3 za = f.a.getBasis().getColumn(2), zb = f.b.getBasis().getColumn(2);
    const btVector3 delta = turnOnto(za, zb);
    if (delta.length2() < kAngleToleranceRad * kAngleToleranceRad) return false;
    btVector3 n1, n2;
    btPlaneSpace1(zb, n1, n2);
    applyAngular(a, b, solveTwoRows(a.invInertia + b.invInertia, n1, n2, delta.dot(n1), delta.dot(n2)));
    return true;
}

// One limit row past its limit: turn the bodies back by the excess.
bool projectLimitRow(Side& a, Side& b, const LimitRow& row) {
    if (row.excess <= kAngleToleranceRad) return false;
    const btScalar w = row.axisWorld.dot((a.invInertia + b.invInertia) * row.axisWorld);
    if (w < SIMD_EPSILON) return false;
    applyAngular(a, b, row.axisWorld * (-row.excess / w));
    return true;
}

// The rows of `c`'s limit past the limit (none when within it) for the two frames and the two bodies' bases.
int violatedLimitRows(const figure::FigureConstraint& c, const Frames& f, const btMatrix3x3& body1Basis,
                      const btMatrix3x3& body2Basis, LimitRow rows[2]) {
    if (const auto* h = std::get_if<figure::HingeRange>(&c.limit))
        return hingeRangeRow(f.a.getBasis(), f.b.getBasis(), static_cast<btScalar>(h->lowerRad),
                             static_cast<btScalar>(h->upperRad), 0, rows[0]);
    if (const auto* cone = std::get_if<figure::ConeLimit>(&c.limit)) {
        btVector3 y, z;
        const btVector3 axis = (body2Basis * toBt(cone->axisInBody2)).normalized();
        btPlaneSpace1(axis, y, z);
        btMatrix3x3 basis;
        basis.setValue(axis.x(), y.x(), z.x(), axis.y(), y.y(), z.y(), axis.z(), y.z(), z.z());
        return directionLimitRows(body1Basis * toBt(cone->shaftInBody1), basis, LimitShape::Cone,
                                  static_cast<btScalar>(cone->halfAngleRad), 0, 0, rows);
    }
    if (const auto* p = std::get_if<figure::PyramidLimit>(&c.limit))
        return directionLimitRows(body1Basis * toBt(p->shaftInBody1), body2Basis * toBt(p->basisInBody2),
                                  LimitShape::Pyramid, static_cast<btScalar>(p->halfAngle1Rad),
                                  static_cast<btScalar>(p->halfAngle2Rad), 0, rows);
    return 0;
}

bool projectLimit(Side& a, Side& b, const figure::FigureConstraint& c, const Frames& f, const btMatrix3x3& body1Basis,
                  const btMatrix3x3& body2Basis) {
    LimitRow rows[2];
    const int n = violatedLimitRows(c, f, body1Basis, body2Basis, rows);
    bool corrected = false;
    for (int i = 0; i < n; ++i) corrected = projectLimitRow(a, b, rows[i]) || corrected;
    return corrected;
}

bool projectContact(Side& a, Side& b, const btManifoldPoint& cp) {
    // Immovable sides keep the world points Bullet found; movable ones carry theirs along.
    const btVector3 pa = a.body ? a.transform() * cp.m_localPointA : cp.m_positionWorldOnA;
    const btVector3 pb = b.body ? b.transform() * cp.m_localPointB : cp.m_positionWorldOnB;
    const btVector3& n = cp.m_normalWorldOnB;
    const btScalar depth = -(pa - pb).dot(n) - kContactSlopM;
    if (depth <= kAnchorToleranceM) return false;
    const btVector3 ra = a.body ? pa - a.x : btVector3(0, 0, 0), rb = b.body ? pb - b.x : btVector3(0, 0, 0);
    const btVector3 ran = ra.cross(n), rbn = rb.cross(n);
    const btScalar w = a.invMass + b.invMass + ran.dot(a.invInertia * ran) + rbn.dot(b.invInertia * rbn);
    if (w < SIMD_EPSILON) return false;
    applyLinear(a, b, n * (kContactFraction * depth / w), ra, rb);
    return true;
}

// One contact manifold touching the ragdoll, with its sides (null: immovable).
struct ContactSides {
    btPersistentManifold* manifold;
    Side* a;
    Side* b;
};

// A static plane (the ground) that a body of the ragdoll has manifolds with.
struct PlaneContact {
    Side* side;
    const btCollisionObject* plane;
};

// The point of `shape` (at `world`) deepest along −normal, and its height along normal. A compound's deepest
// child point; a shape that is neither convex nor a compound has none (height: BT_LARGE_FLOAT).
btVector3 deepestPoint(const btCollisionShape& shape, const btTransform& world, const btVector3& normal,
                       btScalar& height) {
    height = BT_LARGE_FLOAT;
    if (shape.getShapeType() == COMPOUND_SHAPE_PROXYTYPE) {
        const auto& compound = static_cast<const btCompoundShape&>(shape);
        btVector3 best(0, 0, 0);
        for (int i = 0; i < compound.getNumChildShapes(); ++i) {
            btScalar h = 0;
            const btVector3 p =
                deepestPoint(*compound.getChildShape(i), world * compound.getChildTransform(i), normal, h);
            if (h < height) {
                height = h;
                best = p;
            }
        }
        return best;
    }
    if (!shape.isConvex()) return btVector3(0, 0, 0);
    // With the margin: a hull's surface is its points grown by it; a box's corners already include it.
    const btVector3 local =
        static_cast<const btConvexShape&>(shape).localGetSupportingVertex(-(world.getBasis().transpose() * normal));
    const btVector3 p = world * local;
    height = p.dot(normal);
    return p;
}

// The body's deepest point below the plane, projected as a contact point when the manifolds of the pair do not
// know it. A body whipped round in the substep (a foot slapping down as its shin lands: 40 rad/s and more, 0.7
// rad in a substep) turns vertices into the ground that were out of the manifold's reach when the substep began;
// the manifold's points, carried along, stay above it, so the pass saw nothing while the foot ended 7–15 cm
// deep. A point the manifolds know (one of them within a millimetre of it) is left to them: at rest on a face or
// an edge the support point is any of several equal corners, and projecting just one of them would tip the body.
bool projectPlane(const PlaneContact& pc, std::span<const ContactSides> contacts) {
    Side& a = *pc.side;
    const auto& shape = static_cast<const btStaticPlaneShape&>(*pc.plane->getCollisionShape());
    const btTransform& planeWorld = pc.plane->getWorldTransform();
    const btVector3 n = planeWorld.getBasis() * shape.getPlaneNormal();
    const btScalar offset = shape.getPlaneConstant() + n.dot(planeWorld.getOrigin());
    btScalar height = 0;
    const btVector3 p = deepestPoint(*a.body->getCollisionShape(), a.transform(), n, height);
    const btScalar depth = offset - height - kContactSlopM;
    if (depth <= kAnchorToleranceM) return false;
    for (const ContactSides& cs : contacts) {
        const bool first = cs.a == &a && cs.manifold->getBody1() == pc.plane;
        if (!first && !(cs.b == &a && cs.manifold->getBody0() == pc.plane)) continue;
        for (int k = 0; k < cs.manifold->getNumContacts(); ++k) {
            const btManifoldPoint& cp = cs.manifold->getContactPoint(k);
            const btVector3 known = a.transform() * (first ? cp.m_localPointA : cp.m_localPointB);
            if (offset - known.dot(n) - kContactSlopM > depth - kKnownPointM) return false;
        }
    }
    const btVector3 ra = p - a.x, ran = ra.cross(n);
    const btScalar w = a.invMass + ran.dot(a.invInertia * ran);
    if (w < SIMD_EPSILON) return false;
    Side immovable;
    applyLinear(a, immovable, n * (kContactFraction * depth / w), ra, btVector3(0, 0, 0));
    return true;
}

// A contact point on static geometry that the velocity solve held by static friction, where the pass found it.
struct Stick {
    Side* side;
    btVector3 local; ///< the point in the body's frame
    btVector3 world; ///< where it was when the pass began
    btVector3 normal;
};

// Static friction at the position level: the point goes back to where it was along the contact plane (the
// normal is the contact rule's). Without it the pass slid every resting body's contacts freely while it closed
// the joints the velocity solve had let sag under the weight, and the velocity solve's friction then held them
// where they had slid: each step the figure inched along the ground (a lying humanoid crawled at 15–25 mm/s and
// never came to rest in most of the stress runs that fail `no-rest`).
bool projectStick(const Stick& st) {
    Side& a = *st.side;
    const btVector3 p = a.transform() * st.local;
    btVector3 slide = p - st.world;
    slide -= st.normal * slide.dot(st.normal);
    const btScalar length = slide.length();
    if (length <= kAnchorToleranceM) return false;
    const btVector3 t = slide / length;
    const btVector3 ra = p - a.x, rat = ra.cross(t);
    const btScalar w = a.invMass + rat.dot(a.invInertia * rat);
    if (w < SIMD_EPSILON) return false;
    Side immovable;
    applyLinear(a, immovable, -t * (length / w), ra, btVector3(0, 0, 0));
    return true;
}

// Method::positionVelocity: the pass moved the body by Δx since the step integrated it by v·dt. The fraction of
// that motion the pass took back (how far Δx goes against v, over |v|·dt, clamped to [0, 1]) is removed from v,
// so that a motion the pass reverts every substep does not live on in the velocity. A move across v takes
// nothing; no speed grows and none turns round. The same for ω and the pass's turn Δθ. (Measured against
// removing only v's component along Δx, which keeps the rest: this passes more of the stress matrix.)
btVector3 withoutTakenBack(const btVector3& v, const btVector3& moved, btScalar dt) {
    const btScalar vv = v.length2();
    if (vv < SIMD_EPSILON * SIMD_EPSILON) return v;
    const btScalar back = btClamped(-moved.dot(v) / (vv * dt), btScalar(0), btScalar(1));
    return v * (1 - back);
}

void takeBackVelocity(const Side& s, btScalar dt) {
    if (!(dt > 0)) return;
    btQuaternion dq = s.q * s.q0.inverse();
    if (dq.w() < 0) dq = -dq;
    const btScalar angle = dq.getAngle();
    const btVector3 turned = angle > SIMD_EPSILON ? dq.getAxis() * angle : btVector3(0, 0, 0);
    s.body->setLinearVelocity(withoutTakenBack(s.body->getLinearVelocity(), s.x - s.x0, dt));
    s.body->setAngularVelocity(withoutTakenBack(s.body->getAngularVelocity(), turned, dt));
}

// Every joint at once: a Newton step on the ragdoll's joint tree with the bodies' masses (Baraff's block
// factorisation, as the direct velocity solve uses), so that closing one joint does not open its neighbours.
// Per joint: the anchor gap (3 rows), the locked axes (fixed: 3, hinge: 2) and the limit rows past their limit
// (as equalities: the step puts them back on the limit). Joints that close a loop, a second joint to the world in
// one tree, and sliders are left to the sweeps. Nodes: the movable bodies (6: position, rotation vector), then
// the joints; H = [[M, −Jᵀ], [−J, 0]], H [Δx; λ] = [0; C], so that J Δx = −C and M Δx = Jᵀ λ.
class JointTree {
  public:
    struct Joint {
        int constraint;
        int a, b; // body indices; −1: immovable
    };
    // A joint's rows this step: the two anchor copies, and angular rows J_A = [0, n], J_B = [0, −n], each with
    // its error C (the step makes C + n·(Δθ_A − Δθ_B) = 0).
    struct Rows {
        btVector3 anchorA, anchorB;
        int angular = 0;
        btVector3 axis[5];
        btScalar error[5];
    };
    // Lays the tree out once per pass from the joints' endpoints; false when there is nothing to solve.
    bool build(std::span<const Joint> joints, int bodies) {
        m_afterValid = false;
        m_bodies = bodies;
        std::vector<int>& root = m_root;
        root.resize(static_cast<std::size_t>(bodies));
        std::iota(root.begin(), root.end(), 0);
        std::vector<char>& grounded = m_grounded;
        grounded.assign(static_cast<std::size_t>(bodies), 0);
        const auto find = [&](int i) {
            while (root[static_cast<std::size_t>(i)] != i) i = root[static_cast<std::size_t>(i)];
            return i;
        };
        m_joints.clear();
        for (const Joint& j : joints) {
            if (j.a < 0 && j.b < 0) continue;
            if (j.a >= 0 && j.b >= 0) {
                const int ra = find(j.a), rb = find(j.b);
                if (ra == rb) continue; // closes a loop
                if (grounded[static_cast<std::size_t>(ra)] && grounded[static_cast<std::size_t>(rb)]) continue;
                root[static_cast<std::size_t>(ra)] = rb;
                grounded[static_cast<std::size_t>(rb)] |= grounded[static_cast<std::size_t>(ra)];
            } else {
                const int r = find(j.a >= 0 ? j.a : j.b);
                if (grounded[static_cast<std::size_t>(r)]) continue; // a second hold on the world
                grounded[static_cast<std::size_t>(r)] = 1;
            }
            m_joints.push_back(j);
        }
        if (m_joints.empty()) return false;
        // Parents: a grounded tree hangs from its world joint, any other from its first body.
        const int nodes = bodies + static_cast<int>(m_joints.size());
        m_parent.assign(static_cast<std::size_t>(nodes), -2);
        std::vector<std::vector<int>>& jointsAt = m_jointsAt;
        if (jointsAt.size() < static_cast<std::size_t>(bodies)) jointsAt.resize(static_cast<std::size_t>(bodies));
        for (auto& at : jointsAt) at.clear();
        for (std::size_t k = 0; k < m_joints.size(); ++k) {
            if (m_joints[k].a >= 0) jointsAt[static_cast<std::size_t>(m_joints[k].a)].push_back(static_cast<int>(k));
            if (m_joints[k].b >= 0) jointsAt[static_cast<std::size_t>(m_joints[k].b)].push_back(static_cast<int>(k));
        }
        std::vector<int>& stack = m_stack;
        stack.clear();
        auto hang = [&](int body) { // everything reachable from `body`, whose parent is already set
            stack.push_back(body);
            while (!stack.empty()) {
                const int x = stack.back();
                stack.pop_back();
                for (int k : jointsAt[static_cast<std::size_t>(x)]) {
                    const int node = bodies + k;
                    if (m_parent[static_cast<std::size_t>(node)] != -2) continue;
                    m_parent[static_cast<std::size_t>(node)] = x;
                    const Joint& j = m_joints[static_cast<std::size_t>(k)];
                    const int other = j.a == x ? j.b : j.a;
                    if (other < 0 || m_parent[static_cast<std::size_t>(other)] != -2) continue;
                    m_parent[static_cast<std::size_t>(other)] = node;
                    stack.push_back(other);
                }
            }
        };
        for (std::size_t k = 0; k < m_joints.size(); ++k) {
            const Joint& j = m_joints[k];
            if (j.a >= 0 && j.b >= 0) continue;
            const int body = j.a >= 0 ? j.a : j.b;
            m_parent[static_cast<std::size_t>(bodies) + k] = -1;
            m_parent[static_cast<std::size_t>(body)] = bodies + static_cast<int>(k);
            hang(body);
        }
        for (int x = 0; x < bodies; ++x)
            if (m_parent[static_cast<std::size_t>(x)] == -2) {
                m_parent[static_cast<std::size_t>(x)] = -1;
                hang(x);
            }
        return true;
    }

    // One Newton step of `sides` for the joints' rows (`rowsOf(joint)`). False (nothing moved) when every row is
    // within its tolerance already, or the factorisation fails.
    template <typename RowsOf>
    bool step(std::vector<Side>& sides, RowsOf rowsOf) {
        const int bodies = m_bodies;
        // After an accepted step the bodies are where it measured its error: its rows are this step's.
        const bool reuse = m_afterValid;
        m_afterValid = false;
        if (reuse) std::swap(m_rows, m_after);
        m_rows.resize(m_joints.size());
        m_after.resize(m_joints.size());
        m_dims.assign(m_parent.size(), 6);
        bool open = false;
        for (std::size_t k = 0; k < m_joints.size(); ++k) {
            if (!reuse) m_rows[k] = rowsOf(m_joints[k]);
            const Rows& r = m_rows[k];
            m_dims[static_cast<std::size_t>(bodies) + k] = 3 + r.angular;
            open = open || (r.anchorB - r.anchorA).length2() > kAnchorToleranceM * kAnchorToleranceM;
            for (int i = 0; i < r.angular; ++i) open = open || btFabs(r.error[i]) > kAngleToleranceRad;
        }
        if (!open || !m_tree.reset(m_dims, m_parent)) return false;
        for (int x = 0; x < bodies; ++x) {
            const Side& s = sides[static_cast<std::size_t>(x)];
            double* d = m_tree.diag(x);
            std::fill(d, d + 36, 0.0);
            if (s.body == nullptr) { // immovable inside the tree: a very heavy body
                for (int q = 0; q < 6; ++q) d[7 * q] = 1e12;
                continue;
            }
            const btVector3& il = s.invInertiaLocal;
            const auto inv = [](btScalar v) { return v > 0 ? 1 / v : btScalar(1e12); };
            const btMatrix3x3 inertia = s.r.scaled(btVector3(inv(il.x()), inv(il.y()), inv(il.z()))) * s.r.transpose();
            for (int q = 0; q < 3; ++q) {
                d[7 * q] = 1.0 / double(s.invMass);
                for (int c = 0; c < 3; ++c) d[6 * (3 + q) + 3 + c] = double(inertia[q][c]);
            }
        }
        m_rhs.assign(static_cast<std::size_t>(m_tree.size()), 0.0);
        double negJ[8 * 6]; // −J of one side, rows × 6, row-major
        for (std::size_t k = 0; k < m_joints.size(); ++k) {
            const Joint& j = m_joints[k];
            const Rows& r = m_rows[k];
            const int node = bodies + static_cast<int>(k);
            const int rows = 3 + r.angular;
            std::fill(m_tree.diag(node), m_tree.diag(node) + rows * rows, 0.0);
            double* rhs = m_rhs.data() + m_tree.offset(node);
            const btVector3 gap = r.anchorB - r.anchorA;
            for (int q = 0; q < 3; ++q) rhs[q] = double(gap[q]);
            for (int i = 0; i < r.angular; ++i) rhs[3 + i] = double(r.error[i]);
            // J_A = [−I, [r_A]×; 0, n], J_B = [I, −[r_B]×; 0, −n].
            for (int side = 0; side < 2; ++side) {
                const int x = side ? j.b : j.a;
                if (x < 0) continue;
                const Side& s = sides[static_cast<std::size_t>(x)];
                const btMatrix3x3 rx = skew((side ? r.anchorB : r.anchorA) - s.x);
                const double sign = side ? 1.0 : -1.0;
                std::fill(negJ, negJ + 6 * rows, 0.0);
                for (int q = 0; q < 3; ++q) {
                    negJ[6 * q + q] = -sign;
                    for (int c = 0; c < 3; ++c) negJ[6 * q + 3 + c] = sign * double(rx[q][c]);
                }
                for (int i = 0; i < r.angular; ++i)
                    for (int c = 0; c < 3; ++c) negJ[6 * (3 + i) + 3 + c] = sign * double(r.axis[i][c]);
                if (m_tree.parent(node) == x) {
                    std::copy(negJ, negJ + 6 * rows, m_tree.toParent(node)); // H_{joint,body}
                } else { // the body hangs from the joint: H_{body,joint} = (H_{joint,body})ᵀ
                    double* e = m_tree.toParent(x);
                    for (int q = 0; q < rows; ++q)
                        for (int c = 0; c < 6; ++c) e[rows * c + q] = negJ[6 * q + c];
                }
            }
        }
        if (!m_tree.factor()) return false;
        m_tree.solve(m_rhs.data());
        if (!std::all_of(m_rhs.begin(), m_rhs.end(), [](double v) { return std::isfinite(v); })) return false;
        // The step is exact only to first order: where the mass-weighted solution turns light, thin bodies a long
        // way (a nearly straight rope of 10 cm links closes 1 mm gaps by turning links 0.3 rad one way and the
        // next the other), the second-order rest can exceed what it closed. So the error is measured after the
        // move, and a step that leaves more than it found is halved, then dropped.
        const double before = error(m_rows);
        m_saved = sides;
        for (double scale = 1;; scale *= 0.5) {
            for (int x = 0; x < bodies; ++x) {
                const double* dx = m_rhs.data() + m_tree.offset(x);
                const btScalar f = static_cast<btScalar>(scale);
                move(sides[static_cast<std::size_t>(x)],
                     btVector3(btScalar(dx[0]), btScalar(dx[1]), btScalar(dx[2])) * f,
                     btVector3(btScalar(dx[3]), btScalar(dx[4]), btScalar(dx[5])) * f);
            }
            for (std::size_t k = 0; k < m_joints.size(); ++k) m_after[k] = rowsOf(m_joints[k]);
            if (error(m_after) < before) {
                m_afterValid = true;
                return true;
            }
            for (std::size_t x = 0; x < sides.size(); ++x) sides[x] = m_saved[x];
            if (scale <= 0.25) return false;
        }
    }

  private:
    // The largest error of `rows`: anchor gaps in metres, angles as the arc they make at 0.1 m.
    static double error(const std::vector<Rows>& rows) {
        double worst = 0;
        for (const Rows& r : rows) {
            worst = std::max(worst, double((r.anchorB - r.anchorA).length()));
            for (int i = 0; i < r.angular; ++i) worst = std::max(worst, 0.1 * std::abs(double(r.error[i])));
        }
        return worst;
    }

    int m_bodies = 0;
    std::vector<Joint> m_joints;
    std::vector<int> m_root, m_stack; // build()'s scratch
    std::vector<char> m_grounded;
    std::vector<std::vector<int>> m_jointsAt;
    std::vector<int> m_parent, m_dims;
    std::vector<Rows> m_rows, m_after;
    bool m_afterValid = false; // m_after holds the rows at the bodies' current poses
    std::vector<Side> m_saved;
    BlockTree m_tree;
    std::vector<double> m_rhs;
};

// The pass's buffers, kept from call to call for their capacity: one set per thread, since worlds (each on one
// thread) may step concurrently.
struct Scratch {
    std::vector<Side> bodies;
    std::vector<ContactSides> contacts;
    std::vector<PlaneContact> planes;
    std::vector<Stick> sticks;
    std::vector<char> grounded;
    std::vector<JointTree::Joint> joints;
    JointTree tree;
};
thread_local Scratch t_scratch;

} // namespace

void positionPass(Ragdoll& r, int sweeps, int treeMode, std::span<btPersistentManifold* const> manifolds, btScalar dt,
                  bool takeVelocity) {
    const figure::Figure& f = r.figure();
    Scratch& scratch = t_scratch;
    std::vector<Side>& bodies = scratch.bodies;
    // One side per Bullet rigid body (figure bodies merged by Method::mergeFixed share one).
    bodies.clear();
    bodies.reserve(static_cast<std::size_t>(r.rigidBodyCount()));
    for (int i = 0; i < r.rigidBodyCount(); ++i) bodies.push_back(sideOf(&r.rigidBody(i)));
    Side world;
    // The contacts' sides: this ragdoll's bodies by index, everything else immovable.
    auto sideFor = [&](const btCollisionObject* o) -> Side* {
        for (std::size_t i = 0; i < bodies.size(); ++i)
            if (static_cast<const btCollisionObject*>(&r.rigidBody(static_cast<int>(i))) == o) return &bodies[i];
        return nullptr;
    };
    std::vector<ContactSides>& contacts = scratch.contacts;
    contacts.clear();
    for (btPersistentManifold* m : manifolds) {
        Side* a = sideFor(m->getBody0());
        Side* b = sideFor(m->getBody1());
        if (a || b) contacts.push_back({m, a, b});
    }
    // Static planes touching the ragdoll's bodies, once per pair (continuous collision adds a second manifold).
    std::vector<PlaneContact>& planes = scratch.planes;
    planes.clear();
    for (const ContactSides& cs : contacts) {
        if ((cs.a != nullptr) == (cs.b != nullptr)) continue;
        Side* side = cs.a ? cs.a : cs.b;
        const btCollisionObject* other = cs.a ? cs.manifold->getBody1() : cs.manifold->getBody0();
        if (other->getCollisionShape()->getShapeType() != STATIC_PLANE_PROXYTYPE) continue;
        if (std::none_of(planes.begin(), planes.end(),
                         [&](const PlaneContact& p) { return p.side == side && p.plane == other; }))
            planes.push_back({side, other});
    }
    // Contact points on static (or kinematic) geometry held by static friction in the velocity solve.
    std::vector<Stick>& sticks = scratch.sticks;
    sticks.clear();
    for (const ContactSides& cs : contacts) {
        if ((cs.a != nullptr) == (cs.b != nullptr)) continue;
        const btCollisionObject* other = cs.a ? cs.manifold->getBody1() : cs.manifold->getBody0();
        if (!other->isStaticOrKinematicObject()) continue;
        Side* side = cs.a ? cs.a : cs.b;
        for (int k = 0; k < cs.manifold->getNumContacts(); ++k) {
            const btManifoldPoint& cp = cs.manifold->getContactPoint(k);
            const btScalar bound = kStickFrictionFraction * cp.m_combinedFriction * cp.m_appliedImpulse;
            if (cp.m_appliedImpulse <= 0 || std::abs(cp.m_appliedImpulseLateral1) > bound ||
                std::abs(cp.m_appliedImpulseLateral2) > bound)
                continue;
            const btVector3 local = cs.a ? cp.m_localPointA : cp.m_localPointB;
            const btVector3 at = side->transform() * local;
            if (side->body->getVelocityInLocalPoint(at - side->x).length() > kStickSpeedMps) continue;
            sticks.push_back({side, local, at, cp.m_normalWorldOnB});
        }
    }
    Side immovableA, immovableB;
    const btMatrix3x3 spawnBasis = r.spawnTransform().getBasis();
    JointTree& tree = scratch.tree;
    const bool haveTree = treeMode > 0 && [&] {
        std::vector<JointTree::Joint>& joints = scratch.joints;
        joints.clear();
        for (int i = 0; i < static_cast<int>(f.constraints.size()); ++i) {
            const figure::FigureConstraint& c = f.constraints[static_cast<std::size_t>(i)];
            if (c.type == figure::JointType::Spring || c.type == figure::JointType::Slider) continue;
            const int a = r.rigidIndexOf(c.body1);
            const int b = c.body2 >= 0 ? r.rigidIndexOf(c.body2) : -1;
            if (a == b) continue; // merged: holds exactly
            joints.push_back({i, bodies[static_cast<std::size_t>(a)].body ? a : -1,
                              b >= 0 && bodies[static_cast<std::size_t>(b)].body ? b : -1});
        }
        return tree.build(joints, static_cast<int>(bodies.size()));
    }();
    auto rowsOf = [&](const JointTree::Joint& j) {
        const figure::FigureConstraint& c = f.constraints[static_cast<std::size_t>(j.constraint)];
        Side& a = j.a >= 0 ? bodies[static_cast<std::size_t>(j.a)] : immovableA;
        Side& b = j.b >= 0 ? bodies[static_cast<std::size_t>(j.b)] : world;
        const Frames fr = framesOf(a, b, r.rigidFramesLocal(j.constraint));
        JointTree::Rows rows;
        rows.anchorA = fr.a.getOrigin();
        rows.anchorB = fr.b.getOrigin();
        if (treeMode < 2) return rows;
        if (c.type == figure::JointType::Fixed) {
            btQuaternion q;
            (fr.b.getBasis() * fr.a.getBasis().transpose()).getRotation(q);
            if (q.w() < 0) q = -q;
            const btScalar angle = q.getAngle();
            const btVector3 delta = angle > SIMD_EPSILON ? q.getAxis() * angle : btVector3(0, 0, 0);
            for (int i = 0; i < 3; ++i) {
                rows.axis[rows.angular] = btVector3(i == 0, i == 1, i == 2);
                rows.error[rows.angular++] = -delta[i];
            }
        } else if (c.type == figure::JointType::Hinge) {
            const btVector3 zb = fr.b.getBasis().getColumn(2);
            const btVector3 delta = turnOnto(fr.a.getBasis().getColumn(2), zb);
            btVector3 n1(0, 0, 0), n2(0, 0, 0);
            btPlaneSpace1(zb, n1, n2);
            for (const btVector3& n : {n1, n2}) {
                rows.axis[rows.angular] = n;
                rows.error[rows.angular++] = -delta.dot(n);
            }
        }
        LimitRow limit[2];
        const int n = violatedLimitRows(c, fr, a.r * r.bodyInRigid(c.body1).getBasis(),
                                        b.body ? b.r * r.bodyInRigid(c.body2).getBasis() : spawnBasis, limit);
        for (int i = 0; i < n; ++i)
            if (limit[i].excess > kAngleToleranceRad && rows.angular < 5) {
                rows.axis[rows.angular] = limit[i].axisWorld;
                rows.error[rows.angular++] = limit[i].excess;
            }
        return rows;
    };
    for (int sweep = 0; sweep < sweeps; ++sweep) {
        bool corrected = false;
        for (int i = 0; i < static_cast<int>(f.constraints.size()); ++i) {
            const figure::FigureConstraint& c = f.constraints[static_cast<std::size_t>(i)];
            if (c.type == figure::JointType::Spring) continue;
            Side& a = bodies[static_cast<std::size_t>(r.rigidIndexOf(c.body1))];
            Side& b = c.body2 >= 0 ? bodies[static_cast<std::size_t>(r.rigidIndexOf(c.body2))] : world;
            if ((a.body == nullptr && b.body == nullptr) || &a == &b) continue; // &a == &b: merged, holds exactly
            const auto& local = r.rigidFramesLocal(i);
            if (!std::holds_alternative<std::monostate>(c.limit))
                corrected = projectLimit(a, b, c, framesOf(a, b, local), a.r * r.bodyInRigid(c.body1).getBasis(),
                                         b.body ? b.r * r.bodyInRigid(c.body2).getBasis() : spawnBasis) ||
                            corrected;
            if (c.type == figure::JointType::Fixed || c.type == figure::JointType::Slider)
                corrected = projectOrientation(a, b, framesOf(a, b, local)) || corrected;
            else if (c.type == figure::JointType::Hinge)
                corrected = projectHingeAxis(a, b, framesOf(a, b, local)) || corrected;
            corrected = projectAnchor(a, b, framesOf(a, b, local), c.type == figure::JointType::Slider) || corrected;
        }
        for (const ContactSides& cs : contacts) {
            Side& a = cs.a ? *cs.a : immovableA;
            Side& b = cs.b ? *cs.b : immovableB;
            for (int k = 0; k < cs.manifold->getNumContacts(); ++k)
                corrected = projectContact(a, b, cs.manifold->getContactPoint(k)) || corrected;
        }
        for (const PlaneContact& pc : planes) corrected = projectPlane(pc, contacts) || corrected;
        for (const Stick& st : sticks) corrected = projectStick(st) || corrected;
        if (!corrected) break; // nothing left to correct
    }
    // Then the joints over the tree: Newton steps until every row is within tolerance (three at most: after the
    // sweeps the errors are millimetres and one step leaves only the second-order rest; from centimetres and
    // tens of degrees, three reach the tolerance).
    std::vector<char>& grounded = scratch.grounded;
    grounded.assign(bodies.size(), 0);
    if (haveTree && treeMode >= 2) {
        for (const ContactSides& cs : contacts)
            if ((cs.a != nullptr) != (cs.b != nullptr) && cs.manifold->getNumContacts() > 0)
                grounded[static_cast<std::size_t>((cs.a ? cs.a : cs.b) - bodies.data())] = 1;
        for (std::size_t i = 0; i < bodies.size(); ++i)
            if (grounded[i]) scaleMass(bodies[i], 1 / kGroundedTreeMassFactor);
    }
    for (int n = 0; haveTree && n < 3; ++n)
        if (!tree.step(bodies, rowsOf)) break;
    for (std::size_t i = 0; i < bodies.size(); ++i)
        if (grounded[i]) scaleMass(bodies[i], kGroundedTreeMassFactor);
    for (Side& s : bodies) {
        if (!s.moved) continue;
        s.body->setCenterOfMassTransform(s.transform());
        if (takeVelocity) takeBackVelocity(s, dt);
    }
}

} // namespace afb::bullet::detail
