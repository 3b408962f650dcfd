#pragma once
// What every ragdoll representation measures the same way: body states, how far a figure constraint is from holding,
// and whether the figure is at rest by its own rules (docs/format.md §6.1). bullet::Ragdoll uses them, and so does the
// tools library's plain-Bullet reference (sim::RawRagdoll), so both are judged by one definition. Public but internal
// in spirit (not part of afb/afb.h).
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include <btBulletDynamicsCommon.h>

#include "afb/figure/Figure.h"
#include "afb/figure/Placement.h"

namespace afb::bullet {

/// How far a figure constraint is from holding now.
struct JointError {
    double anchorM = 0;        ///< separation of the two anchor copies (sliders: off the axis only); 0 for springs
    double limitExcessRad = 0; ///< how far a cone, pyramid or hinge limit is exceeded; 0 inside or without one
};

/// A ragdoll's bodies in figure body order (bullet::Ragdoll's and sim::RawRagdoll's).
using BodyList = std::span<btRigidBody* const>;

/// One body's state as any backend can give it (a btMultiBody link has no btRigidBody): the body frame (centre
/// of mass, principal axes) and its velocities, world.
struct BodySample {
    btTransform transform;
    btVector3 linearVelocity;  ///< of the centre of mass, m/s
    btVector3 angularVelocity; ///< rad/s
};

/// The constraint frame of constraint `c` as attached to body1 and to body2 (or the world), world space now, from
/// `frames`: the frame in body1's frame and in body2's frame (world for a world constraint).
std::pair<btTransform, btTransform> constraintFramesWorldOf(const figure::FigureConstraint& c, BodyList bodies,
                                                            const std::pair<btTransform, btTransform>& frames);

/// The error of constraint `c` (frames as for constraintFramesWorldOf; `spawn`: the entity transform, whose
/// rotation stands for body2's in a world constraint): the distance of the two frames' origins, and
/// figure::limitExcessRad in double.
JointError jointErrorOf(const figure::FigureConstraint& c, BodyList bodies,
                        const std::pair<btTransform, btTransform>& frames, const btTransform& spawn);

/// The same two, from the bodies' world transforms (body frames) in figure body order.
std::pair<btTransform, btTransform> constraintFramesWorldOf(const figure::FigureConstraint& c,
                                                            std::span<const btTransform> bodies,
                                                            const std::pair<btTransform, btTransform>& frames);
JointError jointErrorOf(const figure::FigureConstraint& c, std::span<const btTransform> bodies,
                        const std::pair<btTransform, btTransform>& frames, const btTransform& spawn);

/// World transforms of the bodies (body frames: centre of mass, principal axes), metres.
std::vector<figure::Transform> bodyTransformsOf(BodyList bodies);
/// World transforms and velocities of the bodies.
std::vector<figure::BodyState> bodyStatesOf(BodyList bodies);
/// Bodies Bullet is simulating now (not asleep).
int awakeCountOf(BodyList bodies);

/// The engine's TestIfAtRest (docs/format.md §6.1) over a figure's bodies, one call per simulation step: speeds and
/// accelerations under the suspend speeds, or no body moved more than noMoveTranslation / noMoveRotation over a
/// noMoveTime window, within the min/max move times.
class RestTest {
  public:
    explicit RestTest(const figure::RestRules& rules) : m_rules(rules) {}

    /// After a step of `dtSeconds`, `activeSeconds` after the figure last woke: true when the rules say the
    /// bodies (in figure body order) are at rest now.
    bool update(BodyList bodies, double dtSeconds, double activeSeconds);
    /// The same from body samples (any backend), in figure body order.
    bool update(std::span<const BodySample> bodies, double dtSeconds, double activeSeconds);
    /// Forgets the window and the previous velocities (the figure woke).
    void reset();

  private:
    template <class Get>
    bool updateWith(std::size_t count, const Get& get, double dtSeconds, double activeSeconds);

    figure::RestRules m_rules;
    double m_windowStart = -1;
    std::vector<btTransform> m_window;
    std::vector<std::pair<btVector3, btVector3>> m_previous;
    bool m_havePrevious = false;
};

} // namespace afb::bullet
