#include "afb/decl/Library.h"

#include <algorithm>
#include <set>

#include "afb/decl/AfParser.h"
#include "afb/detail/Lexer.h"

namespace afb::decl {
namespace fs = std::filesystem;

namespace {

bool startsWithIgnoreCase(std::string_view s, std::string_view prefix) {
    return s.size() >= prefix.size() && text::equalsIgnoreCase(s.substr(0, prefix.size()), prefix);
}

// Regular files directly in `dir` whose extension is `extension` (case-insensitive), sorted; nullopt when
// `dir` does not exist. Unreadable folders are reported and give what could be listed.
std::optional<std::vector<fs::path>> listFiles(const fs::path& dir, std::string_view extension,
                                               text::Diagnostics& diagnostics) {
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) return std::nullopt;
    std::vector<fs::path> out;
    fs::directory_iterator it(dir, ec);
    for (; !ec && it != fs::directory_iterator(); it.increment(ec)) {
        std::error_code typeError;
        if (!it->is_regular_file(typeError)) continue;
        if (text::equalsIgnoreCase(it->path().extension().string(), extension)) out.push_back(it->path());
    }
    if (ec) diagnostics.error({dir.string(), 0, 0}, "cannot list folder: " + ec.message());
    std::sort(out.begin(), out.end());
    return out;
}

// idStr::StripFileExtension: everything from the last '.' on.
std::string stripExtension(std::string name) {
    const auto dot = name.rfind('.');
    if (dot != std::string::npos) name.erase(dot);
    return name;
}

std::optional<std::string> nonEmpty(std::optional<std::string> value) {
    if (value && value->empty()) return std::nullopt;
    return value;
}

// Key lookup shared by EntityDef-like key lists: last written wins, case-insensitive.
std::optional<std::string> lookup(const std::vector<std::pair<std::string, std::string>>& keyValues,
                                  std::string_view key) {
    for (auto it = keyValues.rbegin(); it != keyValues.rend(); ++it)
        if (text::equalsIgnoreCase(it->first, key)) return it->second;
    return std::nullopt;
}

} // namespace

std::optional<std::string> ResolvedEntity::get(std::string_view key) const { return lookup(keyValues, key); }

// --- opening and indexing ----------------------------------------------------------------------------

std::optional<Library> Library::open(const fs::path& baseDir, text::Diagnostics& diagnostics) {
    std::error_code ec;
    if (!fs::is_directory(baseDir, ec)) {
        diagnostics.error({baseDir.string(), 0, 0}, "content folder not found (not a directory)");
        return std::nullopt;
    }
    Library library;
    fs::path base = fs::absolute(baseDir, ec);
    if (ec) base = baseDir;
    base = base.lexically_normal();
    if (!base.has_filename() && base.has_relative_path()) base = base.parent_path(); // drop a trailing '/'
    library.m_baseDir = base;

    const auto afPaths = listFiles(base / "af", ".af", diagnostics);
    const auto defPaths = listFiles(base / "def", ".def", diagnostics);
    if (!afPaths && !defPaths)
        diagnostics.warning({base.string(), 0, 0},
                            "no af/ or def/ folder here: is this a content folder like Doom's base/?");

    if (afPaths) {
        for (const fs::path& path : *afPaths) {
            std::optional<AfFile> af = loadAf(path, diagnostics);
            if (!af) {
                library.m_failedFiles.push_back(path);
                continue;
            }
            library.m_afFiles.push_back({path, std::move(*af)});
            library.m_files.push_back(path);
            library.indexFile(library.m_afFiles.back(), library.m_afFiles.size() - 1, diagnostics);
        }
    }
    if (defPaths) {
        for (const fs::path& path : *defPaths) {
            std::optional<DefFile> def = loadDef(path, diagnostics);
            if (!def) {
                library.m_failedFiles.push_back(path);
                continue;
            }
            library.m_defFiles.push_back({path, std::move(*def)});
            library.m_files.push_back(path);
            library.indexFile(library.m_defFiles.back(), library.m_defFiles.size() - 1, diagnostics);
        }
    }
    return library;
}

namespace {
// Adds `name` to `index` unless a decl of that name (case-insensitive) is there already: the engine keeps
// the first definition and warns about the later one.
template <class IndexMap, class Ref, class LocationOf>
void addToIndex(IndexMap& index, std::string_view type, const std::string& name, const SourceLocation& location,
                Ref ref, LocationOf&& locationOf, text::Diagnostics& diagnostics) {
    const auto [it, inserted] = index.try_emplace(text::lowerAscii(name), ref);
    if (!inserted)
        diagnostics.warning(location, std::string(type) + " '" + name + "' is also defined at " +
                                          locationOf(it->second).str() + "; the first definition is used");
}
} // namespace

void Library::indexFile(const AfSource& source, std::size_t fileIndex, text::Diagnostics& diagnostics) {
    const auto locationOf = [this](DeclRef r) { return m_afFiles[r.file].content.decls[r.decl].location; };
    for (std::size_t i = 0; i < source.content.decls.size(); ++i) {
        const AfDecl& decl = source.content.decls[i];
        addToIndex(m_figures, "articulatedFigure", decl.name, decl.location, DeclRef{fileIndex, i}, locationOf,
                   diagnostics);
    }
}

void Library::indexFile(const DefSource& source, std::size_t fileIndex, text::Diagnostics& diagnostics) {
    const auto entityLocation = [this](DeclRef r) { return m_defFiles[r.file].content.entityDefs[r.decl].location; };
    const auto modelLocation = [this](DeclRef r) { return m_defFiles[r.file].content.models[r.decl].location; };
    for (std::size_t i = 0; i < source.content.entityDefs.size(); ++i) {
        const EntityDef& decl = source.content.entityDefs[i];
        addToIndex(m_entityDefs, "entityDef", decl.name, decl.location, DeclRef{fileIndex, i}, entityLocation,
                   diagnostics);
    }
    for (std::size_t i = 0; i < source.content.models.size(); ++i) {
        const ModelDef& decl = source.content.models[i];
        addToIndex(m_modelDefs, "model", decl.name, decl.location, DeclRef{fileIndex, i}, modelLocation, diagnostics);
    }
}

// --- lookup ---------------------------------------------------------------------------------------------

std::optional<LibraryEntry<EntityDef>> Library::findEntityDef(std::string_view name) const {
    const auto it = m_entityDefs.find(text::lowerAscii(name));
    if (it == m_entityDefs.end()) return std::nullopt;
    const DefSource& source = m_defFiles[it->second.file];
    return LibraryEntry<EntityDef>{source.content.entityDefs[it->second.decl], source.path};
}

std::optional<LibraryEntry<ModelDef>> Library::findModelDef(std::string_view name) const {
    const auto it = m_modelDefs.find(text::lowerAscii(name));
    if (it == m_modelDefs.end()) return std::nullopt;
    const DefSource& source = m_defFiles[it->second.file];
    return LibraryEntry<ModelDef>{source.content.models[it->second.decl], source.path};
}

std::optional<LibraryEntry<AfDecl>> Library::findFigure(std::string_view name) const {
    const auto it = m_figures.find(text::lowerAscii(name));
    if (it == m_figures.end()) return std::nullopt;
    const AfSource& source = m_afFiles[it->second.file];
    return LibraryEntry<AfDecl>{source.content.decls[it->second.decl], source.path};
}

std::vector<std::string> Library::entityDefNames() const {
    std::vector<std::string> out;
    for (const auto& [key, ref] : m_entityDefs) out.push_back(m_defFiles[ref.file].content.entityDefs[ref.decl].name);
    return out;
}

std::vector<std::string> Library::modelDefNames() const {
    std::vector<std::string> out;
    for (const auto& [key, ref] : m_modelDefs) out.push_back(m_defFiles[ref.file].content.models[ref.decl].name);
    return out;
}

std::vector<std::string> Library::figureNames() const {
    std::vector<std::string> out;
    for (const auto& [key, ref] : m_figures) out.push_back(m_afFiles[ref.file].content.decls[ref.decl].name);
    return out;
}

// --- model decls ------------------------------------------------------------------------------------------

namespace {

using AnimIndex = std::map<std::string, std::size_t, std::less<>>; // full name → index into the flat anims

// `remove x` deletes every inherited anim named x or whose alias is x (so `pain` takes pain1, pain2); an x that
// matches none is an error.
bool removeInheritedAnims(const ModelDef& m, const std::string& where, ModelDef& flat, AnimIndex& animIndex,
                          text::Diagnostics& diagnostics) {
    const std::set<std::string, std::less<>> targets(m.removes.begin(), m.removes.end());
    std::set<std::string, std::less<>> used;
    std::vector<ModelAnim> kept;
    for (ModelAnim& a : flat.anims) {
        const std::string alias = a.alias();
        if (targets.count(a.name)) used.insert(a.name);
        if (targets.count(alias)) used.insert(alias);
        if (!targets.count(a.name) && !targets.count(alias)) kept.push_back(std::move(a));
    }
    for (const std::string& r : m.removes)
        if (!used.count(r)) {
            diagnostics.error(m.location, where + " removes anim '" + r + "', which it does not inherit");
            return false;
        }
    flat.anims = std::move(kept);
    animIndex.clear();
    for (std::size_t i = 0; i < flat.anims.size(); ++i) animIndex.emplace(flat.anims[i].name, i);
    return true;
}

// One decl of the inherit chain applied over what its parents left in `flat`, as CopyDecl and its statements
// would (docs/format.md §7.1): mesh, skin and offset replace; `remove` deletes inherited anims; an anim replaces
// an inherited one of its name in place or is appended (twice in one decl is an error); channels replace by name.
bool applyModelDecl(const ModelDef& m, ModelDef& flat, AnimIndex& animIndex, text::Diagnostics& diagnostics) {
    const std::string where = "model decl '" + m.name + "'";
    if (m.mesh) flat.mesh = m.mesh;
    if (m.skin) flat.skin = m.skin;
    if (m.offset) flat.offset = m.offset;
    if (!flat.mesh && (!m.anims.empty() || !m.channels.empty())) {
        diagnostics.error(m.location, where + " defines anims or channels but has no mesh, and inherits none");
        return false;
    }
    if (!m.removes.empty() && !removeInheritedAnims(m, where, flat, animIndex, diagnostics)) return false;
    const std::size_t inheritedCount = flat.anims.size();
    for (const ModelAnim& a : m.anims) {
        const auto found = animIndex.find(a.name);
        if (found == animIndex.end()) {
            animIndex.emplace(a.name, flat.anims.size());
            flat.anims.push_back(a);
        } else if (found->second < inheritedCount) {
            flat.anims[found->second] = a; // overrides the inherited anim in place
        } else {
            diagnostics.error(a.location, "duplicate anim '" + a.name + "' in " + where);
            return false;
        }
    }
    for (const ModelChannel& c : m.channels) {
        const auto same = std::find_if(flat.channels.begin(), flat.channels.end(),
                                       [&](const ModelChannel& x) { return text::equalsIgnoreCase(x.name, c.name); });
        if (same != flat.channels.end()) *same = c;
        else flat.channels.push_back(c);
    }
    return true;
}

} // namespace

std::optional<ResolvedModel> Library::resolveModel(std::string_view name, text::Diagnostics& diagnostics) const {
    const auto leaf = findModelDef(name);
    if (!leaf) {
        diagnostics.error({m_baseDir.string(), 0, 0}, "model decl '" + std::string(name) + "' not found");
        return std::nullopt;
    }

    // Walk up the inherit chain (iteratively; a chain is as long as the library allows).
    ResolvedModel result;
    std::vector<const ModelDef*> chain;
    std::set<std::string, std::less<>> seen;
    for (const ModelDef* current = &leaf->decl;;) {
        chain.push_back(current);
        result.chain.push_back(current->name);
        seen.insert(text::lowerAscii(current->name));
        if (!current->inherit) break;
        const auto parent = findModelDef(*current->inherit);
        if (!parent) {
            diagnostics.error(current->location, "model decl '" + current->name + "' inherits '" + *current->inherit +
                                                     "', which is not defined");
            return std::nullopt;
        }
        if (seen.count(text::lowerAscii(parent->decl.name))) {
            std::string cycle;
            for (const std::string& n : result.chain) cycle += n + " -> ";
            diagnostics.error(current->location, "model decl inherit cycle: " + cycle + parent->decl.name);
            return std::nullopt;
        }
        current = &parent->decl;
    }

    // Apply from the root down.
    ModelDef& flat = result.model;
    flat.name = leaf->decl.name;
    flat.location = leaf->decl.location;
    AnimIndex animIndex;
    for (auto it = chain.rbegin(); it != chain.rend(); ++it)
        if (!applyModelDecl(**it, flat, animIndex, diagnostics)) return std::nullopt;
    if (!flat.mesh) {
        diagnostics.error(leaf->decl.location, "model decl '" + leaf->decl.name + "' has no mesh" +
                                                   (chain.size() > 1 ? " (nor does any decl it inherits)" : ""));
        return std::nullopt;
    }
    return result;
}

// --- entities -------------------------------------------------------------------------------------------

namespace {

// idDeclEntityDef::Parse's inheritance: every key starting with "inherit" (idDict::MatchPrefix,
// case-insensitive) names a parent; the parents' resolved dicts fill in missing keys in that order
// (idDict::SetDefaults). The result is a pre-order walk that takes each key from the first decl defining it,
// so each decl is visited once and the walk needs no recursion.
struct EntityFrame {
    const EntityDef* def = nullptr;
    std::vector<std::string> parents;
    std::size_t next = 0;
};

// The dict idDeclEntityDef builds from one decl: one entry per key (case-insensitive), the last value
// written, at the position of the first.
std::vector<std::pair<std::string, std::string>> ownDict(const EntityDef& def) {
    std::vector<std::pair<std::string, std::string>> dict;
    std::map<std::string, std::size_t, std::less<>> index;
    for (const auto& [key, value] : def.keyValues) {
        const auto [it, inserted] = index.try_emplace(text::lowerAscii(key), dict.size());
        if (inserted) dict.emplace_back(key, value);
        else dict[it->second].second = value;
    }
    return dict;
}

} // namespace

std::optional<ResolvedEntity> Library::resolveEntity(std::string_view name, text::Diagnostics& diagnostics) const {
    const auto entry = findEntityDef(name);
    if (!entry) {
        diagnostics.error({m_baseDir.string(), 0, 0}, "entityDef '" + std::string(name) + "' not found");
        return std::nullopt;
    }
    const EntityDef& entity = entry->decl;
    ResolvedEntity r;
    r.entityName = entity.name;
    r.entityLocation = entity.location;
    if (!mergeEntityKeys(entity, r, diagnostics)) return std::nullopt;
    // Both of these report what they find, so one run names every missing piece.
    const bool modelOk = resolveEntityModel(entity, r, diagnostics);
    const bool figureOk = resolveEntityFigure(entity, r, diagnostics);
    if (!modelOk || !figureOk) return std::nullopt;
    return r;
}

// Keys, merged through the inherit graph into r.keyValues and r.entityChain (diamonds are fine, cycles are
// errors).
bool Library::mergeEntityKeys(const EntityDef& entity, ResolvedEntity& r, text::Diagnostics& diagnostics) const {
    std::vector<EntityFrame> stack;
    std::set<std::string, std::less<>> visited, onPath;
    std::map<std::string, std::size_t, std::less<>> keyIndex;
    const auto visit = [&](const EntityDef& def) {
        visited.insert(text::lowerAscii(def.name));
        onPath.insert(text::lowerAscii(def.name));
        r.entityChain.push_back(def.name);
        EntityFrame frame{&def, {}, 0};
        for (auto& [key, value] : ownDict(def)) {
            if (startsWithIgnoreCase(key, "inherit")) {
                frame.parents.push_back(value);
            } else if (keyIndex.try_emplace(text::lowerAscii(key), r.keyValues.size()).second) {
                r.keyValues.emplace_back(key, value);
            }
        }
        stack.push_back(std::move(frame));
    };
    visit(entity);
    while (!stack.empty()) {
        EntityFrame& top = stack.back();
        if (top.next == top.parents.size()) {
            onPath.erase(text::lowerAscii(top.def->name));
            stack.pop_back();
            continue;
        }
        const std::string& parentName = top.parents[top.next++];
        const auto parent = findEntityDef(parentName);
        if (!parent) {
            diagnostics.error(top.def->location,
                              "entityDef '" + top.def->name + "' inherits '" + parentName + "', which is not defined");
            return false;
        }
        const std::string key = text::lowerAscii(parent->decl.name);
        if (onPath.count(key)) {
            std::string cycle;
            bool inCycle = false;
            for (const EntityFrame& f : stack) {
                inCycle = inCycle || text::lowerAscii(f.def->name) == key;
                if (inCycle) cycle += f.def->name + " -> ";
            }
            diagnostics.error(top.def->location, "entityDef inherit cycle: " + cycle + parent->decl.name);
            return false;
        }
        if (visited.count(key)) continue;
        visit(parent->decl); // invalidates `top`
    }
    return true;
}

// The model decl, its mesh and its af_pose (docs/format.md §7.1).
bool Library::resolveEntityModel(const EntityDef& entity, ResolvedEntity& r, text::Diagnostics& diagnostics) const {
    const std::string where = "entityDef '" + entity.name + "'";
    const std::optional<std::string> modelKey = nonEmpty(r.get("model"));
    if (!modelKey) {
        diagnostics.error(entity.location, where + " has no \"model\" key: a ragdoll needs a model decl with "
                                                   "anim af_pose");
        return false;
    }
    if (!findModelDef(*modelKey)) {
        const bool isMesh = modelKey->size() >= 8 && modelKey->substr(modelKey->size() - 8) == ".md5mesh";
        diagnostics.error(entity.location,
                          isMesh ? where + " has \"model\" '" + *modelKey +
                                       "', a mesh file, not a model decl: the engine then has no animator, so no "
                                       "af_pose and no ragdoll"
                                 : "model decl '" + *modelKey + "' (\"model\" of " + where + ") not found");
        return false;
    }
    std::optional<ResolvedModel> model = resolveModel(*modelKey, diagnostics);
    if (!model) return false;
    r.model = std::move(model->model);
    r.modelChain = std::move(model->chain);
    r.modelName = r.model.name;
    r.modelLocation = r.model.location;
    bool ok = true;
    if (auto mesh = contentPath(*r.model.mesh, "mesh", r.modelLocation, diagnostics)) r.meshPath = std::move(*mesh);
    else ok = false;
    return resolveAfPose(r, diagnostics) && ok;
}

// idAF::Load asks for GetAnim("af_pose"): every anim whose alias is af_pose (af_pose, af_pose1, …), one
// picked at random when there are several. Sets r.afPoseAnim and r.afPosePath from r.model.
bool Library::resolveAfPose(ResolvedEntity& r, text::Diagnostics& diagnostics) const {
    std::vector<const ModelAnim*> poses;
    for (const ModelAnim& a : r.model.anims)
        if (a.alias() == "af_pose") poses.push_back(&a);
    if (poses.empty()) {
        diagnostics.error(r.modelLocation, "model decl " + r.modelName + " has no anim af_pose (a ragdoll needs it)");
        return false;
    }
    const ModelAnim* pose = r.model.findAnim("af_pose");
    if (!pose) pose = poses.front();
    if (poses.size() > 1)
        diagnostics.warning(pose->location, "model decl " + r.modelName + " has " + std::to_string(poses.size()) +
                                                " af_pose variants (the engine picks one at random); using '" +
                                                pose->name + "'");
    r.afPoseAnim = pose->name;
    auto path = contentPath(pose->files.front(), "af_pose anim", pose->location, diagnostics);
    if (!path) return false;
    r.afPosePath = std::move(*path);
    return true;
}

// The figure (docs/format.md §7.2): idAFEntity_Base reads "articulatedFigure", idActor reads "ragdoll"; idAF::Load
// strips any extension before looking the decl up.
bool Library::resolveEntityFigure(const EntityDef& entity, ResolvedEntity& r, text::Diagnostics& diagnostics) const {
    const std::string where = "entityDef '" + entity.name + "'";
    const std::optional<std::string> afKey = nonEmpty(r.get("articulatedFigure"));
    const std::optional<std::string> ragdollKey = nonEmpty(r.get("ragdoll"));
    if (!afKey && !ragdollKey) {
        diagnostics.error(entity.location, where + " has neither \"articulatedFigure\" nor \"ragdoll\": it names "
                                                   "no figure");
        return false;
    }
    r.figureKey = afKey ? "articulatedFigure" : "ragdoll";
    const std::string value = afKey ? *afKey : *ragdollKey;
    const std::string figure = stripExtension(value);
    if (afKey && ragdollKey && !text::equalsIgnoreCase(figure, stripExtension(*ragdollKey)))
        diagnostics.warning(entity.location, where + " sets both \"articulatedFigure\" '" + *afKey +
                                                 "' and \"ragdoll\" '" + *ragdollKey +
                                                 "'; using \"articulatedFigure\" (AF entities read it, actors "
                                                 "read \"ragdoll\")");
    const auto found = findFigure(figure);
    if (!found) {
        diagnostics.error(entity.location, "articulatedFigure '" + figure + "' (\"" + r.figureKey + "\" '" + value +
                                               "' of " + where + ") not found in af/");
        return false;
    }
    r.figureName = found->decl.name;
    r.figureLocation = found->decl.location;
    r.figureFile = found->file;
    return true;
}

// A path from a decl, relative to the content folder, made absolute; the file must exist and the path must
// stay inside the folder (no absolute paths, no '..').
std::optional<fs::path> Library::contentPath(const std::string& relative, const std::string& what,
                                             const SourceLocation& where, text::Diagnostics& diagnostics) const {
    std::string generic = relative;
    std::replace(generic.begin(), generic.end(), '\\', '/'); // the engine's file system takes both separators
    const fs::path path(generic);
    bool escapes = generic.empty() || path.has_root_name() || path.has_root_directory();
    for (const fs::path& part : path) escapes = escapes || part == "..";
    if (escapes) {
        diagnostics.error(where, what + " path '" + relative +
                                     "' must be relative to the content folder and stay inside it (no leading '/', "
                                     "no '..')");
        return std::nullopt;
    }
    const fs::path full = (m_baseDir / path).lexically_normal();
    std::error_code ec;
    if (!fs::is_regular_file(full, ec)) {
        diagnostics.error(where, what + " file '" + relative + "' not found (looked for " + full.string() + ")");
        return std::nullopt;
    }
    return full;
}

} // namespace afb::decl
