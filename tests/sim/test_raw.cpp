// The plain-Bullet reference (sim::RawRagdoll, the chart's "raw"): the same bodies as the adapter, Bullet's own
// constraints and defaults, and the same measurements in a drop.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>

#include "EntityFixture.h"
#include "afb/bullet/RagdollAsset.h"
#include "afb/detail/Convert.h"
#include "afb/sim/Drop.h"
#include "afb/sim/RawRagdoll.h"
#include "afb/sim/Scene.h"

using namespace afb;

namespace {

// |a − b| within 1e-9 relative to the larger magnitude (absolute below 1).
bool same(double a, double b) { return std::abs(a - b) <= 1e-9 * std::max({1.0, std::abs(a), std::abs(b)}); }

// The humanoid twice, at the same spawn: the adapter (default method, its fixed wrists unmerged: raw builds one
// btRigidBody per figure body) and raw, in two zero-gravity scenes.
bullet::Method unmergedDefault() {
    bullet::Method m;
    m.mergeFixed = false;
    return m;
}
struct Pair {
    std::shared_ptr<const bullet::RagdollAsset> asset =
        bullet::RagdollAsset::create(test::loadEntity("humanoid").figure);
    sim::Scene adapterScene{unmergedDefault(), {.gravityMps2 = 0, .ground = false}};
    sim::Scene rawScene{sim::rawMethod(), {.gravityMps2 = 0, .ground = false}};
    bullet::Ragdoll* adapter = nullptr;
    sim::RawRagdoll* raw = nullptr;
    Pair() {
        bullet::SpawnOptions where;
        where.entityTransform = btTransform(btQuaternion(btVector3(0, 0, 1), btScalar(0.7)), btVector3(1, 2, 3));
        adapter = &adapterScene.spawn(asset, where);
        raw = &rawScene.spawnRaw(asset, where);
    }
};

} // namespace

TEST_CASE("raw: the method is Bullet's defaults and none of afbullet's techniques", "[sim][raw]") {
    const bullet::Method m = sim::rawMethod();
    const btContactSolverInfo bulletDefaults; // what a plain world starts with
    CHECK(sim::isRaw(m));
    CHECK(m.iterations == bulletDefaults.m_numIterations);
    CHECK(m.splitImpulse == (bulletDefaults.m_splitImpulse != 0));
    CHECK(m.contactErp == Approx(bulletDefaults.m_erp2));
    CHECK(m.jointErp == Approx(bulletDefaults.m_erp));
    CHECK(m.warmStarting == ((bulletDefaults.m_solverMode & SOLVER_USE_WARMSTARTING) != 0));
    CHECK(m.warmStartingFactor == Approx(bulletDefaults.m_warmstartingFactor));
    CHECK(m.frictionDirections == ((bulletDefaults.m_solverMode & SOLVER_USE_2_FRICTION_DIRECTIONS) ? 2 : 1));
    CHECK(m.substeps == 1);
    CHECK(m.jointIterations == 0);
    CHECK(m.positionIterations == 0);
    CHECK_FALSE(m.multipointContacts);
    CHECK_FALSE(m.speculativeContacts);
    CHECK_FALSE(m.speculativeLimits);
    CHECK(m.ccd == bullet::CcdPolicy::Off);
    CHECK(sim::rawMethodError(m).empty());
    bullet::Method wrong = m;
    wrong.positionIterations = 2;
    CHECK(sim::rawMethodError(wrong).find("position-iterations") != std::string::npos);
    bullet::Method merged = m; // RawRagdoll builds one btRigidBody per figure body, always
    merged.mergeFixed = true;
    CHECK(sim::rawMethodError(merged).find("merge-fixed") != std::string::npos);
    CHECK(sim::methodByName("raw") == m);
    CHECK(sim::methodByName("default") == bullet::methodPreset("default"));
    CHECK_FALSE(sim::methodByName("nonsense"));
}

TEST_CASE("raw: builds the same bodies as the adapter", "[sim][raw]") {
    Pair p;
    const figure::Figure& f = p.asset->figure();
    REQUIRE(p.raw->bodyCount() == static_cast<int>(f.bodies.size()));
    REQUIRE(p.adapter->bodyCount() == p.raw->bodyCount());
    for (int i = 0; i < p.raw->bodyCount(); ++i) {
        const btRigidBody& r = p.raw->body(i);
        const btRigidBody& a = p.adapter->body(i);
        const figure::FigureBody& fb = f.bodies[static_cast<std::size_t>(i)];
        INFO(fb.name);
        CHECK(same(r.getMass(), a.getMass()));
        CHECK(r.getMass() == Approx(fb.massKg).epsilon(1e-6)); // btScalar may be float
        for (int k = 0; k < 3; ++k) {
            CHECK(same(r.getLocalInertia()[k], a.getLocalInertia()[k]));
            CHECK(r.getLocalInertia()[k] == Approx(fb.inertiaKgM2[k]).epsilon(1e-5));
        }
        CHECK(r.getCollisionShape() == a.getCollisionShape()); // the asset's shape: same polytope and margin
        // The same principal frame at the same place.
        const btTransform& tr = r.getCenterOfMassTransform();
        const btTransform& ta = a.getCenterOfMassTransform();
        CHECK((tr.getOrigin() - ta.getOrigin()).length() < 1e-9);
        for (int row = 0; row < 3; ++row) CHECK((tr.getBasis()[row] - ta.getBasis()[row]).length() < 1e-9);
        CHECK(r.getFriction() == a.getFriction());
        CHECK(r.getRestitution() == a.getRestitution());
        CHECK(r.getLinearDamping() == a.getLinearDamping());
        CHECK(r.getAngularDamping() == a.getAngularDamping());
        CHECK(r.getBroadphaseHandle()->m_collisionFilterGroup == a.getBroadphaseHandle()->m_collisionFilterGroup);
        CHECK(r.getBroadphaseHandle()->m_collisionFilterMask == a.getBroadphaseHandle()->m_collisionFilterMask);
        for (int j = 0; j < p.raw->bodyCount(); ++j)
            CHECK(r.checkCollideWith(&p.raw->body(j)) == a.checkCollideWith(&p.adapter->body(j)));
    }
}

TEST_CASE("raw: differs only in the policies of plain Bullet", "[sim][raw]") {
    Pair p;
    const figure::Figure& f = p.asset->figure();
    for (int i = 0; i < p.raw->bodyCount(); ++i) {
        const btRigidBody& r = p.raw->body(i);
        const btRigidBody& a = p.adapter->body(i);
        // No CCD; Bullet's own deactivation thresholds instead of the figure's rest rules.
        CHECK(r.getCcdMotionThreshold() == 0);
        CHECK(a.getCcdMotionThreshold() > 0);
        const btRigidBody::btRigidBodyConstructionInfo defaults(1, nullptr, nullptr);
        CHECK(r.getLinearSleepingThreshold() == defaults.m_linearSleepingThreshold);
        CHECK(r.getAngularSleepingThreshold() == defaults.m_angularSleepingThreshold);
        CHECK(a.getLinearSleepingThreshold() == 0);
    }
    // One Bullet constraint per joint, of Bullet's own types, solved with the world's iterations; the adapter
    // adds limit and friction rows and its own iteration count.
    CHECK(p.rawScene.world().getNumConstraints() == static_cast<int>(f.constraints.size()));
    CHECK(p.adapterScene.world().getNumConstraints() > p.rawScene.world().getNumConstraints());
    for (int c = 0; c < static_cast<int>(f.constraints.size()); ++c) {
        const figure::FigureConstraint& fc = f.constraints[static_cast<std::size_t>(c)];
        INFO(fc.name);
        const btTypedConstraint* rc = p.raw->constraint(c);
        REQUIRE(rc != nullptr);
        CHECK(rc->getOverrideNumSolverIterations() == -1);
        const bool limited = !std::holds_alternative<std::monostate>(fc.limit);
        switch (fc.type) {
        case figure::JointType::Fixed: CHECK(rc->getConstraintType() == D6_SPRING_2_CONSTRAINT_TYPE); break;
        case figure::JointType::Hinge: {
            REQUIRE(rc->getConstraintType() == HINGE_CONSTRAINT_TYPE);
            const auto* h = static_cast<const btHingeConstraint*>(rc);
            const auto* range = std::get_if<figure::HingeRange>(&fc.limit);
            REQUIRE(range);
            CHECK(h->getLowerLimit() == Approx(range->lowerRad).margin(1e-6));
            CHECK(h->getUpperLimit() == Approx(range->upperRad).margin(1e-6));
            break;
        }
        case figure::JointType::Universal:
            REQUIRE(rc->getConstraintType() == CONETWIST_CONSTRAINT_TYPE);
            CHECK(static_cast<const btConeTwistConstraint*>(rc)->getTwistSpan() == 0); // twist locked
            break;
        case figure::JointType::BallAndSocket:
            if (limited) {
                REQUIRE(rc->getConstraintType() == CONETWIST_CONSTRAINT_TYPE);
                CHECK(static_cast<const btConeTwistConstraint*>(rc)->getTwistSpan() < 0); // twist free
            } else {
                CHECK(rc->getConstraintType() == POINT2POINT_CONSTRAINT_TYPE);
            }
            break;
        default: FAIL("the humanoid has no such joint");
        }
        // Built in its load pose, every joint holds: anchors together, limits (cone frames included) respected,
        // measured exactly as for the adapter.
        CHECK(p.raw->jointError(c).anchorM < 1e-5);
        CHECK(p.raw->jointError(c).limitExcessRad == Approx(p.adapter->jointError(c).limitExcessRad).margin(1e-6));
        CHECK(p.raw->jointError(c).anchorM == Approx(p.adapter->jointError(c).anchorM).margin(1e-6));
    }
}

TEST_CASE("raw: a drop measures plain Bullet the way it measures the adapter", "[sim][raw]") {
    const figure::Figure humanoid = test::loadEntity("humanoid").figure;
    sim::DropOptions o;
    o.heightM = 1.0;
    o.seconds = 3.0;
    o.method = sim::rawMethod();
    const sim::DropResult raw = sim::runDrop(humanoid, o);
    o.method = bullet::Method{};
    const sim::DropResult adapter = sim::runDrop(humanoid, o);
    INFO("raw: anchor " << raw.maxAnchorErrorM << " m at " << raw.worstAnchorJoint << ", limit "
                        << raw.maxLimitViolationDeg << " deg, penetration " << raw.maxPenetrationM
                        << " m; default: anchor " << adapter.maxAnchorErrorM << " m, limit "
                        << adapter.maxLimitViolationDeg << " deg");
    CHECK(raw.method.name == "raw");
    CHECK(raw.steps == adapter.steps);
    CHECK(raw.bodies == adapter.bodies);
    CHECK(std::isfinite(raw.maxAnchorErrorM));
    CHECK(raw.maxAnchorErrorM > 0);
    CHECK(raw.maxPenetrationM > 0);
    CHECK(raw.awakeBodySteps > 0);
    CHECK(raw.finalPose.size() == adapter.finalPose.size());
    // What the chart exists to show: plain Bullet holds the humanoid's joints less well than afbullet's default.
    CHECK(raw.maxAnchorErrorM > adapter.maxAnchorErrorM);
    // Deterministic: the same run again gives the same numbers.
    o.method = sim::rawMethod();
    const sim::DropResult again = sim::runDrop(humanoid, o);
    CHECK(again.maxAnchorErrorM == raw.maxAnchorErrorM);
    CHECK(again.maxLimitViolationDeg == raw.maxLimitViolationDeg);
    CHECK(again.settleTimeS == raw.settleTimeS);
}
