// Levels of detail of a live ragdoll: its bodies merged into fewer rigid bodies and back, at the pose
// and momentum they have, so that nothing moves at the switch (docs/performance.md).
#include <algorithm>

#include <Eigen/Dense>

#include "RagdollWorldLink.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/detail/Convert.h"

namespace afb::bullet {
namespace {

// Whether `level` puts each of `bodies` bodies in exactly one non-empty group.
bool isPartition(const figure::LodLevel& level, std::size_t bodies) {
    std::vector<char> seen(bodies, 0);
    std::size_t count = 0;
    for (const std::vector<int>& group : level.groups) {
        if (group.empty()) return false;
        for (const int b : group) {
            if (b < 0 || static_cast<std::size_t>(b) >= bodies || seen[static_cast<std::size_t>(b)]) return false;
            seen[static_cast<std::size_t>(b)] = 1;
            ++count;
        }
    }
    return count == bodies;
}

// A group ascending and the groups by first body: the order RagdollAsset's layouts use.
figure::LodLevel normalised(figure::LodLevel level) {
    for (std::vector<int>& group : level.groups) std::sort(group.begin(), group.end());
    std::sort(level.groups.begin(), level.groups.end(),
              [](const std::vector<int>& a, const std::vector<int>& b) { return a.front() < b.front(); });
    return level;
}

} // namespace

std::string Ragdoll::setLod(const figure::LodLevel& level) {
    if (m_multibody) return "LOD: the multibody backend has no levels of detail (rigid backend only)";
    if (!isPartition(level, figure().bodies.size()))
        return "LOD: the groups must hold every body of figure " + figure().name + " exactly once";
    const figure::LodLevel sorted = normalised(level);
    relayout(&sorted);
    return {};
}

void Ragdoll::setFullDetail() {
    if (m_multibody || !m_lodLayout) return;
    relayout(nullptr);
}

// Takes every Bullet object of the ragdoll out of the world, makes the new layout at the figure bodies' current
// poses, and puts the new rigid bodies and constraints in with the same momentum; rest, frozen contact, the
// guard's saved state and the RagdollWorld's tables follow.
void Ragdoll::relayout(const figure::LodLevel* level) {
    std::vector<BodySample> now;
    figureBodySamples(now);
    const bool resting = atRest();
    // The deepest frozen contact names collision objects that are about to go: kept by figure body.
    FrozenContact contact = m_frozenContact;
    const auto bodyOf = [&](const btCollisionObject* o) {
        for (std::size_t k = 0; k < m_bodies.size(); ++k)
            if (m_bodies[k] == o) return m_layout->rigids[k].representative;
        return -1;
    };
    const int contactA = bodyOf(contact.a), contactB = bodyOf(contact.b);

    if (m_manager) detail::RagdollWorldLink::detachBodies(*m_manager, *this);
    removeBulletObjects();
    std::vector<std::unique_ptr<btCollisionShape>> compounds; // the old level's shapes live until here
    compounds.swap(m_lodCompounds);
    if (level) {
        // World poses (the spawn transform's float basis is not exactly orthonormal: through model space, the
        // combined frame would be off by its rounding).
        std::vector<figure::Transform> poses;
        poses.reserve(now.size());
        for (const BodySample& s : now) poses.push_back(toEigen(s.transform));
        m_lodLayout = std::make_unique<RigidLayout>(m_asset->layoutAt(*level, poses, m_lodCompounds));
        m_layout = m_lodLayout.get();
    } else {
        m_lodLayout.reset();
        m_layout = &m_asset->layout(m_method.mergeFixed);
    }
    addBodies();
    placeRigids(now);
    if (!m_keyframes.modes.empty())
        for (std::size_t k = 0; k < m_bodies.size(); ++k) applyRigidMode(k); // the new rigids of keyframed bodies
    compounds.clear();
    addConstraints();
    filterPairs();
    if (m_manager) detail::RagdollWorldLink::attachBodies(*m_manager, *this);
    rememberGoodState();
    if (resting) {
        putToRest();
        const auto objectOf = [&](int body, const btCollisionObject* other) -> const btCollisionObject* {
            return body >= 0 ? &this->body(body) : other;
        };
        if (m_frozen) m_frozenContact = {contact.depthM, objectOf(contactA, contact.a), objectOf(contactB, contact.b)};
    }
}

// Each rigid body takes its bodies' state: at its frame (where its bodies' frames put it), with their total
// momentum as its centre's velocity and their total angular momentum about its centre as I ω (in double: the
// combined inertia is exact, so merging a rigid's own velocity field gives it back).
void Ragdoll::placeRigids(std::span<const BodySample> bodies) {
    const figure::Figure& f = figure();
    for (std::size_t k = 0; k < m_bodies.size(); ++k) {
        const RigidLayout::Rigid& r = m_layout->rigids[k];
        const std::size_t rep = static_cast<std::size_t>(r.representative);
        btRigidBody& b = *m_bodies[k];
        const btTransform t = bodies[rep].transform * m_layout->bodyInRigidBt[rep].inverse();
        btVector3 v = bodies[rep].linearVelocity, w = bodies[rep].angularVelocity;
        if (r.bodies.size() > 1) {
            const figure::Transform frame = toEigen(t);
            Eigen::Vector3d momentum = Eigen::Vector3d::Zero(), angular = Eigen::Vector3d::Zero();
            for (const int i : r.bodies) {
                const figure::FigureBody& body = f.bodies[static_cast<std::size_t>(i)];
                const BodySample& s = bodies[static_cast<std::size_t>(i)];
                const Eigen::Matrix3d rot = toEigen(s.transform).rotation;
                const Eigen::Vector3d vi = toEigen(s.linearVelocity), wi = toEigen(s.angularVelocity);
                momentum += body.massKg * vi;
                angular += rot * body.inertiaKgM2.asDiagonal() * rot.transpose() * wi +
                           body.massKg * (toEigen(s.transform.getOrigin()) - frame.position).cross(vi);
            }
            const Eigen::Matrix3d inertia = frame.rotation * r.inertiaKgM2.asDiagonal() * frame.rotation.transpose();
            v = toBt(Eigen::Vector3d(momentum / r.massKg));
            w = toBt(Eigen::Vector3d(inertia.ldlt().solve(angular)));
        }
        placeRigid(b, t, v, w);
        if (b.getBroadphaseHandle()) m_world.updateSingleAabb(&b);
    }
}

} // namespace afb::bullet
