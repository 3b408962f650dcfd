#pragma once
// Levels of detail of a figure: its bodies partitioned into groups, each group simulated as one rigid
// body (bullet::Ragdoll::setLod). Engine-neutral: which bodies go together, from a caller's list or by mass.
#include <string>
#include <variant>
#include <vector>

#include "afb/figure/Figure.h"

namespace afb::figure {

/// A level of detail: every body of the figure in exactly one group. Each group is ascending, the groups are
/// ordered by their first body, and bodies joined by a `fixed` constraint share a group at every level.
struct LodLevel {
    std::vector<std::vector<int>> groups; ///< body indices (into Figure::bodies) per group
    /// Equal when the groups are.
    friend bool operator==(const LodLevel&, const LodLevel&) = default;
};

/// A caller's level: groups of body names (case-sensitive, as the .af names them). Bodies not named stay alone
/// (or with the bodies a `fixed` constraint joins them to). An error message instead when a name is unknown, a body
/// is named more than once, or a group's bodies are not connected by the figure's constraints between them.
std::variant<LodLevel, std::string> lodFromNames(const Figure& figure,
                                                 const std::vector<std::vector<std::string>>& groups);

/// The automatic level of `targetBodies` rigid bodies: starting from the bodies (with `fixed` constraints merged),
/// the lightest group (ties: the one with the lowest first body) is merged into the lightest group a constraint
/// joins it to (ties: lowest first body), until `targetBodies` groups remain or no group has a neighbour left.
/// The bundled humanoid at 6: pelvis, torso + head, each arm, each leg.
LodLevel automaticLod(const Figure& figure, int targetBodies);

} // namespace afb::figure
