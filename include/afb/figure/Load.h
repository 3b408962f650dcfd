#pragma once
// Loading a figure end to end: entityDef (through decl::Library) or explicit files → skeleton → Figure.
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "afb/decl/Library.h"
#include "afb/decl/Md5Mesh.h"
#include "afb/figure/Figure.h"

namespace afb::figure {

/// A built figure with the inputs it came from (the mesh is kept for skinning).
struct LoadedFigure {
    Figure figure;                ///< the built figure, SI units
    decl::Md5Mesh mesh;           ///< the md5mesh the skeleton came from
    decl::AfDecl decl;            ///< the articulatedFigure decl as parsed
    std::filesystem::path afFile; ///< where the decl came from
    /// The entity asks to spawn at rest until touched: `"nodrop" "1"` (the engine's key) or `"sleep" "1"` (the
    /// id modding page's spelling). Always false for loadFigureFiles.
    bool startAtRest = false;
};

/// Resolves `entity` in `library` (inherit chain, model decl, mesh, af_pose, figure) and builds its figure.
/// Parse errors, resolution errors and figure findings all go to `diagnostics`; nullopt on any error. `strict`:
/// see FigureInput::strict.
std::optional<LoadedFigure> loadEntityFigure(const decl::Library& library, std::string_view entity,
                                             const UnitSystem& units, text::Diagnostics& diagnostics,
                                             bool strict = false);

/// Explicit files: a figure decl named `figureName` in `afFile` (the first decl when empty), on `meshFile` posed
/// by `afPoseFile`, with the model decl's visual `offset` (Doom units).
std::optional<LoadedFigure> loadFigureFiles(const std::filesystem::path& afFile, std::string_view figureName,
                                            const std::filesystem::path& meshFile,
                                            const std::filesystem::path& afPoseFile, const Eigen::Vector3d& offset,
                                            const UnitSystem& units, text::Diagnostics& diagnostics,
                                            RootTranslation rootTranslation = RootTranslation::OffsetAdded,
                                            bool strict = false);

} // namespace afb::figure
