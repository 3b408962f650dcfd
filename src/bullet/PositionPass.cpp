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

#include "PositionBodies.h"
#include "PositionTree.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/detail/Constraints.h"
#include "afb/detail/Convert.h"

namespace afb::bullet::detail {
namespace {

using namespace position;

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

// The versions of a check's sides when it last found nothing to correct (0: not yet). Every check is a function of
// its sides' poses and of what stays fixed through the pass, so it finds nothing again until one side has moved:
// a sweep skips it till then, and the sweep that confirms the pass is done costs next to nothing.
struct Settled {
    unsigned a = 0, b = 0;
    bool holds(const Side& sa, const Side& sb) const { return a == sa.version + 1 && b == sb.version + 1; }
    void set(const Side& sa, const Side& sb) {
        a = sa.version + 1;
        b = sb.version + 1;
    }
};

// One contact manifold touching the ragdoll, with its sides (null: immovable).
struct ContactSides {
    btPersistentManifold* manifold;
    Side* a;
    Side* b;
    Settled settled[MANIFOLD_CACHE_SIZE]{}; // per point
};

// A static plane (the ground) that a body of the ragdoll has manifolds with.
struct PlaneContact {
    Side* side;
    const btCollisionObject* plane;
    Settled settled{};
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
    Settled settled{};
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

// The pass's buffers, kept from call to call for their capacity: one set per thread, since worlds (each on one
// thread) may step concurrently.
struct Scratch {
    std::vector<Side> bodies;
    std::vector<const btCollisionObject*> objects; // per side, its Bullet body (keyframed ones too)
    std::vector<ContactSides> contacts;
    std::vector<PlaneContact> planes;
    std::vector<Stick> sticks;
    std::vector<Settled> settledJoints; // per figure constraint
    std::vector<char> grounded;
    std::vector<JointTree::Joint> joints;
    JointTree tree;
};
thread_local Scratch t_scratch;

// One pass over one ragdoll: its bodies and the contacts touching them, gathered once, then the sweeps and the
// tree steps, then the poses written back.
class Pass {
  public:
    Pass(Ragdoll& r, int treeMode, Scratch& scratch)
        : m_r(r), m_f(r.figure()), m_treeMode(treeMode), m_s(scratch), m_bodies(scratch.bodies),
          m_spawnBasis(r.spawnTransform().getBasis()) {
        // One side per Bullet rigid body (figure bodies merged by Method::mergeFixed share one).
        m_bodies.clear();
        m_bodies.reserve(static_cast<std::size_t>(r.rigidBodyCount()));
        scratch.objects.clear();
        for (int i = 0; i < r.rigidBodyCount(); ++i) {
            btRigidBody& body = r.rigidBody(i);
            m_bodies.push_back(sideOf(&body));
            scratch.objects.push_back(&body);
        }
    }
    void gather(std::span<btPersistentManifold* const> manifolds);
    bool buildTree();
    JointTree::Rows rowsOf(const JointTree::Joint& j);
    bool sweep();
    void treeSteps(bool haveTree);
    void writeBack(btScalar dt, bool takeVelocity);

  private:
    Side* sideFor(const btCollisionObject* o);
    void gatherSticks();

    Ragdoll& m_r;
    const figure::Figure& m_f;
    int m_treeMode;
    Scratch& m_s;
    std::vector<Side>& m_bodies;
    Side m_world, m_immovableA, m_immovableB;
    btMatrix3x3 m_spawnBasis;
};

// The contacts' sides: this ragdoll's bodies by index, everything else immovable.
Side* Pass::sideFor(const btCollisionObject* o) {
    const std::vector<const btCollisionObject*>& objects = m_s.objects;
    for (std::size_t i = 0; i < objects.size(); ++i)
        if (objects[i] == o) return m_bodies[i].body ? &m_bodies[i] : nullptr; // keyframed: immovable, as static
    return nullptr;
}

void Pass::gather(std::span<btPersistentManifold* const> manifolds) {
    std::vector<ContactSides>& contacts = m_s.contacts;
    contacts.clear();
    for (btPersistentManifold* m : manifolds) {
        Side* a = sideFor(m->getBody0());
        Side* b = sideFor(m->getBody1());
        if (a || b) contacts.push_back({m, a, b, {}});
    }
    // Static planes touching the ragdoll's bodies, once per pair (continuous collision adds a second manifold).
    std::vector<PlaneContact>& planes = m_s.planes;
    planes.clear();
    for (const ContactSides& cs : contacts) {
        if ((cs.a != nullptr) == (cs.b != nullptr)) continue;
        Side* side = cs.a ? cs.a : cs.b;
        const btCollisionObject* other = cs.a ? cs.manifold->getBody1() : cs.manifold->getBody0();
        if (other->getCollisionShape()->getShapeType() != STATIC_PLANE_PROXYTYPE) continue;
        if (std::none_of(planes.begin(), planes.end(),
                         [&](const PlaneContact& p) { return p.side == side && p.plane == other; }))
            planes.push_back({side, other, {}});
    }
    gatherSticks();
}

// Contact points on static (or kinematic) geometry held by static friction in the velocity solve.
void Pass::gatherSticks() {
    std::vector<Stick>& sticks = m_s.sticks;
    sticks.clear();
    for (const ContactSides& cs : m_s.contacts) {
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
            sticks.push_back({side, local, at, cp.m_normalWorldOnB, {}});
        }
    }
}

// The joints the tree step takes: those that keep a shared point (a slider's line is left to the sweeps).
bool Pass::buildTree() {
    if (m_treeMode <= 0) return false;
    std::vector<JointTree::Joint>& joints = m_s.joints;
    joints.clear();
    for (int i = 0; i < static_cast<int>(m_f.constraints.size()); ++i) {
        const figure::FigureConstraint& c = m_f.constraints[static_cast<std::size_t>(i)];
        if (figure::freedomOf(c.type).anchor != figure::AnchorHold::Point) continue;
        const int a = m_r.rigidIndexOf(c.body1);
        const int b = c.body2 >= 0 ? m_r.rigidIndexOf(c.body2) : -1;
        if (a == b) continue; // merged: holds exactly
        joints.push_back({i, m_bodies[static_cast<std::size_t>(a)].body ? a : -1,
                          b >= 0 && m_bodies[static_cast<std::size_t>(b)].body ? b : -1});
    }
    return m_s.tree.build(joints, static_cast<int>(m_bodies.size()));
}

// A joint's rows for the tree step: its anchor, and in mode 2 its locked axes and the limit rows past their limit.
JointTree::Rows Pass::rowsOf(const JointTree::Joint& j) {
    const figure::FigureConstraint& c = m_f.constraints[static_cast<std::size_t>(j.constraint)];
    // The joint's bodies at their poses (a keyframed one is in the tree as immovable: index −1).
    Side& a = m_bodies[static_cast<std::size_t>(m_r.rigidIndexOf(c.body1))];
    Side& b = c.body2 >= 0 ? m_bodies[static_cast<std::size_t>(m_r.rigidIndexOf(c.body2))] : m_world;
    const Frames fr = framesOf(a, b, m_r.rigidFramesLocal(j.constraint));
    JointTree::Rows rows;
    rows.anchorA = fr.a.getOrigin();
    rows.anchorB = fr.b.getOrigin();
    if (m_treeMode < 2) return rows;
    const figure::RotationHold held = figure::freedomOf(c.type).rotation;
    if (held == figure::RotationHold::All) {
        btQuaternion q;
        (fr.b.getBasis() * fr.a.getBasis().transpose()).getRotation(q);
        if (q.w() < 0) q = -q;
        const btScalar angle = q.getAngle();
        const btVector3 delta = angle > SIMD_EPSILON ? q.getAxis() * angle : btVector3(0, 0, 0);
        for (int i = 0; i < 3; ++i) {
            rows.axis[rows.angular] = btVector3(i == 0, i == 1, i == 2);
            rows.error[rows.angular++] = -delta[i];
        }
    } else if (held == figure::RotationHold::AllButAxis) {
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
    const int n = violatedLimitRows(c, fr, a.r * m_r.bodyInRigid(c.body1).getBasis(),
                                    b.placed ? b.r * m_r.bodyInRigid(c.body2).getBasis() : m_spawnBasis, limit);
    for (int i = 0; i < n; ++i)
        if (limit[i].excess > kAngleToleranceRad && rows.angular < 5) {
            rows.axis[rows.angular] = limit[i].axisWorld;
            rows.error[rows.angular++] = limit[i].excess;
        }
    return rows;
}

// One sweep: every joint (limit, locked axes, anchor), then every contact; whether anything was corrected.
bool Pass::sweep() {
    bool corrected = false;
    for (int i = 0; i < static_cast<int>(m_f.constraints.size()); ++i) {
        const figure::FigureConstraint& c = m_f.constraints[static_cast<std::size_t>(i)];
        const figure::JointFreedom freedom = figure::freedomOf(c.type);
        if (freedom.anchor == figure::AnchorHold::None) continue;
        Side& a = m_bodies[static_cast<std::size_t>(m_r.rigidIndexOf(c.body1))];
        Side& b = c.body2 >= 0 ? m_bodies[static_cast<std::size_t>(m_r.rigidIndexOf(c.body2))] : m_world;
        if ((a.body == nullptr && b.body == nullptr) || &a == &b) continue; // &a == &b: merged, holds exactly
        Settled& settled = m_s.settledJoints[static_cast<std::size_t>(i)];
        if (settled.holds(a, b)) continue;
        // The frames are taken again only after a projection moved the bodies (one that returns false moved
        // nothing, so the frames it saw still hold).
        const auto& local = m_r.rigidFramesLocal(i);
        Frames frames = framesOf(a, b, local);
        bool projectedAny = false;
        const auto moved = [&](bool projected) {
            if (projected) frames = framesOf(a, b, local);
            projectedAny = projectedAny || projected;
        };
        if (!std::holds_alternative<std::monostate>(c.limit))
            moved(projectLimit(a, b, c, frames, a.r * m_r.bodyInRigid(c.body1).getBasis(),
                               b.placed ? b.r * m_r.bodyInRigid(c.body2).getBasis() : m_spawnBasis));
        if (freedom.rotation == figure::RotationHold::All) moved(projectOrientation(a, b, frames));
        else if (freedom.rotation == figure::RotationHold::AllButAxis) moved(projectHingeAxis(a, b, frames));
        projectedAny = projectAnchor(a, b, frames, freedom.anchor == figure::AnchorHold::Line) || projectedAny;
        if (projectedAny) corrected = true;
        else settled.set(a, b);
    }
    for (ContactSides& cs : m_s.contacts) {
        Side& a = cs.a ? *cs.a : m_immovableA;
        Side& b = cs.b ? *cs.b : m_immovableB;
        for (int k = 0; k < cs.manifold->getNumContacts(); ++k) {
            Settled& settled = cs.settled[k];
            if (settled.holds(a, b)) continue;
            if (projectContact(a, b, cs.manifold->getContactPoint(k))) corrected = true;
            else settled.set(a, b);
        }
    }
    for (PlaneContact& pc : m_s.planes) {
        if (pc.settled.holds(*pc.side, m_world)) continue;
        if (projectPlane(pc, m_s.contacts)) corrected = true;
        else pc.settled.set(*pc.side, m_world);
    }
    for (Stick& st : m_s.sticks) {
        if (st.settled.holds(*st.side, m_world)) continue;
        if (projectStick(st)) corrected = true;
        else st.settled.set(*st.side, m_world);
    }
    return corrected;
}

// The joints over the tree: Newton steps until every row is within tolerance (three at most: after the sweeps the
// errors are millimetres and one step leaves only the second-order rest; from centimetres and tens of degrees,
// three reach the tolerance).
void Pass::treeSteps(bool haveTree) {
    std::vector<char>& grounded = m_s.grounded;
    grounded.assign(m_bodies.size(), 0);
    if (haveTree && m_treeMode >= 2) {
        for (const ContactSides& cs : m_s.contacts)
            if ((cs.a != nullptr) != (cs.b != nullptr) && cs.manifold->getNumContacts() > 0)
                grounded[static_cast<std::size_t>((cs.a ? cs.a : cs.b) - m_bodies.data())] = 1;
        for (std::size_t i = 0; i < m_bodies.size(); ++i)
            if (grounded[i]) scaleMass(m_bodies[i], 1 / kGroundedTreeMassFactor);
    }
    const auto rows = [this](const JointTree::Joint& j) { return rowsOf(j); };
    for (int n = 0; haveTree && n < 3; ++n)
        if (!m_s.tree.step(m_bodies, rows)) break;
    for (std::size_t i = 0; i < m_bodies.size(); ++i)
        if (grounded[i]) scaleMass(m_bodies[i], kGroundedTreeMassFactor);
}

void Pass::writeBack(btScalar dt, bool takeVelocity) {
    for (Side& s : m_bodies) {
        if (!s.moved) continue;
        s.body->setCenterOfMassTransform(s.transform());
        if (takeVelocity) takeBackVelocity(s, dt);
    }
}

} // namespace

void positionPass(Ragdoll& r, int sweeps, int treeMode, std::span<btPersistentManifold* const> manifolds, btScalar dt,
                  bool takeVelocity) {
    Pass pass(r, treeMode, t_scratch);
    t_scratch.settledJoints.assign(r.figure().constraints.size(), Settled{});
    pass.gather(manifolds);
    const bool haveTree = pass.buildTree();
    // A sweep that corrects nothing has found every joint within the tolerances the tree step closes them to:
    // the step is left out then.
    bool open = true;
    for (int sweep = 0; sweep < sweeps && open; ++sweep) open = pass.sweep();
    if (open) pass.treeSteps(haveTree);
    pass.writeBack(dt, takeVelocity);
}

} // namespace afb::bullet::detail
