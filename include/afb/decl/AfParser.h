#pragma once
// Reading and writing `.af` files (docs/format.md §1).
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "afb/decl/Af.h"
#include "afb/text/Diagnostics.h"

namespace afb::decl {

/// Parses `.af` text holding any number of `articulatedFigure` decls (other decl types are skipped with a
/// warning). On any error: nullopt, with `file:line:col` errors in `diagnostics` — nothing is half-loaded.
/// Engine fallbacks that a file may rely on silently (unknown `mod`, unknown contents names, octal numbers,
/// case-only duplicate names, `angles` with joint forms) are reported as warnings.
std::optional<AfFile> parseAf(std::string_view text, const std::string& fileName, text::Diagnostics& diagnostics);

/// Reads and parses one `.af` file.
std::optional<AfFile> loadAf(const std::filesystem::path& path, text::Diagnostics& diagnostics);

/// Canonical `.af` text of one decl: blocks in their original order, keys in a fixed order, only the keys the
/// decl holds, numbers in their shortest exact form. `parseAf(writeAf(d))` gives back `d`.
std::string writeAf(const AfDecl& decl);
/// Canonical text of every decl of a file, separated by blank lines.
std::string writeAf(const AfFile& file);

} // namespace afb::decl
