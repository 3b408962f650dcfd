// Economy: pairs pruned once per figure never touch within the limits.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <deque>
#include <random>

#include "EntityFixture.h"
#include "afb/bullet/RagdollAsset.h"
#include "afb/figure/Collision.h"
#include "afb/figure/Limits.h"
#include "afb/sim/Scene.h"

using namespace afb;

namespace {

constexpr double kPi = 3.14159265358979323846;

/// Random poses of a figure with every joint inside its limit: a tree of the figure's joints (sliders, springs and
/// world joints left out) from body 0, each child turned about its joint's anchor relative to its parent by a
/// rotation drawn until limitExcessRad is 0 (hinges about their axis, universal joints without twist).
class PoseSampler {
  public:
    explicit PoseSampler(const figure::Figure& f, std::uint32_t seed) : m_figure(f), m_rng(seed) {
        const std::size_t n = f.bodies.size();
        std::vector<bool> seen(n, false);
        std::deque<int> queue{0};
        seen[0] = true;
        while (!queue.empty()) {
            const int b = queue.front();
            queue.pop_front();
            for (std::size_t k = 0; k < f.constraints.size(); ++k) {
                const figure::FigureConstraint& c = f.constraints[k];
                if (c.body2 < 0 || c.type == figure::JointType::Slider || c.type == figure::JointType::Spring) continue;
                if (c.body1 != b && c.body2 != b) continue;
                const int child = c.body1 == b ? c.body2 : c.body1;
                if (seen[static_cast<std::size_t>(child)]) continue;
                seen[static_cast<std::size_t>(child)] = true;
                m_order.push_back({child, b, static_cast<int>(k)});
                queue.push_back(child);
            }
        }
        m_reached = seen;
    }
    /// Whether body `b` is posed by the sampler (joined to body 0).
    bool reaches(int b) const { return m_reached[static_cast<std::size_t>(b)]; }

    /// Body frames in model space.
    std::vector<figure::Transform> sample() {
        std::vector<figure::Transform> pose;
        for (const figure::FigureBody& b : m_figure.bodies) pose.push_back(b.loadPose);
        for (const Link& link : m_order) {
            const figure::FigureConstraint& c = m_figure.constraints[static_cast<std::size_t>(link.constraint)];
            const figure::Transform& parentLoad = m_figure.bodies[static_cast<std::size_t>(link.parent)].loadPose;
            const figure::Transform& childLoad = m_figure.bodies[static_cast<std::size_t>(link.child)].loadPose;
            // The child's pose relative to its parent at the load pose, then turned about the anchor.
            const figure::Transform rel = parentLoad.inverse() * childLoad;
            const Eigen::Vector3d anchorInParent = parentLoad.inverse().apply(
                m_figure.bodies[static_cast<std::size_t>(c.body1)].loadPose.apply(c.frameInBody1.position));
            for (int attempt = 0;; ++attempt) {
                const Eigen::Matrix3d turn = attempt < 1000 ? drawTurn(c, parentLoad) : Eigen::Matrix3d::Identity();
                figure::Transform about{turn, anchorInParent - turn * anchorInParent};
                const figure::Transform child = pose[static_cast<std::size_t>(link.parent)] * about * rel;
                const Eigen::Matrix3d& r1 =
                    c.body1 == link.child ? child.rotation : pose[static_cast<std::size_t>(c.body1)].rotation;
                const Eigen::Matrix3d& r2 =
                    c.body2 == link.child ? child.rotation : pose[static_cast<std::size_t>(c.body2)].rotation;
                if (figure::limitExcessRad(c, r1, r2) <= 1e-9) {
                    pose[static_cast<std::size_t>(link.child)] = child;
                    break;
                }
            }
        }
        return pose;
    }

  private:
    struct Link {
        int child, parent, constraint;
    };
    // A turn in the parent's frame: about the hinge axis, about an axis across the shaft (universal), or any.
    Eigen::Matrix3d drawTurn(const figure::FigureConstraint& c, const figure::Transform& parentLoad) {
        std::uniform_real_distribution<double> angle(-kPi, kPi);
        std::normal_distribution<double> normal;
        const figure::Transform& b1 = m_figure.bodies[static_cast<std::size_t>(c.body1)].loadPose;
        const Eigen::Matrix3d frame = parentLoad.rotation.transpose() * b1.rotation * c.frameInBody1.rotation;
        Eigen::Vector3d axis(normal(m_rng), normal(m_rng), normal(m_rng));
        if (c.type == figure::JointType::Fixed) return Eigen::Matrix3d::Identity();
        if (c.type == figure::JointType::Hinge) axis = frame.col(2);
        if (c.type == figure::JointType::Universal) axis -= axis.dot(frame.col(0)) * frame.col(0);
        // Half the draws at the limit's own size (poses near its edge), half anywhere.
        double bound = kPi;
        if (const auto* cone = std::get_if<figure::ConeLimit>(&c.limit)) bound = cone->halfAngleRad;
        if (const auto* p = std::get_if<figure::PyramidLimit>(&c.limit))
            bound = std::max(p->halfAngle1Rad, p->halfAngle2Rad) * 1.5;
        const double a = std::uniform_real_distribution<double>(0, 1)(m_rng) < 0.5
                             ? angle(m_rng)
                             : std::uniform_real_distribution<double>(-bound, bound)(m_rng);
        return Eigen::AngleAxisd(a, axis.normalized()).toRotationMatrix();
    }

    const figure::Figure& m_figure;
    std::mt19937 m_rng;
    std::vector<Link> m_order;
    std::vector<bool> m_reached;
};

/// Samples `poses` poses inside the limits and checks that the two bodies of every pruned pair stay apart in each;
/// returns how many pairs were pruned.
std::size_t checkPruning(const figure::Figure& f, int poses) {
    const auto asset = bullet::RagdollAsset::create(f);
    const auto& pruned = asset->prunedPairs();
    const auto all = figure::selfCollisionPairs(f);
    INFO(f.name << ": " << pruned.size() << " of " << all.size() << " self-collision pairs pruned");
    CHECK(pruned.size() + asset->contactPairs().size() == all.size());
    if (pruned.empty()) return 0;
    PoseSampler sampler(f, 12345);
    std::vector<double> closest(pruned.size(), 1e9);
    for (int s = 0; s < poses; ++s) {
        const std::vector<figure::Transform> pose = sampler.sample();
        auto posed = [&](int b) {
            figure::FigureBody body = f.bodies[static_cast<std::size_t>(b)];
            body.loadPose = pose[static_cast<std::size_t>(b)];
            return body;
        };
        for (std::size_t k = 0; k < pruned.size(); ++k)
            closest[k] = std::min(closest[k], figure::separation(posed(pruned[k].first), posed(pruned[k].second)));
    }
    for (std::size_t k = 0; k < pruned.size(); ++k) {
        INFO(f.bodies[static_cast<std::size_t>(pruned[k].first)].name
             << " / " << f.bodies[static_cast<std::size_t>(pruned[k].second)].name << ": closest " << closest[k]
             << " m");
        CHECK(sampler.reaches(pruned[k].first));
        CHECK(closest[k] > 0);
    }
    return pruned.size();
}

} // namespace

TEST_CASE("economy: pruned self-collision pairs never touch within the joint limits", "[bullet][economy]") {
    for (const char* entity : {"humanoid", "chain", "lamp", "buggy"})
        checkPruning(test::loadEntity(entity).figure, 400);
}

TEST_CASE("economy: pruned pairs on the corpus figures never touch within the limits", "[bullet][economy][corpus]") {
    AFB_REQUIRE_CORPUS(corpus);
    for (const char* entity : {"monster_zsec_machinegun", "monster_zsec_pistol"}) // 2 pairs each (docs/performance.md)
        CHECK(checkPruning(test::loadEntity(entity, corpus / "doom3-kroom3/base").figure, 600) > 0);
}

namespace {

/// Pairs in the world's pair cache that involve a body of `r`.
int pairsOf(sim::Scene& scene, const bullet::Ragdoll& r) {
    int n = 0;
    btOverlappingPairCache* cache = scene.world().getBroadphase()->getOverlappingPairCache();
    for (int k = 0; k < cache->getNumOverlappingPairs(); ++k) {
        const btBroadphasePair& p = cache->getOverlappingPairArray()[k];
        for (int i = 0; i < r.bodyCount(); ++i)
            if (p.m_pProxy0->m_clientObject == &r.body(i) || p.m_pProxy1->m_clientObject == &r.body(i)) ++n;
    }
    return n;
}

} // namespace

TEST_CASE("economy: a ragdoll spawned at rest stays frozen, costs no pairs or constraints, never wakes by itself",
          "[bullet][economy]") {
    const auto loaded = test::loadEntity("humanoid");
    const auto asset = bullet::RagdollAsset::create(loaded.figure);
    sim::Scene scene(*bullet::methodPreset("default"));
    const int constraintsBefore = scene.world().getNumConstraints();
    bullet::SpawnOptions o;
    o.entityTransform = test::standing(loaded.figure, 0, 0);
    o.startAtRest = true;
    bullet::Ragdoll& r = scene.spawn(asset, o);
    CHECK(r.atRest());
    CHECK(r.frozen());
    const std::vector<figure::Transform> before = r.bodyTransforms();
    for (int s = 0; s < 600; ++s) scene.step(1.0 / 60);
    CHECK(r.atRest());
    CHECK(r.frozen());
    CHECK(r.awakeBodyCount() == 0);
    CHECK(scene.world().getNumConstraints() == constraintsBefore); // its constraints are out of the world
    CHECK(pairsOf(scene, r) == 0);                                 // no pairs with the ground or itself
    const std::vector<figure::Transform> after = r.bodyTransforms();
    for (std::size_t i = 0; i < before.size(); ++i) {
        CHECK(after[i].position == before[i].position);
        CHECK(after[i].rotation == before[i].rotation);
    }
}

TEST_CASE("economy: a frozen ragdoll wakes on an impulse, whole, with its mass and constraints back",
          "[bullet][economy]") {
    const auto loaded = test::loadEntity("humanoid");
    const auto asset = bullet::RagdollAsset::create(loaded.figure);
    sim::Scene scene(*bullet::methodPreset("default"));
    const int constraintsBefore = scene.world().getNumConstraints();
    bullet::SpawnOptions o;
    o.entityTransform = test::standing(loaded.figure, 0, 0);
    o.startAtRest = true;
    bullet::Ragdoll& r = scene.spawn(asset, o);
    scene.step(1.0 / 60);
    const auto& bodies = loaded.figure.bodies;
    const auto headBody = std::find_if(bodies.begin(), bodies.end(), [](const auto& b) { return b.name == "head"; });
    REQUIRE(headBody != bodies.end());
    const int head = headBody->joint;
    const int body = loaded.figure.jointBody[static_cast<std::size_t>(head)];
    REQUIRE(body >= 0);
    const btVector3 at = r.body(body).getCenterOfMassPosition();
    CHECK_FALSE(r.applyImpulse(head, btVector3(btScalar(r.impulseThresholdNs() * 0.5), 0, 0), at));
    CHECK(r.frozen());
    CHECK(r.applyImpulse(head, btVector3(btScalar(r.impulseThresholdNs() * 4), 0, 0), at));
    CHECK_FALSE(r.atRest());
    CHECK_FALSE(r.frozen());
    CHECK(scene.world().getNumConstraints() == constraintsBefore + r.bulletConstraintCount());
    for (int k = 0; k < r.rigidBodyCount(); ++k) { // merged hands and forearms: their compound's mass
        const bullet::RigidLayout::Rigid& b = r.layout().rigids[static_cast<std::size_t>(k)];
        CHECK(r.rigidBody(k).getInvMass() == Approx(1.0 / b.massKg).epsilon(1e-6));
        CHECK(r.rigidBody(k).getLocalInertia().x() == Approx(b.inertiaKgM2.x()).epsilon(1e-6));
        CHECK(r.rigidBody(k).isActive());
        CHECK_FALSE(r.rigidBody(k).isStaticOrKinematicObject());
    }
    const btVector3 start = r.body(body).getCenterOfMassPosition();
    for (int s = 0; s < 10; ++s) scene.step(1.0 / 60);
    CHECK(r.body(body).getCenterOfMassPosition().x() > start.x() + 0.01); // pushed along +X
}

TEST_CASE("economy: a frozen ragdoll wakes when a falling body lands on it", "[bullet][economy]") {
    const auto loaded = test::loadEntity("humanoid");
    const auto asset = bullet::RagdollAsset::create(loaded.figure);
    sim::Scene scene(*bullet::methodPreset("default"));
    bullet::SpawnOptions o;
    o.entityTransform = test::standing(loaded.figure, 0, 0);
    o.startAtRest = true;
    bullet::Ragdoll& resting = scene.spawn(asset, o);
    // A second humanoid dropped onto the first from half a metre above its head.
    bullet::SpawnOptions above;
    above.entityTransform = o.entityTransform;
    above.entityTransform.getOrigin() += btVector3(0.1f, 0, 2.3f);
    bullet::Ragdoll& falling = scene.spawn(asset, above);
    int wokeAt = -1;
    for (int s = 0; s < 120 && wokeAt < 0; ++s) {
        scene.step(1.0 / 60);
        if (!resting.frozen()) wokeAt = s;
    }
    INFO("woke at step " << wokeAt);
    CHECK(wokeAt > 10); // not before the faller got there (0.5 m of fall: about 19 steps)
    CHECK_FALSE(falling.atRest());
    CHECK_FALSE(resting.atRest());
}

TEST_CASE("economy: a frozen ragdoll with nothing active near sinks behind one box, and comes back when approached",
          "[bullet][economy]") {
    const auto loaded = test::loadEntity("humanoid");
    const auto asset = bullet::RagdollAsset::create(loaded.figure);
    sim::Scene scene(*bullet::methodPreset("default"));
    const int objectsBefore = scene.world().getNumCollisionObjects();
    bullet::SpawnOptions o;
    o.entityTransform = test::standing(loaded.figure, 0, 0);
    o.startAtRest = true;
    bullet::Ragdoll& resting = scene.spawn(asset, o);
    CHECK(scene.world().getNumCollisionObjects() == objectsBefore + resting.rigidBodyCount());
    for (int s = 0; s < 40; ++s) scene.step(1.0 / 60);
    CHECK(resting.frozen());
    CHECK(resting.sunk());
    CHECK(scene.world().getNumCollisionObjects() == objectsBefore + 1); // one box instead of its bodies
    // Nothing of it is active: the world skips the box's AABB each step, as it skips a sleeping body's (an active
    // box was updated every substep and kept in the broadphase's dynamic tree: 1000 of them cost half a step).
    int activeObjects = 0;
    for (int i = 0; i < scene.world().getNumCollisionObjects(); ++i)
        activeObjects += scene.world().getCollisionObjectArray()[i]->isActive() ? 1 : 0;
    CHECK(activeObjects == 0);
    // surface() brings the bodies back, frozen (a game about to ray-test it); quiet, it sinks again.
    resting.surface();
    CHECK_FALSE(resting.sunk());
    CHECK(resting.frozen());
    CHECK(scene.world().getNumCollisionObjects() == objectsBefore + resting.rigidBodyCount());
    for (int s = 0; s < 40; ++s) scene.step(1.0 / 60);
    CHECK(resting.sunk());
    // A second humanoid dropped onto it from 3 m above its head: it lands after the first one sank (about 0.8 s of
    // fall), brings its bodies back as it nears, and wakes it when it touches.
    bullet::SpawnOptions above;
    above.entityTransform = o.entityTransform;
    above.entityTransform.getOrigin() += btVector3(0.1f, 0, 4.8f);
    bullet::Ragdoll& falling = scene.spawn(asset, above);
    int surfacedAt = -1, wokeAt = -1;
    for (int s = 0; s < 180 && wokeAt < 0; ++s) {
        scene.step(1.0 / 60);
        if (surfacedAt < 0 && !resting.sunk()) surfacedAt = s;
        if (!resting.frozen()) wokeAt = s;
    }
    INFO("surfaced at step " << surfacedAt << ", woke at step " << wokeAt);
    CHECK(surfacedAt > 20);      // not before the faller got near
    CHECK(wokeAt >= surfacedAt); // its bodies were back before the touch
    CHECK(wokeAt > 0);
    CHECK_FALSE(falling.atRest());
}

TEST_CASE("economy: sinking is off in a RagdollWorld unless turned on", "[bullet][economy]") {
    const auto loaded = test::loadEntity("humanoid");
    const auto asset = bullet::RagdollAsset::create(loaded.figure);
    sim::Scene scene(*bullet::methodPreset("default"));
    scene.ragdollWorld().setSinking(false);
    bullet::SpawnOptions o;
    o.entityTransform = test::standing(loaded.figure, 0, 0);
    o.startAtRest = true;
    bullet::Ragdoll& r = scene.spawn(asset, o);
    for (int s = 0; s < 120; ++s) scene.step(1.0 / 60);
    CHECK(r.frozen());
    CHECK_FALSE(r.sunk());
}

TEST_CASE("economy: a sunk ragdoll wakes whole on an impulse and is removed cleanly", "[bullet][economy]") {
    const auto loaded = test::loadEntity("humanoid");
    const auto asset = bullet::RagdollAsset::create(loaded.figure);
    sim::Scene scene(*bullet::methodPreset("default"));
    const int objectsBefore = scene.world().getNumCollisionObjects();
    const int constraintsBefore = scene.world().getNumConstraints();
    bullet::SpawnOptions o;
    o.entityTransform = test::standing(loaded.figure, 0, 0);
    o.startAtRest = true;
    bullet::Ragdoll& r = scene.spawn(asset, o);
    const std::vector<figure::Transform> before = r.bodyTransforms();
    for (int s = 0; s < 40; ++s) scene.step(1.0 / 60);
    REQUIRE(r.sunk());
    // The world holds the ground and the sunk ragdoll's box, which names its ragdoll but is none of its bodies.
    int boxes = 0;
    for (int k = 0; k < scene.world().getNumCollisionObjects(); ++k) {
        const btCollisionObject* object = scene.world().getCollisionObjectArray()[k];
        if (object == scene.ground()) {
            CHECK(scene.ragdollWorld().ragdollOf(object) == nullptr);
            continue;
        }
        ++boxes;
        CHECK(scene.ragdollWorld().ragdollOf(object) == &r);
        CHECK(r.figureBodyOf(*object, object->getWorldTransform().getOrigin()) == -1);
    }
    CHECK(boxes == 1);
    const std::vector<figure::Transform> after = r.bodyTransforms();
    for (std::size_t i = 0; i < before.size(); ++i) CHECK(after[i].position == before[i].position);
    const int body = r.rigidBodyCount() / 2;
    CHECK(r.applyImpulse(loaded.figure.bodies[static_cast<std::size_t>(body)].joint,
                         btVector3(btScalar(r.impulseThresholdNs() * 4), 0, 0),
                         r.body(body).getCenterOfMassPosition()));
    CHECK_FALSE(r.sunk());
    CHECK_FALSE(r.frozen());
    CHECK(scene.world().getNumCollisionObjects() == objectsBefore + r.rigidBodyCount());
    CHECK(scene.world().getNumConstraints() == constraintsBefore + r.bulletConstraintCount());
    for (int s = 0; s < 40; ++s) scene.step(1.0 / 60);
    // A second one, sunk, then destroyed: nothing of it stays in the world.
    const int objectsWithFirst = scene.world().getNumCollisionObjects();
    bullet::SpawnOptions o2 = o;
    o2.entityTransform.getOrigin() += btVector3(5, 0, 0);
    auto second = scene.ragdollWorld().spawn(asset, o2);
    for (int s = 0; s < 40; ++s) scene.step(1.0 / 60);
    REQUIRE(second->sunk());
    CHECK(scene.world().getNumCollisionObjects() == objectsWithFirst + 1);
    second.reset();
    CHECK(scene.world().getNumCollisionObjects() == objectsWithFirst);
    for (int s = 0; s < 10; ++s) scene.step(1.0 / 60);
}
