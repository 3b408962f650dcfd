#pragma once
// Loads an entity's figure from a content folder for tests, failing the test with the diagnostics when it
// does not load.
#include <catch2/catch.hpp>

#include <filesystem>
#include <optional>
#include <string>

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

} // namespace afb::test
