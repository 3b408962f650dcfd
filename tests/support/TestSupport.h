#pragma once
// Shared helpers for the Catch2 suites.
#include <cstdlib>
#include <filesystem>
#include <optional>

namespace afb::test {

/// The real-world corpus (`../shared/data`, or $AFB_CORPUS_DIR), or nullopt when absent.
inline std::optional<std::filesystem::path> corpusDir() {
    if (const char* env = std::getenv("AFB_CORPUS_DIR"); env && *env) {
        if (std::filesystem::is_directory(env)) return std::filesystem::path(env);
        return std::nullopt;
    }
#ifdef AFB_DEFAULT_CORPUS_DIR
    if (std::filesystem::is_directory(AFB_DEFAULT_CORPUS_DIR)) return std::filesystem::path(AFB_DEFAULT_CORPUS_DIR);
#endif
    return std::nullopt;
}

/// The repository's own content folder (holds af/, def/, models/).
inline std::filesystem::path sourceDir() { return AFB_SOURCE_DIR; }

} // namespace afb::test

/// Skips the current Catch2 test case with a message when the corpus is absent.
#define AFB_REQUIRE_CORPUS(var)                                                                                        \
    const auto var##_opt = ::afb::test::corpusDir();                                                                   \
    if (!var##_opt) {                                                                                                  \
        WARN("corpus not found (../shared/data or AFB_CORPUS_DIR): skipped");                                          \
        return;                                                                                                        \
    }                                                                                                                  \
    const std::filesystem::path var = *var##_opt
