#pragma once
// Reading input files with a size bound: the only file I/O of the text and decl layers.
#include <filesystem>
#include <optional>
#include <string>

#include "afb/text/Diagnostics.h"

namespace afb::text {

/// Largest file any parser reads (no idTech4 text file comes near it); bigger files get an error.
inline constexpr std::uintmax_t kMaxFileBytes = 256u << 20;

/// The whole file, or nullopt with an error (missing, unreadable, a directory, too large).
std::optional<std::string> readFile(const std::filesystem::path& path, Diagnostics& diagnostics);

} // namespace afb::text
