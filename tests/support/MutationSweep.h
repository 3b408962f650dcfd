#pragma once
// Numeric mutation of `.af` text: every number of a figure replaced by hostile values, each variant
// parsed, built and dropped (as `afb drop` does) in a child process so that a crash is counted, not fatal. A
// variant must end in a clean error, a reported repair, or a finite simulation.
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include "afb/bullet/RagdollAsset.h"
#include "afb/decl/AfParser.h"
#include "afb/decl/Library.h"
#include "afb/detail/Lexer.h"
#include "afb/figure/Figure.h"
#include "afb/figure/Load.h"
#include "afb/sim/Drop.h"
#include "afb/sim/Scene.h"
#include "afb/text/Files.h"

namespace afb::test {

/// The values each number is replaced by. The last four are not numbers to the idTech4 lexer.
inline const std::vector<std::string>& hostileValues() {
    static const std::vector<std::string> values = {"0",    "-1",  "1e-30", "1e-7", "1e5",
                                                    "1e30", "nan", "inf",   "-inf", "1e999"};
    return values;
}

/// One number of the text: its bytes (with a directly preceding minus sign) and where it starts.
struct NumberSpan {
    std::size_t offset = 0;
    std::size_t length = 0;
    std::uint32_t line = 0;
};

/// Every number token of `text`, in order.
inline std::vector<NumberSpan> numberSpans(const std::string& text) {
    std::vector<NumberSpan> spans;
    text::Diagnostics ignored;
    text::Lexer lexer(text, "mutation", ignored);
    std::optional<text::Token> minus;
    for (text::Token t = lexer.next(); t.kind != text::TokenKind::End; t = lexer.next()) {
        if (t.kind == text::TokenKind::Number) {
            auto offset = static_cast<std::size_t>(t.text.data() - text.data());
            std::size_t length = t.text.size();
            if (minus && static_cast<std::size_t>(minus->text.data() - text.data()) + 1 == offset) {
                --offset;
                ++length;
            }
            spans.push_back({offset, length, t.line});
        }
        minus = t.isPunct('-') ? std::optional<text::Token>(t) : std::nullopt;
    }
    return spans;
}

/// `text` with the given spans replaced (spans in ascending order, not overlapping).
inline std::string mutate(const std::string& text, const std::vector<std::pair<NumberSpan, std::string>>& edits) {
    std::string out;
    std::size_t at = 0;
    for (const auto& [span, value] : edits) {
        out.append(text, at, span.offset - at);
        out += value;
        at = span.offset + span.length;
    }
    out.append(text, at, std::string::npos);
    return out;
}

/// A figure to mutate: its `.af` text and the skeleton it is built on.
struct MutationTarget {
    std::string label;      ///< for messages: file and figure
    std::string afFile;     ///< diagnostics name
    std::string afText;     ///< the original text
    std::string figureName; ///< the decl to build (empty: the first)
    std::shared_ptr<figure::Skeleton> skeleton;
};

/// How one variant ended.
enum class MutationOutcome { Error, Repaired, Clean, NonFinite, Crash };

inline const char* toString(MutationOutcome o) {
    switch (o) {
    case MutationOutcome::Error: return "error";
    case MutationOutcome::Repaired: return "repaired";
    case MutationOutcome::Clean: return "clean";
    case MutationOutcome::NonFinite: return "non-finite";
    case MutationOutcome::Crash: return "crash";
    }
    return "?";
}

/// Parses and builds `afText` on the target's skeleton.
inline std::optional<figure::Figure> buildVariant(const MutationTarget& target, const std::string& afText, bool strict,
                                                  text::Diagnostics& diagnostics) {
    const auto af = decl::parseAf(afText, target.afFile, diagnostics);
    if (!af || diagnostics.hasErrors()) return std::nullopt;
    const decl::AfDecl* chosen = nullptr;
    for (const decl::AfDecl& d : af->decls)
        if (target.figureName.empty() || text::equalsIgnoreCase(d.name, target.figureName)) {
            chosen = &d;
            break;
        }
    if (!chosen) return std::nullopt;
    figure::FigureInput input{chosen, target.skeleton.get(), {}, false};
    input.strict = strict;
    return figure::buildFigure(input, diagnostics);
}

/// True when every body of every ragdoll in `scene` has a finite position and orientation.
inline bool sceneFinite(const sim::Scene& scene) {
    for (const auto& ragdoll : scene.ragdolls())
        for (const figure::Transform& t : ragdoll->bodyTransforms())
            if (!t.position.allFinite() || !t.rotation.allFinite()) return false;
    return true;
}

/// Runs one variant in this process as `afb drop --steps <steps>` runs a figure (sim::runDrop: 1 m above a ground
/// plane, the default method, the figure's rest rules).
inline MutationOutcome runVariant(const MutationTarget& target, const std::string& afText, bool strict = false,
                                  int steps = 60) {
    text::Diagnostics diagnostics;
    std::optional<figure::Figure> figure = buildVariant(target, afText, strict, diagnostics);
    if (!figure) return MutationOutcome::Error;
    bool repaired = false;
    for (const text::Diagnostic& d : diagnostics.items())
        if (d.message.find("repaired") != std::string::npos) repaired = true;
    sim::DropOptions drop;
    drop.steps = steps;
    if (sim::runDrop(*figure, drop).nonFinite) return MutationOutcome::NonFinite;
    return repaired ? MutationOutcome::Repaired : MutationOutcome::Clean;
}

/// runVariant in a child process: a signal (or a hang past 20 s) is a Crash.
inline MutationOutcome runVariantIsolated(const MutationTarget& target, const std::string& afText, bool strict = false,
                                          int steps = 60) {
    const pid_t pid = fork();
    if (pid == 0) {
        alarm(20);
        _exit(static_cast<int>(runVariant(target, afText, strict, steps)));
    }
    if (pid < 0) return runVariant(target, afText, strict, steps);
    int status = 0;
    waitpid(pid, &status, 0);
    if (WIFEXITED(status) && WEXITSTATUS(status) <= static_cast<int>(MutationOutcome::NonFinite))
        return static_cast<MutationOutcome>(WEXITSTATUS(status));
    return MutationOutcome::Crash;
}

/// The figures of the entities in a content folder (`af/`, `def/`, `models/`) that build unmutated, one target
/// per figure (the first entity naming it), on the skeleton its entity gives it.
inline std::vector<MutationTarget> entityTargets(const std::filesystem::path& baseDir,
                                                 const std::vector<std::string>& entities) {
    std::vector<MutationTarget> targets;
    text::Diagnostics diagnostics;
    const std::optional<decl::Library> library = decl::Library::open(baseDir, diagnostics);
    if (!library) return targets;
    for (const std::string& entity : entities) {
        std::optional<figure::LoadedFigure> loaded = figure::loadEntityFigure(*library, entity, {}, diagnostics);
        if (!loaded) continue;
        const std::string file = loaded->afFile.string(), name = loaded->decl.name;
        bool seen = false;
        for (const MutationTarget& t : targets)
            if (t.afFile == file && text::equalsIgnoreCase(t.figureName, name)) seen = true;
        const std::optional<std::string> afText = text::readFile(loaded->afFile, diagnostics);
        if (seen || !afText) continue;
        targets.push_back({loaded->afFile.filename().string() + " " + name, file, *afText, name,
                           std::make_shared<figure::Skeleton>(std::move(loaded->figure.skeleton))});
    }
    return targets;
}

} // namespace afb::test
