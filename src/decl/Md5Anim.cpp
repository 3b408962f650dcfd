#include "afb/decl/Md5Anim.h"

#include <algorithm>
#include <bit>
#include <cstdint>
#include <functional>
#include <limits>

#include "Md5Common.h"
#include "afb/detail/Lexer.h"
#include "afb/text/Files.h"

namespace afb::decl {
namespace {

using text::Lexer;
using text::Token;
using text::TokenKind;

// The shortest text each entry can be written in. A count larger than the rest of the input could hold is
// rejected before anything is allocated, so a file claiming two billion frames costs nothing.
constexpr std::size_t kMinAnimJointBytes = 21; // `""0 0 0` in hierarchy plus `(0 0 0)(0 0 0)` in baseframe
constexpr std::size_t kMinFrameBytes = 23;     // `(0 0 0)(0 0 0)` in bounds plus `frame 0{}`; values add 2 each

using detail::quotedName;
using detail::reserveFor;

// docs/format.md §7.4: a fixed sequence of sections, each with exactly the announced number of entries.
class AnimParser : detail::Md5ParserBase {
  public:
    AnimParser(std::string_view source, const std::string& fileName, text::Diagnostics& diagnostics)
        : Md5ParserBase(source, fileName, diagnostics) {}

    Md5Anim parse() {
        Md5Anim anim;
        if (m_lex.atEnd()) m_lex.fail(m_lex.peek(), "empty md5anim file: expected 'MD5Version 10'");
        expectKeyword("MD5Version", "at the start of an md5anim file");
        const Token versionToken = m_lex.peek();
        if (m_lex.parseInt("MD5Version") != detail::kMd5Version)
            m_lex.fail(versionToken, "MD5Version " + std::string(versionToken.text) + " is not supported (only 10)");
        expectKeyword("commandline", "after MD5Version");
        anim.commandline = m_lex.expectString("the commandline");

        expectKeyword("numFrames", "after commandline");
        const Token framesToken = m_lex.peek();
        const int numFrames = parseSizedCount("numFrames", kMinFrameBytes);
        if (numFrames == 0) m_lex.fail(framesToken, "numFrames 0: an md5anim needs at least one frame");

        expectKeyword("numJoints", "after numFrames");
        const Token jointsToken = m_lex.peek();
        const int numJoints = parseSizedCount("numJoints", kMinAnimJointBytes);
        if (numJoints == 0) m_lex.fail(jointsToken, "numJoints 0: an md5anim needs at least one joint");

        expectKeyword("frameRate", "after numJoints");
        const Token rateToken = m_lex.peek();
        const std::int64_t frameRate = m_lex.parseInt("frameRate");
        if (frameRate < 0) m_lex.fail(rateToken, "frameRate " + std::to_string(frameRate) + " is negative");
        anim.frameRate = static_cast<int>(frameRate);

        expectKeyword("numAnimatedComponents", "after frameRate");
        const Token componentsToken = m_lex.peek();
        const std::uint64_t components =
            m_lex.parseCount("numAnimatedComponents", std::numeric_limits<std::uint32_t>::max());
        const std::uint64_t maxComponents = 6 * static_cast<std::uint64_t>(numJoints);
        if (components > maxComponents)
            m_lex.fail(componentsToken, "numAnimatedComponents " + std::string(componentsToken.text) +
                                            " is more than 6 per joint (at most " + std::to_string(maxComponents) +
                                            " for numJoints " + std::to_string(numJoints) + ")");
        anim.numAnimatedComponents = static_cast<int>(components);
        // Each value of each frame needs at least a digit and a separator.
        const std::uint64_t frameBytes = kMinFrameBytes + (components > 0 ? 2 * components - 1 : 0);
        if (static_cast<std::uint64_t>(numFrames) * frameBytes > bytesAfter(componentsToken))
            m_lex.fail(framesToken, "numFrames " + std::string(framesToken.text) + " with numAnimatedComponents " +
                                        std::string(componentsToken.text) +
                                        " values each is more than the file can hold");

        anim.hierarchy.reserve(reserveFor(numJoints));
        parseBlock("hierarchy", numJoints, "numJoints", [&](int i) {
            anim.hierarchyLocations.push_back(m_lex.locationOf(m_lex.peek()));
            anim.hierarchy.push_back(parseHierarchyEntry(i, anim.numAnimatedComponents));
        });
        anim.bounds.reserve(reserveFor(numFrames));
        parseBlock("bounds", numFrames, "numFrames", [&](int) {
            Md5Bounds b;
            b.min = parseVec3("the bounds minimum");
            b.max = parseVec3("the bounds maximum");
            anim.bounds.push_back(b);
        });
        anim.baseframe.reserve(reserveFor(numJoints));
        parseBlock("baseframe", numJoints, "numJoints", [&](int) {
            Md5BaseJoint j;
            j.position = parseVec3("the baseframe position");
            j.orientation = parseVec3("the baseframe orientation");
            anim.baseframe.push_back(j);
        });

        anim.frames.reserve(reserveFor(numFrames));
        for (int k = 0; k < numFrames; ++k) anim.frames.push_back(parseFrame(k, numFrames, anim.numAnimatedComponents));
        if (!m_lex.atEnd()) {
            const Token t = m_lex.next();
            if (t.isName("frame")) m_lex.fail(t, "more frames than numFrames " + std::to_string(numFrames));
            m_lex.fail(t, "unexpected " + t.describe() + " after the last frame");
        }
        return anim;
    }

  private:
    // `name { <count> lines }`, each line read by `parseLine(index)`.
    template <class ParseLine>
    void parseBlock(std::string_view name, int count, std::string_view countName, ParseLine&& parseLine) {
        expectKeyword(name, "(the next md5anim section)");
        m_lex.expectPunct('{', "after '" + std::string(name) + "'");
        for (int i = 0; i < count; ++i) {
            if (m_lex.peek().isPunct('}'))
                m_lex.fail(m_lex.peek(), "the " + std::string(name) + " block ends after " + std::to_string(i) +
                                             " lines, but " + std::string(countName) + " is " + std::to_string(count));
            parseLine(i);
        }
        const Token close = m_lex.next();
        if (!close.isPunct('}'))
            m_lex.fail(close, "expected '}' closing the " + std::string(name) + " block after " +
                                  std::string(countName) + " " + std::to_string(count) + " lines, found " +
                                  close.describe() + " (more lines than " + std::string(countName) + "?)");
    }

    Md5HierarchyEntry parseHierarchyEntry(int index, int numComponents) {
        Md5HierarchyEntry e;
        e.name = m_lex.expectString("a joint name");
        const Token parentToken = m_lex.peek();
        const std::int64_t parent = m_lex.parseInt("the parent joint index");
        if (index == 0 && parent != -1)
            m_lex.fail(parentToken, "joint 0 " + quotedName(e.name) + " has parent " + std::to_string(parent) +
                                        ": the first joint must be the root (parent -1)");
        if (index > 0 && (parent < 0 || parent >= index))
            m_lex.fail(parentToken, "joint " + std::to_string(index) + " " + quotedName(e.name) + " has parent " +
                                        std::to_string(parent) + ": only joint 0 may be a root, and parents must " +
                                        "precede children (a parent index 0.." + std::to_string(index - 1) + ")");
        e.parent = static_cast<int>(parent);

        const Token flagsToken = m_lex.peek();
        const std::int64_t flags = m_lex.parseInt("the joint's component flags");
        if (flags < 0 || flags > kMd5AllComponents)
            m_lex.fail(flagsToken, "joint " + std::to_string(index) + " " + quotedName(e.name) + " has flags " +
                                       std::to_string(flags) + ", out of range 0..63");
        e.flags = static_cast<int>(flags);

        const Token startToken = m_lex.peek();
        const std::int64_t start = m_lex.parseInt("the joint's first component index");
        const int used = animatedComponentCount(e.flags);
        if (start < 0 || start + used > numComponents)
            m_lex.fail(startToken, "joint " + std::to_string(index) + " " + quotedName(e.name) + " reads " +
                                       std::to_string(used) + " components from start index " + std::to_string(start) +
                                       ", past numAnimatedComponents " + std::to_string(numComponents));
        e.startIndex = static_cast<int>(start);
        return e;
    }

    // `frame k { C values }`, k running 0, 1, 2, … in order.
    std::vector<double> parseFrame(int k, int numFrames, int numComponents) {
        const Token t = m_lex.next();
        if (t.kind == TokenKind::End)
            m_lex.fail(t, "the file ends after " + std::to_string(k) + " frames, but numFrames is " +
                              std::to_string(numFrames));
        if (!t.isName("frame")) m_lex.fail(t, "expected 'frame " + std::to_string(k) + "', found " + t.describe());
        const Token indexToken = m_lex.peek();
        const std::uint64_t index = m_lex.parseCount("frame index", std::numeric_limits<std::uint64_t>::max());
        if (index != static_cast<std::uint64_t>(k))
            m_lex.fail(indexToken, "frame index " + std::string(indexToken.text) + " should be " + std::to_string(k) +
                                       " (frames are numbered 0, 1, 2, ... in order)");
        m_lex.expectPunct('{', "after 'frame " + std::to_string(k) + "'");
        std::vector<double> values;
        values.reserve(reserveFor(numComponents));
        for (int i = 0; i < numComponents; ++i) {
            if (m_lex.peek().isPunct('}'))
                m_lex.fail(m_lex.peek(), "frame " + std::to_string(k) + " has " + std::to_string(i) +
                                             " values, but numAnimatedComponents is " + std::to_string(numComponents));
            values.push_back(m_lex.parseFloat("a frame value"));
        }
        const Token close = m_lex.next();
        if (close.kind == TokenKind::Number || close.isPunct('-'))
            m_lex.fail(close, "frame " + std::to_string(k) + " has more values than numAnimatedComponents " +
                                  std::to_string(numComponents));
        if (!close.isPunct('}'))
            m_lex.fail(close, "expected '}' closing frame " + std::to_string(k) + ", found " + close.describe());
        return values;
    }
};

} // namespace

int animatedComponentCount(int flags) { return std::popcount(static_cast<unsigned>(flags & kMd5AllComponents)); }

namespace {

// The first joint index where the hierarchies differ (the shorter one's count when one is a prefix of the
// other), and how; nullopt when they match.
std::optional<std::pair<std::size_t, std::string>> firstDifference(const Md5Anim& anim, const Md5Mesh& mesh) {
    const std::size_t common = std::min(anim.hierarchy.size(), mesh.joints.size());
    for (std::size_t i = 0; i < common; ++i) {
        const Md5HierarchyEntry& a = anim.hierarchy[i];
        const Md5Joint& m = mesh.joints[i];
        if (a.name != m.name) // case-sensitive, unlike joint lookups (docs/format.md §8 item 1)
            return std::pair{i, "joint " + std::to_string(i) + " is " + quotedName(a.name) + " in the anim but " +
                                    quotedName(m.name) + " in the mesh (names are compared case-sensitively)"};
        if (a.parent != m.parent)
            return std::pair{i, "joint " + std::to_string(i) + " " + quotedName(a.name) + " has parent " +
                                    std::to_string(a.parent) + " in the anim but " + std::to_string(m.parent) +
                                    " in the mesh"};
    }
    if (anim.hierarchy.size() != mesh.joints.size())
        return std::pair{common, "the anim has " + std::to_string(anim.hierarchy.size()) + " joints, the mesh has " +
                                     std::to_string(mesh.joints.size())};
    return std::nullopt;
}

// Where joint `i` is written in `locations`, if it is.
std::optional<text::SourceLocation> locationOf(const std::vector<text::SourceLocation>& locations, std::size_t i) {
    if (i < locations.size() && locations[i].line > 0) return locations[i];
    return std::nullopt;
}

} // namespace

std::optional<std::string> hierarchyMismatch(const Md5Anim& anim, const Md5Mesh& mesh) {
    // The count first, as the engine's CheckModelHierarchy does.
    if (anim.hierarchy.size() != mesh.joints.size())
        return "the anim has " + std::to_string(anim.hierarchy.size()) + " joints, the mesh has " +
               std::to_string(mesh.joints.size());
    if (auto d = firstDifference(anim, mesh)) return d->second;
    return std::nullopt;
}

std::optional<text::Diagnostic> hierarchyMismatchDiagnostic(const Md5Anim& anim, const Md5Mesh& mesh,
                                                            const std::string& context) {
    const auto message = hierarchyMismatch(anim, mesh);
    if (!message) return std::nullopt;
    // The joint to point at: the first that differs, or, for counts that differ, the first joint past the end of
    // the shorter file (in the file that has it).
    const std::size_t joint = anim.hierarchy.size() != mesh.joints.size()
                                  ? std::min(anim.hierarchy.size(), mesh.joints.size())
                                  : firstDifference(anim, mesh)->first;
    const auto inAnim = locationOf(anim.hierarchyLocations, joint), inMesh = locationOf(mesh.jointLocations, joint);
    text::Diagnostic d;
    d.message = context + *message;
    if (inAnim) d.where = *inAnim;
    else if (inMesh) d.where = *inMesh;
    if (inAnim && inMesh) d.message += " (the mesh's joint " + std::to_string(joint) + ": " + inMesh->str() + ")";
    return d;
}

std::optional<Md5Anim> parseMd5Anim(std::string_view text, const std::string& fileName,
                                    text::Diagnostics& diagnostics) {
    try {
        AnimParser parser(text, fileName, diagnostics);
        return parser.parse();
    } catch (const text::ParseError& e) {
        diagnostics.error(e.where, e.what());
        return std::nullopt;
    }
}

std::optional<Md5Anim> loadMd5Anim(const std::filesystem::path& path, text::Diagnostics& diagnostics) {
    const std::optional<std::string> data = text::readFile(path, diagnostics);
    if (!data) return std::nullopt;
    return parseMd5Anim(*data, path.string(), diagnostics);
}

} // namespace afb::decl
