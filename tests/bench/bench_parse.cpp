// Parse throughput on the real-world corpus (../shared/data, or $AFB_CORPUS_DIR):
//   BM_ParseLargestMd5Mesh  parseMd5Mesh on the largest .md5mesh found (bytes/s)
//   BM_LexLargestMd5Mesh    the lexer alone on the same file (bytes/s, tokens/s)
//   BM_ParseAllAf           parseAf on every .af file (bytes/s, decls/s)
// Each benchmark is skipped with an error when its inputs are absent.
#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include <benchmark/benchmark.h>

#include "afb/decl/AfParser.h"
#include "afb/decl/Md5Mesh.h"
#include "afb/detail/Lexer.h"
#include "afb/text/Diagnostics.h"

namespace {

namespace fs = std::filesystem;

std::optional<fs::path> corpusDir() {
    if (const char* env = std::getenv("AFB_CORPUS_DIR"); env && *env) {
        if (fs::is_directory(env)) return fs::path(env);
        return std::nullopt;
    }
#ifdef AFB_DEFAULT_CORPUS_DIR
    if (fs::is_directory(AFB_DEFAULT_CORPUS_DIR)) return fs::path(AFB_DEFAULT_CORPUS_DIR);
#endif
    return std::nullopt;
}

struct InputFile {
    std::string name; ///< path relative to the corpus folder
    std::string text;
};

std::string readAll(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

/// Every input the benchmarks time, read once.
struct Corpus {
    std::optional<fs::path> root;
    std::optional<InputFile> largestMesh;
    std::vector<InputFile> afFiles;
    std::size_t afBytes = 0;
};

const Corpus& corpus() {
    static const Corpus c = [] {
        Corpus r;
        r.root = corpusDir();
        if (!r.root) return r;
        std::optional<fs::path> mesh;
        std::uintmax_t meshSize = 0;
        std::vector<fs::path> afs;
        std::error_code ec;
        for (auto it = fs::recursive_directory_iterator(*r.root, fs::directory_options::skip_permission_denied, ec);
             !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
            if (!it->is_regular_file(ec)) continue;
            const fs::path& p = it->path();
            if (p.extension() == ".md5mesh") {
                const auto size = it->file_size(ec);
                if (!ec && (!mesh || size > meshSize)) {
                    mesh = p;
                    meshSize = size;
                }
            } else if (p.extension() == ".af") {
                afs.push_back(p);
            }
        }
        std::sort(afs.begin(), afs.end());
        if (mesh) r.largestMesh = InputFile{fs::relative(*mesh, *r.root).string(), readAll(*mesh)};
        for (const auto& p : afs) {
            r.afFiles.push_back({fs::relative(p, *r.root).string(), readAll(p)});
            r.afBytes += r.afFiles.back().text.size();
        }
        return r;
    }();
    return c;
}

/// The largest mesh, or nullptr after skipping `state` with an error.
const InputFile* meshOrSkip(benchmark::State& state) {
    const Corpus& c = corpus();
    if (!c.root) {
        state.SkipWithError("corpus not found (../shared/data or AFB_CORPUS_DIR)");
        return nullptr;
    }
    if (!c.largestMesh) {
        state.SkipWithError("no .md5mesh in the corpus");
        return nullptr;
    }
    return &*c.largestMesh;
}

void BM_ParseLargestMd5Mesh(benchmark::State& state) {
    const InputFile* mesh = meshOrSkip(state);
    if (!mesh) return;
    state.SetLabel(mesh->name);
    for (auto _ : state) {
        afb::text::Diagnostics diags;
        auto parsed = afb::decl::parseMd5Mesh(mesh->text, mesh->name, diags);
        if (!parsed) {
            state.SkipWithError(("md5mesh " + mesh->name + " does not parse: " + diags.str()).c_str());
            break;
        }
        benchmark::DoNotOptimize(parsed);
    }
    state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(mesh->text.size()));
}
BENCHMARK(BM_ParseLargestMd5Mesh)->Unit(benchmark::kMillisecond);

void BM_LexLargestMd5Mesh(benchmark::State& state) {
    const InputFile* mesh = meshOrSkip(state);
    if (!mesh) return;
    state.SetLabel(mesh->name);
    std::int64_t tokens = 0;
    for (auto _ : state) {
        afb::text::Diagnostics diags;
        try {
            afb::text::Lexer lexer(mesh->text, mesh->name, diags);
            while (true) {
                const afb::text::Token t = lexer.next();
                if (t.kind == afb::text::TokenKind::End) break;
                benchmark::DoNotOptimize(t);
                ++tokens;
            }
        } catch (const afb::text::ParseError& e) {
            state.SkipWithError(("md5mesh " + mesh->name + " does not lex: " + e.what()).c_str());
            break;
        }
    }
    state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(mesh->text.size()));
    state.counters["tokens/s"] = benchmark::Counter(static_cast<double>(tokens), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_LexLargestMd5Mesh)->Unit(benchmark::kMillisecond);

void BM_ParseAllAf(benchmark::State& state) {
    const Corpus& c = corpus();
    if (!c.root) {
        state.SkipWithError("corpus not found (../shared/data or AFB_CORPUS_DIR)");
        return;
    }
    if (c.afFiles.empty()) {
        state.SkipWithError("no .af file in the corpus");
        return;
    }
    state.SetLabel(std::to_string(c.afFiles.size()) + " files");
    std::int64_t decls = 0;
    bool failed = false;
    for (auto _ : state) {
        for (const InputFile& f : c.afFiles) {
            afb::text::Diagnostics diags;
            auto parsed = afb::decl::parseAf(f.text, f.name, diags);
            if (!parsed) {
                state.SkipWithError((".af file " + f.name + " does not parse: " + diags.str()).c_str());
                failed = true;
                break;
            }
            decls += static_cast<std::int64_t>(parsed->decls.size());
            benchmark::DoNotOptimize(parsed);
        }
        if (failed) break;
    }
    state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(c.afBytes));
    state.counters["decls/s"] = benchmark::Counter(static_cast<double>(decls), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_ParseAllAf)->Unit(benchmark::kMicrosecond);

} // namespace
