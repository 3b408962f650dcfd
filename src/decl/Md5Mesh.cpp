#include "afb/decl/Md5Mesh.h"

#include <algorithm>
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
// rejected before anything is allocated, so a file claiming two billion joints costs nothing.
constexpr std::size_t kMinMeshJointBytes = 17; // `""0(0 0 0)(0 0 0)`
constexpr std::size_t kMinMeshBytes = 48;      // `mesh{shader""numverts 0 numtris 0 numweights 0}`
constexpr std::size_t kMinVertBytes = 14;      // `vert 0(0 0)0 1`
constexpr std::size_t kMinTriBytes = 11;       // `tri 0 0 0 0`
constexpr std::size_t kMinWeightBytes = 19;    // `weight 0 0 0(0 0 0)`

using detail::quotedName;
using detail::reserveFor;

// docs/format.md §7.3. The engine reads this grammar as a fixed sequence of expected tokens (no non-fatal flag),
// so every deviation is an error; on top of it every count, index and reference is checked here.
class MeshParser : detail::Md5ParserBase {
  public:
    MeshParser(std::string_view source, const std::string& fileName, text::Diagnostics& diagnostics)
        : Md5ParserBase(source, fileName, diagnostics) {}

    Md5Mesh parse() {
        Md5Mesh mesh;
        if (m_lex.atEnd()) m_lex.fail(m_lex.peek(), "empty md5mesh file: expected 'MD5Version 10'");
        expectKeyword("MD5Version", "at the start of an md5mesh file");
        const Token versionToken = m_lex.peek();
        if (m_lex.parseInt("MD5Version") != detail::kMd5Version)
            m_lex.fail(versionToken, "MD5Version " + std::string(versionToken.text) + " is not supported (only 10)");
        expectKeyword("commandline", "after MD5Version");
        mesh.commandline = m_lex.expectString("the commandline");
        expectKeyword("numJoints", "after commandline");
        const int numJoints = parseSizedCount("numJoints", kMinMeshJointBytes);
        expectKeyword("numMeshes", "after numJoints");
        const int numMeshes = parseSizedCount("numMeshes", kMinMeshBytes);

        expectKeyword("joints", "after numMeshes");
        m_lex.expectPunct('{', "after 'joints'");
        mesh.joints.reserve(reserveFor(numJoints));
        for (int i = 0; i < numJoints; ++i) {
            if (m_lex.peek().isPunct('}'))
                m_lex.fail(m_lex.peek(), "the joints block ends after " + std::to_string(i) +
                                             " joints, but numJoints is " + std::to_string(numJoints));
            mesh.jointLocations.push_back(m_lex.locationOf(m_lex.peek()));
            mesh.joints.push_back(parseJoint(i));
        }
        const Token close = m_lex.next();
        if (!close.isPunct('}'))
            m_lex.fail(close, "expected '}' closing the joints block after numJoints " + std::to_string(numJoints) +
                                  " joints, found " + close.describe() +
                                  (close.kind == TokenKind::String ? " (more joints than numJoints)" : ""));

        mesh.meshes.reserve(reserveFor(numMeshes));
        for (int m = 0; m < numMeshes; ++m) {
            const Token t = m_lex.next();
            if (t.kind == TokenKind::End)
                m_lex.fail(t, "the file ends after " + std::to_string(m) + " mesh blocks, but numMeshes is " +
                                  std::to_string(numMeshes));
            if (!t.isName("mesh"))
                m_lex.fail(t, "expected 'mesh' block " + std::to_string(m) + " of numMeshes " +
                                  std::to_string(numMeshes) + ", found " + t.describe());
            mesh.meshes.push_back(parseSubMesh(m, numJoints));
        }
        if (!m_lex.atEnd()) {
            const Token t = m_lex.next();
            if (t.isName("mesh")) m_lex.fail(t, "more mesh blocks than numMeshes " + std::to_string(numMeshes));
            m_lex.fail(t, "unexpected " + t.describe() + " after the last mesh block");
        }
        return mesh;
    }

  private:
    struct Where {
        std::uint32_t line, column;
    };

    [[noreturn]] void failAt(Where w, const std::string& message) const {
        throw text::ParseError({m_lex.fileName(), w.line, w.column}, message);
    }

    // md5 entries are numbered 0, 1, 2, … in order; anything else is an error.
    void expectOrdinal(std::string_view what, std::string_view lineKeyword, int expected) {
        const Token t = m_lex.peek();
        const std::uint64_t n = m_lex.parseCount(what, std::numeric_limits<std::uint64_t>::max());
        if (n != static_cast<std::uint64_t>(expected))
            m_lex.fail(t, std::string(what) + " " + std::string(t.text) + " should be " + std::to_string(expected) +
                              " ('" + std::string(lineKeyword) + "' lines are numbered 0, 1, 2, ... in order)");
    }

    // The keyword starting line `index` of a list announced by `countName count`.
    void expectListLine(std::string_view keyword, int index, std::string_view countName, int count) {
        const Token t = m_lex.next();
        if (!t.isName(keyword))
            m_lex.fail(t, "expected '" + std::string(keyword) + "' line " + std::to_string(index) + " of " +
                              std::string(countName) + " " + std::to_string(count) + ", found " + t.describe());
    }

    // The keyword after a list: a further line of the list means its count was too small.
    void expectAfterList(std::string_view keyword, std::string_view listKeyword, std::string_view countName,
                         int count) {
        const Token t = m_lex.next();
        if (t.isName(listKeyword))
            m_lex.fail(t, "more '" + std::string(listKeyword) + "' lines than " + std::string(countName) + " " +
                              std::to_string(count));
        if (!t.isName(keyword))
            m_lex.fail(t, "expected '" + std::string(keyword) + "' after the " + std::string(countName) + " " +
                              std::to_string(count) + " '" + std::string(listKeyword) + "' lines, found " +
                              t.describe());
    }

    Md5Joint parseJoint(int index) {
        Md5Joint joint;
        joint.name = m_lex.expectString("a joint name");
        const Token parentToken = m_lex.peek();
        const std::int64_t parent = m_lex.parseInt("the parent joint index");
        // The engine only checks `parent < numJoints - 1`, but computes each joint's local transform from its
        // parent's, so the parent must already be known (docs/format.md §7.3, §8 item 21).
        if (parent < -1 || parent >= index)
            m_lex.fail(parentToken, "joint " + std::to_string(index) + " " + quotedName(joint.name) + " has parent " +
                                        std::to_string(parent) +
                                        ": parents must precede children (a parent index below " +
                                        std::to_string(index) + ", or -1 for a root)");
        joint.parent = static_cast<int>(parent);
        joint.position = parseVec3("the joint position");
        joint.orientation = parseVec3("the joint orientation");
        return joint;
    }

    Md5SubMesh parseSubMesh(int meshIndex, int numJoints) {
        Md5SubMesh sub;
        m_lex.expectPunct('{', "after 'mesh'");
        Token t = m_lex.next();
        if (t.isName("name")) {
            sub.name = m_lex.expectString("the mesh name");
            t = m_lex.next();
        }
        if (!t.isName("shader"))
            m_lex.fail(t, "expected 'shader' in mesh block " + std::to_string(meshIndex) + ", found " + t.describe());
        sub.shader = m_lex.expectString("the shader name");

        expectKeyword("numverts", "after the shader");
        const int numVerts = parseSizedCount("numverts", kMinVertBytes);
        sub.verts.reserve(reserveFor(numVerts));
        std::vector<Where> firstWeightAt; // where each vertex's weight range was written, for the check below
        firstWeightAt.reserve(reserveFor(numVerts));
        for (int i = 0; i < numVerts; ++i) {
            expectListLine("vert", i, "numverts", numVerts);
            expectOrdinal("vertex index", "vert", i);
            Md5Vert vert;
            m_lex.expectPunct('(', "around the texture coordinates");
            vert.s = m_lex.parseFloat("the texture coordinate s");
            vert.t = m_lex.parseFloat("the texture coordinate t");
            m_lex.expectPunct(')', "around the texture coordinates");
            const Token firstToken = m_lex.peek();
            firstWeightAt.push_back({firstToken.line, firstToken.column});
            const std::int64_t firstWeight = m_lex.parseInt("the vertex's first weight index");
            const Token countToken = m_lex.peek();
            const std::int64_t weightCount = m_lex.parseInt("the vertex's weight count");
            if (firstWeight < 0)
                m_lex.fail(firstToken, "vertex " + std::to_string(i) + " has a negative first weight index " +
                                           std::to_string(firstWeight));
            if (weightCount < 1)
                m_lex.fail(countToken, "vertex " + std::to_string(i) + " has no weights (weight count " +
                                           std::to_string(weightCount) + "); every vertex needs at least one");
            vert.firstWeight = static_cast<int>(firstWeight);
            vert.weightCount = static_cast<int>(weightCount);
            sub.verts.push_back(vert);
        }

        expectAfterList("numtris", "vert", "numverts", numVerts);
        const int numTris = parseSizedCount("numtris", kMinTriBytes);
        sub.tris.reserve(reserveFor(numTris));
        for (int i = 0; i < numTris; ++i) {
            expectListLine("tri", i, "numtris", numTris);
            expectOrdinal("triangle index", "tri", i);
            Md5Tri tri;
            for (int& v : tri.v) {
                const Token vt = m_lex.peek();
                const std::int64_t index = m_lex.parseInt("a triangle vertex index");
                if (index < 0 || index >= numVerts)
                    m_lex.fail(vt, "triangle " + std::to_string(i) + " uses vertex " + std::to_string(index) +
                                       ", out of range (numverts " + std::to_string(numVerts) + ")");
                v = static_cast<int>(index);
            }
            sub.tris.push_back(tri);
        }

        expectAfterList("numweights", "tri", "numtris", numTris);
        const int numWeights = parseSizedCount("numweights", kMinWeightBytes);
        sub.weights.reserve(reserveFor(numWeights));
        for (int i = 0; i < numWeights; ++i) {
            expectListLine("weight", i, "numweights", numWeights);
            expectOrdinal("weight index", "weight", i);
            Md5Weight weight;
            const Token jt = m_lex.peek();
            const std::int64_t joint = m_lex.parseInt("the weight's joint index");
            if (joint < 0 || joint >= numJoints)
                m_lex.fail(jt, "weight " + std::to_string(i) + " refers to joint " + std::to_string(joint) +
                                   ", out of range (numJoints " + std::to_string(numJoints) + ")");
            weight.joint = static_cast<int>(joint);
            weight.bias = m_lex.parseFloat("the weight bias");
            weight.offset = parseVec3("the weight offset");
            sub.weights.push_back(weight);
        }

        const Token close = m_lex.next();
        if (close.isName("weight"))
            m_lex.fail(close, "more 'weight' lines than numweights " + std::to_string(numWeights));
        if (!close.isPunct('}'))
            m_lex.fail(close,
                       "expected '}' closing mesh block " + std::to_string(meshIndex) + ", found " + close.describe());

        // Weight ranges can only be checked once numweights is known.
        for (std::size_t i = 0; i < sub.verts.size(); ++i) {
            const Md5Vert& v = sub.verts[i];
            const std::int64_t end = std::int64_t{v.firstWeight} + v.weightCount;
            if (end > numWeights)
                failAt(firstWeightAt[i], "vertex " + std::to_string(i) + " uses weights " +
                                             std::to_string(v.firstWeight) + ".." + std::to_string(end - 1) +
                                             ", out of range (numweights " + std::to_string(numWeights) + ")");
        }
        return sub;
    }
};

} // namespace

std::optional<int> findJoint(const Md5Mesh& mesh, std::string_view name) {
    for (std::size_t i = 0; i < mesh.joints.size(); ++i)
        if (text::equalsIgnoreCase(mesh.joints[i].name, name)) return static_cast<int>(i);
    return std::nullopt;
}

std::size_t totalVertCount(const Md5Mesh& mesh) {
    std::size_t n = 0;
    for (const Md5SubMesh& m : mesh.meshes) n += m.verts.size();
    return n;
}

std::size_t totalTriCount(const Md5Mesh& mesh) {
    std::size_t n = 0;
    for (const Md5SubMesh& m : mesh.meshes) n += m.tris.size();
    return n;
}

std::size_t totalWeightCount(const Md5Mesh& mesh) {
    std::size_t n = 0;
    for (const Md5SubMesh& m : mesh.meshes) n += m.weights.size();
    return n;
}

std::optional<Md5Mesh> parseMd5Mesh(std::string_view text, const std::string& fileName,
                                    text::Diagnostics& diagnostics) {
    try {
        MeshParser parser(text, fileName, diagnostics);
        return parser.parse();
    } catch (const text::ParseError& e) {
        diagnostics.error(e.where, e.what());
        return std::nullopt;
    }
}

std::optional<Md5Mesh> loadMd5Mesh(const std::filesystem::path& path, text::Diagnostics& diagnostics) {
    const std::optional<std::string> data = text::readFile(path, diagnostics);
    if (!data) return std::nullopt;
    return parseMd5Mesh(*data, path.string(), diagnostics);
}

} // namespace afb::decl
