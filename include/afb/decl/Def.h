#pragma once
// `.def` files (docs/format.md §7.1, §7.2): `entityDef` key/value decls and `model` decls, as the file says them.
// Inheritance is not applied here; `decl::Library` resolves it.
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "afb/decl/Af.h"
#include "afb/text/Diagnostics.h"

namespace afb::decl {

/// One `entityDef name { "key" "value" ... }` decl (idDeclEntityDef), keys as written and in file order.
struct EntityDef {
    /// Decl name as written (looked up case-insensitively).
    std::string name;
    /// Where the decl starts.
    SourceLocation location;
    /// Every key/value pair in file order, duplicates included; `inherit` keys are kept (the Library merges
    /// them).
    std::vector<std::pair<std::string, std::string>> keyValues;
    /// Equal when they say the same thing; source locations never count.
    bool operator==(const EntityDef&) const = default;

    /// Value of `key` (ASCII case-insensitive, as idDict); of several, the last one written wins.
    std::optional<std::string> get(std::string_view key) const;
    /// True when `key` is present (case-insensitive).
    bool has(std::string_view key) const { return get(key).has_value(); }
};

/// `channel <torso|legs|head|eyelids> ( joint list )` of a model decl.
struct ModelChannel {
    /// Channel name as written (compared case-insensitively).
    std::string name;
    /// The joint list in containedJoints syntax, tokens joined as the engine joins them: "*Waist -*Hips
    /// SPINNER".
    std::string joints;
    /// Where the `channel` keyword is.
    SourceLocation location;
    /// Equal when they say the same thing; source locations never count.
    bool operator==(const ModelChannel&) const = default;
};

/// `anim <name> <file>[, <file2>[, <file3>]] [{ ... }]` of a model decl.
struct ModelAnim {
    /// Anim name as written (case-sensitive); a digit suffix makes it a random variant of its alias.
    std::string name;
    /// One to three synced `.md5anim` paths, relative to the content folder.
    std::vector<std::string> files;
    /// The text between the `{` and `}` of the frame-command block, verbatim; nullopt without a block.
    std::optional<std::string> block;
    /// Where the `anim` keyword is.
    SourceLocation location;
    /// Equal when they say the same thing; source locations never count.
    bool operator==(const ModelAnim&) const = default;

    /// The engine's alias: the name without its digit suffix (`pain2` → `pain`).
    std::string alias() const;
};

/// One `model name { ... }` decl (idDeclModelDef), only the statements it wrote (inheritance not applied).
struct ModelDef {
    /// Decl name as written (looked up case-insensitively).
    std::string name;
    /// Where the decl starts.
    SourceLocation location;
    /// `inherit <model>`: the model decl this one copies first.
    std::optional<std::string> inherit;
    /// `skin <skinDecl>`.
    std::optional<std::string> skin;
    /// `mesh <path.md5mesh>`, relative to the content folder.
    std::optional<std::string> mesh;
    /// `offset ( x y z )`: visual offset added to joint 0, Doom units.
    std::optional<Vec3> offset;
    /// `channel` statements in file order.
    std::vector<ModelChannel> channels;
    /// `anim` statements in file order.
    std::vector<ModelAnim> anims;
    /// `remove <anim>` statements in file order (each deletes inherited anims by name or alias).
    std::vector<std::string> removes;
    /// Equal when they say the same thing; source locations never count.
    bool operator==(const ModelDef&) const = default;

    /// The anim named exactly `name` (case-sensitive), or nullptr.
    const ModelAnim* findAnim(std::string_view name) const;
};

/// Everything a `.def` file holds that afbullet reads; other decl types are skipped.
struct DefFile {
    /// `entityDef` decls (and untyped decls, which default to entityDef) in file order.
    std::vector<EntityDef> entityDefs;
    /// `model` decls in file order.
    std::vector<ModelDef> models;
    /// Equal when they say the same thing; source locations never count.
    bool operator==(const DefFile&) const = default;
};

/// Parses `.def` text. `entityDef` and `model` decls are read; `export`, `skin`, `table`, `material` and
/// other decl types are skipped silently. On any error: nullopt with `file:line:col` errors — nothing is
/// half-loaded. Duplicate entityDef keys and other tolerated oddities are reported as warnings.
std::optional<DefFile> parseDef(std::string_view text, const std::string& fileName, text::Diagnostics& diagnostics);

/// Reads and parses one `.def` file (locations name `path` as given).
std::optional<DefFile> loadDef(const std::filesystem::path& path, text::Diagnostics& diagnostics);

/// True for the channel names a `channel` statement accepts (torso, legs, head, eyelids; case-insensitive).
/// `all` is not one of them: idDeclModelDef::Parse starts its search after ANIMCHANNEL_ALL.
bool isModelChannelName(std::string_view name);

/// idDeclModelDef::ParseAnim's name rule: some character after the first must not be a digit. So empty and
/// one-character names, purely numeric names and names like `a1` or `x12` are rejected by the engine.
bool isValidAnimName(std::string_view name);

} // namespace afb::decl
