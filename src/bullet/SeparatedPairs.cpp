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
        if (m_manifold != nullptr && m_manifold->getNumContacts() == 0) {
            if (stillApart(w0, w1) || apart(w0, w1)) return;
        }
        m_gap = -1; // the pair may touch: the next step tests it afresh
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
        if (!(gap > m_manifold->getContactBreakingThreshold() + kSafetyM)) {
            m_gap = -1;
            return false;
        }
        m_gap = gap;
        m_object0 = w0->getCollisionObject();
        // Kept to bound the motion since this test (stillApart).
        m_axis = axis;
        m_at0 = t0;
        m_at1 = t1;
        m_reach0 = reach(*shape0);
        m_reach1 = reach(*shape1);
        return true;
    }

    // Whether the gap found by the last apart() along its axis is still wider than the threshold, from how far the
    // bodies have moved since, without a support point. Along a fixed axis a, a point p of a shape (local, |p| ≤
    // the shape's reach r) moves from o + R p to o' + R' p: by a·(o' − o) + a·((R' − R) p), the second term at
    // most ‖R' − R‖ r (the Frobenius norm bounds the spectral one). So the gap shrinks by at most
    // a·(Δo₀ − Δo₁) + ‖ΔR₀‖ r₀ + ‖ΔR₁‖ r₁: a pair falling or turning together keeps its gap.
    // The threshold is the manifold's now: speculative contacts widen it with the bodies' speeds.
    bool stillApart(const btCollisionObjectWrapper* w0, const btCollisionObjectWrapper* w1) const {
        if (!(m_gap > 0) || w0->getCollisionObject() != m_object0) return false;
        const btTransform& t0 = w0->getWorldTransform();
        const btTransform& t1 = w1->getWorldTransform();
        const btScalar closing =
            m_axis.dot((t0.getOrigin() - m_at0.getOrigin()) - (t1.getOrigin() - m_at1.getOrigin()));
        const btScalar shrink = closing + rotationNorm(t0.getBasis(), m_at0.getBasis()) * m_reach0 +
                                rotationNorm(t1.getBasis(), m_at1.getBasis()) * m_reach1;
        // The 1 mm of kSafetyM covers the rounding of the bound too.
        return m_gap - shrink > m_manifold->getContactBreakingThreshold() + kSafetyM;
    }

    static btScalar rotationNorm(const btMatrix3x3& a, const btMatrix3x3& b) {
        btScalar sum = 0;
        for (int i = 0; i < 3; ++i) sum += (a[i] - b[i]).length2();
        return btSqrt(sum);
    }

    // The farthest any point of the shape (its margin included) lies from its own origin, metres.
    static btScalar reach(const btConvexShape& shape) {
        btVector3 centre;
        btScalar radius;
        shape.getBoundingSphere(centre, radius);
        return centre.length() + radius;
    }

    // Rounding allowance on the gap, metres.
    static constexpr btScalar kSafetyM = btScalar(0.001);

    btCollisionAlgorithm* m_inner;
    const btPersistentManifold* m_manifold = nullptr; // the inner algorithm's, once it has run
    // The last apart() that held: its gap (negative: none holds), along which axis, at which transforms, and the
    // shapes' reaches (mutable: the test is a cache of a const question).
    mutable btScalar m_gap = -1;
    mutable const btCollisionObject* m_object0 = nullptr;
    mutable btVector3 m_axis;
    mutable btTransform m_at0, m_at1;
    mutable btScalar m_reach0 = 0, m_reach1 = 0;
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
        // Not from the dispatcher's pool: its elements are sized for Bullet's own algorithms, and this one (which
        // keeps two transforms) may be larger. The dispatcher frees what its pool did not hand out with btAlignedFree.
        void* memory = btAlignedAlloc(sizeof(SeparatedPairAlgorithm), 16);
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
