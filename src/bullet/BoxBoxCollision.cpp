// Box–box contacts with speculative points (BoxBoxCollision.h).
#include "BoxBoxCollision.h"

#include <BulletCollision/CollisionDispatch/btBoxBoxDetector.h>
#include <BulletCollision/CollisionDispatch/btCollisionObjectWrapper.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkEpaPenetrationDepthSolver.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkPairDetector.h>
#include <BulletCollision/NarrowPhaseCollision/btPointCollector.h>
#include <BulletCollision/NarrowPhaseCollision/btVoronoiSimplexSolver.h>
#include <BulletDynamics/Dynamics/btRigidBody.h>

#include "OwnedManifoldAlgorithm.h"

namespace afb::bullet::detail {
namespace {

// Forwards the detector's points to the manifold result and counts them.
struct CountingResult : btDiscreteCollisionDetectorInterface::Result {
    explicit CountingResult(btManifoldResult& out) : m_out(out) {}
    void setShapeIdentifiersA(int partId, int index) override { m_out.setShapeIdentifiersA(partId, index); }
    void setShapeIdentifiersB(int partId, int index) override { m_out.setShapeIdentifiersB(partId, index); }
    void addContactPoint(const btVector3& normalOnBInWorld, const btVector3& pointInWorld, btScalar depth) override {
        ++count;
        m_out.addContactPoint(normalOnBInWorld, pointInWorld, depth);
    }
    int count = 0;

  private:
    btManifoldResult& m_out;
};

// Forwards the points of the detector run with the first box moved by -normal·shift, each at its distance with the
// box where it is: its depth there plus the shift along the point's own normal.
struct ShiftedResult : btDiscreteCollisionDetectorInterface::Result {
    ShiftedResult(btManifoldResult& out, const btVector3& normal, btScalar shift)
        : m_out(out), m_normal(normal), m_shift(shift) {}
    void setShapeIdentifiersA(int partId, int index) override { m_out.setShapeIdentifiersA(partId, index); }
    void setShapeIdentifiersB(int partId, int index) override { m_out.setShapeIdentifiersB(partId, index); }
    void addContactPoint(const btVector3& normalOnBInWorld, const btVector3& pointInWorld, btScalar depth) override {
        ++count;
        m_out.addContactPoint(normalOnBInWorld, pointInWorld, depth + m_shift * m_normal.dot(normalOnBInWorld));
    }
    int count = 0;

  private:
    btManifoldResult& m_out;
    btVector3 m_normal;
    btScalar m_shift;
};

// The velocity of the point `p` (world) of an object: a rigid body's, or a multibody link collider's as published
// on it (MultibodyRagdoll::publishVelocities; zero for objects that never set it).
btVector3 pointVelocity(const btCollisionObject* o, const btVector3& p) {
    if (const btRigidBody* b = btRigidBody::upcast(o))
        return b->getVelocityInLocalPoint(p - b->getCenterOfMassPosition());
    return o->getInterpolationLinearVelocity() +
           o->getInterpolationAngularVelocity().cross(p - o->getWorldTransform().getOrigin());
}

class SpeculativeBoxBoxAlgorithm : public OwnedManifoldAlgorithm {
  public:
    SpeculativeBoxBoxAlgorithm(const btCollisionAlgorithmConstructionInfo& ci, const btCollisionObjectWrapper* w0,
                               const btCollisionObjectWrapper* w1)
        : OwnedManifoldAlgorithm(ci, w0, w1, w0->getCollisionObject(), w1->getCollisionObject()) {}

    void processCollision(const btCollisionObjectWrapper* w0, const btCollisionObjectWrapper* w1,
                          const btDispatcherInfo& info, btManifoldResult* out) override {
        if (m_manifold == nullptr) return;
        out->setPersistentManifold(m_manifold);
        const auto* box0 = static_cast<const btBoxShape*>(w0->getCollisionShape());
        const auto* box1 = static_cast<const btBoxShape*>(w1->getCollisionShape());
        btDiscreteCollisionDetectorInterface::ClosestPointInput input;
        input.m_transformA = w0->getWorldTransform();
        input.m_transformB = w1->getWorldTransform();
        input.m_maximumDistanceSquared = BT_LARGE_FLOAT;
        CountingResult overlap(*out);
        btBoxBoxDetector detector(box0, box1);
        detector.getClosestPoints(input, overlap, info.m_debugDraw);
        if (overlap.count == 0) {
            // Apart: GJK's closest points, within the manifold's reach (the limits of the search as
            // btConvexConvexAlgorithm sets them; a box's margin is inside its half extents).
            const btScalar reach = box0->getMargin() + box1->getMargin() + m_manifold->getContactBreakingThreshold() +
                                   out->m_closestPointDistanceThreshold;
            input.m_maximumDistanceSquared = reach * reach;
            btVoronoiSimplexSolver simplex;
            btGjkEpaPenetrationDepthSolver epa;
            btGjkPairDetector gjk(box0, box1, &simplex, &epa);
            btPointCollector closest;
            gjk.getClosestPoints(input, closest, info.m_debugDraw);
            if (!closest.m_hasResult || closest.m_distance < 0 ||
                closest.m_distance > m_manifold->getContactBreakingThreshold()) {
                out->refreshContactPoints();
                return;
            }
            // Only when the boxes can close the gap in this step at their current velocities (with the reach's
            // allowance for acceleration): a point between boxes lying still near each other would do nothing but
            // take a place in the manifold (and, measured, kept a humanoid's feet from resting).
            const btVector3& n = closest.m_normalOnBInWorld;
            const btVector3& onB = closest.m_pointInWorld;
            const btScalar closing = (pointVelocity(w1->getCollisionObject(), onB) -
                                      pointVelocity(w0->getCollisionObject(), onB + n * closest.m_distance))
                                         .dot(n);
            if (closing * info.m_timeStep * kReachAllowance < closest.m_distance) {
                out->refreshContactPoints();
                return;
            }
            // One closest point of two parallel faces is one of their corners: a box landing flat on another
            // would be stopped at that corner alone and tipped over it. So the detector clips the faces with the
            // first box moved onto the second along the normal (by the distance and a little more), and each of
            // its points is reported at its distance now.
            const btScalar shift = closest.m_distance + kOverlapM;
            ShiftedResult shifted(*out, n, shift);
            input.m_transformA.getOrigin() -= n * shift;
            input.m_maximumDistanceSquared = BT_LARGE_FLOAT;
            detector.getClosestPoints(input, shifted, info.m_debugDraw);
            if (shifted.count == 0) out->addContactPoint(n, onB, closest.m_distance);
        }
        out->refreshContactPoints();
    }

  private:
    // The reach's allowance for the acceleration within the step (RagdollWorld's).
    static constexpr btScalar kReachAllowance = btScalar(1.25);
    // How far the clipping run pushes the boxes into each other, metres.
    static constexpr btScalar kOverlapM = btScalar(0.001);
};

struct CreateBoxBox : btCollisionAlgorithmCreateFunc {
    btCollisionAlgorithm* CreateCollisionAlgorithm(btCollisionAlgorithmConstructionInfo& ci,
                                                   const btCollisionObjectWrapper* w0,
                                                   const btCollisionObjectWrapper* w1) override {
        void* memory = ci.m_dispatcher1->allocateCollisionAlgorithm(sizeof(SpeculativeBoxBoxAlgorithm));
        return new (memory) SpeculativeBoxBoxAlgorithm(ci, w0, w1);
    }
};

} // namespace

btCollisionAlgorithmCreateFunc& speculativeBoxBoxCreateFunc() {
    static CreateBoxBox create;
    return create;
}

void useSpeculativeBoxBoxContacts(btCollisionDispatcher& dispatcher, bool on, btCollisionConfiguration& config) {
    dispatcher.registerCollisionCreateFunc(BOX_SHAPE_PROXYTYPE, BOX_SHAPE_PROXYTYPE,
                                           on ? &speculativeBoxBoxCreateFunc()
                                              : config.getCollisionAlgorithmCreateFunc(BOX_SHAPE_PROXYTYPE,
                                                                                       BOX_SHAPE_PROXYTYPE));
}

} // namespace afb::bullet::detail
