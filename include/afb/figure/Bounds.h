#pragma once
// The numeric bounds a figure must keep before it reaches a physics engine (docs/stability.md).
// Outside them a value is either an error (it cannot be simulated) or repaired with a warning that says what was
// changed (FigureInput::strict turns every repair into an error). SI units; the figure converts once.
namespace afb::figure {

/// Thinnest body extent along any of its shape's axes, metres. A thinner positive extent (a bone width of 1e-7,
/// box bounds 1e-30 apart) is raised to this about the shape's centre: float collision (GJK on a hull whose
/// points nearly coincide) fails on thinner shapes.
inline constexpr double kMinThicknessM = 0.001;
/// Largest body extent and largest distance of any body or anchor from the model origin, metres (error beyond:
/// float positions lose millimetres past a few hundred metres, and no figure is that large).
inline constexpr double kMaxFigureExtentM = 100.0;
/// Lightest body mass after density, inertiaScale and totalMass, kg (error below).
inline constexpr double kMinBodyMassKg = 0.01;
/// Heaviest body mass after density, inertiaScale and totalMass, kg (error above).
inline constexpr double kMaxBodyMassKg = 1.0e5;
/// Smallest principal moment relative to the body's largest one. A smaller positive moment is raised to this
/// fraction of the largest (an inertia floor, as Jolt's ragdoll Stabilize does); a moment <= 0 is an error.
inline constexpr double kMinInertiaRatio = 1.0e-3;
/// Largest principal moment as a multiple of mass × (the body's radius about its centre of mass)², which no
/// solid exceeds; inertiaScale may add up to this factor, beyond it is an error (float overflows in the solver).
inline constexpr double kMaxInertiaOverMassRadius2 = 100.0;
/// Largest contact friction (Coulomb coefficient); larger values are clamped.
inline constexpr double kMaxContactFriction = 10.0;
/// Largest joint friction coefficient; larger values are clamped.
inline constexpr double kMaxJointFriction = 10.0;
/// Largest spring stiffness, N/m² (the engine's quadratic law in SI); larger values are errors: an explicit
/// quadratic spring that stiff gains energy every step and overflows.
inline constexpr double kMaxSpringStiffness = 1.0e6;
/// Largest spring damping, N·s/m; larger values are errors, for the same reason as kMaxSpringStiffness.
inline constexpr double kMaxSpringDamping = 1.0e5;

} // namespace afb::figure
