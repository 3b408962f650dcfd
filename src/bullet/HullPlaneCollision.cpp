// Polytope–plane contacts from the polytope's vertices (HullPlaneCollision.h).
//
// Bullet's manifold merges a new point into any cached point within the contact breaking threshold, and a
// speculative threshold is as long as a body travels in a substep (decimetres): a box's corners then replace one
// another instead of adding up, and the corner a body is rolling onto is missing. So this algorithm keeps the
// manifold itself: the (up to) four vertices that come nearest the plane within this step (at their current
// velocities), each matched to its previous point by vertex index so that warm starting carries over.
#include "HullPlaneCollision.h"

#include <algorithm>
#include <vector>

#include <BulletCollision/CollisionDispatch/btCollisionObjectWrapper.h>
#include <BulletDynamics/Dynamics/btRigidBody.h>

#include "OwnedManifoldAlgorithm.h"

namespace afb::bullet::detail {
namespace {

struct Candidate {
    int vertex;
    btVector3 onPolytope; ///< world
    btScalar distance;    ///< signed, along the plane normal
    btScalar rank;        ///< the nearer of now and the end of the step
};

class PolytopePlaneAlgorithm : public OwnedManifoldAlgorithm {
  public:
    PolytopePlaneAlgorithm(const btCollisionAlgorithmConstructionInfo& ci, const btCollisionObjectWrapper* w0,
                           const btCollisionObjectWrapper* w1, bool swapped)
        : OwnedManifoldAlgorithm(ci, w0, w1, (swapped ? w1 : w0)->getCollisionObject(),
                                 (swapped ? w0 : w1)->getCollisionObject()),
          m_swapped(swapped) {}

    void processCollision(const btCollisionObjectWrapper* w0, const btCollisionObjectWrapper* w1,
                          const btDispatcherInfo& info, btManifoldResult* out) override {
        if (m_manifold == nullptr) return;
        out->setPersistentManifold(m_manifold);
        const btCollisionObjectWrapper* polytopeWrap = m_swapped ? w1 : w0;
        const btCollisionObjectWrapper* planeWrap = m_swapped ? w0 : w1;
        const auto* plane = static_cast<const btStaticPlaneShape*>(planeWrap->getCollisionShape());
        const btTransform& planeWorld = planeWrap->getWorldTransform();
        const btVector3 normal = planeWorld.getBasis() * plane->getPlaneNormal();
        const btScalar offset = plane->getPlaneConstant() + normal.dot(planeWorld.getOrigin());
        const btScalar reach = m_manifold->getContactBreakingThreshold() + out->m_closestPointDistanceThreshold;

        // The four vertices that come nearest the plane in this step, within reach: ranked by the nearer of their
        // distance now and at the end of the step at the body's current velocity (a box tipping over an edge
        // needs the corners it is turning onto, not the nearer ones behind it).
        const btTransform& world = polytopeWrap->getWorldTransform();
        // A multibody link's velocity is on its collider (MultibodyRagdoll::publishVelocities; zero for objects
        // that never set it).
        const btCollisionObject* object = polytopeWrap->getCollisionObject();
        const btRigidBody* body = btRigidBody::upcast(object);
        const btVector3 v = body ? body->getLinearVelocity() : object->getInterpolationLinearVelocity();
        const btVector3 w = body ? body->getAngularVelocity() : object->getInterpolationAngularVelocity();
        // The body turns about its own centre of mass (a merged body's: the child's frame is not the body's).
        const btVector3 centre = object->getWorldTransform().getOrigin();
        const btScalar dt = info.m_timeStep;
        auto inManifold = [&](int vertex) {
            for (int k = 0; k < m_manifold->getNumContacts(); ++k)
                if (m_manifold->getContactPoint(k).m_index0 == vertex) return true;
            return false;
        };
        m_candidates.clear();
        auto consider = [&](int vertex, const btVector3& local, btScalar margin) {
            const btVector3 p = world * local - normal * margin;
            const btScalar distance = normal.dot(p) - offset;
            if (distance >= reach) return;
            btScalar rank = btMin(distance, distance + dt * normal.dot(v + w.cross(p - centre)));
            if (inManifold(vertex)) rank -= kKeepM; // a point the solver knows wins a near-tie
            m_candidates.push_back({vertex, p, distance, rank});
        };
        const btCollisionShape* shape = polytopeWrap->getCollisionShape();
        if (shape->getShapeType() == BOX_SHAPE_PROXYTYPE) {
            // A box's margin is inside its half extents: the corners are the surface.
            const btVector3 h = static_cast<const btBoxShape*>(shape)->getHalfExtentsWithMargin();
            for (int i = 0; i < 8; ++i)
                consider(i, btVector3(i & 1 ? h.x() : -h.x(), i & 2 ? h.y() : -h.y(), i & 4 ? h.z() : -h.z()), 0);
        } else {
            // A hull's surface is its points grown by the margin: a vertex reaches `margin` closer to the plane.
            const auto* hull = static_cast<const btConvexHullShape*>(shape);
            const btVector3 scaling = hull->getLocalScaling();
            const btVector3* points = hull->getUnscaledPoints();
            for (int i = 0, n = hull->getNumPoints(); i < n; ++i) consider(i, points[i] * scaling, hull->getMargin());
        }

        const int count = choose(normal);
        const auto& best = m_candidates;

        // Points of vertices no longer among the nearest go; the others are replaced in place (keeping their
        // impulses for warm starting) or added.
        const bool wasEmpty = m_manifold->getNumContacts() == 0;
        for (int k = m_manifold->getNumContacts() - 1; k >= 0; --k) {
            const int vertex = m_manifold->getContactPoint(k).m_index0;
            const bool kept =
                std::any_of(best.begin(), best.begin() + count, [&](const Candidate& c) { return c.vertex == vertex; });
            if (!kept) m_manifold->removeContactPoint(k);
        }
        for (int i = 0; i < count; ++i) add(best[static_cast<std::size_t>(i)], normal, polytopeWrap, planeWrap, w0, w1);
        if (wasEmpty && m_manifold->getNumContacts() > 0 && gContactStartedCallback != nullptr)
            gContactStartedCallback(m_manifold);
    }

  private:
    // Moves the chosen points (at most four) to the front of m_candidates and returns how many. The nearest
    // first; then, among the vertices touching as much as it (within kBandM: a face lying on the plane, a
    // cone's base), the most spread out (farthest-point sampling across the plane, so that four of a cone's
    // twelve rim vertices make a wide square, not a corner); then the next nearest (the corners a body is
    // turning onto). Ties go to points already in the manifold, so a resting body keeps its points and their
    // warm-started impulses from step to step.
    int choose(const btVector3& normal) {
        auto& c = m_candidates;
        std::stable_sort(c.begin(), c.end(), [](const Candidate& x, const Candidate& y) { return x.rank < y.rank; });
        const int n = static_cast<int>(c.size());
        if (n <= 4) return n;
        int band = 1;
        while (band < n && c[static_cast<std::size_t>(band)].rank <= c[0].rank + kBandM) ++band;
        int chosen = 1;
        if (band > 4) {
            auto across = [&](const btVector3& a, const btVector3& b) {
                const btVector3 d = a - b;
                return (d - normal * normal.dot(d)).length2();
            };
            while (chosen < 4) {
                int pick = chosen;
                btScalar pickScore = -1;
                for (int i = chosen; i < band; ++i) {
                    btScalar nearest = BT_LARGE_FLOAT;
                    for (int j = 0; j < chosen; ++j)
                        nearest = btMin(nearest, across(c[static_cast<std::size_t>(i)].onPolytope,
                                                        c[static_cast<std::size_t>(j)].onPolytope));
                    // Spread first; the rank (with its kKeepM hysteresis) breaks near-ties.
                    const btScalar score = btSqrt(nearest) - c[static_cast<std::size_t>(i)].rank;
                    if (score > pickScore + btScalar(1e-4)) {
                        pick = i;
                        pickScore = score;
                    }
                }
                std::swap(c[static_cast<std::size_t>(chosen)], c[static_cast<std::size_t>(pick)]);
                ++chosen;
            }
        }
        return 4; // band <= 4: the band, then the next nearest, already in order
    }

    // One contact point, made as btManifoldResult::addContactPoint makes it (combined material values, the
    // contact-added callback), but matched to the cache by vertex instead of by distance.
    void add(const Candidate& c, const btVector3& normal, const btCollisionObjectWrapper* polytopeWrap,
             const btCollisionObjectWrapper* planeWrap, const btCollisionObjectWrapper* w0,
             const btCollisionObjectWrapper* w1) {
        const btCollisionObject* a = polytopeWrap->getCollisionObject();
        const btCollisionObject* b = planeWrap->getCollisionObject();
        const btVector3 onPlane = c.onPolytope - normal * c.distance;
        btManifoldPoint p(a->getWorldTransform().invXform(c.onPolytope), b->getWorldTransform().invXform(onPlane),
                          normal, c.distance);
        p.m_positionWorldOnA = c.onPolytope;
        p.m_positionWorldOnB = onPlane;
        const btCollisionObject* o0 = w0->getCollisionObject();
        const btCollisionObject* o1 = w1->getCollisionObject();
        p.m_combinedFriction = gCalculateCombinedFrictionCallback(o0, o1);
        p.m_combinedRestitution = gCalculateCombinedRestitutionCallback(o0, o1);
        p.m_combinedRollingFriction = gCalculateCombinedRollingFrictionCallback(o0, o1);
        p.m_combinedSpinningFriction = gCalculateCombinedSpinningFrictionCallback(o0, o1);
        const int flags = o0->getCollisionFlags() | o1->getCollisionFlags();
        if (flags & btCollisionObject::CF_HAS_CONTACT_STIFFNESS_DAMPING) {
            p.m_combinedContactDamping1 = gCalculateCombinedContactDampingCallback(o0, o1);
            p.m_combinedContactStiffness1 = gCalculateCombinedContactStiffnessCallback(o0, o1);
            p.m_contactPointFlags |= BT_CONTACT_FLAG_CONTACT_STIFFNESS_DAMPING;
        }
        if (flags & btCollisionObject::CF_HAS_FRICTION_ANCHOR) p.m_contactPointFlags |= BT_CONTACT_FLAG_FRICTION_ANCHOR;
        btPlaneSpace1(p.m_normalWorldOnB, p.m_lateralFrictionDir1, p.m_lateralFrictionDir2);
        p.m_index0 = c.vertex;

        int at = -1;
        for (int k = 0; k < m_manifold->getNumContacts(); ++k)
            if (m_manifold->getContactPoint(k).m_index0 == c.vertex) at = k;
        if (at >= 0) m_manifold->replaceContactPoint(p, at);
        else at = m_manifold->addManifoldPoint(p);
        if (gContactAddedCallback != nullptr && (flags & btCollisionObject::CF_CUSTOM_MATERIAL_CALLBACK))
            (*gContactAddedCallback)(m_manifold->getContactPoint(at), polytopeWrap, p.m_partId0, p.m_index0, planeWrap,
                                     p.m_partId1, p.m_index1);
    }

    // Vertices within this much of the nearest count as touching with it (a face on the plane), metres.
    static constexpr btScalar kBandM = btScalar(0.002);
    // A vertex already in the manifold ranks this much nearer than it is, metres (hysteresis).
    static constexpr btScalar kKeepM = btScalar(0.001);

    std::vector<Candidate> m_candidates; // reused from step to step
    bool m_swapped;
};

struct CreatePolytopePlane : btCollisionAlgorithmCreateFunc {
    explicit CreatePolytopePlane(bool swapped) { m_swapped = swapped; }
    btCollisionAlgorithm* CreateCollisionAlgorithm(btCollisionAlgorithmConstructionInfo& ci,
                                                   const btCollisionObjectWrapper* w0,
                                                   const btCollisionObjectWrapper* w1) override {
        void* memory = ci.m_dispatcher1->allocateCollisionAlgorithm(sizeof(PolytopePlaneAlgorithm));
        return new (memory) PolytopePlaneAlgorithm(ci, w0, w1, m_swapped);
    }
};

} // namespace

void useVertexHullPlaneContacts(btCollisionDispatcher& dispatcher, bool on, btCollisionConfiguration& config) {
    static CreatePolytopePlane polytopeFirst(false), planeFirst(true);
    for (const int polytope : {CONVEX_HULL_SHAPE_PROXYTYPE, BOX_SHAPE_PROXYTYPE}) {
        dispatcher.registerCollisionCreateFunc(polytope, STATIC_PLANE_PROXYTYPE,
                                               on ? &polytopeFirst
                                                  : config.getCollisionAlgorithmCreateFunc(polytope,
                                                                                           STATIC_PLANE_PROXYTYPE));
        dispatcher.registerCollisionCreateFunc(STATIC_PLANE_PROXYTYPE, polytope,
                                               on ? &planeFirst
                                                  : config.getCollisionAlgorithmCreateFunc(STATIC_PLANE_PROXYTYPE,
                                                                                           polytope));
    }
}

} // namespace afb::bullet::detail
