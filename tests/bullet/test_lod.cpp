// Economy: levels of detail, bodies merged into fewer rigid bodies and back at runtime.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

#include "EntityFixture.h"
#include "afb/bullet/RagdollAsset.h"
#include "afb/detail/Convert.h"
#include "afb/figure/Lod.h"
#include "afb/pose/SkeletonDriver.h"
#include "afb/sim/Scene.h"

using namespace afb;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDt = 1.0 / 60;

int bodyNamed(const figure::Figure& f, const std::string& name) {
    for (std::size_t i = 0; i < f.bodies.size(); ++i)
        if (f.bodies[i].name == name) return static_cast<int>(i);
    FAIL("no body " << name);
    return -1;
}

/// The names of a level's groups, for messages and comparisons.
std::vector<std::vector<std::string>> namesOf(const figure::Figure& f, const figure::LodLevel& level) {
    std::vector<std::vector<std::string>> out;
    for (const std::vector<int>& group : level.groups) {
        out.emplace_back();
        for (const int b : group) out.back().push_back(f.bodies[static_cast<std::size_t>(b)].name);
    }
    return out;
}

/// The largest distance and turn between two skeleton poses' md5 joints (world space), metres and radians.
std::pair<double, double> jointDifference(const figure::Figure& f, const std::vector<figure::Transform>& a,
                                          const std::vector<figure::Transform>& b) {
    const std::vector<figure::Transform> wa = pose::driveSkeleton(f, a).world(), wb = pose::driveSkeleton(f, b).world();
    REQUIRE(wa.size() == wb.size());
    double worstM = 0, worstRad = 0;
    for (std::size_t j = 0; j < wa.size(); ++j) {
        worstM = std::max(worstM, (wa[j].position - wb[j].position).norm());
        worstRad = std::max(worstRad, std::abs(Eigen::AngleAxisd(wa[j].rotation.transpose() * wb[j].rotation).angle()));
    }
    return {worstM, worstRad};
}

/// Total momentum and angular momentum about the figure's centre of mass, from the figure bodies' states.
struct Momentum {
    Eigen::Vector3d linear = Eigen::Vector3d::Zero(), angular = Eigen::Vector3d::Zero();
};
Momentum momentumOf(const figure::Figure& f, const std::vector<figure::BodyState>& states) {
    double mass = 0;
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < states.size(); ++i) {
        mass += f.bodies[i].massKg;
        centre += f.bodies[i].massKg * states[i].pose.position;
    }
    centre /= mass;
    Momentum out;
    for (std::size_t i = 0; i < states.size(); ++i) {
        const figure::FigureBody& b = f.bodies[i];
        const Eigen::Matrix3d& r = states[i].pose.rotation;
        out.linear += b.massKg * states[i].linearVelocity;
        out.angular += r * b.inertiaKgM2.asDiagonal() * r.transpose() * states[i].angularVelocity +
                       b.massKg * (states[i].pose.position - centre).cross(states[i].linearVelocity);
    }
    return out;
}

bullet::SpawnOptions dropWhere() {
    bullet::SpawnOptions where;
    where.entityTransform = btTransform(btQuaternion(btVector3(0, 0, 1), btScalar(0.6)), btVector3(0.2f, -0.1f, 1.0f));
    return where;
}

} // namespace

TEST_CASE("lod: the automatic rule merges the lightest body into its lightest neighbour", "[figure][lod]") {
    const auto loaded = test::loadEntity("humanoid");
    const figure::Figure& f = loaded.figure;
    // Six: feet into shins, upper arms into forearm + hand (the wrists are fixed: always merged), the head into the
    // torso, shins into thighs.
    const figure::LodLevel six = figure::automaticLod(f, 6);
    const std::vector<std::vector<std::string>> expected = {{"pelvis"},
                                                            {"torso", "head"},
                                                            {"l_upperarm", "l_forearm", "l_hand"},
                                                            {"r_upperarm", "r_forearm", "r_hand"},
                                                            {"l_thigh", "l_shin", "l_foot"},
                                                            {"r_thigh", "r_shin", "r_foot"}};
    CHECK(namesOf(f, six) == expected);
    CHECK(figure::automaticLod(f, 100).groups.size() == 13); // the fixed wrists stay merged at every level
    CHECK(figure::automaticLod(f, 0).groups.size() == 1);
    CHECK(figure::automaticLod(f, 1).groups.size() == 1);
    // The same level from the caller's list (wrists named or not).
    const auto listed = figure::lodFromNames(f, {{"torso", "head"},
                                                 {"l_upperarm", "l_forearm"},
                                                 {"r_upperarm", "r_forearm", "r_hand"},
                                                 {"l_thigh", "l_shin", "l_foot"},
                                                 {"r_foot", "r_shin", "r_thigh"}});
    REQUIRE(std::holds_alternative<figure::LodLevel>(listed));
    CHECK(std::get<figure::LodLevel>(listed) == six);
}

TEST_CASE("lod: a bad list is an error and changes nothing", "[bullet][lod]") {
    const auto loaded = test::loadEntity("humanoid");
    const figure::Figure& f = loaded.figure;
    const auto error = [&](const std::vector<std::vector<std::string>>& groups) {
        const auto r = figure::lodFromNames(f, groups);
        return std::holds_alternative<std::string>(r) ? std::get<std::string>(r) : std::string();
    };
    CHECK_THAT(error({{"torso", "tail"}}), Catch::Contains("no body \"tail\""));
    CHECK_THAT(error({{"torso", "head"}, {"head", "pelvis"}}), Catch::Contains("named more than once"));
    CHECK_THAT(error({{"torso", "torso"}}), Catch::Contains("named more than once"));
    CHECK_THAT(error({{"l_hand", "r_hand"}}), Catch::Contains("not connected"));
    CHECK_THAT(error({{"l_thigh", "l_foot"}}), Catch::Contains("not connected")); // the shin between is missing
    CHECK(error({{}, {"pelvis"}}).empty());

    const auto asset = bullet::RagdollAsset::create(f);
    sim::Scene scene(*bullet::methodPreset("default"));
    bullet::Ragdoll& r = scene.spawn(asset, dropWhere());
    for (int s = 0; s < 20; ++s) scene.step(kDt);
    const std::vector<figure::BodyState> before = r.bodyStates();
    const int rigids = r.rigidBodyCount(), constraints = r.bulletConstraintCount();
    figure::LodLevel missing = figure::automaticLod(f, 6);
    missing.groups.pop_back();
    figure::LodLevel twice = figure::automaticLod(f, 6);
    twice.groups.front().push_back(1);
    figure::LodLevel outOfRange = figure::automaticLod(f, 6);
    outOfRange.groups.front().push_back(99);
    for (const figure::LodLevel* bad : {&missing, &twice, &outOfRange}) {
        CHECK_FALSE(r.setLod(*bad).empty());
        CHECK_FALSE(r.lodActive());
        CHECK(r.rigidBodyCount() == rigids);
        CHECK(r.bulletConstraintCount() == constraints);
        const std::vector<figure::BodyState> after = r.bodyStates();
        for (std::size_t i = 0; i < before.size(); ++i) {
            CHECK(after[i].pose.position == before[i].pose.position);
            CHECK(after[i].linearVelocity == before[i].linearVelocity);
        }
    }
    r.setFullDetail(); // at full detail already: nothing happens
    CHECK(r.rigidBodyCount() == rigids);
}

TEST_CASE("lod: switching keeps every md5 joint within 1 cm and 2 degrees of the full figure's pose", "[bullet][lod]") {
    const auto loaded = test::loadEntity("humanoid");
    const figure::Figure& f = loaded.figure;
    const auto asset = bullet::RagdollAsset::create(f);
    sim::Scene scene(*bullet::methodPreset("default"));
    bullet::Ragdoll& r = scene.spawn(asset, dropWhere());
    for (int s = 0; s < 45; ++s) scene.step(kDt); // landed, limbs bent
    const int full = r.rigidBodyCount();

    const std::vector<figure::Transform> before = r.bodyTransforms();
    REQUIRE(r.setLod(figure::automaticLod(f, 6)).empty());
    CHECK(r.lodActive());
    CHECK(r.rigidBodyCount() == 6);
    CHECK(r.bodyCount() == static_cast<int>(f.bodies.size()));
    auto [m, rad] = jointDifference(f, before, r.bodyTransforms());
    INFO("to LOD 6: " << m << " m, " << rad * 180 / kPi << " deg");
    CHECK(m <= 0.01);
    CHECK(rad <= 2 * kPi / 180);
    CHECK(m <= 1e-5); // in fact: rounding only

    for (int s = 0; s < 30; ++s) scene.step(kDt);
    const std::vector<figure::Transform> atLod = r.bodyTransforms();
    r.setFullDetail();
    CHECK_FALSE(r.lodActive());
    CHECK(r.rigidBodyCount() == full);
    std::tie(m, rad) = jointDifference(f, atLod, r.bodyTransforms());
    INFO("back to full: " << m << " m, " << rad * 180 / kPi << " deg");
    CHECK(m <= 0.01);
    CHECK(rad <= 2 * kPi / 180);
    CHECK(m <= 1e-5);
    // And it goes on: a second of simulation at full detail without a guard trip.
    for (int s = 0; s < 60; ++s) scene.step(kDt);
    CHECK(r.guardTrips() == 0);
}

TEST_CASE("lod: a merged group has the exact combined mass, centre and inertia at the pose of the switch",
          "[bullet][lod]") {
    const auto loaded = test::loadEntity("humanoid");
    const figure::Figure& f = loaded.figure;
    const auto asset = bullet::RagdollAsset::create(f);
    sim::Scene scene(*bullet::methodPreset("default"));
    bullet::SpawnOptions where = dropWhere();
    // Kept moving: a method that rests the figure within these 0.75 s would freeze it, and a frozen body is static
    // (inverse mass 0) by design, which is not what this test is about.
    where.comeToRest = false;
    bullet::Ragdoll& r = scene.spawn(asset, where);
    for (int s = 0; s < 45; ++s) scene.step(kDt);
    REQUIRE_FALSE(r.frozen());
    const std::vector<figure::Transform> now = r.bodyTransforms(); // world
    REQUIRE(r.setLod(figure::automaticLod(f, 6)).empty());

    for (const char* name : {"l_thigh", "r_upperarm", "torso"}) {
        INFO(name);
        const int k = r.rigidIndexOf(bodyNamed(f, name));
        const bullet::RigidLayout::Rigid& rigid = r.layout().rigids[static_cast<std::size_t>(k)];
        REQUIRE(rigid.bodies.size() > 1);
        // By hand, in world space: masses add, the centre is the mass-weighted mean, the tensor is each body's
        // R diag(I) Rᵀ plus m (|d|² E − d dᵀ) about that centre.
        double mass = 0;
        Eigen::Vector3d centre = Eigen::Vector3d::Zero();
        for (const int b : rigid.bodies) {
            mass += f.bodies[static_cast<std::size_t>(b)].massKg;
            centre += f.bodies[static_cast<std::size_t>(b)].massKg * now[static_cast<std::size_t>(b)].position;
        }
        centre /= mass;
        Eigen::Matrix3d tensor = Eigen::Matrix3d::Zero();
        for (const int b : rigid.bodies) {
            const figure::FigureBody& body = f.bodies[static_cast<std::size_t>(b)];
            const figure::Transform& t = now[static_cast<std::size_t>(b)];
            const Eigen::Vector3d d = t.position - centre;
            tensor += t.rotation * body.inertiaKgM2.asDiagonal() * t.rotation.transpose();
            tensor += body.massKg * (d.dot(d) * Eigen::Matrix3d::Identity() - d * d.transpose());
        }
        const figure::Transform& frame = rigid.loadPose; // a level's rigid frames are world space, at the switch
        CHECK(std::abs(rigid.massKg - mass) <= 1e-12 * mass);
        CHECK((frame.position - centre).norm() <= 1e-9 * centre.norm());
        const Eigen::Matrix3d got = frame.rotation * rigid.inertiaKgM2.asDiagonal() * frame.rotation.transpose();
        CHECK((got - tensor).cwiseAbs().maxCoeff() <= 1e-9 * tensor.cwiseAbs().maxCoeff());
        // The Bullet body carries them (in its precision) and sits there.
        const btRigidBody& b = r.rigidBody(k);
        CHECK(1 / b.getInvMass() == Approx(mass).epsilon(1e-6));
        CHECK((bullet::toEigen(b.getCenterOfMassPosition()) - centre).norm() < 1e-5);
        // Each body sits in the rigid where it was.
        for (const int i : rigid.bodies) {
            const figure::Transform back = frame * r.layout().bodyInRigid[static_cast<std::size_t>(i)];
            CHECK((back.position - now[static_cast<std::size_t>(i)].position).norm() < 1e-9);
            CHECK((back.rotation - now[static_cast<std::size_t>(i)].rotation).norm() < 1e-9);
        }
    }
}

TEST_CASE("lod: two rigids a joint joins never collide, even when a body of one may touch the other", "[bullet][lod]") {
    // What Bullet's constraint references did when the ragdoll passed them to addConstraint: a joint that disables
    // collision between its bodies keeps their rigids' pair off, whatever else the rigids hold (docs/format.md §6.2).
    const auto loaded = test::loadEntity("humanoid");
    const figure::Figure& f = loaded.figure;
    const auto asset = bullet::RagdollAsset::create(f);
    sim::Scene scene(*bullet::methodPreset("default"));
    bullet::SpawnOptions where = dropWhere();
    where.comeToRest = false;
    bullet::Ragdoll& r = scene.spawn(asset, where);
    scene.step(kDt);
    int jointedButTouching = 0;
    auto check = [&](const char* what) {
        INFO(what);
        const bullet::RigidLayout& layout = r.layout();
        const auto& pairs = r.method().exemptOverlapping ? layout.contactPairsApart : layout.contactPairs;
        for (int a = 0; a < r.rigidBodyCount(); ++a)
            for (int b = a + 1; b < r.rigidBodyCount(); ++b) {
                bool jointed = false;
                for (const figure::FigureConstraint& c : f.constraints)
                    jointed =
                        jointed || (c.disablesCollision && c.body2 >= 0 &&
                                    std::minmax(r.rigidIndexOf(c.body1), r.rigidIndexOf(c.body2)) == std::minmax(a, b));
                const bool listed = std::binary_search(pairs.begin(), pairs.end(), std::make_pair(a, b));
                if (jointed && listed) ++jointedButTouching;
                INFO("rigids " << a << ", " << b);
                CHECK(r.rigidBody(a).checkCollideWith(&r.rigidBody(b)) == (listed && !jointed));
                CHECK(r.rigidBody(b).checkCollideWith(&r.rigidBody(a)) == (listed && !jointed));
            }
    };
    check("merged wrists");
    REQUIRE(r.setLod(figure::automaticLod(f, 6)).empty());
    check("LOD 6");
    CHECK(jointedButTouching > 0); // the case the rule is for occurs (at LOD 6)
}

TEST_CASE("lod: a switch keeps the figure's momentum and angular momentum", "[bullet][lod]") {
    const auto loaded = test::loadEntity("humanoid");
    const figure::Figure& f = loaded.figure;
    const auto asset = bullet::RagdollAsset::create(f);
    sim::Scene scene(*bullet::methodPreset("default"));
    bullet::SpawnOptions where = dropWhere();
    where.entityTransform.setOrigin(btVector3(0, 0, 3));
    bullet::Ragdoll& r = scene.spawn(asset, where);
    scene.step(kDt);
    // Tumbling in the air: a blow to a hand and one to a foot, then a few steps for the joints to move apart.
    const int hand = f.bodies[static_cast<std::size_t>(bodyNamed(f, "r_hand"))].joint;
    const int foot = f.bodies[static_cast<std::size_t>(bodyNamed(f, "l_foot"))].joint;
    REQUIRE(r.applyImpulse(hand, btVector3(30, 10, 5), r.body(bodyNamed(f, "r_hand")).getCenterOfMassPosition()));
    REQUIRE(r.applyImpulse(foot, btVector3(-5, 20, 0), r.body(bodyNamed(f, "l_foot")).getCenterOfMassPosition()));
    for (int s = 0; s < 6; ++s) scene.step(kDt);

    const auto check = [&](const Momentum& a, const Momentum& b) {
        INFO("linear " << a.linear.transpose() << " -> " << b.linear.transpose());
        INFO("angular " << a.angular.transpose() << " -> " << b.angular.transpose());
        CHECK((a.linear - b.linear).norm() <= 1e-6 * a.linear.norm());
        CHECK((a.angular - b.angular).norm() <= 1e-6 * a.angular.norm());
    };
    const Momentum full = momentumOf(f, r.bodyStates());
    REQUIRE(full.angular.norm() > 1);
    REQUIRE(r.setLod(figure::automaticLod(f, 6)).empty());
    const Momentum lod = momentumOf(f, r.bodyStates());
    check(full, lod);
    for (int s = 0; s < 6; ++s) scene.step(kDt);
    const Momentum beforeBack = momentumOf(f, r.bodyStates());
    r.setFullDetail();
    check(beforeBack, momentumOf(f, r.bodyStates()));
    // One level to another: the same.
    const Momentum atFull = momentumOf(f, r.bodyStates());
    REQUIRE(r.setLod(figure::automaticLod(f, 3)).empty());
    CHECK(r.rigidBodyCount() == 3);
    check(atFull, momentumOf(f, r.bodyStates()));
    const Momentum at3 = momentumOf(f, r.bodyStates());
    REQUIRE(r.setLod(figure::automaticLod(f, 8)).empty());
    check(at3, momentumOf(f, r.bodyStates()));
}

TEST_CASE("lod: a LOD-6 humanoid dropped 1 m comes to rest without exploding, and switches while frozen",
          "[bullet][lod]") {
    const auto loaded = test::loadEntity("humanoid");
    const figure::Figure& f = loaded.figure;
    const auto asset = bullet::RagdollAsset::create(f);
    sim::Scene scene(*bullet::methodPreset("default"));
    bullet::Ragdoll& r = scene.spawn(asset, dropWhere());
    REQUIRE(r.setLod(figure::automaticLod(f, 6)).empty());
    double worstAnchor = 0, worstDepth = 0, fastest = 0;
    int restedAt = -1;
    for (int s = 0; s < 600 && restedAt < 0; ++s) {
        scene.step(kDt);
        for (int c = 0; c < static_cast<int>(f.constraints.size()); ++c)
            worstAnchor = std::max(worstAnchor, r.jointError(c).anchorM);
        for (const figure::BodyState& b : r.bodyStates()) {
            REQUIRE(b.linearVelocity.allFinite());
            fastest = std::max(fastest, b.linearVelocity.norm());
        }
        worstDepth = std::max(worstDepth, scene.deepestContact().depthM);
        if (r.atRest()) restedAt = s;
    }
    INFO("rested at step " << restedAt << ", worst anchor " << worstAnchor << " m, deepest " << worstDepth
                           << " m, fastest " << fastest << " m/s");
    CHECK(restedAt > 0);
    CHECK(r.guardTrips() == 0);
    CHECK(worstAnchor < 0.1);
    CHECK(worstDepth < 0.06);
    CHECK(fastest < 10);
    CHECK(r.frozen());

    // At rest, a switch keeps it at rest and frozen, where it lies.
    const std::vector<figure::Transform> lying = r.bodyTransforms();
    r.setFullDetail();
    CHECK(r.atRest());
    CHECK(r.frozen());
    CHECK(jointDifference(f, lying, r.bodyTransforms()).first < 1e-5);
    for (int s = 0; s < 10; ++s) scene.step(kDt);
    CHECK(r.atRest());
    CHECK(jointDifference(f, lying, r.bodyTransforms()).first < 1e-5);
    REQUIRE(r.setLod(figure::automaticLod(f, 6)).empty());
    CHECK(r.frozen());
    // Sunk (sim::Scene sinks resting ragdolls): a switch brings the bodies back, frozen, and it sinks again later.
    for (int s = 0; s < 40; ++s) scene.step(kDt);
    REQUIRE(r.sunk());
    r.setFullDetail();
    CHECK_FALSE(r.sunk());
    CHECK(r.frozen());
    CHECK(jointDifference(f, lying, r.bodyTransforms()).first < 1e-5);
    for (int s = 0; s < 40; ++s) scene.step(kDt);
    CHECK(r.sunk());
    REQUIRE(r.setLod(figure::automaticLod(f, 6)).empty());
    CHECK_FALSE(r.sunk());
    r.wake(); // woken at a level of detail: its masses and constraints come back
    CHECK_FALSE(r.frozen());
    CHECK(r.rigidBody(0).getInvMass() > 0);
    for (int s = 0; s < 60; ++s) scene.step(kDt);
    CHECK(r.guardTrips() == 0);
    // The explosion guard's saved state is the new level's: freezing puts it back to the last good substep.
    const std::vector<figure::Transform> good = r.bodyTransforms();
    r.freeze();
    CHECK(r.frozen());
    CHECK(jointDifference(f, good, r.bodyTransforms()).first < 1e-5);
}

TEST_CASE("lod: the multibody backend refuses a level of detail", "[bullet][lod]") {
    const auto loaded = test::loadEntity("humanoid");
    const auto asset = bullet::RagdollAsset::create(loaded.figure);
    sim::Scene scene(*bullet::methodPreset("multibody"));
    bullet::Ragdoll& r = scene.spawn(asset, dropWhere());
    CHECK_THAT(r.setLod(figure::automaticLod(loaded.figure, 6)), Catch::Contains("rigid backend only"));
    CHECK_FALSE(r.lodActive());
}

TEST_CASE("hits: a ray names the ragdoll and the figure body it hit, merged bodies included", "[bullet][lod]") {
    // Rays from outside the figure aimed at the centre of an extremity (head, hands, feet) hit that body first;
    // the hands are merged with their forearms (fixed wrists), and at LOD 6 more bodies share a rigid.
    const auto loaded = test::loadEntity("humanoid");
    const figure::Figure& f = loaded.figure;
    const auto asset = bullet::RagdollAsset::create(f);
    sim::SceneSettings noGround;
    noGround.ground = false; // rays come from below the feet
    sim::Scene scene(*bullet::methodPreset("default"), noGround);
    bullet::Ragdoll& r = scene.spawn(asset, dropWhere());
    btCollisionObject stranger; // not a ragdoll's
    btBoxShape box(btVector3(1, 1, 1));
    stranger.setCollisionShape(&box);
    const int lHand = bodyNamed(f, "l_hand");
    REQUIRE(r.rigidIndexOf(lHand) == r.rigidIndexOf(bodyNamed(f, "l_forearm")));
    const std::vector<figure::Transform> poses = r.bodyTransforms();
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (const figure::Transform& t : poses) centre += t.position / static_cast<double>(poses.size());
    auto check = [&](const char* what) {
        INFO(what);
        for (const char* name : {"head", "l_hand", "r_hand", "l_foot", "r_foot"}) {
            INFO(name);
            const int body = bodyNamed(f, name);
            const Eigen::Vector3d target = poses[static_cast<std::size_t>(body)].position;
            const btVector3 to = bullet::toBt(target),
                            from = bullet::toBt(Eigen::Vector3d(target + 3.0 * (target - centre).normalized()));
            btCollisionWorld::ClosestRayResultCallback ray(from, to);
            scene.world().rayTest(from, to, ray);
            REQUIRE(ray.hasHit());
            CHECK(scene.ragdollWorld().ragdollOf(ray.m_collisionObject) == &r);
            CHECK(r.figureBodyOf(*ray.m_collisionObject, ray.m_hitPointWorld) == body);
        }
        CHECK(scene.ragdollWorld().ragdollOf(&stranger) == nullptr);
        CHECK(r.figureBodyOf(stranger, btVector3(0, 0, 0)) == -1);
    };
    check("merged wrists");
    REQUIRE(r.setLod(figure::automaticLod(f, 6)).empty());
    check("LOD 6");
}

TEST_CASE("hits: an impulse on a figure body moves that body by impulse over mass", "[bullet]") {
    const auto loaded = test::loadEntity("humanoid");
    const figure::Figure& f = loaded.figure;
    const auto asset = bullet::RagdollAsset::create(f);
    sim::Scene scene(*bullet::methodPreset("default"));
    bullet::Ragdoll& r = scene.spawn(asset, dropWhere());
    const int head = bodyNamed(f, "head");
    REQUIRE(r.layout().rigids[static_cast<std::size_t>(r.rigidIndexOf(head))].bodies.size() == 1);
    const btVector3 impulse(0, 40, 0); // N·s, above the wake threshold
    CHECK_FALSE(r.applyBodyImpulse(r.bodyCount(), impulse, btVector3(0, 0, 0)));
    CHECK_FALSE(r.applyBodyImpulse(head, impulse * btScalar(1e-3), r.body(head).getCenterOfMassPosition()));
    const btVector3 before = r.body(head).getLinearVelocity();
    REQUIRE(r.applyBodyImpulse(head, impulse, r.body(head).getCenterOfMassPosition()));
    const btVector3 change = r.body(head).getLinearVelocity() - before;
    CHECK(double(change.y()) == Approx(40.0 / f.bodies[static_cast<std::size_t>(head)].massKg).epsilon(1e-5));
    CHECK(double(r.body(head).getAngularVelocity().length()) == Approx(0).margin(1e-6));
}
