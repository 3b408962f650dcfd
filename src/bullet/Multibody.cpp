// The reduced-coordinate backend (Multibody.h): docs/format.md §4 joints as btMultiBody links, §4.3/§4.5 limits as
// our own btMultiBodyConstraint rows, §6.1 rest, §6.2 collision filtering.
#include "Multibody.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <variant>

#include <BulletDynamics/Featherstone/btMultiBody.h>
#include <BulletDynamics/Featherstone/btMultiBodyConstraint.h>
#include <BulletDynamics/Featherstone/btMultiBodyDynamicsWorld.h>
#include <BulletDynamics/Featherstone/btMultiBodyFixedConstraint.h>
#include <BulletDynamics/Featherstone/btMultiBodyLinkCollider.h>
#include <BulletDynamics/Featherstone/btMultiBodyPoint2Point.h>

#include "EngineFriction.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/detail/Constraints.h"
#include "afb/detail/Convert.h"
#include "afb/figure/Collision.h"

namespace afb::bullet::detail {

using figure::FigureConstraint;
using figure::JointType;

namespace {

// The position sweeps' contacts, as the rigid backend's position pass (PositionPass.cpp): only what is deeper than
// the slop, half of it per sweep, so resting contacts are not pushed apart and re-made every substep; depths below
// the tolerance are left alone.
constexpr btScalar kSweepContactSlopM = btScalar(0.002);
constexpr btScalar kSweepContactFraction = btScalar(0.5);
constexpr btScalar kSweepToleranceM = btScalar(1e-4);

// Generalised velocities a link may reach (Bullet clamps every coordinate velocity to this after each step; its
// default of 100 would clip a foot's spin at impact and hide an instability instead of showing it).
constexpr btScalar kMaxCoordinateVelocity = 1000;

btQuaternion quatOf(const btMatrix3x3& m) {
    btQuaternion q;
    m.getRotation(q);
    return q;
}

// A tree's kinetic energy (J), linear momentum (N·s, world) and mass (kg), from its link velocities.
struct TreeMotion {
    double energy = 0;
    btVector3 momentum{0, 0, 0};
    btScalar mass = 0;
};
TreeMotion treeMotion(const btMultiBody& mb) {
    const std::size_t n = static_cast<std::size_t>(mb.getNumLinks() + 1);
    btAlignedObjectArray<btVector3> w, v;
    w.resize(static_cast<int>(n));
    v.resize(static_cast<int>(n));
    mb.compTreeLinkVelocities(&w[0], &v[0]); // in each link's frame
    TreeMotion out;
    for (int k = 0; k < static_cast<int>(n); ++k) {
        const bool base = k == 0;
        const btScalar m = base ? mb.getBaseMass() : mb.getLinkMass(k - 1);
        const btVector3& inertia = base ? mb.getBaseInertia() : mb.getLinkInertia(k - 1);
        const btMatrix3x3 toWorld =
            base ? btMatrix3x3(mb.getWorldToBaseRot().inverse()) : mb.getLink(k - 1).m_cachedWorldTransform.getBasis();
        out.energy += 0.5 * static_cast<double>(m * v[k].length2() + w[k].dot(inertia * w[k]));
        out.momentum += toWorld * v[k] * m;
        out.mass += m;
    }
    return out;
}

// A limit of a figure constraint on two links of one multibody (or one link against the world): the same rows as
// the rigid backend's DirectionLimitConstraint and HingeRangeConstraint (directionLimitRows, hingeRangeRow: one
// definition of a limit's excess and of its rate), each row's Jacobian taken over the whole tree, so the row's
// effective mass is the articulated one (Bullet's own limits fill two Jacobians of one tree and lose the cross
// terms).
class MultibodyLimit : public btMultiBodyConstraint {
  public:
    struct Side {
        int link = -1;                              ///< link of the body (−1: base)
        const btCollisionObject* body = nullptr;    ///< its collider (world transform); nullptr: the world
        const btVector3* angularVelocity = nullptr; ///< its angular velocity at the end of the last substep
    };
    struct Direction {
        LimitShape shape;
        btVector3 shaftInA;
        btMatrix3x3 basisInB; ///< world for a world constraint
        btScalar half1, half2;
    };
    struct Hinge {
        btMatrix3x3 frameInA, frameInB; ///< frame B world for a world constraint
        btScalar lower, upper;
    };
    /// §4.4's "no relative spin about the shafts" of a universal joint built as a spherical link: the twist of
    /// frame B relative to frame A about their X axes (shaft 1) held at zero by an equality row about the bisector
    /// of the two X axes (the axis a homokinetic joint does not turn about).
    struct Twist {
        btMatrix3x3 frameInA, frameInB;
    };
    using Kind = std::variant<Direction, Hinge, Twist>;

    MultibodyLimit(btMultiBody* tree, Side a, Side b, Kind limit, LimitRowPolicy policy)
        : btMultiBodyConstraint(tree, nullptr, a.link, b.body ? b.link : a.link, 2,
                                !std::holds_alternative<Twist>(limit), MULTIBODY_CONSTRAINT_LIMIT),
          m_a(a), m_b(b), m_limit(limit), m_policy(policy) {}

    void finalizeMultiDof() override {
        allocateJacobiansMultiDof();
        m_numDofsFinalized = m_jacSizeBoth;
    }
    int getIslandIdA() const override { return m_a.body->getIslandTag(); }
    int getIslandIdB() const override { return m_a.body->getIslandTag(); }
    void debugDraw(btIDebugDraw*) override {}

    void createConstraintRows(btMultiBodyConstraintArray& rows, btMultiBodyJacobianData& data,
                              const btContactSolverInfo& info) override {
        if (m_numDofsFinalized != m_jacSizeBoth) finalizeMultiDof();
        const btScalar dt = info.m_timeStep;
        btScalar margin = 0;
        if (m_policy.speculative && m_a.angularVelocity) {
            // As the rigid rows: the angle the joint can turn in about two steps at its current rate.
            const btVector3 wB = m_b.angularVelocity ? *m_b.angularVelocity : btVector3(0, 0, 0);
            margin = (*m_a.angularVelocity - wB).length() * dt * 2 + btScalar(0.01);
        }
        LimitRow found[2];
        const int n = rowsNow(margin, found);
        const auto* twist = std::get_if<Twist>(&m_limit);
        const btVector3 zero(0, 0, 0);
        const btVector3 pointA = m_a.body->getWorldTransform().getOrigin();
        for (int i = 0; i < n; ++i) {
            const LimitRow& r = found[i];
            fillJacobian(r.axisWorld, data.scratch_r, data.scratch_v, data.scratch_m);
            // Target row velocity: past the limit, Baumgarte recovery of the limit ERP per step; before it
            // (speculative), the joint may close at most the remaining gap in this step. Bullet turns the
            // position error e into the target −e·erp/dt with the world's joint ERP, so e is scaled by it.
            // A twist row is an equality: the joint ERP's Baumgarte recovery of its angle, both ways.
            const btScalar target = twist          ? info.m_erp * r.excess / dt
                                    : r.excess > 0 ? m_policy.errorReduction * r.excess / dt
                                                   : r.excess / dt;
            const btScalar erp = info.m_erp > 0 ? info.m_erp : btScalar(1);
            btMultiBodySolverConstraint& row = rows.expandNonInitializing();
            row.m_solverBodyIdA = data.m_fixedBodyId;
            row.m_solverBodyIdB = data.m_fixedBodyId;
            fillMultiBodyConstraint(row, data, m_jac.data(), nullptr, -r.axisWorld, zero, pointA, pointA,
                                    -target * dt / erp, info, twist ? -SIMD_INFINITY : 0, SIMD_INFINITY, true, 1, false,
                                    0, 0, 1);
            row.m_orgConstraint = this;
            row.m_orgDofIndex = i;
        }
    }

    /// One nonlinear Gauss–Seidel step on positions (velocities untouched): the tree moves along M⁻¹Jᵀ of each
    /// violated row until that row's excess is closed (as far as the linearisation reaches). Returns the largest
    /// excess found, rad.
    btScalar correctPositions(btAlignedObjectArray<btScalar>& r, btAlignedObjectArray<btVector3>& v,
                              btAlignedObjectArray<btMatrix3x3>& m, btAlignedObjectArray<btQuaternion>& q,
                              btAlignedObjectArray<btVector3>& o) {
        if (m_numDofsFinalized != m_jacSizeBoth) finalizeMultiDof();
        const bool twist = std::holds_alternative<Twist>(m_limit);
        btScalar worst = 0;
        for (int pass = 0; pass < 2; ++pass) { // a pyramid's corner: both rows, each from the pose the other left
            LimitRow found[2];
            const int n = rowsNow(0, found);
            const LimitRow* row = nullptr;
            for (int i = 0; i < n; ++i)
                if ((found[i].excess > 0 || (twist && std::abs(found[i].excess) > kTwistSlopRad)) &&
                    (!row || std::abs(found[i].excess) > std::abs(row->excess)))
                    row = &found[i];
            if (!row) break;
            const btScalar excess = row->excess;
            if (pass == 0) worst = std::abs(excess);
            fillJacobian(row->axisWorld, r, v, m);
            m_move.resize(m_jac.size());
            m_bodyA->calcAccelerationDeltasMultiDof(m_jac.data(), m_move.data(), r, v);
            btScalar w = 0;
            for (std::size_t k = 0; k < m_jac.size(); ++k) w += m_jac[k] * m_move[k];
            if (!(w > SIMD_EPSILON)) break;
            // J·Δq is how far the excess falls (the row's velocity times one), so Δq = M⁻¹Jᵀ·excess/w closes it.
            for (btScalar& x : m_move) x *= excess / w;
            m_bodyA->stepPositionsMultiDof(1, nullptr, m_move.data());
            m_bodyA->forwardKinematics(q, o);
            m_bodyA->updateCollisionObjectWorldTransforms(q, o);
        }
        return worst;
    }

  private:
    static constexpr btScalar kTwistSlopRad = btScalar(0.01); ///< a twist the position sweeps leave to the row

    // The rows of this limit at the present pose (the colliders' transforms), with the speculative margin.
    int rowsNow(btScalar margin, LimitRow found[2]) const {
        const btMatrix3x3 rotA = m_a.body->getWorldTransform().getBasis();
        const btMatrix3x3 rotB = m_b.body ? m_b.body->getWorldTransform().getBasis() : btMatrix3x3::getIdentity();
        if (const auto* d = std::get_if<Direction>(&m_limit))
            return directionLimitRows(rotA * d->shaftInA, rotB * d->basisInB, d->shape, d->half1, d->half2, margin,
                                      found);
        if (const auto* h = std::get_if<Hinge>(&m_limit))
            return hingeRangeRow(rotA * h->frameInA, rotB * h->frameInB, h->lower, h->upper, margin, found[0]);
        const Twist& t = std::get<Twist>(m_limit);
        return twistRow(rotA * t.frameInA, rotB * t.frameInB, found[0]);
    }

    // m_jac = the Jacobian of a row about `axisWorld` over the whole tree. The excess grows at axis·(ωA − ωB):
    // the row's velocity J·q̇ = (ωB − ωA)·axis, so a positive impulse reduces the excess (as setLimitRow's rows
    // for rigid bodies).
    void fillJacobian(const btVector3& axisWorld, btAlignedObjectArray<btScalar>& r, btAlignedObjectArray<btVector3>& v,
                      btAlignedObjectArray<btMatrix3x3>& m) {
        const int ndof = m_bodyA->getNumDofs() + 6;
        m_jac.resize(static_cast<std::size_t>(ndof));
        m_jacB.resize(static_cast<std::size_t>(ndof));
        const btVector3 zero(0, 0, 0);
        const btVector3 pointA = m_a.body->getWorldTransform().getOrigin();
        m_bodyA->fillConstraintJacobianMultiDof(m_a.link, pointA, axisWorld, zero, m_jac.data(), r, v, m);
        if (m_b.body) {
            m_bodyA->fillConstraintJacobianMultiDof(m_b.link, pointA, axisWorld, zero, m_jacB.data(), r, v, m);
            for (int k = 0; k < ndof; ++k) m_jac[static_cast<std::size_t>(k)] = m_jacB[k] - m_jac[k];
        } else {
            for (int k = 0; k < ndof; ++k) m_jac[static_cast<std::size_t>(k)] = -m_jac[k];
        }
    }

    // The twist of frame B relative to frame A about their X axes, as a row in directionLimitRows' convention:
    // the excess grows at axis·(ωA − ωB).
    static int twistRow(const btMatrix3x3& frameA, const btMatrix3x3& frameB, LimitRow& out) {
        btQuaternion q = quatOf(frameA.transpose() * frameB);
        if (q.w() < 0) q = -q;
        const btVector3 bisector = frameA.getColumn(0) + frameB.getColumn(0);
        if (bisector.length2() < btScalar(1e-6)) return 0; // swung 180°: no twist axis (a limit prevents it)
        out.axisWorld = -bisector.normalized();
        out.excess = 2 * btAtan2(q.x(), q.w());
        return 1;
    }

    Side m_a, m_b;
    Kind m_limit;
    LimitRowPolicy m_policy;
    std::vector<btScalar> m_jac, m_jacB, m_move;
};

// Bullet integrates a btMultiBody's velocity-product terms (Coriolis, centripetal, gyroscopic) explicitly: once
// a limb spins at tens of rad/s (ω·dt of a radian per step, as at a hard landing), each step's unconstrained
// update multiplies the tree's kinetic energy (measured: ×1.6, ×2.8, ×6 in three steps) until it explodes. No
// force but gravity does work in that update (joint forces do none; damping and contacts come after), so the
// guard, called between Bullet's unconstrained update and the constraint solve, holds the update to gravity's
// work: past it, the motion relative to the centre of mass is scaled down (linear momentum kept).
class EnergyGuard : public btMultiBodyConstraint {
  public:
    EnergyGuard(btMultiBody* tree, const btCollisionObject& base, const btDynamicsWorld& world)
        : btMultiBodyConstraint(tree, nullptr, -1, -1, 0, false, MULTIBODY_CONSTRAINT_LIMIT), m_base(base),
          m_world(world) {}

    /// The tree's motion now, the reference of the next check (after each step, and after any change of the
    /// velocities from outside: impulses, body states).
    void record() {
        const TreeMotion t = treeMotion(*m_bodyA);
        m_energy = t.energy;
        m_momentum = t.momentum;
    }

    void finalizeMultiDof() override {
        allocateJacobiansMultiDof();
        m_numDofsFinalized = m_jacSizeBoth;
    }
    int getIslandIdA() const override { return m_base.getIslandTag(); }
    int getIslandIdB() const override { return m_base.getIslandTag(); }
    void debugDraw(btIDebugDraw*) override {}

    void createConstraintRows(btMultiBodyConstraintArray&, btMultiBodyJacobianData& data,
                              const btContactSolverInfo& info) override {
        btMultiBody& mb = *m_bodyA;
        const TreeMotion now = treeMotion(mb);
        const double dt = info.m_timeStep;
        const btVector3 g = m_world.getGravity();
        // Gravity's work in one semi-implicit step: g·p·dt + ½·M·g²·dt² (exact for a free fall); a small
        // relative slack keeps the guard out of ordinary motion.
        const double fall = 0.5 * static_cast<double>(now.mass * g.length2()) * dt * dt;
        const double allowed =
            m_energy + static_cast<double>(g.dot(m_momentum)) * dt + fall + kSlack * (m_energy + fall) + 1e-9;
        if (!(now.energy > allowed)) return;
        const btVector3 vCom = mb.hasFixedBase() || !(now.mass > 0) ? btVector3(0, 0, 0) : now.momentum / now.mass;
        const double translation = 0.5 * static_cast<double>(now.mass * vCom.length2());
        const double relative = now.energy - translation;
        if (!(relative > 0)) return;
        const btScalar k = static_cast<btScalar>(std::sqrt(std::max(0.0, allowed - translation) / relative));
        // The change, in Bullet's layout of a tree's velocities: base ω, base v (world), then every joint's.
        const int n = mb.getNumDofs() + 6;
        m_delta.resize(static_cast<std::size_t>(n));
        const btScalar* q = mb.getVelocityVector();
        for (int i = 0; i < n; ++i) m_delta[static_cast<std::size_t>(i)] = (k - 1) * q[i];
        if (mb.hasFixedBase()) std::fill(m_delta.begin(), m_delta.begin() + 6, btScalar(0));
        else
            for (int i = 3; i < 6; ++i) m_delta[static_cast<std::size_t>(i)] = (k - 1) * (q[i] - vCom[i - 3]);
        // Contacts and limits have already built their rows from the velocities (the solver converts contacts
        // before any multibody constraint), so the change goes in as a solver velocity change, as an impulse's
        // would: every row then sees it. A tree no row touches yet takes it directly.
        const int companion = mb.getCompanionId();
        if (companion >= 0) {
            for (int i = 0; i < n; ++i) data.m_deltaVelocities[companion + i] += m_delta[static_cast<std::size_t>(i)];
            mb.applyDeltaVeeMultiDof2(m_delta.data(), 1);
        } else {
            mb.applyDeltaVeeMultiDof(m_delta.data(), 1);
        }
    }

  private:
    static constexpr double kSlack = 1e-3;
    const btCollisionObject& m_base;
    const btDynamicsWorld& m_world;
    double m_energy = 0;
    btVector3 m_momentum{0, 0, 0};
    std::vector<btScalar> m_delta;
};

// The Jacobian over a whole tree of a row about `axisWorld` (angular) or along `normalWorld` at two points (linear):
// the rate of body A's motion minus body B's (B the world when `linkB` is absent). Rows within one tree take both
// sides in one piece (Bullet's two half-Jacobians of one tree lose the cross terms).
void relativeJacobian(btMultiBody& tree, int linkA, const btVector3& pointA, std::optional<int> linkB,
                      const btVector3& pointB, const btVector3& axisWorld, const btVector3& normalWorld,
                      std::vector<btScalar>& jac, std::vector<btScalar>& scratch, btAlignedObjectArray<btScalar>& r,
                      btAlignedObjectArray<btVector3>& v, btAlignedObjectArray<btMatrix3x3>& m) {
    const std::size_t ndof = static_cast<std::size_t>(tree.getNumDofs() + 6);
    jac.resize(ndof);
    scratch.resize(ndof);
    tree.fillConstraintJacobianMultiDof(linkA, pointA, axisWorld, normalWorld, jac.data(), r, v, m);
    if (!linkB) return;
    tree.fillConstraintJacobianMultiDof(*linkB, pointB, axisWorld, normalWorld, scratch.data(), r, v, m);
    for (std::size_t k = 0; k < ndof; ++k) jac[k] -= scratch[k];
}

// Joint friction (docs/format.md §4.8) on a joint within one tree: rows resisting the relative angular velocity of the
// two bodies about the free axes (ball 3, universal 2 perpendicular to shaft 1, hinge 1), target velocity 0, each
// impulse bounded by `maxImpulse` per step (MultibodyRagdoll sets it from the joint's reaction force as the rigid
// backend's JointFrictionConstraint).
class JointFriction : public btMultiBodyConstraint {
  public:
    /// `axesInB`: the rows' axes as columns, fixed in body B's frame (world for a world joint); `count` used.
    JointFriction(btMultiBody* tree, int linkA, const btCollisionObject& bodyA, std::optional<int> linkB,
                  const btCollisionObject* bodyB, const btMatrix3x3& axesInB, int count)
        : btMultiBodyConstraint(tree, nullptr, linkA, linkB ? *linkB : linkA, count, false, MULTIBODY_CONSTRAINT_LIMIT),
          m_bodyAObject(bodyA), m_bodyBObject(bodyB), m_linkBOpt(linkB), m_axesInB(axesInB), m_count(count) {}

    /// The bound of each row for the coming step, N·m·s.
    void setMaxImpulse(btScalar impulse) { m_maxImpulse = impulse; }

    void finalizeMultiDof() override {
        allocateJacobiansMultiDof();
        m_numDofsFinalized = m_jacSizeBoth;
    }
    int getIslandIdA() const override { return m_bodyAObject.getIslandTag(); }
    int getIslandIdB() const override { return m_bodyAObject.getIslandTag(); }
    void debugDraw(btIDebugDraw*) override {}

    void createConstraintRows(btMultiBodyConstraintArray& rows, btMultiBodyJacobianData& data,
                              const btContactSolverInfo& info) override {
        if (!(m_maxImpulse > 0)) return;
        if (m_numDofsFinalized != m_jacSizeBoth) finalizeMultiDof();
        const btMatrix3x3 rotB =
            m_bodyBObject ? m_bodyBObject->getWorldTransform().getBasis() : btMatrix3x3::getIdentity();
        const btVector3 zero(0, 0, 0);
        const btVector3 point = m_bodyAObject.getWorldTransform().getOrigin();
        for (int i = 0; i < m_count; ++i) {
            const btVector3 axis = rotB * m_axesInB.getColumn(i);
            relativeJacobian(*m_bodyA, m_linkA, point, m_linkBOpt, point, axis, zero, m_jac, m_scratch, data.scratch_r,
                             data.scratch_v, data.scratch_m);
            btMultiBodySolverConstraint& row = rows.expandNonInitializing();
            row.m_solverBodyIdA = data.m_fixedBodyId;
            row.m_solverBodyIdB = data.m_fixedBodyId;
            fillMultiBodyConstraint(row, data, m_jac.data(), nullptr, axis, zero, point, point, 0, info, -m_maxImpulse,
                                    m_maxImpulse, true, 1, false, 0, 0, 1);
            row.m_orgConstraint = this;
            row.m_orgDofIndex = i;
        }
    }

  private:
    const btCollisionObject& m_bodyAObject;
    const btCollisionObject* m_bodyBObject; ///< nullptr: the world
    std::optional<int> m_linkBOpt;          ///< absent: the world
    btMatrix3x3 m_axesInB;
    int m_count;
    btScalar m_maxImpulse = 0;
    std::vector<btScalar> m_jac, m_scratch;
};

// A spring (docs/format.md §4.7) between anchors fixed in two bodies (of one tree, of two trees, or one body and the
// world): the rigid backend's SpringConstraint law (the quadratic force minus the damping term, each step's
// impulse bounded by what closes the whole deviation or stops the relative motion in that step) as a row whose
// impulse is pinned to F·dt, so it is integrated inside the solver step where gravity is; plus the one-sided
// min/max length rows with the world's joint ERP.
class MultibodySpring : public btMultiBodyConstraint {
  public:
    struct End {
        btMultiBody* tree = nullptr; ///< nullptr: the world
        int link = -1;
        const btCollisionObject* body = nullptr; ///< nullptr: the world
        btVector3 anchor{0, 0, 0};               ///< in the body's frame (world for the world)
    };
    MultibodySpring(const End& a, const End& b, const SpringConstraint::Params& params)
        : btMultiBodyConstraint(a.tree, b.tree && b.tree != a.tree ? b.tree : nullptr, a.link, b.tree ? b.link : a.link,
                                2, false, MULTIBODY_CONSTRAINT_LIMIT),
          m_a(a), m_b(b), m_params(params) {}

    void finalizeMultiDof() override {
        allocateJacobiansMultiDof();
        m_numDofsFinalized = m_jacSizeBoth;
    }
    int getIslandIdA() const override { return m_a.body->getIslandTag(); }
    int getIslandIdB() const override { return (m_b.body ? m_b.body : m_a.body)->getIslandTag(); }
    void debugDraw(btIDebugDraw*) override {}

    void createConstraintRows(btMultiBodyConstraintArray& rows, btMultiBodyJacobianData& data,
                              const btContactSolverInfo& info) override {
        if (m_numDofsFinalized != m_jacSizeBoth) finalizeMultiDof();
        const btVector3 pa = pointA(), pb = pointB();
        const btVector3 d = pb - pa;
        const btScalar length = d.length();
        if (!(length > SIMD_EPSILON)) return;
        const btVector3 n = d / length;
        const btScalar dt = info.m_timeStep;
        // A row along n whose velocity is n·(v_A − v_B) = −dL/dt: a positive impulse pulls the anchors together.
        auto addRow = [&](btScalar posError, btScalar lo, btScalar hi, int index) -> btMultiBodySolverConstraint& {
            const btVector3 zero(0, 0, 0);
            const bool oneTree = m_bodyB == nullptr;
            relativeJacobian(*m_bodyA, m_linkA, pa, oneTree && m_b.tree ? std::optional<int>(m_linkB) : std::nullopt,
                             pb, zero, n, m_jacA, m_scratch, data.scratch_r, data.scratch_v, data.scratch_m);
            if (!oneTree) {
                relativeJacobian(*m_bodyB, m_linkB, pb, std::nullopt, pb, zero, -n, m_jacB, m_scratch, data.scratch_r,
                                 data.scratch_v, data.scratch_m);
            }
            btMultiBodySolverConstraint& row = rows.expandNonInitializing();
            row.m_solverBodyIdA = data.m_fixedBodyId;
            row.m_solverBodyIdB = data.m_fixedBodyId;
            fillMultiBodyConstraint(row, data, m_jacA.data(), oneTree ? nullptr : m_jacB.data(), zero, n, pa, pb,
                                    posError, info, lo, hi, false, 1, false, 0, 0, 1);
            row.m_orgConstraint = this;
            row.m_orgDofIndex = index;
            return row;
        };
        // The force: the engine's terms from the anchors' relative speed along n (the row's velocity), each
        // bounded through the row's effective mass (SpringConstraint::impulse).
        const btScalar rest = m_params.restLength;
        const btScalar k = length > rest ? m_params.stretch : m_params.compress;
        if (k > 0) {
            btMultiBodySolverConstraint& row = addRow(0, 0, 0, 0);
            const btScalar speed = btFabs(rowVelocity());
            const btScalar sign = length > rest ? 1 : -1;
            const btScalar deviation = btFabs(length - rest);
            btScalar spring = k * deviation * deviation * dt;
            btScalar damping = m_params.damping * speed / length * dt;
            const btScalar mass = row.m_jacDiagABInv; // 1 / (J·M⁻¹·Jᵀ); 0 for a row nothing can move
            if (mass > 0) {
                spring = btMin(spring, mass * deviation / dt);
                damping = btMin(damping, mass * speed);
            }
            const btScalar pull = sign * (spring - damping);
            row.m_rhs = 0;
            row.m_lowerLimit = pull;
            row.m_upperLimit = pull;
        }
        if (length < m_params.minLength) addRow(m_params.minLength - length, -SIMD_INFINITY, 0, 1);
        else if (m_params.maxLength > 0 && length > m_params.maxLength)
            addRow(m_params.maxLength - length, 0, SIMD_INFINITY, 1);
    }

  private:
    btVector3 pointA() const { return m_a.body->getWorldTransform() * m_a.anchor; }
    btVector3 pointB() const { return m_b.body ? m_b.body->getWorldTransform() * m_b.anchor : m_b.anchor; }
    // J·q̇ of a filled row (its velocity now).
    btScalar rowVelocity() const {
        btScalar v = 0;
        const btScalar* q = m_bodyA->getVelocityVector();
        for (std::size_t i = 0; i < m_jacA.size(); ++i) v += m_jacA[i] * q[i];
        if (m_bodyB) {
            const btScalar* qb = m_bodyB->getVelocityVector();
            for (std::size_t i = 0; i < m_jacB.size(); ++i) v += m_jacB[i] * qb[i];
        }
        return v;
    }

    End m_a, m_b;
    SpringConstraint::Params m_params;
    std::vector<btScalar> m_jacA, m_jacB, m_scratch;
};

} // namespace

// A link's collider with the figure's §6.2 rules between the ragdoll's own bodies (Bullet's own rule knows only
// parent–child pairs of one tree).
class MultibodyRagdoll::LinkCollider : public btMultiBodyLinkCollider {
  public:
    LinkCollider(btMultiBody* tree, int link, const MultibodyRagdoll& owner, int body)
        : btMultiBodyLinkCollider(tree, link), m_owner(owner), m_body(body) {
        m_checkCollideWith = 1; // Bullet asks checkCollideWithOverride for every pair
    }
    bool checkCollideWithOverride(const btCollisionObject* co) const override {
        const btMultiBodyLinkCollider* other = btMultiBodyLinkCollider::upcast(co);
        if (other == nullptr) return true;
        const auto& parts = m_owner.m_parts;
        const bool ours =
            std::any_of(parts.begin(), parts.end(), [&](const Part& p) { return p.body.get() == other->m_multiBody; });
        if (!ours) return true;
        const int b = static_cast<const LinkCollider*>(other)->m_body;
        return std::binary_search(m_owner.m_colliding.begin(), m_owner.m_colliding.end(),
                                  std::make_pair(std::min(m_body, b), std::max(m_body, b)));
    }

    /// The figure body of this collider if it is one of `owner`'s, else −1.
    static int bodyOf(const btCollisionObject* o, const MultibodyRagdoll& owner) {
        const btMultiBodyLinkCollider* link = btMultiBodyLinkCollider::upcast(o);
        if (link == nullptr) return -1;
        for (const Part& p : owner.m_parts)
            if (p.body.get() == link->m_multiBody) return static_cast<const LinkCollider*>(link)->m_body;
        return -1;
    }

  private:
    const MultibodyRagdoll& m_owner;
    int m_body;
};

// Per substep (Bullet runs actions after integration): the damping, the angular velocities the limits' margins
// read, and the figure's rest rules (§6.1).
class MultibodyRagdoll::Action : public btActionInterface {
  public:
    Action(MultibodyRagdoll& owner, bool comeToRest) : m_owner(owner), m_comeToRest(comeToRest) {}
    bool atRest = false;
    double activeTime = 0;

    void updateAction(btCollisionWorld*, btScalar dt) override {
        if (atRest) {
            for (const auto& c : m_owner.m_colliders)
                if (c->isActive()) {
                    wake();
                    break;
                }
            m_owner.recordMotion();
            return;
        }
        activeTime += dt;
        m_owner.updateFrictionBounds(dt);
        m_owner.dampVelocities(dt);
        m_owner.correctPositions();
        const std::vector<BodySample> samples = m_owner.samples();
        for (std::size_t i = 0; i < samples.size(); ++i) m_owner.m_angularVelocity[i] = samples[i].angularVelocity;
        m_owner.publishVelocities(samples);
        if (m_comeToRest && m_rest.update(samples, dt, activeTime)) m_owner.putToRest();
        m_owner.recordMotion();
    }
    void debugDraw(btIDebugDraw*) override {}

    void wake() {
        atRest = false;
        activeTime = 0;
        m_rest.reset();
        for (Part& p : m_owner.m_parts) {
            p.body->setCanSleep(false);
            p.body->wakeUp();
        }
        for (const auto& c : m_owner.m_colliders) c->activate(true);
    }

  private:
    MultibodyRagdoll& m_owner;
    bool m_comeToRest;
    RestTest m_rest{m_owner.m_asset->figure().rest};
};

MultibodyRagdoll::MultibodyRagdoll(std::shared_ptr<const RagdollAsset> asset, btDynamicsWorld& world,
                                   const SpawnOptions& options)
    : m_asset(std::move(asset)), m_world([&]() -> btMultiBodyDynamicsWorld& {
          auto* w = dynamic_cast<btMultiBodyDynamicsWorld*>(&world);
          if (w == nullptr) throw std::invalid_argument(kNeedsMultiBodyWorld);
          return *w;
      }()),
      m_spawn(options.entityTransform) {
    const figure::Figure& f = m_asset->figure();
    m_colliding = figure::selfCollisionPairs(f);
    if (options.method.exemptOverlapping)
        std::erase_if(m_colliding, [&](const std::pair<int, int>& pair) {
            const auto& overlapping = m_asset->overlappingPairs();
            return std::binary_search(overlapping.begin(), overlapping.end(), pair);
        });
    m_angularVelocity.assign(f.bodies.size(), btVector3(0, 0, 0));
    m_linearVelocity.assign(f.bodies.size(), btVector3(0, 0, 0));
    // Damping: the rigid backend scales each body's velocities by (1 − d)^dt per step (btRigidBody's model). In
    // reduced coordinates the same factor on every generalised velocity scales every body's linear and angular
    // velocity alike: exact when the figure has one damping (every bundled and corpus figure: the §3.4 friction
    // of settings), otherwise the mass-weighted mean.
    double mass = 0, linear = 0, angular = 0;
    for (const figure::FigureBody& b : f.bodies) {
        mass += b.massKg;
        linear += b.massKg * b.linearDamping;
        angular += b.massKg * b.angularDamping;
    }
    if (mass > 0) {
        m_linearDamping = static_cast<btScalar>(linear / mass);
        m_angularDamping = static_cast<btScalar>(angular / mass);
    }
    m_positionIterations = std::max(0, options.method.positionIterations);
    m_action = std::make_unique<Action>(*this, options.comeToRest);
    build(options);
    addColliders(options);
    addConstraints(options.method);
    m_world.addAction(m_action.get());
    if (options.startAtRest) putToRest();
}

MultibodyRagdoll::~MultibodyRagdoll() {
    m_world.removeAction(m_action.get());
    for (auto it = m_constraints.rbegin(); it != m_constraints.rend(); ++it)
        m_world.removeMultiBodyConstraint(it->get());
    for (auto it = m_colliders.rbegin(); it != m_colliders.rend(); ++it) m_world.removeCollisionObject(it->get());
    for (auto it = m_parts.rbegin(); it != m_parts.rend(); ++it) m_world.removeMultiBody(it->body.get());
}

void MultibodyRagdoll::build(const SpawnOptions& options) {
    const figure::Figure& f = m_asset->figure();
    const int n = static_cast<int>(f.bodies.size());
    m_bodies.assign(static_cast<std::size_t>(n), {});
    // Tree edges: joints between two bodies (springs are forces), breadth first from each part's first body, in
    // constraint order, so the origin body is the first tree's base and the build is deterministic.
    std::vector<std::vector<std::pair<int, int>>> adjacent(static_cast<std::size_t>(n)); // (constraint, body)
    for (std::size_t ci = 0; ci < f.constraints.size(); ++ci) {
        const FigureConstraint& c = f.constraints[ci];
        if (c.type == JointType::Spring || c.body2 < 0 || c.body1 == c.body2) continue;
        adjacent[static_cast<std::size_t>(c.body1)].emplace_back(static_cast<int>(ci), c.body2);
        adjacent[static_cast<std::size_t>(c.body2)].emplace_back(static_cast<int>(ci), c.body1);
    }
    m_treeEdge.assign(f.constraints.size(), false);
    std::vector<bool> reached(static_cast<std::size_t>(n), false);
    auto rotation = [&](int b) { return toBt(f.bodies[static_cast<std::size_t>(b)].loadPose.rotation); };
    // A body fixed to the world is its tree's base, and that base is fixed: the attachment is then exact.
    std::vector<int> fixedToWorld(static_cast<std::size_t>(n), -1); // the constraint, per body
    for (std::size_t ci = 0; ci < f.constraints.size(); ++ci) {
        const FigureConstraint& c = f.constraints[ci];
        if (c.type == JointType::Fixed && c.body2 < 0 && fixedToWorld[static_cast<std::size_t>(c.body1)] < 0)
            fixedToWorld[static_cast<std::size_t>(c.body1)] = static_cast<int>(ci);
    }
    std::vector<int> roots;
    for (int b = 0; b < n; ++b)
        if (fixedToWorld[static_cast<std::size_t>(b)] >= 0) roots.push_back(b);
    for (int b = 0; b < n; ++b)
        if (fixedToWorld[static_cast<std::size_t>(b)] < 0) roots.push_back(b);
    for (const int root : roots) {
        if (reached[static_cast<std::size_t>(root)]) continue;
        Part part;
        part.root = root;
        part.fixedBase = fixedToWorld[static_cast<std::size_t>(root)] >= 0;
        if (part.fixedBase) m_treeEdge[static_cast<std::size_t>(fixedToWorld[static_cast<std::size_t>(root)])] = true;
        reached[static_cast<std::size_t>(root)] = true;
        const int partIndex = static_cast<int>(m_parts.size());
        m_bodies[static_cast<std::size_t>(root)] = {partIndex, -1};
        std::vector<int> queue{root};
        int links = 0;
        for (std::size_t q = 0; q < queue.size(); ++q) {
            const int p = queue[q];
            for (const auto& [ci, child] : adjacent[static_cast<std::size_t>(p)]) {
                if (reached[static_cast<std::size_t>(child)]) continue;
                reached[static_cast<std::size_t>(child)] = true;
                m_treeEdge[static_cast<std::size_t>(ci)] = true;
                const FigureConstraint& c = f.constraints[static_cast<std::size_t>(ci)];
                const btTransform inChild = toBt(child == c.body1 ? c.frameInBody1 : c.frameInBody2);
                const btTransform inParent = toBt(child == c.body1 ? c.frameInBody2 : c.frameInBody1);
                Joint j;
                j.child = child;
                j.parent = p;
                j.zeroParentToChild = rotation(child).transpose() * rotation(p);
                j.parentToPivot = inParent.getOrigin();
                j.pivotToChild = -inChild.getOrigin();
                j.frameInParent = inParent.getBasis();
                j.frameInChild = inChild.getBasis();
                switch (c.type) {
                case JointType::Fixed: j.kind = Joint::Kind::Fixed; break;
                case JointType::BallAndSocket: j.kind = Joint::Kind::Spherical; break;
                case JointType::Hinge:
                    j.kind = Joint::Kind::Revolute;
                    j.axisInChild = inChild.getBasis().getColumn(2); // §4.5: the frame's Z is the hinge axis
                    break;
                case JointType::Slider:
                    j.kind = Joint::Kind::Prismatic;
                    j.axisInChild = inChild.getBasis().getColumn(0); // §4.6: the frame's X is the axis
                    break;
                case JointType::Universal: j.kind = Joint::Kind::Universal; break;
                case JointType::Spring: break; // not a tree edge
                }
                ++links;
                j.link = links - 1;
                m_bodies[static_cast<std::size_t>(child)] = {partIndex, j.link};
                part.joints.push_back(j);
                queue.push_back(child);
            }
        }
        const figure::FigureBody& base = f.bodies[static_cast<std::size_t>(root)];
        part.body = std::make_unique<btMultiBody>(links, static_cast<btScalar>(base.massKg), toBt(base.inertiaKgM2),
                                                  part.fixedBase, false);
        btMultiBody& mb = *part.body;
        const btTransform baseWorld = m_spawn * toBt(base.loadPose);
        mb.setBasePos(baseWorld.getOrigin());
        mb.setWorldToBaseRot(quatOf(baseWorld.getBasis()).inverse());
        for (const Joint& j : part.joints) {
            const figure::FigureBody& b = f.bodies[static_cast<std::size_t>(j.child)];
            const btScalar m = static_cast<btScalar>(b.massKg);
            const btVector3 inertia = toBt(b.inertiaKgM2);
            const int parentLink = m_bodies[static_cast<std::size_t>(j.parent)].link;
            const btQuaternion q0 = quatOf(j.zeroParentToChild);
            switch (j.kind) {
            case Joint::Kind::Fixed:
                mb.setupFixed(j.link, m, inertia, parentLink, q0, j.parentToPivot, j.pivotToChild, true);
                break;
            case Joint::Kind::Spherical:
                mb.setupSpherical(j.link, m, inertia, parentLink, q0, j.parentToPivot, j.pivotToChild, true);
                break;
            case Joint::Kind::Revolute:
                mb.setupRevolute(j.link, m, inertia, parentLink, q0, j.axisInChild, j.parentToPivot, j.pivotToChild,
                                 true);
                break;
            case Joint::Kind::Prismatic:
                mb.setupPrismatic(j.link, m, inertia, parentLink, q0, j.axisInChild, j.parentToPivot, j.pivotToChild,
                                  true);
                break;
            case Joint::Kind::Universal:
                // §4.4: two free swings and no spin about the shafts: a spherical link whose twist a row holds
                // (addConstraints). A Cardan pair of revolute links (a massless link turning about one axis, the
                // child about a second) has a singular pose at 90° from the load pose, reached at impact, where
                // the first coordinate spins the child about its own long axis and explodes (README).
                mb.setupSpherical(j.link, m, inertia, parentLink, q0, j.parentToPivot, j.pivotToChild, true);
                break;
            }
        }
        mb.finalizeMultiDof();
        mb.setLinearDamping(0); // damping is the figure's, see dampVelocities
        mb.setAngularDamping(0);
        mb.setMaxCoordinateVelocity(kMaxCoordinateVelocity);
        mb.setHasSelfCollision(true); // pairs are decided by LinkCollider
        m_world.addMultiBody(part.body.get(), options.collisionGroup, options.collisionMask);
        m_parts.push_back(std::move(part));
    }
}

void MultibodyRagdoll::addColliders(const SpawnOptions& options) {
    const figure::Figure& f = m_asset->figure();
    for (std::size_t i = 0; i < f.bodies.size(); ++i) {
        const figure::FigureBody& b = f.bodies[i];
        const BodyRef ref = m_bodies[i];
        btMultiBody& mb = *m_parts[static_cast<std::size_t>(ref.part)].body;
        auto col = std::make_unique<LinkCollider>(&mb, ref.link, *this, static_cast<int>(i));
        col->setCollisionShape(m_asset->shape(static_cast<int>(i)));
        col->setWorldTransform(m_spawn * toBt(b.loadPose));
        col->setFriction(static_cast<btScalar>(b.contactFriction));
        col->setRestitution(static_cast<btScalar>(kBodyRestitution));
        int mask = options.collisionMask;
        if (figure::attachedToWorld(f, static_cast<int>(i))) mask &= ~btBroadphaseProxy::StaticFilter;
        if (b.clipMask == 0) mask = 0; // §6.2: a body with clipMask 0 does no collision tests
        if (options.engineContactFriction) {
            col->setUserIndex2(kEngineFrictionMarker);
            col->setCollisionFlags(col->getCollisionFlags() | btCollisionObject::CF_CUSTOM_MATERIAL_CALLBACK);
        }
        m_world.addCollisionObject(col.get(), options.collisionGroup, mask);
        if (ref.link < 0) mb.setBaseCollider(col.get());
        else mb.getLink(ref.link).m_collider = col.get();
        m_colliders.push_back(std::move(col));
    }
    btAlignedObjectArray<btScalar> r;
    btAlignedObjectArray<btVector3> v;
    btAlignedObjectArray<btMatrix3x3> m;
    for (Part& p : m_parts) {
        refreshTransforms(*p.body);
        // The articulated-body caches (what an impulse before the first step needs), with no force and no time.
        p.body->computeAccelerationsArticulatedBodyAlgorithmMultiDof(0, r, v, m, false, false, false);
    }
}

void MultibodyRagdoll::addConstraints(const Method& method) {
    const figure::Figure& f = m_asset->figure();
    const LimitRowPolicy policy{static_cast<btScalar>(method.limitErp), method.speculativeLimits};
    for (std::size_t ci = 0; ci < f.constraints.size(); ++ci) {
        const FigureConstraint& c = f.constraints[ci];
        const btTransform fa = toBt(c.frameInBody1);
        const btTransform fb = c.body2 >= 0 ? toBt(c.frameInBody2) : m_spawn * toBt(c.frameInBody2);
        m_frames.emplace_back(fa, fb);
        if (c.type == JointType::Spring) {
            addSpring(c, fa, fb);
            continue;
        }
        const BodyRef a = m_bodies[static_cast<std::size_t>(c.body1)];
        btMultiBody* treeA = m_parts[static_cast<std::size_t>(a.part)].body.get();
        const bool sameTree = c.body2 < 0 || m_bodies[static_cast<std::size_t>(c.body2)].part == a.part;
        if (!m_treeEdge[ci]) {
            // A loop or a world attachment: a constraint on the anchors (and a fixed joint's frames), solved like
            // a rigid body's joint, so it can separate again.
            std::unique_ptr<btMultiBodyConstraint> joint;
            if (c.body2 >= 0) {
                const BodyRef b = m_bodies[static_cast<std::size_t>(c.body2)];
                btMultiBody* treeB = m_parts[static_cast<std::size_t>(b.part)].body.get();
                if (c.type == JointType::Fixed)
                    joint = std::make_unique<btMultiBodyFixedConstraint>(treeA, a.link, treeB, b.link, fa.getOrigin(),
                                                                         fb.getOrigin(), fa.getBasis(), fb.getBasis());
                else
                    joint = std::make_unique<btMultiBodyPoint2Point>(treeA, a.link, treeB, b.link, fa.getOrigin(),
                                                                     fb.getOrigin());
            } else {
                if (c.type == JointType::Fixed)
                    joint =
                        std::make_unique<btMultiBodyFixedConstraint>(treeA, a.link, static_cast<btRigidBody*>(nullptr),
                                                                     fa.getOrigin(), fb.getOrigin(), fa.getBasis(),
                                                                     fb.getBasis());
                else
                    joint = std::make_unique<btMultiBodyPoint2Point>(treeA, a.link, static_cast<btRigidBody*>(nullptr),
                                                                     fa.getOrigin(), fb.getOrigin());
            }
            joint->setMaxAppliedImpulse(BT_LARGE_FLOAT); // Bullet's default caps it at 100 N·s
            m_world.addMultiBodyConstraint(joint.get());
            if (sameTree) addFriction(static_cast<int>(ci), joint.get());
            m_constraints.push_back(std::move(joint));
        } else {
            addFriction(static_cast<int>(ci), nullptr);
        }
        if (!sameTree) continue; // a limit or friction across two trees: not modelled (no corpus figure has one)
        // Limits: the rigid backend's rows (Ragdoll::addConstraints), on the links.
        const btMatrix3x3 b2Rot = c.body2 >= 0 ? btMatrix3x3::getIdentity() : m_spawn.getBasis();
        std::optional<MultibodyLimit::Kind> limit;
        if (const auto* cone = std::get_if<figure::ConeLimit>(&c.limit))
            limit = MultibodyLimit::Direction{LimitShape::Cone, toBt(cone->shaftInBody1),
                                              basisWithX(b2Rot * toBt(cone->axisInBody2)),
                                              static_cast<btScalar>(cone->halfAngleRad), 0};
        else if (const auto* pyramid = std::get_if<figure::PyramidLimit>(&c.limit))
            limit = MultibodyLimit::Direction{LimitShape::Pyramid, toBt(pyramid->shaftInBody1),
                                              b2Rot * toBt(pyramid->basisInBody2),
                                              static_cast<btScalar>(pyramid->halfAngle1Rad),
                                              static_cast<btScalar>(pyramid->halfAngle2Rad)};
        else if (const auto* range = std::get_if<figure::HingeRange>(&c.limit))
            limit = MultibodyLimit::Hinge{fa.getBasis(), fb.getBasis(), static_cast<btScalar>(range->lowerRad),
                                          static_cast<btScalar>(range->upperRad)};
        if (!limit) continue;
        const MultibodyLimit::Side sideA{a.link, m_colliders[static_cast<std::size_t>(c.body1)].get(),
                                         &m_angularVelocity[static_cast<std::size_t>(c.body1)]};
        MultibodyLimit::Side sideB;
        if (c.body2 >= 0)
            sideB = {m_bodies[static_cast<std::size_t>(c.body2)].link,
                     m_colliders[static_cast<std::size_t>(c.body2)].get(),
                     &m_angularVelocity[static_cast<std::size_t>(c.body2)]};
        auto row = std::make_unique<MultibodyLimit>(treeA, sideA, sideB, *limit, policy);
        m_world.addMultiBodyConstraint(row.get());
        m_limits.push_back(row.get());
        m_constraints.push_back(std::move(row));
    }
    // The universal joints' twist rows (§4.4), parent side first.
    for (Part& p : m_parts)
        for (const Joint& j : p.joints) {
            if (j.kind != Joint::Kind::Universal) continue;
            const MultibodyLimit::Side parent{m_bodies[static_cast<std::size_t>(j.parent)].link,
                                              m_colliders[static_cast<std::size_t>(j.parent)].get(), nullptr};
            const MultibodyLimit::Side child{j.link, m_colliders[static_cast<std::size_t>(j.child)].get(), nullptr};
            auto row = std::make_unique<MultibodyLimit>(p.body.get(), parent, child,
                                                        MultibodyLimit::Twist{j.frameInParent, j.frameInChild}, policy);
            m_world.addMultiBodyConstraint(row.get());
            m_limits.push_back(row.get());
            m_constraints.push_back(std::move(row));
        }
    for (Part& p : m_parts) {
        auto guard =
            std::make_unique<EnergyGuard>(p.body.get(), *m_colliders[static_cast<std::size_t>(p.root)], m_world);
        m_world.addMultiBodyConstraint(guard.get());
        m_guards.push_back(guard.get());
        m_constraints.push_back(std::move(guard));
    }
    recordMotion();
}

void MultibodyRagdoll::addFriction(int ci, btMultiBodyConstraint* loop) {
    const figure::Figure& f = m_asset->figure();
    const FigureConstraint& c = f.constraints[static_cast<std::size_t>(ci)];
    if (!(c.friction > 0)) return;
    // The rows' axes in body 2's frame (world for a world joint), as the rigid backend's (Ragdoll::addConstraints).
    const btMatrix3x3 frame = m_frames[static_cast<std::size_t>(ci)].second.getBasis();
    btMatrix3x3 axes = btMatrix3x3::getIdentity();
    int count = 0;
    switch (c.type) {
    case JointType::BallAndSocket: count = 3; break;
    case JointType::Universal: // the two directions perpendicular to shaft 1 (the frame's X)
        count = 2;
        axes.setValue(frame[0][1], frame[0][2], 0, frame[1][1], frame[1][2], 0, frame[2][1], frame[2][2], 0);
        break;
    case JointType::Hinge: // the hinge axis (the frame's Z)
        count = 1;
        axes.setValue(frame[0][2], 0, 0, frame[1][2], 0, 0, frame[2][2], 0, 0);
        break;
    default: return; // fixed and slider joints have no friction (§4.6), springs none (§4.7)
    }
    const BodyRef a = m_bodies[static_cast<std::size_t>(c.body1)];
    btMultiBody& tree = *m_parts[static_cast<std::size_t>(a.part)].body;
    Friction fr;
    fr.coefficientTimesLever = static_cast<btScalar>(c.friction * f.units.metresPerUnit);
    fr.loop = loop;
    if (!loop) {
        // A tree joint: its reaction is what the child's subtree needs beyond gravity and its contacts.
        const std::vector<Joint>& joints = m_parts[static_cast<std::size_t>(a.part)].joints;
        int child = -1;
        for (const Joint& j : joints)
            if ((j.child == c.body1 && j.parent == c.body2) || (j.child == c.body2 && j.parent == c.body1))
                child = j.child;
        if (child < 0) return;
        for (int b = 0; b < bodyCount(); ++b) {
            if (m_bodies[static_cast<std::size_t>(b)].part != a.part) continue;
            int up = b;
            while (up >= 0 && up != child) {
                const auto it =
                    std::find_if(joints.begin(), joints.end(), [&](const Joint& j) { return j.child == up; });
                up = it == joints.end() ? -1 : it->parent;
            }
            if (up == child) fr.subtree.push_back(b);
        }
    }
    std::optional<int> linkB;
    const btCollisionObject* bodyB = nullptr;
    if (c.body2 >= 0) {
        linkB = m_bodies[static_cast<std::size_t>(c.body2)].link;
        bodyB = m_colliders[static_cast<std::size_t>(c.body2)].get();
    }
    auto rows = std::make_unique<JointFriction>(&tree, a.link, *m_colliders[static_cast<std::size_t>(c.body1)], linkB,
                                                bodyB, axes, count);
    fr.rows = rows.get();
    m_world.addMultiBodyConstraint(rows.get());
    m_frictions.push_back(fr);
    m_constraints.push_back(std::move(rows));
}

void MultibodyRagdoll::addSpring(const FigureConstraint& c, const btTransform& fa, const btTransform& fb) {
    const SpringConstraint::Params p = SpringConstraint::Params::of(c.spring);
    auto end = [&](int body, const btVector3& anchor) {
        MultibodySpring::End e;
        e.anchor = anchor;
        if (body < 0) return e;
        const BodyRef ref = m_bodies[static_cast<std::size_t>(body)];
        e.tree = m_parts[static_cast<std::size_t>(ref.part)].body.get();
        e.link = ref.link;
        e.body = m_colliders[static_cast<std::size_t>(body)].get();
        return e;
    };
    auto spring = std::make_unique<MultibodySpring>(end(c.body1, fa.getOrigin()), end(c.body2, fb.getOrigin()), p);
    m_world.addMultiBodyConstraint(spring.get());
    m_constraints.push_back(std::move(spring));
}

void MultibodyRagdoll::updateFrictionBounds(btScalar dt) {
    if (m_frictions.empty() || !(dt > 0)) return;
    // §4.8 as the rigid backend: each row's bound is friction × the joint's reaction force in the step just
    // solved, in SI (× metres per unit), times the step. A tree joint has no constraint force of its own: its
    // reaction is the force the child's subtree needed beyond gravity and its contacts, Σ(m·Δv − m·g·dt − p)/dt
    // (Bullet's joint feedback counts the velocity-product terms twice: 4·m·g at the bottom of a rod's swing for
    // the exact 2.5·m·g). A loop or world joint's reaction is its constraint's applied impulse.
    const std::vector<BodySample> now = samples();
    m_contactImpulse.assign(m_bodies.size(), btVector3(0, 0, 0));
    btDispatcher& dispatcher = *m_world.getDispatcher();
    for (int i = 0, n = dispatcher.getNumManifolds(); i < n; ++i) {
        const btPersistentManifold* m = dispatcher.getManifoldByIndexInternal(i);
        if (m->getNumContacts() == 0) continue;
        const int a = LinkCollider::bodyOf(m->getBody0(), *this), b = LinkCollider::bodyOf(m->getBody1(), *this);
        if (a < 0 && b < 0) continue;
        for (int k = 0; k < m->getNumContacts(); ++k) {
            const btManifoldPoint& cp = m->getContactPoint(k);
            // On body 0 (A): along the normal from B towards A, and the two friction directions.
            const btVector3 p = cp.m_normalWorldOnB * cp.m_appliedImpulse +
                                cp.m_lateralFrictionDir1 * cp.m_appliedImpulseLateral1 +
                                cp.m_lateralFrictionDir2 * cp.m_appliedImpulseLateral2;
            if (a >= 0) m_contactImpulse[static_cast<std::size_t>(a)] += p;
            if (b >= 0) m_contactImpulse[static_cast<std::size_t>(b)] -= p;
        }
    }
    const btVector3 g = m_world.getGravity();
    const figure::Figure& f = m_asset->figure();
    for (const Friction& fr : m_frictions) {
        btScalar force = 0;
        if (fr.loop) {
            btVector3 impulse(0, 0, 0);
            for (int i = 0; i < std::min(3, fr.loop->getNumRows()); ++i) impulse[i] = fr.loop->getAppliedImpulse(i);
            force = impulse.length() / dt;
        } else {
            btVector3 impulse(0, 0, 0);
            for (const int b : fr.subtree) {
                const std::size_t k = static_cast<std::size_t>(b);
                const btScalar m = static_cast<btScalar>(f.bodies[k].massKg);
                impulse += (now[k].linearVelocity - m_linearVelocity[k]) * m - g * (m * dt) - m_contactImpulse[k];
            }
            force = impulse.length() / dt;
        }
        static_cast<JointFriction*>(fr.rows)->setMaxImpulse(fr.coefficientTimesLever * force * dt);
    }
}

void MultibodyRagdoll::correctPositions() {
    if (m_positionIterations <= 0) return;
    // This substep's contacts of the ragdoll's bodies (found at the start of the substep; their depths are
    // recomputed from the bodies' poses as the sweeps move them).
    m_sweepContacts.clear();
    btDispatcher& dispatcher = *m_world.getDispatcher();
    for (int i = 0, n = dispatcher.getNumManifolds(); i < n; ++i) {
        btPersistentManifold* m = dispatcher.getManifoldByIndexInternal(i);
        if (m->getNumContacts() == 0) continue;
        const int a = LinkCollider::bodyOf(m->getBody0(), *this), b = LinkCollider::bodyOf(m->getBody1(), *this);
        if (a >= 0 || b >= 0) m_sweepContacts.push_back({m, a, b});
    }
    btAlignedObjectArray<btScalar> r;
    btAlignedObjectArray<btVector3> v;
    btAlignedObjectArray<btMatrix3x3> m;
    btAlignedObjectArray<btQuaternion> q;
    btAlignedObjectArray<btVector3> o;
    for (int sweep = 0; sweep < m_positionIterations; ++sweep) {
        btScalar worst = 0;
        bool corrected = false;
        for (btMultiBodyConstraint* c : m_limits)
            worst = std::max(worst, static_cast<MultibodyLimit*>(c)->correctPositions(r, v, m, q, o));
        // Contacts last, so that a sweep ends with the limbs the limits moved out of the ground again.
        for (const SweepContact& c : m_sweepContacts)
            for (int k = 0; k < c.manifold->getNumContacts(); ++k)
                corrected = correctContact(c, c.manifold->getContactPoint(k), r, v, m, q, o) || corrected;
        if (worst == 0 && !corrected) break;
    }
}

bool MultibodyRagdoll::correctContact(const SweepContact& c, const btManifoldPoint& cp,
                                      btAlignedObjectArray<btScalar>& r, btAlignedObjectArray<btVector3>& v,
                                      btAlignedObjectArray<btMatrix3x3>& m, btAlignedObjectArray<btQuaternion>& q,
                                      btAlignedObjectArray<btVector3>& o) {
    // The depth now: the ragdoll's sides carry their points along, other objects keep the world points found.
    const btVector3 pa = c.bodyA >= 0
                             ? m_colliders[static_cast<std::size_t>(c.bodyA)]->getWorldTransform() * cp.m_localPointA
                             : cp.m_positionWorldOnA;
    const btVector3 pb = c.bodyB >= 0
                             ? m_colliders[static_cast<std::size_t>(c.bodyB)]->getWorldTransform() * cp.m_localPointB
                             : cp.m_positionWorldOnB;
    const btVector3& n = cp.m_normalWorldOnB; // from B towards A
    const btScalar depth = -(pa - pb).dot(n) - kSweepContactSlopM;
    if (depth <= kSweepToleranceM) return false;
    const BodyRef refA = c.bodyA >= 0 ? m_bodies[static_cast<std::size_t>(c.bodyA)] : BodyRef{-1, -1};
    const BodyRef refB = c.bodyB >= 0 ? m_bodies[static_cast<std::size_t>(c.bodyB)] : BodyRef{-1, -1};
    bool corrected = false;
    // One tree at a time: a contact between two bodies of one tree is one row over it (J_A − J_B); between two
    // trees (parts joined by a spring only), each tree takes half, the other counted immovable.
    for (const int side : {0, 1}) {
        const BodyRef& ref = side == 0 ? refA : refB;
        const int body = side == 0 ? c.bodyA : c.bodyB;
        if (body < 0 || (side == 1 && refA.part == refB.part && c.bodyA >= 0)) continue;
        btMultiBody& mb = *m_parts[static_cast<std::size_t>(ref.part)].body;
        const std::size_t ndof = static_cast<std::size_t>(mb.getNumDofs() + 6);
        m_sweepJac.assign(ndof, 0);
        m_sweepJacB.resize(ndof);
        m_sweepMove.resize(ndof);
        // J·q̇ = (v_A − v_B)·n: the rate at which the depth falls.
        mb.fillContactJacobianMultiDof(ref.link, side == 0 ? pa : pb, side == 0 ? n : -n, m_sweepJac.data(), r, v, m);
        const bool both = c.bodyA >= 0 && c.bodyB >= 0 && refA.part == refB.part;
        if (both) {
            mb.fillContactJacobianMultiDof(refB.link, pb, -n, m_sweepJacB.data(), r, v, m);
            for (std::size_t k = 0; k < ndof; ++k) m_sweepJac[k] += m_sweepJacB[k];
        }
        mb.calcAccelerationDeltasMultiDof(m_sweepJac.data(), m_sweepMove.data(), r, v);
        btScalar w = 0;
        for (std::size_t k = 0; k < ndof; ++k) w += m_sweepJac[k] * m_sweepMove[k];
        if (!(w > SIMD_EPSILON)) continue;
        const bool shared = c.bodyA >= 0 && c.bodyB >= 0 && !both;
        const btScalar close = kSweepContactFraction * depth * (shared ? btScalar(0.5) : btScalar(1));
        for (btScalar& x : m_sweepMove) x *= close / w;
        mb.stepPositionsMultiDof(1, nullptr, m_sweepMove.data());
        mb.forwardKinematics(q, o);
        mb.updateCollisionObjectWorldTransforms(q, o);
        corrected = true;
    }
    return corrected;
}

void MultibodyRagdoll::publishVelocities(std::span<const BodySample> samples) {
    m_linearVelocity.resize(samples.size());
    for (std::size_t i = 0; i < samples.size(); ++i) {
        m_linearVelocity[i] = samples[i].linearVelocity;
        m_colliders[i]->setInterpolationLinearVelocity(samples[i].linearVelocity);
        m_colliders[i]->setInterpolationAngularVelocity(samples[i].angularVelocity);
    }
}

void MultibodyRagdoll::recordMotion() {
    for (btMultiBodyConstraint* g : m_guards) static_cast<EnergyGuard*>(g)->record();
}

void MultibodyRagdoll::refreshTransforms(btMultiBody& body) {
    btAlignedObjectArray<btQuaternion> q;
    btAlignedObjectArray<btVector3> o;
    body.forwardKinematics(q, o);
    body.updateCollisionObjectWorldTransforms(q, o);
}

void MultibodyRagdoll::dampVelocities(btScalar dt) {
    if (m_linearDamping <= 0 && m_angularDamping <= 0) return;
    const btScalar d = btScalar(0.5) * (m_linearDamping + m_angularDamping);
    const btScalar k = btPow(btScalar(1) - d, dt);
    for (Part& p : m_parts) {
        btMultiBody& mb = *p.body;
        mb.setBaseVel(mb.getBaseVel() * k);
        mb.setBaseOmega(mb.getBaseOmega() * k);
        for (int l = 0; l < mb.getNumLinks(); ++l) {
            btScalar* v = mb.getJointVelMultiDof(l);
            for (int dof = 0; dof < mb.getLink(l).m_dofCount; ++dof) v[dof] *= k;
        }
    }
}

btCollisionObject& MultibodyRagdoll::collider(int i) { return *m_colliders[static_cast<std::size_t>(i)]; }
const btCollisionObject& MultibodyRagdoll::collider(int i) const { return *m_colliders[static_cast<std::size_t>(i)]; }

std::vector<BodySample> MultibodyRagdoll::samples() const {
    std::vector<BodySample> out(m_bodies.size());
    std::vector<btVector3> omega, vel;
    for (std::size_t k = 0; k < m_parts.size(); ++k) {
        const btMultiBody& mb = *m_parts[k].body;
        omega.resize(static_cast<std::size_t>(mb.getNumLinks() + 1));
        vel.resize(omega.size());
        mb.compTreeLinkVelocities(omega.data(), vel.data()); // in each link's frame
        for (std::size_t i = 0; i < m_bodies.size(); ++i) {
            if (m_bodies[i].part != static_cast<int>(k)) continue;
            const btTransform& t = m_colliders[i]->getWorldTransform();
            const std::size_t slot = static_cast<std::size_t>(m_bodies[i].link + 1);
            out[i] = {t, t.getBasis() * vel[slot], t.getBasis() * omega[slot]};
        }
    }
    return out;
}

std::vector<btTransform> MultibodyRagdoll::transforms() const {
    std::vector<btTransform> out;
    out.reserve(m_colliders.size());
    for (const auto& c : m_colliders) out.push_back(c->getWorldTransform());
    return out;
}

std::pair<btTransform, btTransform> MultibodyRagdoll::constraintFramesWorld(int i) const {
    const std::vector<btTransform> t = transforms();
    return constraintFramesWorldOf(m_asset->figure().constraints[static_cast<std::size_t>(i)], t,
                                   m_frames[static_cast<std::size_t>(i)]);
}

JointError MultibodyRagdoll::jointError(int i) const {
    return jointErrorOf(m_asset->figure().constraints[static_cast<std::size_t>(i)], transforms(),
                        m_frames[static_cast<std::size_t>(i)], m_spawn);
}

int MultibodyRagdoll::awakeBodyCount() const {
    int n = 0;
    for (const auto& c : m_colliders) n += c->isActive() ? 1 : 0;
    return n;
}

void MultibodyRagdoll::setBodyStates(std::span<const figure::BodyState> states) {
    auto pose = [&](int b) { return toBt(states[static_cast<std::size_t>(b)].pose); };
    auto omega = [&](int b) { return toBt(states[static_cast<std::size_t>(b)].angularVelocity); };
    auto velocity = [&](int b) { return toBt(states[static_cast<std::size_t>(b)].linearVelocity); };
    for (Part& p : m_parts) {
        btMultiBody& mb = *p.body;
        if (!p.fixedBase) { // a fixed base stays where the world holds it
            const btTransform base = pose(p.root);
            mb.setBasePos(base.getOrigin());
            mb.setWorldToBaseRot(quatOf(base.getBasis()).inverse());
            mb.setBaseVel(velocity(p.root));
            mb.setBaseOmega(omega(p.root));
        }
        for (const Joint& j : p.joints) {
            const btTransform tp = pose(j.parent), tc = pose(j.child);
            const btVector3 wRel = omega(j.child) - omega(j.parent);
            // Zero coordinates put the child at R_P·R0ᵀ; a revolute coordinate q turns it about its axis by q
            // (btMultibodyLink::updateCacheMultiDof), a spherical one by its quaternion, both in the child's frame.
            const btMatrix3x3 local = j.zeroParentToChild * tp.getBasis().transpose() * tc.getBasis();
            switch (j.kind) {
            case Joint::Kind::Fixed: break;
            case Joint::Kind::Revolute: {
                const btQuaternion q = quatOf(local);
                const btScalar along = btVector3(q.x(), q.y(), q.z()).dot(j.axisInChild);
                mb.setJointPos(j.link, 2 * btAtan2(along, q.w()));
                mb.setJointVel(j.link, (tc.getBasis() * j.axisInChild).dot(wRel));
                break;
            }
            case Joint::Kind::Prismatic: {
                const btVector3 offset = tc.getOrigin() - tp.getOrigin();
                const btVector3 inChild = tc.getBasis().transpose() * (offset - tp.getBasis() * j.parentToPivot);
                mb.setJointPos(j.link, (inChild - j.pivotToChild).dot(j.axisInChild));
                const btVector3 rel = velocity(j.child) - velocity(j.parent) - omega(j.parent).cross(offset);
                mb.setJointVel(j.link, (tc.getBasis() * j.axisInChild).dot(rel));
                break;
            }
            case Joint::Kind::Spherical:
            case Joint::Kind::Universal: { // a spherical link too; its twist row pulls a twisted pose back
                const btQuaternion q = quatOf(local);
                btScalar pos[4] = {q.x(), q.y(), q.z(), q.w()};
                mb.setJointPosMultiDof(j.link, pos);
                const btVector3 w = tc.getBasis().transpose() * wRel;
                btScalar vel[3] = {w.x(), w.y(), w.z()};
                mb.setJointVelMultiDof(j.link, vel);
                break;
            }
            }
        }
        refreshTransforms(mb);
    }
    wake();
    recordMotion();
    publishVelocities(samples());
}

void MultibodyRagdoll::applyImpulse(int i, const btVector3& impulse, const btVector3& worldPoint) {
    const BodyRef ref = m_bodies[static_cast<std::size_t>(i)];
    btMultiBody& mb = *m_parts[static_cast<std::size_t>(ref.part)].body;
    const btScalar magnitude = impulse.length();
    if (!(magnitude > 0)) return;
    const int ndof = mb.getNumDofs() + 6;
    std::vector<btScalar> jac(static_cast<std::size_t>(ndof)), delta(static_cast<std::size_t>(ndof));
    btAlignedObjectArray<btScalar> r;
    btAlignedObjectArray<btVector3> v;
    btAlignedObjectArray<btMatrix3x3> m;
    // Δq̇ = M⁻¹·Jᵀ·|p| for the direction of p at the point: how the solver applies a contact impulse.
    mb.fillContactJacobianMultiDof(ref.link, worldPoint, impulse / magnitude, jac.data(), r, v, m);
    for (btScalar& x : jac) x *= magnitude;
    mb.calcAccelerationDeltasMultiDof(jac.data(), delta.data(), r, v);
    mb.applyDeltaVeeMultiDof(delta.data(), 1);
    recordMotion();
    publishVelocities(samples());
}

bool MultibodyRagdoll::atRest() const { return m_action->atRest; }
double MultibodyRagdoll::activeSeconds() const { return m_action->activeTime; }

void MultibodyRagdoll::putToRest() {
    for (Part& p : m_parts) {
        btMultiBody& mb = *p.body;
        mb.setBaseVel(btVector3(0, 0, 0));
        mb.setBaseOmega(btVector3(0, 0, 0));
        for (int l = 0; l < mb.getNumLinks(); ++l) {
            btScalar* v = mb.getJointVelMultiDof(l);
            for (int dof = 0; dof < mb.getLink(l).m_dofCount; ++dof) v[dof] = 0;
        }
        mb.setCanSleep(true);
        mb.goToSleep();
    }
    for (const auto& c : m_colliders) c->forceActivationState(ISLAND_SLEEPING);
    m_action->atRest = true;
    recordMotion();
    publishVelocities(samples());
}

void MultibodyRagdoll::wake() { m_action->wake(); }

} // namespace afb::bullet::detail
