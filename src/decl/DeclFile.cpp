#include "DeclFile.h"

#include <array>

namespace afb::decl::detail {
namespace {
// Decl types registered by the engine (DeclManager.cpp) and by the Doom 3 game (model, export).
constexpr std::array<std::string_view, 15> kDeclTypes = {"table", "material",  "skin",
                                                         "sound", "entityDef", "mapDef",
                                                         "fx",    "particle",  "articulatedFigure",
                                                         "pda",   "email",     "video",
                                                         "audio", "model",     "export"};
} // namespace

bool isDeclTypeName(std::string_view word) {
    for (std::string_view t : kDeclTypes)
        if (text::equalsIgnoreCase(t, word)) return true;
    return false;
}

std::string canonicalDeclType(std::string_view word) {
    for (std::string_view t : kDeclTypes)
        if (text::equalsIgnoreCase(t, word)) return std::string(t);
    return std::string(word);
}

} // namespace afb::decl::detail
