#pragma once
// Loads an entity's figure from a content folder for tests, failing the test with the diagnostics when it
// does not load.
#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <optional>
#include <string>

#include <LinearMath/btTransform.h>

#include "TestSupport.h"
#include "afb/decl/Library.h"
#include "afb/figure/Load.h"

namespace afb::test {

/// `entity` of the content folder `base` (default: the repository's bundled content), built in SI units.
inline figure::LoadedFigure loadEntity(const std::string& entity, const std::filesystem::path& base = sourceDir()) {
    text::Diagnostics diags;
    std::optional<figure::LoadedFigure> loaded;
    if (auto lib = decl::Library::open(base, diags)) loaded = figure::loadEntityFigure(*lib, entity, {}, diags);
    INFO(diags.str());
    REQUIRE(loaded);
    return std::move(*loaded);
}

/// The figure's load pose upright with its lowest point `height` metres above the ground at (x, y).
inline btTransform standing(const figure::Figure& f, double x, double y, double height = 0.001) {
    double lowest = 1e9;
    for (const figure::FigureBody& b : f.bodies)
        for (const Eigen::Vector3d& v : b.shape.vertices) lowest = std::min(lowest, b.loadPose.apply(v).z());
    return btTransform(btQuaternion::getIdentity(), btVector3(btScalar(x), btScalar(y), btScalar(height - lowest)));
}

} // namespace afb::test
