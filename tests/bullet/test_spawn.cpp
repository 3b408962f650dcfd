// Spawning figures into Bullet (float build): RagdollAsset shapes and margins, Ragdoll placement, a figure at rest
// staying at rest without gravity, shared shapes and clean removal (docs/format.md §2.5, §3.1, §4.1, §4.5, §6.2).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "EntityFixture.h"
#include "FigureFixture.h"
#include "TestSupport.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/bullet/RagdollAsset.h"
#include "afb/decl/Library.h"
#include "afb/detail/Convert.h"
#include "afb/figure/Collision.h"
#include "afb/figure/Load.h"
#include "afb/figure/Lod.h"
#include "afb/sim/Scene.h"

using namespace afb;
using bullet::Ragdoll;
using bullet::RagdollAsset;
using bullet::SpawnOptions;
using Eigen::Matrix3d;
using Eigen::Vector3d;
using figure::Figure;

namespace {

// A zero-gravity world without ground, from the one scene the tools use.
struct World {
    sim::Scene scene{bullet::Method{}, {.gravityMps2 = 0, .ground = false}};
    btDiscreteDynamicsWorld& world = scene.world();
};

struct NamedFigure {
    std::string name;
    Figure figure;
};

// The bundled `chain` entity, loaded once.
const Figure& chainFigure() {
    static const Figure figure = [] {
        text::Diagnostics d;
        const auto library = decl::Library::open(test::sourceDir(), d);
        INFO(d.str());
        REQUIRE(library);
        auto loaded = figure::loadEntityFigure(*library, "chain", {}, d);
        INFO(d.str());
        REQUIRE(loaded);
        return loaded->figure;
    }();
    return figure;
}

// The three complete corpus sets (the other corpus .af files have no meshes), loaded once.
const std::vector<NamedFigure>& zsecFigures(const std::filesystem::path& corpus) {
    static const std::vector<NamedFigure> figures = [&] {
        text::Diagnostics d;
        const auto library = decl::Library::open(corpus / "doom3-kroom3" / "base", d);
        REQUIRE(library);
        std::vector<NamedFigure> out;
        for (const char* entity : {"monster_zsec_machinegun", "monster_zsec_pistol", "monster_zsec_shotgun"}) {
            text::Diagnostics fd;
            auto loaded = figure::loadEntityFigure(*library, entity, {}, fd);
            INFO(entity << "\n" << fd.str());
            REQUIRE(loaded);
            out.push_back({entity, loaded->figure});
        }
        return out;
    }();
    return figures;
}

// A rotated and translated entity transform.
btTransform spawnTransform() {
    const btQuaternion q(btVector3(1, 2, 3).normalized(), btScalar(0.7));
    return btTransform(q, btVector3(btScalar(1.5), btScalar(-2.0), btScalar(0.75)));
}

figure::Transform toFigure(const btTransform& t) { return bullet::toEigen(t); }

double rotationAngle(const Matrix3d& a, const Matrix3d& b) {
    return Eigen::AngleAxisd(Eigen::Quaterniond(a * b.transpose()).normalized()).angle();
}

struct Drift {
    double moveM = 0;
    double turnRad = 0;
};

// A ragdoll of `figure` at rest in a zero-gravity world, spawned rotated and translated.
struct Scene {
    World w;
    std::shared_ptr<const RagdollAsset> asset;
    std::unique_ptr<Ragdoll> ragdoll;
    std::vector<figure::Transform> start;

    explicit Scene(const Figure& figure) : asset(RagdollAsset::create(figure)) {
        SpawnOptions options;
        options.entityTransform = spawnTransform();
        ragdoll = std::make_unique<Ragdoll>(asset, w.world, options);
        for (int i = 0; i < ragdoll->bodyCount(); ++i) start.push_back(toFigure(ragdoll->body(i).getWorldTransform()));
    }
    // 60 fixed steps of 1/60 s, no substeps.
    void run() {
        const btScalar dt = btScalar(1.0 / 60.0);
        for (int step = 0; step < 60; ++step) w.world.stepSimulation(dt, 1, dt);
    }
    Drift worstDrift() const {
        Drift worst;
        for (int i = 0; i < ragdoll->bodyCount(); ++i) {
            const figure::Transform now = toFigure(ragdoll->body(i).getWorldTransform());
            const auto k = static_cast<std::size_t>(i);
            worst.moveM = std::max(worst.moveM, (now.position - start[k].position).norm());
            worst.turnRad = std::max(worst.turnRad, rotationAngle(now.rotation, start[k].rotation));
        }
        return worst;
    }
};

// Hinges whose range excludes the load pose (φ = 0): the engine's cone limit pushes such a hinge into its range
// at once (docs/format.md §4.3, §4.5), so the figure cannot stay at rest. Returns their names.
std::vector<std::string> hingesStartingOutside(const Figure& figure) {
    std::vector<std::string> names;
    for (const figure::FigureConstraint& c : figure.constraints)
        if (const auto* r = std::get_if<figure::HingeRange>(&c.limit); r && (r->lowerRad > 0 || r->upperRad < 0))
            names.push_back(c.name);
    return names;
}

// Spawns `figure` without gravity and steps one second: nothing may move. Hinge limits that exclude the load
// pose are dropped for this (they move the figure by design); what they do is checked separately.
void checkZeroGravityDrift(const std::string& name, const Figure& figure) {
    Figure atRest = figure;
    const std::vector<std::string> outside = hingesStartingOutside(figure);
    for (figure::FigureConstraint& c : atRest.constraints)
        if (std::find(outside.begin(), outside.end(), c.name) != outside.end()) c.limit = std::monostate{};
    Scene scene(atRest);
    scene.run();
    const Drift d = scene.worstDrift();
    if (std::getenv("AFB_TEST_VERBOSE")) {
        std::printf("zero-gravity drift %s: %.3g m, %.3g rad; hinge limits excluding the load pose:", name.c_str(),
                    d.moveM, d.turnRad);
        for (const std::string& n : outside) std::printf(" %s", n.c_str());
        std::printf("\n");
    }
    INFO(name << ": worst move " << d.moveM << " m, worst turn " << d.turnRad << " rad");
    CHECK(d.moveM <= 1e-4);
    CHECK(d.turnRad <= 1e-3);
}

// With every limit kept, hinges that start outside their range end up inside it (within 1°), and nothing else
// drifts further than the hinges drag it.
void checkHingesPushedIn(const std::string& name, const Figure& figure) {
    Scene scene(figure);
    scene.run();
    const Drift d = scene.worstDrift();
    if (std::getenv("AFB_TEST_VERBOSE"))
        std::printf("zero-gravity drift %s with all limits: %.3g m, %.3g rad\n", name.c_str(), d.moveM, d.turnRad);
    for (int i = 0; i < static_cast<int>(figure.constraints.size()); ++i) {
        const figure::FigureConstraint& c = figure.constraints[static_cast<std::size_t>(i)];
        const auto* r = std::get_if<figure::HingeRange>(&c.limit);
        if (!r) continue;
        auto* hinge = dynamic_cast<btHingeConstraint*>(scene.ragdoll->constraint(i));
        REQUIRE(hinge);
        const double angle = static_cast<double>(hinge->getHingeAngle());
        INFO(name << " hinge " << c.name << ": angle " << angle << " rad, range [" << r->lowerRad << ", " << r->upperRad
                  << "]");
        const double slack = std::numbers::pi / 180;
        CHECK(angle >= r->lowerRad - slack);
        CHECK(angle <= r->upperRad + slack);
    }
}

// Right after construction each body sits at spawn × loadPose.
void checkSpawnPose(const std::string& name, const Figure& figure) {
    World w;
    const auto asset = RagdollAsset::create(figure);
    SpawnOptions options;
    options.entityTransform = spawnTransform();
    Ragdoll ragdoll(asset, w.world, options);
    REQUIRE(ragdoll.bodyCount() == static_cast<int>(figure.bodies.size()));
    const figure::Transform spawn = toFigure(options.entityTransform);
    for (int i = 0; i < ragdoll.bodyCount(); ++i) {
        const figure::FigureBody& body = figure.bodies[static_cast<std::size_t>(i)];
        INFO(name << " body " << body.name);
        const figure::Transform expected = spawn * body.loadPose;
        const figure::Transform got = toFigure(ragdoll.body(i).getWorldTransform());
        CHECK((got.position - expected.position).norm() <= 1e-5);
        CHECK(rotationAngle(got.rotation, expected.rotation) <= 1e-5);
        CHECK(ragdoll.body(i).getCollisionShape() == asset->shape(i));
    }
    // §4.1: every constraint is exactly satisfied at spawn, so its two frames coincide in the world.
    for (int i = 0; i < static_cast<int>(figure.constraints.size()); ++i) {
        const figure::FigureConstraint& c = figure.constraints[static_cast<std::size_t>(i)];
        if (c.type == figure::JointType::Spring) continue;
        INFO(name << " constraint " << c.name);
        const auto [a, b] = ragdoll.constraintFramesWorld(i);
        CHECK((bullet::toEigen(a.getOrigin()) - bullet::toEigen(b.getOrigin())).norm() <= 1e-5);
        CHECK(rotationAngle(bullet::toEigen(a.getBasis()), bullet::toEigen(b.getBasis())) <= 1e-5);
    }
}

// Outward unit normal and offset of each face of a body's polytope (n·p ≤ offset inside), metres.
struct Plane {
    Vector3d normal;
    double offset;
};
std::vector<Plane> facePlanes(const figure::BodyShape& shape) {
    std::vector<Plane> planes;
    for (const std::vector<int>& face : shape.faces) {
        Vector3d n = Vector3d::Zero();
        for (std::size_t k = 0; k < face.size(); ++k)
            n += shape.vertices[static_cast<std::size_t>(face[k])].cross(
                shape.vertices[static_cast<std::size_t>(face[(k + 1) % face.size()])]);
        if (n.norm() == 0.0) continue;
        n.normalize();
        planes.push_back({n, n.dot(shape.vertices[static_cast<std::size_t>(face[0])])});
    }
    return planes;
}

// The margin policy (RagdollAsset.h): the shape with its margin never leaves the polytope, and reaches every face.
void checkMargins(const std::string& name, const Figure& figure) {
    const auto asset = RagdollAsset::create(figure);
    std::mt19937 rng(20240611);
    std::normal_distribution<double> normal;
    const double tolerance = 2e-5; // float shapes
    for (int i = 0; i < static_cast<int>(figure.bodies.size()); ++i) {
        const figure::FigureBody& body = figure.bodies[static_cast<std::size_t>(i)];
        INFO(name << " body " << body.name);
        const auto* shape = dynamic_cast<const btConvexShape*>(asset->shape(i));
        REQUIRE(shape);
        const double margin = asset->margin(i);
        CHECK(margin > 0);
        CHECK(margin <= bullet::kMaxMarginM);
        CHECK(static_cast<double>(shape->getMargin()) == Approx(margin).epsilon(1e-6));
        const std::vector<Plane> planes = facePlanes(body.shape);
        REQUIRE(planes.size() == body.shape.faces.size());
        // min(kMaxMarginM, 0.2 × the distance from the centre of mass to the nearest face).
        double inradius = 1e9;
        for (const Plane& plane : planes) inradius = std::min(inradius, plane.offset);
        CHECK(margin == Approx(std::min(bullet::kMaxMarginM, 0.2 * inradius)).epsilon(1e-5));
        double worstOutside = -1e9;
        for (int k = 0; k < 500; ++k) {
            Vector3d dir(normal(rng), normal(rng), normal(rng));
            dir.normalize();
            const Vector3d p = bullet::toEigen(shape->localGetSupportingVertex(bullet::toBt(dir)));
            for (const Plane& plane : planes) worstOutside = std::max(worstOutside, plane.normal.dot(p) - plane.offset);
        }
        INFO("worst distance outside a face " << worstOutside << " m");
        CHECK(worstOutside <= tolerance);
        for (const Plane& plane : planes) {
            const Vector3d p = bullet::toEigen(shape->localGetSupportingVertex(bullet::toBt(plane.normal)));
            INFO("face normal " << plane.normal.transpose() << ", gap " << plane.offset - plane.normal.dot(p));
            CHECK(plane.normal.dot(p) >= plane.offset - 2 * margin - tolerance);
        }
    }
}

// Two boxes joined by a hinge about model +Y through (0, 0, 50), limited by `limit a0, a1, a2`.
Figure hingeFigure(const std::string& limit) {
    const std::vector<test::TestJoint> joints = {{"origin", -1, 0, 0, 0},
                                                 {"Hips", 0, 0, 0, 40},
                                                 {"Spine", 1, 0, 0, 60}};
    const test::BuiltFigure b = test::buildTestFigure(R"(articulatedFigure t {
	body "pelvis" { joint "origin" model box( ( -4, -4, -8 ), ( 4, 4, 8 ) ) origin ( 0, 0, 40 ) angles ( 0, 0, 20 ) }
	body "chest" { joint "Spine" model box( ( -4, -4, -8 ), ( 4, 4, 8 ) ) origin ( 0, 0, 60 ) angles ( 10, 0, 0 ) }
	hinge "h" { body1 "chest" body2 "pelvis" anchor ( 0, 0, 50 ) axis ( 0, 1, 0 ) )" +
                                                          limit + R"( }
}
)",
                                                      joints);
    INFO(b.diagnostics.str());
    REQUIRE(b.figure);
    return *b.figure;
}

} // namespace

TEST_CASE("bullet: the bundled chain stays at rest without gravity", "[bullet]") {
    CHECK(hingesStartingOutside(chainFigure()).empty());
    checkZeroGravityDrift("chain", chainFigure());
}

TEST_CASE("bullet: the corpus zsec figures stay at rest without gravity", "[bullet]") {
    AFB_REQUIRE_CORPUS(corpus);
    for (const NamedFigure& f : zsecFigures(corpus)) {
        checkZeroGravityDrift(f.name, f.figure);
        checkHingesPushedIn(f.name, f.figure);
    }
}

TEST_CASE("bullet: bodies spawn at spawn × loadPose and constraint frames coincide (§2.5, §4.1)", "[bullet]") {
    checkSpawnPose("chain", chainFigure());
    checkSpawnPose("hinge", hingeFigure(""));
    const auto corpus = test::corpusDir();
    if (!corpus) return;
    for (const NamedFigure& f : zsecFigures(*corpus)) checkSpawnPose(f.name, f.figure);
}

TEST_CASE("bullet: margins keep every shape inside its polytope and touching every face", "[bullet]") {
    checkMargins("chain", chainFigure());
    checkMargins("hinge", hingeFigure(""));
    const auto corpus = test::corpusDir();
    if (!corpus) return;
    for (const NamedFigure& f : zsecFigures(*corpus)) checkMargins(f.name, f.figure);
}

TEST_CASE("bullet: ragdolls of one asset share shapes / destroying one removes its objects", "[bullet]") {
    World w;
    const auto asset = RagdollAsset::create(chainFigure());
    const int bodies = static_cast<int>(asset->figure().bodies.size());
    auto first = std::make_unique<Ragdoll>(asset, w.world);
    const int objectsOne = w.world.getNumCollisionObjects();
    const int constraintsOne = w.world.getNumConstraints();
    CHECK(objectsOne == bodies);
    CHECK(constraintsOne == first->bulletConstraintCount());
    {
        SpawnOptions options;
        options.entityTransform = spawnTransform();
        Ragdoll second(asset, w.world, options);
        CHECK(w.world.getNumCollisionObjects() == 2 * bodies);
        CHECK(w.world.getNumConstraints() == constraintsOne + second.bulletConstraintCount());
        for (int i = 0; i < bodies; ++i) {
            INFO("body " << i);
            CHECK(first->body(i).getCollisionShape() == second.body(i).getCollisionShape());
            CHECK(second.body(i).getCollisionShape() == asset->shape(i));
            CHECK(&first->body(i) != &second.body(i));
        }
        w.world.stepSimulation(btScalar(1.0 / 60), 1, btScalar(1.0 / 60));
    }
    CHECK(w.world.getNumCollisionObjects() == objectsOne);
    CHECK(w.world.getNumConstraints() == constraintsOne);
    first.reset();
    CHECK(w.world.getNumCollisionObjects() == 0);
    CHECK(w.world.getNumConstraints() == 0);
    w.world.stepSimulation(btScalar(1.0 / 60), 1, btScalar(1.0 / 60)); // nothing dangling
}

TEST_CASE("bullet: RagdollWorld::spawn adds a ragdoll the caller owns, and destroying it removes it", "[bullet]") {
    World w;
    const auto asset = RagdollAsset::create(chainFigure());
    const int objects = w.world.getNumCollisionObjects();
    const int constraints = w.world.getNumConstraints();
    std::unique_ptr<Ragdoll> ragdoll = w.scene.ragdollWorld().spawn(asset, {.startAtRest = true});
    REQUIRE(ragdoll);
    CHECK(w.scene.ragdollWorld().ragdollOf(&ragdoll->collisionObject(0)) == ragdoll.get());
    CHECK(ragdoll->frozen()); // a spawn at rest is frozen: the RagdollWorld's rest, which a plain world lacks
    CHECK(w.world.getNumCollisionObjects() == objects + ragdoll->rigidBodyCount());
    ragdoll.reset();
    CHECK(w.world.getNumCollisionObjects() == objects);
    CHECK(w.world.getNumConstraints() == constraints);
    w.scene.step(1.0 / 60); // the world steps on without it
}

TEST_CASE("bullet: the world knows every ragdoll body's ragdoll through spawns, removals and LOD switches",
          "[bullet]") {
    // RagdollWorld's owner table (hashed by address): it grows past its first size, renumbers the ragdolls after a
    // removed one, and takes a ragdoll's new bodies after a level-of-detail switch.
    World w;
    const auto asset = RagdollAsset::create(test::loadEntity("humanoid").figure);
    std::vector<std::unique_ptr<Ragdoll>> live;
    auto spawn = [&](int k) {
        SpawnOptions o;
        o.entityTransform.setOrigin(btVector3(btScalar(3 * k), 0, 0));
        live.push_back(w.scene.ragdollWorld().spawn(asset, o));
    };
    auto check = [&] {
        for (std::size_t i = 0; i < live.size(); ++i)
            for (int k = 0; k < live[i]->rigidBodyCount(); ++k) {
                INFO("ragdoll " << i << ", rigid body " << k);
                CHECK(w.scene.ragdollWorld().ragdollOf(&live[i]->rigidBody(k)) == live[i].get());
            }
        btCollisionObject stranger;
        CHECK(w.scene.ragdollWorld().ragdollOf(&stranger) == nullptr);
        CHECK(w.scene.ragdollWorld().ragdollOf(nullptr) == nullptr);
    };
    for (int k = 0; k < 12; ++k) spawn(k); // over a hundred rigid bodies: the table grows several times
    check();
    for (std::size_t i = live.size(); i-- > 0;) // every third from the back: later ragdolls move down
        if (i % 3 == 0) live.erase(live.begin() + static_cast<std::ptrdiff_t>(i));
    check();
    REQUIRE(live.size() > 2);
    CHECK(live[1]->setLod(figure::automaticLod(asset->figure(), 6)).empty());
    CHECK(live[1]->rigidBodyCount() == 6);
    check();
    for (int k = 12; k < 20; ++k) spawn(k);
    live[1]->setFullDetail();
    check();
    w.scene.step(1.0 / 60);
    live.clear();
    check();
}

TEST_CASE("bullet: collision filtering follows selfCollisionPairs and world attachment (§6.2)", "[bullet]") {
    auto check = [](const std::string& name, const Figure& figure) {
        World w;
        const auto asset = RagdollAsset::create(figure);
        Ragdoll ragdoll(asset, w.world);
        // §6.2's pairs, less those the joints keep apart (RagdollAsset::prunedPairs, tests/bullet/test_economy.cpp).
        const auto pairs = asset->contactPairs();
        const auto all = figure::selfCollisionPairs(figure);
        for (const auto& p : asset->prunedPairs()) CHECK(std::binary_search(all.begin(), all.end(), p));
        for (int i = 0; i < ragdoll.bodyCount(); ++i) {
            const btBroadphaseProxy* proxy = ragdoll.body(i).getBroadphaseHandle();
            REQUIRE(proxy);
            INFO(name << " body " << i);
            CHECK(((proxy->m_collisionFilterMask & btBroadphaseProxy::StaticFilter) == 0) ==
                  figure::attachedToWorld(figure, i));
            for (int j = i + 1; j < ragdoll.bodyCount(); ++j) {
                INFO("pair " << i << ", " << j);
                const bool collide = std::binary_search(pairs.begin(), pairs.end(), std::make_pair(i, j));
                CHECK(ragdoll.body(i).checkCollideWithOverride(&ragdoll.body(j)) == collide);
                CHECK(ragdoll.body(j).checkCollideWithOverride(&ragdoll.body(i)) == collide);
            }
        }
    };
    check("chain", chainFigure());
    CHECK(figure::attachedToWorld(chainFigure(), 0)); // link1 hangs from the world ("hook")
    const auto corpus = test::corpusDir();
    if (!corpus) return;
    for (const NamedFigure& f : zsecFigures(*corpus)) check(f.name, f.figure);
}

TEST_CASE("bullet: the hinge angle is φ, body1 relative to body2 about the axis, with the figure's limits (§4.5)",
          "[bullet]") {
    const Figure figure = hingeFigure("limit 30, 90, 0");
    const auto* range = std::get_if<figure::HingeRange>(&figure.constraints[0].limit);
    REQUIRE(range);
    World w;
    const auto asset = RagdollAsset::create(figure);
    SpawnOptions options;
    options.entityTransform = spawnTransform();
    options.method = *bullet::methodPreset("legacy"); // Bullet's own hinge limit (no speculative limit row)
    Ragdoll ragdoll(asset, w.world, options);
    auto* hinge = dynamic_cast<btHingeConstraint*>(ragdoll.constraint(0));
    REQUIRE(hinge);
    CHECK(static_cast<double>(hinge->getLowerLimit()) == Approx(-75 * std::numbers::pi / 180).margin(1e-5));
    CHECK(static_cast<double>(hinge->getUpperLimit()) == Approx(15 * std::numbers::pi / 180).margin(1e-5));
    CHECK(static_cast<double>(hinge->getHingeAngle()) == Approx(0).margin(1e-5));
    // Turn body1 (chest) right-handedly about the hinge axis (model +Y, through the anchor) by +10°.
    const btTransform spawn = options.entityTransform;
    const btVector3 axisWorld = spawn.getBasis() * btVector3(0, 1, 0);
    const btVector3 anchorWorld = spawn * btVector3(0, 0, btScalar(50 * 0.0254));
    const btQuaternion turn(axisWorld, btScalar(10 * std::numbers::pi / 180));
    btTransform t = ragdoll.body(1).getWorldTransform();
    t.setOrigin(anchorWorld + quatRotate(turn, t.getOrigin() - anchorWorld));
    t.setRotation(turn * t.getRotation());
    ragdoll.body(1).setWorldTransform(t);
    CHECK(static_cast<double>(hinge->getHingeAngle()) == Approx(10 * std::numbers::pi / 180).margin(1e-4));
}
