#pragma once
// The part every contact algorithm of ours shares (HullPlaneCollision, BoxBoxCollision): it owns one persistent
// manifold for its pair, made by the dispatcher when the pair needs collision and released with the algorithm, and
// hands it to Bullet's compound algorithms through getAllContactManifolds.
#include <BulletCollision/CollisionDispatch/btActivatingCollisionAlgorithm.h>
#include <btBulletCollisionCommon.h>

namespace afb::bullet::detail {

class OwnedManifoldAlgorithm : public btActivatingCollisionAlgorithm {
  public:
    /// The manifold is made for (`body0`, `body1`) in that order (its body 0 is `body0`).
    OwnedManifoldAlgorithm(const btCollisionAlgorithmConstructionInfo& ci, const btCollisionObjectWrapper* w0,
                           const btCollisionObjectWrapper* w1, const btCollisionObject* body0,
                           const btCollisionObject* body1)
        : btActivatingCollisionAlgorithm(ci, w0, w1) {
        if (m_dispatcher->needsCollision(body0, body1)) m_manifold = m_dispatcher->getNewManifold(body0, body1);
    }
    ~OwnedManifoldAlgorithm() override {
        if (m_manifold != nullptr) m_dispatcher->releaseManifold(m_manifold);
    }
    OwnedManifoldAlgorithm(const OwnedManifoldAlgorithm&) = delete;
    OwnedManifoldAlgorithm& operator=(const OwnedManifoldAlgorithm&) = delete;

    btScalar calculateTimeOfImpact(btCollisionObject*, btCollisionObject*, const btDispatcherInfo&,
                                   btManifoldResult*) override {
        return 1; // not used by btDiscreteDynamicsWorld
    }
    void getAllContactManifolds(btManifoldArray& manifolds) override {
        if (m_manifold != nullptr) manifolds.push_back(m_manifold);
    }

  protected:
    btPersistentManifold* m_manifold = nullptr;
};

} // namespace afb::bullet::detail
