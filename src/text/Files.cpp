#include "afb/text/Files.h"

#include <fstream>

namespace afb::text {

std::optional<std::string> readFile(const std::filesystem::path& path, Diagnostics& diagnostics) {
    const SourceLocation where{path.string(), 0, 0};
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) {
        diagnostics.error(where, std::filesystem::exists(path, ec) ? "not a regular file" : "no such file");
        return std::nullopt;
    }
    const std::uintmax_t size = std::filesystem::file_size(path, ec);
    if (ec) {
        diagnostics.error(where, "cannot read file size: " + ec.message());
        return std::nullopt;
    }
    if (size > kMaxFileBytes) {
        diagnostics.error(where, "file is " + std::to_string(size) + " bytes, more than the " +
                                     std::to_string(kMaxFileBytes) + " a text file may have");
        return std::nullopt;
    }
    std::ifstream in(path, std::ios::binary);
    std::string data(static_cast<std::size_t>(size), '\0');
    if (!in || !in.read(data.data(), static_cast<std::streamsize>(size))) {
        diagnostics.error(where, "cannot read file");
        return std::nullopt;
    }
    return data;
}

} // namespace afb::text
