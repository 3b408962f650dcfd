#include "afb/figure/Load.h"

#include <cstdlib>

#include "afb/decl/AfParser.h"
#include "afb/decl/Md5Anim.h"
#include "afb/detail/Lexer.h"

namespace afb::figure {

std::optional<LoadedFigure> loadFigureFiles(const std::filesystem::path& afFile, std::string_view figureName,
                                            const std::filesystem::path& meshFile,
                                            const std::filesystem::path& afPoseFile, const Eigen::Vector3d& offset,
                                            const UnitSystem& units, text::Diagnostics& diagnostics,
                                            RootTranslation rootTranslation, bool strict) {
    std::optional<decl::AfFile> af = decl::loadAf(afFile, diagnostics);
    std::optional<decl::Md5Mesh> mesh = decl::loadMd5Mesh(meshFile, diagnostics);
    std::optional<decl::Md5Anim> pose = decl::loadMd5Anim(afPoseFile, diagnostics);
    if (!af || !mesh || !pose) return std::nullopt;
    const decl::AfDecl* chosen = nullptr;
    for (const decl::AfDecl& d : af->decls)
        if (figureName.empty() || text::equalsIgnoreCase(d.name, figureName)) {
            chosen = &d;
            break;
        }
    if (!chosen) {
        diagnostics.error({afFile.string(), 0, 0}, figureName.empty() ? "no articulatedFigure in the file"
                                                                      : "no articulatedFigure named '" +
                                                                            std::string(figureName) + "' in the file");
        return std::nullopt;
    }
    std::optional<Skeleton> skeleton =
        Skeleton::build(*mesh, *pose, offset, diagnostics, afPoseFile.string(), rootTranslation);
    if (!skeleton) return std::nullopt;
    std::optional<Figure> figure = buildFigure({chosen, &*skeleton, units, strict}, diagnostics);
    if (!figure) return std::nullopt;
    return LoadedFigure{std::move(*figure), std::move(*mesh), *chosen, afFile};
}

std::optional<LoadedFigure> loadEntityFigure(const decl::Library& library, std::string_view entity,
                                             const UnitSystem& units, text::Diagnostics& diagnostics, bool strict) {
    const std::optional<decl::ResolvedEntity> r = library.resolveEntity(entity, diagnostics);
    if (!r) return std::nullopt;
    Eigen::Vector3d offset = Eigen::Vector3d::Zero();
    if (r->model.offset) offset = {r->model.offset->x, r->model.offset->y, r->model.offset->z};
    // docs/format.md §2.1: actors ("ragdoll") replace the root translation by the offset; AF entities add it.
    const RootTranslation root =
        r->figureKey == "ragdoll" ? RootTranslation::ReplacedByOffset : RootTranslation::OffsetAdded;
    std::optional<LoadedFigure> loaded = loadFigureFiles(r->figureFile, r->figureName, r->meshPath, r->afPosePath,
                                                         offset, units, diagnostics, root, strict);
    if (loaded) {
        auto on = [&](std::string_view key) {
            const std::optional<std::string> v = r->get(key);
            return v && !v->empty() && std::atof(v->c_str()) != 0.0;
        };
        loaded->startAtRest = on("nodrop") || on("sleep");
    }
    return loaded;
}

} // namespace afb::figure
