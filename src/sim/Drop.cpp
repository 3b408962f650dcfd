// Drop runs (src/sim): the scene, the per-step measurements and their aggregation over worlds and threads.
#include "afb/sim/Drop.h"

#include <LinearMath/btScalar.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <random>
#include <thread>

#include "afb/bullet/Convert.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/pose/SkeletonDriver.h"

namespace afb::sim {
namespace {

using bullet::Ragdoll;
using bullet::RagdollAsset;
constexpr double kPi = 3.14159265358979323846;
constexpr double kExplodeSpeedMps = 100.0;
constexpr double kExplodeAnchorM = 0.1;

double wrap(double a) { return std::remainder(a, 2 * kPi); }

// How far constraint `i` of `r` is violated now: anchor separation (m) and limit excess (rad).
std::pair<double, double> constraintError(const Ragdoll& r, int i) {
    const figure::FigureConstraint& c = r.figure().constraints[static_cast<std::size_t>(i)];
    if (c.type == decl::ConstraintType::Spring) return {0, 0};
    const auto [a, b] = r.constraintFramesWorld(i);
    double anchor = (a.getOrigin() - b.getOrigin()).length();
    if (c.type == decl::ConstraintType::Slider) { // free along the axis: only the perpendicular part counts
        const btVector3 axis = b.getBasis().getColumn(0);
        const btVector3 d = a.getOrigin() - b.getOrigin();
        anchor = (d - axis * d.dot(axis)).length();
    }
    double excess = 0;
    const btMatrix3x3 body1 = r.body(c.body1).getCenterOfMassTransform().getBasis();
    const btMatrix3x3 body2 = c.body2 >= 0 ? r.body(c.body2).getCenterOfMassTransform().getBasis()
                                           : r.spawnTransform().getBasis();
    if (const auto* h = std::get_if<figure::HingeRange>(&c.limit)) {
        const btMatrix3x3 rel = b.getBasis().transpose() * a.getBasis();
        const double phi = std::atan2(rel[1][0], rel[0][0]);
        const double centre = 0.5 * (h->lowerRad + h->upperRad), half = 0.5 * (h->upperRad - h->lowerRad);
        excess = std::max(0.0, std::abs(wrap(phi - centre)) - half);
    } else if (const auto* cone = std::get_if<figure::ConeLimit>(&c.limit)) {
        const btVector3 s = body1 * bullet::toBt(cone->shaftInBody1), x = body2 * bullet::toBt(cone->axisInBody2);
        excess = std::max(0.0, std::acos(std::clamp(static_cast<double>(s.dot(x)), -1.0, 1.0)) - cone->halfAngleRad);
    } else if (const auto* p = std::get_if<figure::PyramidLimit>(&c.limit)) {
        const btVector3 s = body1 * bullet::toBt(p->shaftInBody1);
        const btMatrix3x3 basis = body2 * bullet::toBt(p->basisInBody2);
        const double sf = s.dot(basis.getColumn(0)), sl = s.dot(basis.getColumn(1)), su = s.dot(basis.getColumn(2));
        excess = std::max({0.0, std::abs(std::atan2(sl, sf)) - p->halfAngle1Rad, std::abs(std::atan2(su, sf)) - p->halfAngle2Rad});
    }
    return {anchor, excess};
}

// Model-space bounds of a figure's bodies at the load pose, for spacing and spawn height.
void figureBounds(const figure::Figure& f, const btMatrix3x3& rotation, btVector3& lo, btVector3& hi) {
    lo = btVector3(BT_LARGE_FLOAT, BT_LARGE_FLOAT, BT_LARGE_FLOAT);
    hi = -lo;
    for (const figure::FigureBody& b : f.bodies)
        for (const Eigen::Vector3d& v : b.shape.vertices) {
            const btVector3 p = rotation * bullet::toBt(b.loadPose.apply(v));
            lo.setMin(p);
            hi.setMax(p);
        }
}

struct Partial {
    DropResult r;
    double stepSeconds = 0;
    std::vector<double> restTimes; // per instance, −1 if never
    bool haveFirst = false;
    std::vector<figure::Transform> firstBodies;
};

Partial runWorld(const figure::Figure& f, const std::shared_ptr<const RagdollAsset>& asset, const DropOptions& o,
                 const std::vector<btTransform>& spawns, bool holdsFirst, int steps) {
    Partial out;
    btDefaultCollisionConfiguration config;
    btCollisionDispatcher dispatcher(&config);
    btDbvtBroadphase broadphase;
    btSequentialImpulseConstraintSolver solver;
    btDiscreteDynamicsWorld world(&dispatcher, &broadphase, &solver, &config);
    const double g = f.units.gravityMps2;
    world.setGravity(btVector3(0, 0, btScalar(-g)));
    world.getSolverInfo().m_numIterations = o.iterations;
    btStaticPlaneShape groundShape(btVector3(0, 0, 1), 0);
    btRigidBody ground(0, nullptr, &groundShape);
    ground.setFriction(1);
    world.addRigidBody(&ground);

    std::vector<std::unique_ptr<Ragdoll>> dolls;
    for (const btTransform& t : spawns) {
        bullet::SpawnOptions so;
        so.entityTransform = t;
        so.constraintIterations = o.constraintIterations;
        so.comeToRest = o.sleeping;
        so.startAtRest = o.startAtRest;
        dolls.push_back(std::make_unique<Ragdoll>(asset, world, so));
    }
    out.restTimes.assign(dolls.size(), -1);

    auto energy = [&] {
        double e = 0;
        for (const auto& d : dolls)
            for (int i = 0; i < d->bodyCount(); ++i) {
                const btRigidBody& b = d->body(i);
                const double m = 1.0 / b.getInvMass();
                const btVector3 w = b.getAngularVelocity();
                const btVector3 iw = b.getInvInertiaTensorWorld().inverse() * w;
                e += 0.5 * m * b.getLinearVelocity().length2() + 0.5 * w.dot(iw) + m * g * b.getCenterOfMassPosition().z();
            }
        return e;
    };
    const double e0 = energy();
    const btScalar dt = btScalar(1.0 / o.hz), subDt = btScalar(1.0 / (o.hz * o.substeps));
    for (int step = 0; step < steps; ++step) {
        const auto t0 = std::chrono::steady_clock::now();
        world.stepSimulation(dt, o.substeps, subDt);
        out.stepSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        const double now = (step + 1) / o.hz;
        ++out.r.steps;

        bool allRest = true;
        for (std::size_t k = 0; k < dolls.size(); ++k) {
            Ragdoll& d = *dolls[k];
            for (int i = 0; i < d.bodyCount(); ++i) {
                const btRigidBody& b = d.body(i);
                if (b.isActive()) ++out.r.awakeBodySteps;
                const double speed = b.getLinearVelocity().length();
                const btVector3 p = b.getCenterOfMassPosition();
                if (!std::isfinite(speed) || !std::isfinite(static_cast<double>(p.x() + p.y() + p.z())) ||
                    speed > kExplodeSpeedMps) {
                    if (!out.r.exploded) out.r.explodedAtS = now;
                    out.r.exploded = true;
                }
                if (std::isfinite(speed)) out.r.maxSpeedMps = std::max(out.r.maxSpeedMps, speed);
            }
            for (int c = 0; c < static_cast<int>(d.figure().constraints.size()); ++c) {
                const auto [anchor, excess] = constraintError(d, c);
                out.r.maxAnchorErrorM = std::max(out.r.maxAnchorErrorM, anchor);
                out.r.maxLimitViolationDeg = std::max(out.r.maxLimitViolationDeg, excess * 180.0 / kPi);
                if (anchor > kExplodeAnchorM && !out.r.exploded) {
                    out.r.exploded = true;
                    out.r.explodedAtS = now;
                }
            }
            if (d.atRest() && out.restTimes[k] < 0) out.restTimes[k] = now;
            allRest = allRest && d.atRest();
        }
        for (int m = 0; m < dispatcher.getNumManifolds(); ++m) {
            const btPersistentManifold* man = dispatcher.getManifoldByIndexInternal(m);
            for (int c = 0; c < man->getNumContacts(); ++c)
                out.r.maxPenetrationM = std::max(out.r.maxPenetrationM, -static_cast<double>(man->getContactPoint(c).getDistance()));
        }
        out.r.maxEnergyGainJ = std::max(out.r.maxEnergyGainJ, energy() - e0);
        if (o.stopAtRest && allRest) break;
    }
    if (holdsFirst && !dolls.empty()) {
        out.haveFirst = true;
        out.firstBodies = dolls[0]->bodyTransforms();
    }
    dolls.clear();
    world.removeRigidBody(&ground);
    return out;
}

} // namespace

std::string bulletVersion() {
    const int v = btGetVersion();
    return std::to_string(v / 100) + "." + std::to_string(v % 100);
}

const char* bulletPrecision() { return sizeof(btScalar) == sizeof(double) ? "double" : "float"; }

DropResult runDrop(const figure::Figure& figure, const DropOptions& o) {
    bullet::installEngineContactFriction(); // the drop tool owns its process: the engine's contact friction
    const auto asset = RagdollAsset::create(figure);
    const int count = std::max(1, o.count);
    const int worlds = std::clamp(o.worlds, 1, count);
    const int steps = o.steps ? std::max(0, *o.steps) : static_cast<int>(std::lround(o.seconds * o.hz));

    // Spawn transforms: a grid, each figure turned (fixed set or seeded), its lowest point at the height.
    std::mt19937 rng(o.seed.value_or(0));
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    btVector3 lo, hi;
    figureBounds(figure, btMatrix3x3::getIdentity(), lo, hi);
    const double spacing = (hi - lo).length() + 0.5;
    const int columns = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(count))));
    std::vector<std::vector<btTransform>> perWorld(static_cast<std::size_t>(worlds));
    for (int i = 0; i < count; ++i) {
        double yaw = 37.0 * i * kPi / 180.0, tilt = 0, tiltDir = 0;
        if (o.seed) {
            yaw = unit(rng) * 2 * kPi;
            tilt = unit(rng) * kPi / 2;
            tiltDir = unit(rng) * 2 * kPi;
        }
        btQuaternion q(btVector3(0, 0, 1), btScalar(yaw));
        if (tilt > 0) q = btQuaternion(btVector3(btScalar(std::cos(tiltDir)), btScalar(std::sin(tiltDir)), 0), btScalar(tilt)) * q;
        const btMatrix3x3 rot(q);
        figureBounds(figure, rot, lo, hi);
        const double x = (i % columns) * spacing, y = (i / columns) * spacing;
        btTransform t(rot, btVector3(btScalar(x), btScalar(y), btScalar(o.heightM - lo.z())));
        perWorld[static_cast<std::size_t>(i % worlds)].push_back(t);
    }

    std::vector<Partial> parts(static_cast<std::size_t>(worlds));
    const auto wall0 = std::chrono::steady_clock::now();
    {
        std::vector<std::thread> threads;
        for (int w = 1; w < worlds; ++w)
            threads.emplace_back([&, w] { parts[static_cast<std::size_t>(w)] = runWorld(figure, asset, o, perWorld[static_cast<std::size_t>(w)], false, steps); });
        parts[0] = runWorld(figure, asset, o, perWorld[0], true, steps);
        for (std::thread& t : threads) t.join();
    }
    const double wallSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();

    DropResult r = parts[0].r;
    r.figure = figure.name;
    r.precision = bulletPrecision();
    r.bodies = static_cast<int>(figure.bodies.size()) * count;
    r.constraints = static_cast<int>(figure.constraints.size()) * count;
    double stepSeconds = parts[0].stepSeconds, lastRest = 0;
    bool allRested = true;
    for (std::size_t w = 0; w < parts.size(); ++w) {
        const DropResult& p = parts[w].r;
        if (w > 0) {
            r.awakeBodySteps += p.awakeBodySteps;
            r.maxAnchorErrorM = std::max(r.maxAnchorErrorM, p.maxAnchorErrorM);
            r.maxLimitViolationDeg = std::max(r.maxLimitViolationDeg, p.maxLimitViolationDeg);
            r.maxPenetrationM = std::max(r.maxPenetrationM, p.maxPenetrationM);
            r.maxEnergyGainJ = std::max(r.maxEnergyGainJ, p.maxEnergyGainJ);
            r.maxSpeedMps = std::max(r.maxSpeedMps, p.maxSpeedMps);
            if (p.exploded && (!r.exploded || *p.explodedAtS < *r.explodedAtS)) r.explodedAtS = p.explodedAtS;
            r.exploded = r.exploded || p.exploded;
            stepSeconds = std::max(stepSeconds, parts[w].stepSeconds); // worlds run side by side
        }
        for (double t : parts[w].restTimes) {
            allRested = allRested && t >= 0;
            lastRest = std::max(lastRest, t);
        }
    }
    if (allRested && r.steps > 0) r.settleTimeS = lastRest;
    r.wallMs = wallSeconds * 1000.0;
    r.usPerStep = r.steps > 0 ? stepSeconds * 1e6 / r.steps : 0;
    r.usPerBodyStep = r.bodies > 0 ? r.usPerStep * worlds / r.bodies : 0;

    // The first instance's pose, in its own model space (metres).
    const std::vector<figure::Transform> bodies = parts[0].firstBodies;
    r.firstBodies = bodies;
    r.firstSpawn = bullet::toEigen(perWorld[0][0]);
    const pose::SkeletonPose pose = pose::driveSkeleton(figure, bodies);
    const Eigen::Quaterniond qe(pose.entity.rotation);
    const double entity[7] = {pose.entity.position.x(), pose.entity.position.y(), pose.entity.position.z(),
                              qe.w(), qe.x(), qe.y(), qe.z()};
    std::copy(entity, entity + 7, r.entity);
    for (int j = 0; j < figure.skeleton.jointCount(); ++j) {
        const figure::Transform& t = pose.model[static_cast<std::size_t>(j)];
        const Eigen::Quaterniond q(t.rotation);
        r.finalPose.push_back({figure.skeleton.name(j), {t.position.x(), t.position.y(), t.position.z()}, {q.w(), q.x(), q.y(), q.z()}});
    }
    return r;
}

} // namespace afb::sim
