#pragma once
// An indexed content folder (Doom's `base/`: `af/`, `def/`, `models/`) and the resolution of an entity to
// what a ragdoll needs: merged keys, model decl, mesh, af_pose anim and articulated figure (docs/format.md §7).
#include <cstddef>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "afb/decl/Af.h"
#include "afb/decl/Def.h"
#include "afb/text/Diagnostics.h"

namespace afb::decl {

/// A model decl with its `inherit` chain applied.
struct ResolvedModel {
    /// Mesh/skin/offset inherited unless overridden; channels and anims merged (a child's anim of an
    /// inherited name replaces it in place, new ones are appended), `remove`s applied; `inherit` and
    /// `removes` are empty. Name and location are the requested decl's.
    ModelDef model;
    /// The decl and its ancestors, child first.
    std::vector<std::string> chain;
    /// Equal when they say the same thing; source locations never count.
    bool operator==(const ResolvedModel&) const = default;
};

/// An entityDef followed through its `inherit` chain to its model decl, mesh, af_pose and figure.
struct ResolvedEntity {
    /// The entityDef's name as written in its decl.
    std::string entityName;
    /// Where the entityDef starts.
    SourceLocation entityLocation;
    /// The entityDef and every entityDef it inherits from, in merge priority (child first, each once).
    std::vector<std::string> entityChain;
    /// Merged keys: the child's, then each inherited key it lacks (idDict::SetDefaults); no `inherit*` keys.
    std::vector<std::pair<std::string, std::string>> keyValues;

    /// The model decl named by the `"model"` key, as written in that decl.
    std::string modelName;
    /// Where that model decl starts.
    SourceLocation modelLocation;
    /// The model decl and its `inherit` ancestors, child first.
    std::vector<std::string> modelChain;
    /// The model decl with inheritance applied (ResolvedModel::model).
    ModelDef model;

    /// Absolute path of the mesh (content folder / `mesh`); the file exists.
    std::filesystem::path meshPath;
    /// The anim used as af_pose: `af_pose` itself, else the first of its random variants (`af_pose1`, …).
    std::string afPoseAnim;
    /// Absolute path of that anim's first file; the file exists.
    std::filesystem::path afPosePath;

    /// The key the figure came from: `articulatedFigure` or `ragdoll`.
    std::string figureKey;
    /// The articulatedFigure decl's name as written in its decl.
    std::string figureName;
    /// Where that decl starts.
    SourceLocation figureLocation;
    /// Absolute path of the `.af` file holding it.
    std::filesystem::path figureFile;

    /// Equal when they say the same thing; source locations never count.
    bool operator==(const ResolvedEntity&) const = default;

    /// Merged value of `key` (case-insensitive), or nullopt.
    std::optional<std::string> get(std::string_view key) const;
};

/// A decl held by the Library and the file it came from. Valid while the Library lives.
template <class Decl>
struct LibraryEntry {
    /// The decl as parsed.
    const Decl& decl;
    /// Absolute path of its file.
    const std::filesystem::path& file;
};

/// A content folder's `af/*.af` and `def/*.def`, parsed once and indexed by decl name (case-insensitive, as
/// the engine's decl manager). Immutable after `open`; no global state, no printing, no I/O after `open`
/// except the existence checks of `resolveEntity`.
class Library {
  public:
    /// Parses every `af/*.af` and `def/*.def` directly in those folders (not recursive, like the engine's
    /// decl folders), in sorted path order. A file with a parse error is reported and left out (none of its
    /// decls is indexed), and the others are still indexed: `open` fails only when `baseDir` is not a
    /// readable folder. Duplicate decl names (case-insensitive) are warned about with both locations; the
    /// first one in path order wins, as in the engine.
    static std::optional<Library> open(const std::filesystem::path& baseDir, text::Diagnostics& diagnostics);

    /// The content folder, absolute.
    const std::filesystem::path& baseDir() const { return m_baseDir; }
    /// Files indexed, `af/` files then `def/` files, each group sorted.
    const std::vector<std::filesystem::path>& files() const { return m_files; }
    /// Files left out because they failed to read or parse.
    const std::vector<std::filesystem::path>& failedFiles() const { return m_failedFiles; }

    /// The entityDef named `name` (case-insensitive).
    std::optional<LibraryEntry<EntityDef>> findEntityDef(std::string_view name) const;
    /// The model decl named `name` (case-insensitive).
    std::optional<LibraryEntry<ModelDef>> findModelDef(std::string_view name) const;
    /// The articulatedFigure decl named `name` (case-insensitive).
    std::optional<LibraryEntry<AfDecl>> findFigure(std::string_view name) const;

    /// Names of every indexed entityDef as written, sorted case-insensitively.
    std::vector<std::string> entityDefNames() const;
    /// Names of every indexed model decl as written, sorted case-insensitively.
    std::vector<std::string> modelDefNames() const;
    /// Names of every indexed articulatedFigure decl as written, sorted case-insensitively.
    std::vector<std::string> figureNames() const;

    /// The model decl `name` with its `inherit` chain applied (see ResolvedEntity::model); nullopt with
    /// errors for an unknown or missing parent, a cycle, a `remove` that matches no inherited anim, a
    /// duplicate anim that is not an override, or no mesh.
    std::optional<ResolvedModel> resolveModel(std::string_view name, text::Diagnostics& diagnostics) const;

    /// Follows entityDef `name` to everything a ragdoll needs. Errors (each reported, then nullopt): unknown
    /// entity, missing or cyclic `inherit`, no `"model"` key or no model decl of that name, model errors,
    /// no `af_pose` anim, no figure key, unknown figure, a path that leaves the content folder, a missing
    /// file. The figure comes from `"articulatedFigure"` when set, else from `"ragdoll"` (any extension
    /// stripped, as idAF::Load does); when both are set and differ, a warning says which was used.
    std::optional<ResolvedEntity> resolveEntity(std::string_view name, text::Diagnostics& diagnostics) const;

  private:
    struct DeclRef {
        std::size_t file = 0; ///< index into m_afFiles or m_defFiles
        std::size_t decl = 0; ///< index into that file's decls / entityDefs / models
    };
    using Index = std::map<std::string, DeclRef, std::less<>>; // key: lower-cased name

    struct AfSource {
        std::filesystem::path path;
        AfFile content;
    };
    struct DefSource {
        std::filesystem::path path;
        DefFile content;
    };

    Library() = default;
    void indexFile(const AfSource& source, std::size_t fileIndex, text::Diagnostics& diagnostics);
    void indexFile(const DefSource& source, std::size_t fileIndex, text::Diagnostics& diagnostics);
    // resolveEntity's steps; each reports its own errors and returns false when it found one.
    bool mergeEntityKeys(const EntityDef& entity, ResolvedEntity& r, text::Diagnostics& diagnostics) const;
    bool resolveEntityModel(const EntityDef& entity, ResolvedEntity& r, text::Diagnostics& diagnostics) const;
    bool resolveAfPose(ResolvedEntity& r, text::Diagnostics& diagnostics) const;
    bool resolveEntityFigure(const EntityDef& entity, ResolvedEntity& r, text::Diagnostics& diagnostics) const;
    std::optional<std::filesystem::path> contentPath(const std::string& relative, const std::string& what,
                                                     const SourceLocation& where, text::Diagnostics& diagnostics) const;

    std::filesystem::path m_baseDir;
    std::vector<std::filesystem::path> m_files;
    std::vector<std::filesystem::path> m_failedFiles;
    std::vector<AfSource> m_afFiles;
    std::vector<DefSource> m_defFiles;
    Index m_entityDefs, m_modelDefs, m_figures;
};

} // namespace afb::decl
