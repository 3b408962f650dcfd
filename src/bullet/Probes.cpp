// The measurements every ragdoll representation shares: joint errors and the rest rules (docs/format.md §6.1).
#include "afb/detail/Probes.h"

#include "afb/detail/Convert.h"
#include "afb/figure/Limits.h"

namespace afb::bullet {

namespace {

// The frames and errors of a constraint from any list of body transforms (`at(i)`: body i's world transform).
template <class At>
std::pair<btTransform, btTransform> framesWorld(const figure::FigureConstraint& c, const At& at,
                                                const std::pair<btTransform, btTransform>& frames) {
    const btTransform a = at(c.body1) * frames.first;
    const btTransform b = c.body2 >= 0 ? at(c.body2) * frames.second : frames.second;
    return {a, b};
}

template <class At>
JointError jointError(const figure::FigureConstraint& c, const At& at,
                      const std::pair<btTransform, btTransform>& frames, const btTransform& spawn) {
    JointError e;
    if (c.type == figure::JointType::Spring) return e;
    const auto [a, b] = framesWorld(c, at, frames);
    const btVector3 d = a.getOrigin() - b.getOrigin();
    e.anchorM = d.length();
    if (c.type == figure::JointType::Slider) { // free along the axis: only the perpendicular part counts
        const btVector3 axis = b.getBasis().getColumn(0);
        e.anchorM = (d - axis * d.dot(axis)).length();
    }
    // One definition of a limit's excess (figure/Limits.h), in double, for every backend's metrics.
    const btMatrix3x3 body1 = at(c.body1).getBasis();
    const btMatrix3x3 body2 = c.body2 >= 0 ? at(c.body2).getBasis() : spawn.getBasis();
    e.limitExcessRad = figure::limitExcessRad(c, toEigen(body1), toEigen(body2));
    return e;
}

} // namespace

std::pair<btTransform, btTransform> constraintFramesWorldOf(const figure::FigureConstraint& c, BodyList bodies,
                                                            const std::pair<btTransform, btTransform>& frames) {
    return framesWorld(
        c, [&](int i) -> const btTransform& { return bodies[static_cast<std::size_t>(i)]->getCenterOfMassTransform(); },
        frames);
}

std::pair<btTransform, btTransform> constraintFramesWorldOf(const figure::FigureConstraint& c,
                                                            std::span<const btTransform> bodies,
                                                            const std::pair<btTransform, btTransform>& frames) {
    return framesWorld(
        c, [&](int i) -> const btTransform& { return bodies[static_cast<std::size_t>(i)]; }, frames);
}

JointError jointErrorOf(const figure::FigureConstraint& c, BodyList bodies,
                        const std::pair<btTransform, btTransform>& frames, const btTransform& spawn) {
    return jointError(
        c, [&](int i) -> const btTransform& { return bodies[static_cast<std::size_t>(i)]->getCenterOfMassTransform(); },
        frames, spawn);
}

JointError jointErrorOf(const figure::FigureConstraint& c, std::span<const btTransform> bodies,
                        const std::pair<btTransform, btTransform>& frames, const btTransform& spawn) {
    return jointError(
        c, [&](int i) -> const btTransform& { return bodies[static_cast<std::size_t>(i)]; }, frames, spawn);
}

std::vector<figure::Transform> bodyTransformsOf(BodyList bodies) {
    std::vector<figure::Transform> out;
    out.reserve(bodies.size());
    for (const auto& b : bodies) out.push_back(toEigen(b->getCenterOfMassTransform()));
    return out;
}

std::vector<figure::BodyState> bodyStatesOf(BodyList bodies) {
    std::vector<figure::BodyState> out;
    out.reserve(bodies.size());
    for (const auto& b : bodies)
        out.push_back({toEigen(b->getCenterOfMassTransform()), toEigen(b->getLinearVelocity()),
                       toEigen(b->getAngularVelocity())});
    return out;
}

int awakeCountOf(BodyList bodies) {
    int n = 0;
    for (const auto& b : bodies) n += b->isActive() ? 1 : 0;
    return n;
}

// docs/format.md §6.1 TestIfAtRest, over any list of bodies: `get(i)` gives body i's BodySample.
template <class Get>
bool RestTest::updateWith(std::size_t count, const Get& get, double dt, double activeTime) {
    const figure::RestRules& r = m_rules;
    bool speedsLow = m_havePrevious;
    if (m_previous.size() != count) m_previous.resize(count);
    for (std::size_t i = 0; i < count; ++i) {
        const BodySample b = get(i);
        const btVector3 v = b.linearVelocity, w = b.angularVelocity;
        if (m_havePrevious) {
            const double accel = (v - m_previous[i].first).length() / dt;
            const double angAccel = (w - m_previous[i].second).length() / dt;
            if (v.length() > r.linearSpeedMps || w.length() > r.angularSpeedRadps || accel > r.linearAccelMps2 ||
                angAccel > r.angularAccelRadps2)
                speedsLow = false;
        }
        m_previous[i] = {v, w};
    }
    m_havePrevious = true;
    if (r.minMoveTimeS > 0 && activeTime < r.minMoveTimeS) return false;
    if (r.maxMoveTimeS > 0 && activeTime > r.maxMoveTimeS) return true;
    // The no-move window: compare every body with its pose at the window's start.
    const auto startWindow = [&] {
        m_windowStart = activeTime;
        m_window.clear();
        for (std::size_t i = 0; i < count; ++i) m_window.push_back(get(i).transform);
    };
    if (m_windowStart < 0) {
        startWindow();
    } else if (activeTime - m_windowStart > r.noMoveTimeS) {
        bool still = true;
        for (std::size_t i = 0; i < count; ++i) {
            const btTransform now = get(i).transform;
            const btTransform& then = m_window[i];
            const btQuaternion dq = now.getRotation() * then.getRotation().inverse();
            if ((now.getOrigin() - then.getOrigin()).length() >= r.noMoveTranslationM ||
                dq.getAngleShortestPath() >= r.noMoveRotationRad)
                still = false;
        }
        startWindow();
        if (still) return true;
    }
    return speedsLow;
}

bool RestTest::update(BodyList bodies, double dt, double activeTime) {
    return updateWith(
        bodies.size(),
        [&](std::size_t i) {
            const btRigidBody& b = *bodies[i];
            return BodySample{b.getCenterOfMassTransform(), b.getLinearVelocity(), b.getAngularVelocity()};
        },
        dt, activeTime);
}

bool RestTest::update(std::span<const BodySample> bodies, double dt, double activeTime) {
    return updateWith(
        bodies.size(), [&](std::size_t i) { return bodies[i]; }, dt, activeTime);
}

void RestTest::reset() {
    m_windowStart = -1;
    m_havePrevious = false;
}

} // namespace afb::bullet
