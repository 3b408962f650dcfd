#include "afb/decl/Af.h"

#include "afb/detail/Lexer.h"

namespace afb::decl {

std::optional<std::uint32_t> contentsBitsOfName(std::string_view name) {
    using text::equalsIgnoreCase;
    if (equalsIgnoreCase(name, "none")) return 0u;
    if (equalsIgnoreCase(name, "solid")) return kContentsSolid;
    if (equalsIgnoreCase(name, "playerclip")) return kContentsPlayerClip;
    if (equalsIgnoreCase(name, "monsterclip")) return kContentsMonsterClip;
    if (equalsIgnoreCase(name, "body")) return kContentsBody;
    if (equalsIgnoreCase(name, "corpse")) return kContentsCorpse;
    return std::nullopt;
}

std::uint32_t contentsBits(const ContentsList& list, std::optional<std::size_t>* firstUnknown) {
    std::uint32_t bits = 0;
    if (firstUnknown) firstUnknown->reset();
    for (std::size_t i = 0; i < list.names.size(); ++i) {
        const std::optional<std::uint32_t> b = contentsBitsOfName(list.names[i]);
        if (!b) {
            if (firstUnknown) *firstUnknown = i;
            break; // docs/format.md §1.6: the first unknown name ends the list
        }
        bits = (*b == 0) ? 0 : (bits | *b);
    }
    return bits;
}

void AfSettingsValues::apply(const AfSettings& s) {
    if (s.model) model = *s.model;
    if (s.skin) skin = *s.skin;
    if (s.friction) {
        friction = {s.friction->linear, s.friction->angular, s.friction->contact};
        if (s.friction->constraint) constraintFriction = *s.friction->constraint;
    }
    if (s.suspendSpeed) suspendSpeed = *s.suspendSpeed;
    if (s.noMoveTime) noMoveTime = *s.noMoveTime;
    if (s.noMoveTranslation) noMoveTranslation = *s.noMoveTranslation;
    if (s.noMoveRotation) noMoveRotation = *s.noMoveRotation;
    if (s.minMoveTime) minMoveTime = *s.minMoveTime;
    if (s.maxMoveTime) maxMoveTime = *s.maxMoveTime;
    if (s.totalMass) totalMass = *s.totalMass;
    if (s.contents) contents = *s.contents;
    if (s.clipMask) clipMask = *s.clipMask;
    if (s.selfCollision) selfCollision = *s.selfCollision;
}

const char* keywordOf(ConstraintType type) {
    switch (type) {
    case ConstraintType::Fixed: return "fixed";
    case ConstraintType::BallAndSocket: return "ballAndSocketJoint";
    case ConstraintType::Universal: return "universalJoint";
    case ConstraintType::Hinge: return "hinge";
    case ConstraintType::Slider: return "slider";
    case ConstraintType::Spring: return "spring";
    }
    return "?";
}

AfSettingsValues AfDecl::finalSettings() const {
    AfSettingsValues v;
    for (const AfBlockRef& ref : order)
        if (ref.kind == AfBlockRef::Kind::Settings) v.apply(settings[ref.index]);
    return v;
}

AfSettingsValues AfDecl::settingsForBody(std::size_t bodyIndex) const {
    AfSettingsValues v;
    for (const AfBlockRef& ref : order) {
        if (ref.kind == AfBlockRef::Kind::Body && ref.index == bodyIndex) break;
        if (ref.kind == AfBlockRef::Kind::Settings) v.apply(settings[ref.index]);
    }
    return v;
}

std::string AfDecl::defaultBody1(std::size_t constraintIndex) const {
    for (const AfBlockRef& ref : order) {
        if (ref.kind == AfBlockRef::Kind::Constraint && ref.index == constraintIndex) break;
        if (ref.kind == AfBlockRef::Kind::Body) return bodies[ref.index].name;
    }
    return "world";
}

} // namespace afb::decl
