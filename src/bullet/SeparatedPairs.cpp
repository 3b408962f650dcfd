// Convex pairs that are plainly apart skip the narrow phase (SeparatedPairs.h).
#include "SeparatedPairs.h"

#include <utility>

#include <BulletCollision/CollisionDispatch/btCollisionObjectWrapper.h>

#include "BoxBoxCollision.h"

namespace afb::bullet::detail {
namespace {

// Bullet's convex–convex algorithm behind a separating-axis test.
class SeparatedPairAlgorithm : public btCollisionAlgorithm {
  public:
    SeparatedPairAlgorithm(const btCollisionAlgorithmConstructionInfo& ci, btCollisionAlgorithm* inner)
        : btCollisionAlgorithm(ci), m_inner(inner) {}
    ~SeparatedPairAlgorithm() override {
        m_inner->~btCollisionAlgorithm();
        m_dispatcher->freeCollisionAlgorithm(m_inner);
    }
    SeparatedPairAlgorithm(const SeparatedPairAlgorithm&) = delete;
    SeparatedPairAlgorithm& operator=(const SeparatedPairAlgorithm&) = delete;

    void processCollision(const btCollisionObjectWrapper* w0, const btCollisionObjectWrapper* w1,
                          const btDispatcherInfo& info, btManifoldResult* out) override {
        if (m_manifold != nullptr && m_manifold->getNumContacts() == 0 && apart(w0, w1)) return;
        m_inner->processCollision(w0, w1, info, out);
        m_manifold = out->getPersistentManifold();
    }

    btScalar calculateTimeOfImpact(btCollisionObject* a, btCollisionObject* b, const btDispatcherInfo& info,
                                   btManifoldResult* out) override {
        return m_inner->calculateTimeOfImpact(a, b, info, out);
    }
    void getAllContactManifolds(btManifoldArray& manifolds) override { m_inner->getAllContactManifolds(manifolds); }

  private:
    // Whether the shapes are farther apart along the line between their centres than the manifold keeps points
    // at: btManifoldResult drops a point deeper than the breaking threshold, and the depth GJK reports is never
    // less than the true distance (it approaches it from above). The gap along one axis is at most the distance.
    bool apart(const btCollisionObjectWrapper* w0, const btCollisionObjectWrapper* w1) const {
        const auto* shape0 = static_cast<const btConvexShape*>(w0->getCollisionShape());
        const auto* shape1 = static_cast<const btConvexShape*>(w1->getCollisionShape());
        const btTransform& t0 = w0->getWorldTransform();
        const btTransform& t1 = w1->getWorldTransform();
        btVector3 axis = t1.getOrigin() - t0.getOrigin();
        const btScalar length2 = axis.length2();
        if (!(length2 > SIMD_EPSILON)) return false;
        axis /= btSqrt(length2);
        const btVector3 far0 = t0(shape0->localGetSupportingVertex(axis * t0.getBasis()));
        const btVector3 near1 = t1(shape1->localGetSupportingVertex(-axis * t1.getBasis()));
        const btScalar gap = axis.dot(near1 - far0);
        return gap > m_manifold->getContactBreakingThreshold() + kSafetyM;
    }

    // Rounding allowance on the gap, metres.
    static constexpr btScalar kSafetyM = btScalar(0.001);

    btCollisionAlgorithm* m_inner;
    const btPersistentManifold* m_manifold = nullptr; // the inner algorithm's, once it has run
};

// Constant once made, so one object serves every world: the algorithm behind the test is `inner`'s, or, without
// one, Bullet's from the creating dispatcher's own configuration (the world being built) for the pair's shapes.
struct CreateSeparatedPair : btCollisionAlgorithmCreateFunc {
    explicit CreateSeparatedPair(btCollisionAlgorithmCreateFunc* innerCreate = nullptr) : inner(innerCreate) {}
    btCollisionAlgorithm* CreateCollisionAlgorithm(btCollisionAlgorithmConstructionInfo& ci,
                                                   const btCollisionObjectWrapper* w0,
                                                   const btCollisionObjectWrapper* w1) override {
        auto* dispatcher = static_cast<btCollisionDispatcher*>(ci.m_dispatcher1);
        btCollisionAlgorithmCreateFunc* create =
            inner ? inner
                  : dispatcher->getCollisionConfiguration()->getCollisionAlgorithmCreateFunc(
                        w0->getCollisionShape()->getShapeType(), w1->getCollisionShape()->getShapeType());
        btCollisionAlgorithm* wrapped = create->CreateCollisionAlgorithm(ci, w0, w1);
        void* memory = dispatcher->allocateCollisionAlgorithm(sizeof(SeparatedPairAlgorithm));
        return new (memory) SeparatedPairAlgorithm(ci, wrapped);
    }
    btCollisionAlgorithmCreateFunc* const inner;
};

} // namespace

void useSeparatedPairSkip(btCollisionDispatcher& dispatcher, bool on, btCollisionConfiguration& config,
                          bool speculativeBoxes) {
    static CreateSeparatedPair bulletOwn, speculative(&speculativeBoxBoxCreateFunc());
    constexpr int kHull = CONVEX_HULL_SHAPE_PROXYTYPE, kBox = BOX_SHAPE_PROXYTYPE;
    for (auto [t0, t1] : {std::pair{kHull, kHull}, {kHull, kBox}, {kBox, kHull}})
        dispatcher.registerCollisionCreateFunc(t0, t1,
                                               on ? &bulletOwn : config.getCollisionAlgorithmCreateFunc(t0, t1));
    // Boxes against boxes: in front of whichever algorithm useSpeculativeBoxBoxContacts installed.
    if (on) dispatcher.registerCollisionCreateFunc(kBox, kBox, speculativeBoxes ? &speculative : &bulletOwn);
}

} // namespace afb::bullet::detail
