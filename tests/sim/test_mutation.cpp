// A figure that parses must never crash the runtime or put NaN into the world. Every number of the
// bundled figures (and, for the full sweep, of the corpus figures) is replaced by hostile values; each variant
// must end in a clean error, a reported repair or a finite 60-step simulation, never a signal.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <regex>
#include <sstream>

#include "FigureFixture.h"
#include "MutationSweep.h"
#include "TestSupport.h"

namespace {

using afb::test::MutationOutcome;
using afb::test::MutationTarget;
using afb::test::NumberSpan;

/// A deterministic sequence (a 64-bit LCG, fixed seed) for sampling variants.
struct Lcg {
    std::uint64_t state;
    std::size_t below(std::size_t n) {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return static_cast<std::size_t>((state >> 33) % n);
    }
};

std::vector<MutationTarget> bundledTargets() {
    return afb::test::entityTargets(afb::test::sourceDir(), {"humanoid", "chain", "props", "lamp", "buggy"});
}

/// A skeleton of every joint `afText` names (`joint "J"`, `joint( "J" )`, `bonecenter`/`bonedir( "A", "B" )`),
/// children of "origin", on a rising spiral 6 units in radius and 4 apart in height: no two joints coincide, so
/// every bone and direction has a length. For corpus figures whose mesh is not in the corpus: their numbers are
/// what the sweep varies, the pose is only somewhere to build them.
std::shared_ptr<afb::figure::Skeleton> syntheticSkeleton(const std::string& afText) {
    static const std::regex named(R"re(\b(?:joint\s*\(?|bone(?:center|dir)\s*\()\s*"([^"]+)"(?:\s*,\s*"([^"]+)")?)re",
                                  std::regex::icase);
    std::vector<afb::test::TestJoint> joints = {{"origin", -1, 0, 0, 0}};
    auto add = [&](const std::string& name) {
        for (const afb::test::TestJoint& j : joints)
            if (afb::text::equalsIgnoreCase(j.name, name)) return;
        const double k = static_cast<double>(joints.size());
        joints.push_back({name, 0, 6 * std::cos(2.4 * k), 6 * std::sin(2.4 * k), 4 * k});
    };
    for (auto it = std::sregex_iterator(afText.begin(), afText.end(), named); it != std::sregex_iterator(); ++it)
        for (std::size_t g = 1; g <= 2; ++g)
            if ((*it)[g].matched) add((*it)[g].str());
    afb::text::Diagnostics d;
    auto skeleton = afb::figure::Skeleton::build(afb::test::md5Mesh(joints), afb::test::md5Anim(joints),
                                                 Eigen::Vector3d::Zero(), d, "synthetic");
    return skeleton ? std::make_shared<afb::figure::Skeleton>(std::move(*skeleton)) : nullptr;
}

/// The corpus figures: the complete zsec entities, then every other figure of the corpus's af/ folder on the
/// first zsec skeleton it builds on unmutated (the zombie figures share its joint names), else on a synthetic
/// skeleton of the joints it names (the demons and the other zombies, whose meshes are not in the corpus).
std::vector<MutationTarget> corpusTargets(const std::filesystem::path& corpus) {
    const std::filesystem::path base = corpus / "doom3-kroom3" / "base";
    std::vector<MutationTarget> targets =
        afb::test::entityTargets(base, {"monster_zsec_machinegun", "monster_zsec_pistol", "monster_zsec_shotgun"});
    const std::vector<MutationTarget> skeletons = targets;
    std::vector<std::filesystem::path> files;
    for (const auto& e : std::filesystem::directory_iterator(base / "af"))
        if (e.path().extension() == ".af") files.push_back(e.path());
    std::sort(files.begin(), files.end());
    for (const auto& file : files) {
        afb::text::Diagnostics d;
        const auto text = afb::text::readFile(file, d);
        const auto af = text ? afb::decl::parseAf(*text, file.string(), d) : std::nullopt;
        if (!af) continue;
        for (const auto& decl : af->decls) {
            bool covered = false;
            for (const MutationTarget& t : targets) // the library spells the corpus path its own way
                if (std::filesystem::equivalent(t.afFile, file) && afb::text::equalsIgnoreCase(t.figureName, decl.name))
                    covered = true;
            for (const MutationTarget& s : skeletons) {
                if (covered) break;
                MutationTarget t{file.filename().string() + " " + decl.name + " (on " + s.figureName + ")",
                                 file.string(), *text, decl.name, s.skeleton};
                afb::text::Diagnostics findings;
                if (afb::test::buildVariant(t, *text, false, findings)) {
                    targets.push_back(std::move(t));
                    covered = true;
                }
            }
            if (!covered) {
                MutationTarget t{file.filename().string() + " " + decl.name + " (on a synthetic skeleton)",
                                 file.string(), *text, decl.name, syntheticSkeleton(*text)};
                afb::text::Diagnostics findings;
                if (t.skeleton && afb::test::buildVariant(t, *text, false, findings)) {
                    targets.push_back(std::move(t));
                    covered = true;
                } else {
                    WARN("not swept: " << file.filename().string() << " " << decl.name << ":\n" << findings.str());
                }
            }
        }
    }
    return targets;
}

/// Outcome counts over a sweep, with the first few failures described.
struct Tally {
    std::map<MutationOutcome, std::size_t> counts;
    std::vector<std::string> failures;

    void add(const MutationTarget& t, const std::vector<std::pair<NumberSpan, std::string>>& edits, MutationOutcome o) {
        ++counts[o];
        if (o != MutationOutcome::NonFinite && o != MutationOutcome::Crash) return;
        std::ostringstream s;
        s << toString(o) << ": " << t.label << ":";
        for (const auto& [span, value] : edits)
            s << " line " << span.line << " '" << t.afText.substr(span.offset, span.length) << "' -> " << value;
        if (failures.size() < 50) failures.push_back(s.str());
    }
    std::size_t bad() const {
        auto at = [&](MutationOutcome o) { return counts.count(o) ? counts.at(o) : 0; };
        return at(MutationOutcome::NonFinite) + at(MutationOutcome::Crash);
    }
    std::string summary() const {
        std::ostringstream s;
        for (const auto& [o, n] : counts) s << toString(o) << " " << n << "  ";
        for (const std::string& f : failures) s << "\n  " << f;
        return s.str();
    }
};

using Edits = std::vector<std::pair<NumberSpan, std::string>>;

// AFB_MUTATION_VERBOSE=1 prints every variant with its outcome and time.
void runOne(Tally& tally, const MutationTarget& t, const Edits& edits, int steps = 60) {
    const auto start = std::chrono::steady_clock::now();
    const MutationOutcome o = afb::test::runVariantIsolated(t, afb::test::mutate(t.afText, edits), false, steps);
    tally.add(t, edits, o);
    if (std::getenv("AFB_MUTATION_VERBOSE")) {
        const auto ms =
            std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - start).count();
        std::fprintf(stderr, "%s:", t.label.c_str());
        for (const auto& [span, value] : edits)
            std::fprintf(stderr, " line %u '%s' -> %s", span.line, t.afText.substr(span.offset, span.length).c_str(),
                         value.c_str());
        std::fprintf(stderr, ": %s, %lld ms\n", toString(o), static_cast<long long>(ms));
    }
}

/// A sweep's counts: every number × every hostile value, and the sampled pairs.
struct SweepTallies {
    Tally singles, pairs;
};

/// Every number × every hostile value; then `pairs` sampled pairs of two numbers, each with a sampled value.
SweepTallies sweep(const MutationTarget& t, std::size_t pairs, int steps) {
    SweepTallies tallies;
    const auto& values = afb::test::hostileValues();
    Lcg lcg{17};
    const std::vector<NumberSpan> spans = afb::test::numberSpans(t.afText);
    for (const NumberSpan& span : spans)
        for (const std::string& value : values) runOne(tallies.singles, t, {{span, value}}, steps);
    for (std::size_t p = 0; p < pairs && spans.size() > 1; ++p) {
        std::size_t a = lcg.below(spans.size()), b = lcg.below(spans.size() - 1);
        if (b >= a) ++b;
        if (b < a) std::swap(a, b);
        runOne(tallies.pairs, t,
               {{spans[a], values[lcg.below(values.size())]}, {spans[b], values[lcg.below(values.size())]}}, steps);
    }
    return tallies;
}

/// The spans of every bone width (the number before the closing parenthesis of `bone(`).
std::vector<NumberSpan> boneWidths(const MutationTarget& t) {
    std::vector<NumberSpan> widths;
    const std::vector<NumberSpan> spans = afb::test::numberSpans(t.afText);
    for (std::size_t at = t.afText.find("bone("); at != std::string::npos; at = t.afText.find("bone(", at + 1)) {
        const std::size_t close = t.afText.find(')', t.afText.find(')', t.afText.find(')', at) + 1) + 1);
        const NumberSpan* last = nullptr;
        for (const NumberSpan& s : spans)
            if (s.offset > at && s.offset < close) last = &s;
        if (last) widths.push_back(*last);
    }
    return widths;
}

} // namespace

TEST_CASE("numberSpans finds every number with its minus sign", "[mutation]") {
    const std::string text = "body \"a\" { origin ( -1.5, 2, 0x10 ) width 3 }";
    const auto spans = afb::test::numberSpans(text);
    REQUIRE(spans.size() == 4);
    CHECK(text.substr(spans[0].offset, spans[0].length) == "-1.5");
    CHECK(text.substr(spans[2].offset, spans[2].length) == "0x10");
    CHECK(afb::test::mutate(text, {{spans[0], "nan"}, {spans[3], "1e5"}}) ==
          "body \"a\" { origin ( nan, 2, 0x10 ) width 1e5 }");
}

TEST_CASE("bundled figures survive a deterministic sample of numeric mutations", "[mutation]") {
    const std::vector<MutationTarget> targets = bundledTargets();
    REQUIRE(targets.size() == 5);
    const auto& values = afb::test::hostileValues();
    Tally tally;
    Lcg lcg{17};
    for (const MutationTarget& t : targets) {
        REQUIRE(afb::test::runVariant(t, t.afText) != MutationOutcome::Error);
        // Crashes this sweep once found: a bone width made tiny or huge reached Bullet's GJK.
        const std::vector<NumberSpan> widths = boneWidths(t);
        for (std::size_t k = 0; k < std::min<std::size_t>(widths.size(), 2); ++k)
            for (const char* value : {"1e-30", "1e-7", "1e5"}) runOne(tally, t, {{widths[k], value}});
        // A fixed sample of single and double mutations.
        const std::vector<NumberSpan> spans = afb::test::numberSpans(t.afText);
        for (int k = 0; k < 10; ++k)
            runOne(tally, t, {{spans[lcg.below(spans.size())], values[lcg.below(values.size())]}});
        for (int k = 0; k < 4; ++k) {
            std::size_t a = lcg.below(spans.size()), b = lcg.below(spans.size() - 1);
            if (b >= a) ++b;
            if (b < a) std::swap(a, b);
            runOne(tally, t,
                   {{spans[a], values[lcg.below(values.size())]}, {spans[b], values[lcg.below(values.size())]}});
        }
    }
    INFO(tally.summary());
    CHECK(tally.bad() == 0);
    // The sample reaches every good ending: a refusal, a repair that then simulates, and a clean run.
    CHECK(tally.counts[MutationOutcome::Error] > 0);
    CHECK(tally.counts[MutationOutcome::Repaired] > 0);
    CHECK(tally.counts[MutationOutcome::Clean] > 0);
}

TEST_CASE("a hair-thin bone is repaired, or refused under strict", "[mutation]") {
    const std::vector<MutationTarget> targets = bundledTargets();
    REQUIRE_FALSE(targets.empty());
    const MutationTarget& humanoid = targets.front();
    const std::vector<NumberSpan> widths = boneWidths(humanoid);
    REQUIRE_FALSE(widths.empty());
    const std::string thin = afb::test::mutate(humanoid.afText, {{widths.front(), "1e-7"}});
    // The width is repaired to 1 mm; the bone is then so light (totalMass shares 70 kg by volume) that its mass
    // is below the bound, an error: either way nothing thin reaches Bullet.
    afb::text::Diagnostics lenient;
    afb::test::buildVariant(humanoid, thin, false, lenient);
    CHECK(lenient.str().find("bone width is 2.54e-06 mm") != std::string::npos);
    CHECK(lenient.str().find("repaired: raised to 1 mm") != std::string::npos);
    const MutationOutcome outcome = afb::test::runVariant(humanoid, thin);
    CHECK((outcome == MutationOutcome::Error || outcome == MutationOutcome::Repaired));
    afb::text::Diagnostics strict;
    CHECK_FALSE(afb::test::buildVariant(humanoid, thin, true, strict));
    CHECK(strict.str().find("strict") != std::string::npos);
}

TEST_CASE("an inertiaScale of 1e30 is refused before it overflows the solver", "[mutation]") {
    const std::vector<MutationTarget> targets = bundledTargets();
    REQUIRE_FALSE(targets.empty());
    const MutationTarget& humanoid = targets.front();
    const std::size_t at = humanoid.afText.find("inertiaScale (");
    REQUIRE(at != std::string::npos);
    for (const NumberSpan& span : afb::test::numberSpans(humanoid.afText))
        if (span.offset > at) {
            const std::string huge = afb::test::mutate(humanoid.afText, {{span, "1e30"}});
            afb::text::Diagnostics findings;
            CHECK_FALSE(afb::test::buildVariant(humanoid, huge, false, findings));
            CHECK(findings.str().find("x mass x radius^2") != std::string::npos);
            CHECK(afb::test::runVariant(humanoid, huge) == MutationOutcome::Error);
            break;
        }
}

// The full sweep: every number of every bundled and corpus figure with every value, plus sampled pairs
// (AFB_MUTATION_PAIRS per figure, default 200), each dropped for AFB_MUTATION_STEPS steps (default 120, as
// `afb drop --steps 120`). AFB_MUTATION_ONLY=text keeps the figures whose label contains it. Run with
// `afb_tests "[.full]" -s` in a Release build (an hour or more).
TEST_CASE("full numeric mutation sweep", "[.full][mutation-full]") {
    std::vector<MutationTarget> targets = bundledTargets();
    if (const auto corpus = afb::test::corpusDir()) {
        std::vector<MutationTarget> more = corpusTargets(*corpus);
        targets.insert(targets.end(), more.begin(), more.end());
    }
    auto fromEnv = [](const char* name, std::size_t fallback) {
        const char* v = std::getenv(name);
        return v ? std::strtoul(v, nullptr, 10) : fallback;
    };
    std::ostringstream labels;
    for (const MutationTarget& t : targets) labels << "\n  " << t.label;
    WARN(targets.size() << " figures:" << labels.str());
    const std::size_t pairs = fromEnv("AFB_MUTATION_PAIRS", 200);
    const int steps = static_cast<int>(fromEnv("AFB_MUTATION_STEPS", 120));
    const char* only = std::getenv("AFB_MUTATION_ONLY");
    Tally singles, pairTally;
    std::size_t figures = 0, numbers = 0;
    auto merge = [](Tally& into, const Tally& from) {
        for (const auto& [o, n] : from.counts) into.counts[o] += n;
        into.failures.insert(into.failures.end(), from.failures.begin(), from.failures.end());
    };
    for (const MutationTarget& t : targets) {
        if (only && t.label.find(only) == std::string::npos) continue;
        ++figures;
        const std::size_t n = afb::test::numberSpans(t.afText).size();
        numbers += n;
        const SweepTallies one = sweep(t, pairs, steps);
        WARN(t.label << ": " << n << " numbers; singles: " << one.singles.summary()
                     << "; pairs: " << one.pairs.summary());
        merge(singles, one.singles);
        merge(pairTally, one.pairs);
    }
    WARN("total over " << figures << " figures, " << numbers << " numbers, " << steps
                       << " steps; singles: " << singles.summary() << "; pairs: " << pairTally.summary());
    CHECK(singles.bad() == 0);
    CHECK(pairTally.bad() == 0);
}
