// The measurements every ragdoll representation shares: joint errors and the rest rules (af-format §6.1).
#include "afb/bullet/Probes.h"

#include "afb/bullet/Convert.h"
#include "afb/figure/Limits.h"

namespace afb::bullet {

std::pair<btTransform, btTransform> constraintFramesWorldOf(const figure::FigureConstraint& c, const BodyList& bodies,
                                                            const std::pair<btTransform, btTransform>& frames) {
    const btTransform a = bodies[static_cast<std::size_t>(c.body1)]->getCenterOfMassTransform() * frames.first;
    const btTransform b = c.body2 >= 0
                              ? bodies[static_cast<std::size_t>(c.body2)]->getCenterOfMassTransform() * frames.second
                              : frames.second;
    return {a, b};
}

JointError jointErrorOf(const figure::FigureConstraint& c, const BodyList& bodies,
                        const std::pair<btTransform, btTransform>& frames, const btTransform& spawn) {
    JointError e;
    if (c.type == figure::JointType::Spring) return e;
    const auto [a, b] = constraintFramesWorldOf(c, bodies, frames);
    const btVector3 d = a.getOrigin() - b.getOrigin();
    e.anchorM = d.length();
    if (c.type == figure::JointType::Slider) { // free along the axis: only the perpendicular part counts
        const btVector3 axis = b.getBasis().getColumn(0);
        e.anchorM = (d - axis * d.dot(axis)).length();
    }
    // One definition of a limit's excess (figure/Limits.h), in double, for every backend's metrics.
    const btMatrix3x3 body1 = bodies[static_cast<std::size_t>(c.body1)]->getCenterOfMassTransform().getBasis();
    const btMatrix3x3 body2 = c.body2 >= 0
                                  ? bodies[static_cast<std::size_t>(c.body2)]->getCenterOfMassTransform().getBasis()
                                  : spawn.getBasis();
    e.limitExcessRad = figure::limitExcessRad(c, toEigen(body1), toEigen(body2));
    return e;
}

std::vector<figure::Transform> bodyTransformsOf(const BodyList& bodies) {
    std::vector<figure::Transform> out;
    out.reserve(bodies.size());
    for (const auto& b : bodies) out.push_back(toEigen(b->getCenterOfMassTransform()));
    return out;
}

std::vector<figure::BodyState> bodyStatesOf(const BodyList& bodies) {
    std::vector<figure::BodyState> out;
    out.reserve(bodies.size());
    for (const auto& b : bodies)
        out.push_back({toEigen(b->getCenterOfMassTransform()), toEigen(b->getLinearVelocity()),
                       toEigen(b->getAngularVelocity())});
    return out;
}

int awakeCountOf(const BodyList& bodies) {
    int n = 0;
    for (const auto& b : bodies) n += b->isActive() ? 1 : 0;
    return n;
}

// af-format §6.1 TestIfAtRest.
bool RestTest::update(const BodyList& bodies, double dt, double activeTime) {
    const figure::RestRules& r = m_rules;
    bool speedsLow = m_havePrevious;
    if (m_previous.size() != bodies.size()) m_previous.resize(bodies.size());
    for (std::size_t i = 0; i < bodies.size(); ++i) {
        const btVector3 v = bodies[i]->getLinearVelocity(), w = bodies[i]->getAngularVelocity();
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
    if (m_windowStart < 0) {
        startWindow(bodies, activeTime);
    } else if (activeTime - m_windowStart > r.noMoveTimeS) {
        bool still = true;
        for (std::size_t i = 0; i < bodies.size(); ++i) {
            const btTransform& now = bodies[i]->getCenterOfMassTransform();
            const btTransform& then = m_window[i];
            const btQuaternion dq = now.getRotation() * then.getRotation().inverse();
            if ((now.getOrigin() - then.getOrigin()).length() >= r.noMoveTranslationM ||
                dq.getAngleShortestPath() >= r.noMoveRotationRad)
                still = false;
        }
        startWindow(bodies, activeTime);
        if (still) return true;
    }
    return speedsLow;
}

void RestTest::reset() {
    m_windowStart = -1;
    m_havePrevious = false;
}

void RestTest::startWindow(const BodyList& bodies, double activeTime) {
    m_windowStart = activeTime;
    m_window.clear();
    for (const auto& b : bodies) m_window.push_back(b->getCenterOfMassTransform());
}

} // namespace afb::bullet
