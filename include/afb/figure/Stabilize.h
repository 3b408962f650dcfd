#pragma once
// Mass and inertia stabilisation (opt-in): the approach of Jolt's Ragdoll::Stabilize, written here. A
// sequential-impulse solver converges slowly where a light body sits between heavy ones or a body's principal
// moments are far apart (a thin rod spins up about its long axis); evening out those ratios trades a little
// physical truth (which body carries how much of the figure's mass) for a solver that converges.
#include <string>
#include <vector>

#include "afb/figure/Figure.h"

namespace afb::figure {

/// The ratios stabilisation keeps a figure within.
struct StabilizeOptions {
    /// Across every constraint between two bodies, the heavier is at most this many times the lighter.
    double maxMassRatio = 10.0;
    /// In every body, the largest principal moment is at most this many times the smallest.
    double maxInertiaRatio = 10.0;
};

/// What stabilisation changed, one line per body ("l1: mass 1000 -> 190 kg, moments scaled 0.19").
struct StabilizeReport {
    std::vector<std::string> changes; ///< one line per changed body, in body order
    /// True when stabilisation changed any body.
    bool changed() const { return !changes.empty(); }
};

/// True when some constraint joins masses, or some body has principal moments, further apart than `options`
/// allow (what `afb inspect` reports as needing stabilisation).
bool needsStabilizing(const Figure& figure, const StabilizeOptions& options = {});

/// `figure` with its masses evened out along its constraints and its inertias clamped:
///  - masses: sweeps over the constraints (in figure order, 8 at most) move mass from the heavier body of a pair
///    whose ratio exceeds maxMassRatio to the lighter, keeping the pair's sum, until every pair is within it; the
///    total mass is unchanged and every body's inertia is scaled with its mass (same density);
///  - inertia: every principal moment is raised to at least the largest / maxInertiaRatio.
/// Centres of mass, shapes, frames and everything else are unchanged. Deterministic.
Figure stabilizeMassProperties(const Figure& figure, const StabilizeOptions& options = {},
                               StabilizeReport* report = nullptr);

} // namespace afb::figure
