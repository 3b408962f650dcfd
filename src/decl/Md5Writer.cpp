// Canonical `.md5mesh` and `.md5anim` text (docs/format.md §7.3, §7.4): the inverse of parseMd5Mesh and
// parseMd5Anim, laid out as the id exporters lay them out (one entry a line, tab-indented blocks).
#include <algorithm>
#include <charconv>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "afb/decl/Md5Anim.h"
#include "afb/decl/Md5Mesh.h"

namespace afb::decl {
namespace {

// Shortest fixed-point text that reads back as exactly this double. Fixed rather than exponent form because
// that is what md5 exporters write; a value rounded to d decimals therefore prints with at most d decimals
// and no trailing zeros. A negative value is written as '-' then the number, which the lexer reads back as
// two tokens, as the engine does.
std::string md5Number(double v) {
    if (v == 0) v = 0; // -0 and 0 read back equal; write "0"
    char buf[512];     // DBL_MAX in fixed form is 309 digits
    auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::fixed);
    const std::string_view text(buf, static_cast<std::size_t>(end - buf));
    // A large integral value prints without '.'; the lexer would read it as an integer, which must fit 64
    // bits. The exponent form reads back as the same double.
    if (ec != std::errc{} || (text.find('.') == std::string_view::npos && std::abs(v) >= 1e15))
        end = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::scientific).ptr;
    return std::string(buf, end);
}

std::string vec(const Vec3& v) { return "( " + md5Number(v.x) + " " + md5Number(v.y) + " " + md5Number(v.z) + " )"; }

// md5 strings have no escapes: a quote or a line break cannot be written inside one.
std::string quoted(const std::string& s, const char* what) {
    if (s.find_first_of(std::string_view("\"\n\r\0", 4)) != std::string::npos)
        throw std::invalid_argument(std::string(what) + " \"" + s.substr(0, 60) +
                                    "\" holds a quote, a line break or a NUL byte, which md5 text cannot hold");
    return "\"" + s + "\"";
}

std::string header(int version, const std::string& commandline) {
    return "MD5Version " + std::to_string(version) + "\ncommandline " + quoted(commandline, "the commandline") + "\n\n";
}

void writeSubMesh(std::string& out, const Md5SubMesh& m) {
    out += "\nmesh {\n";
    if (!m.name.empty()) out += "\tname " + quoted(m.name, "the mesh name") + "\n";
    out += "\tshader " + quoted(m.shader, "the shader") + "\n\n";
    out += "\tnumverts " + std::to_string(m.verts.size()) + "\n";
    for (std::size_t i = 0; i < m.verts.size(); ++i) {
        const Md5Vert& v = m.verts[i];
        out += "\tvert " + std::to_string(i) + " ( " + md5Number(v.s) + " " + md5Number(v.t) + " ) " +
               std::to_string(v.firstWeight) + " " + std::to_string(v.weightCount) + "\n";
    }
    out += "\n\tnumtris " + std::to_string(m.tris.size()) + "\n";
    for (std::size_t i = 0; i < m.tris.size(); ++i) {
        const Md5Tri& t = m.tris[i];
        out += "\ttri " + std::to_string(i) + " " + std::to_string(t.v[0]) + " " + std::to_string(t.v[1]) + " " +
               std::to_string(t.v[2]) + "\n";
    }
    out += "\n\tnumweights " + std::to_string(m.weights.size()) + "\n";
    for (std::size_t i = 0; i < m.weights.size(); ++i) {
        const Md5Weight& w = m.weights[i];
        out += "\tweight " + std::to_string(i) + " " + std::to_string(w.joint) + " " + md5Number(w.bias) + " " +
               vec(w.offset) + "\n";
    }
    out += "}\n";
}

// The frame's values, one line per joint: a line starts at every animated joint's startIndex (the exporters'
// layout). Values no joint reads still belong to the frame and stay on the line before them.
void writeFrame(std::string& out, std::size_t index, const std::vector<double>& values,
                const std::vector<bool>& lineStarts) {
    out += "\nframe " + std::to_string(index) + " {\n";
    for (std::size_t i = 0; i < values.size(); ++i) {
        if (lineStarts[i]) out += (i == 0 ? "\t" : "\n\t");
        else out += " ";
        out += md5Number(values[i]);
    }
    if (!values.empty()) out += "\n";
    out += "}\n";
}

void checkAnimCounts(const Md5Anim& anim) {
    const auto describe = [](const char* what, std::size_t n) { return std::string(what) + std::to_string(n); };
    if (anim.baseframe.size() != anim.hierarchy.size())
        throw std::invalid_argument(describe("md5anim: baseframe entries ", anim.baseframe.size()) +
                                    describe(" differ from hierarchy entries ", anim.hierarchy.size()));
    if (anim.bounds.size() != anim.frames.size())
        throw std::invalid_argument(describe("md5anim: bounds ", anim.bounds.size()) +
                                    describe(" differ from frames ", anim.frames.size()));
    for (std::size_t k = 0; k < anim.frames.size(); ++k)
        if (anim.frames[k].size() != static_cast<std::size_t>(std::max(anim.numAnimatedComponents, 0)))
            throw std::invalid_argument(describe("md5anim: frame ", k) +
                                        describe(" has values ", anim.frames[k].size()) +
                                        " but numAnimatedComponents is " + std::to_string(anim.numAnimatedComponents));
}

} // namespace

std::string writeMd5Mesh(const Md5Mesh& mesh) {
    std::string out = header(mesh.version, mesh.commandline);
    out += "numJoints " + std::to_string(mesh.joints.size()) + "\nnumMeshes " + std::to_string(mesh.meshes.size()) +
           "\n\n";
    out += "joints {\n";
    for (const Md5Joint& j : mesh.joints)
        out += "\t" + quoted(j.name, "the joint name") + "\t" + std::to_string(j.parent) + " " + vec(j.position) + " " +
               vec(j.orientation) + "\n";
    out += "}\n";
    for (const Md5SubMesh& m : mesh.meshes) writeSubMesh(out, m);
    return out;
}

std::string writeMd5Anim(const Md5Anim& anim) {
    checkAnimCounts(anim);
    std::string out = header(anim.version, anim.commandline);
    out += "numFrames " + std::to_string(anim.frames.size()) + "\nnumJoints " + std::to_string(anim.hierarchy.size()) +
           "\nframeRate " + std::to_string(anim.frameRate) + "\nnumAnimatedComponents " +
           std::to_string(anim.numAnimatedComponents) + "\n\n";
    out += "hierarchy {\n";
    for (const Md5HierarchyEntry& e : anim.hierarchy)
        out += "\t" + quoted(e.name, "the joint name") + "\t" + std::to_string(e.parent) + " " +
               std::to_string(e.flags) + " " + std::to_string(e.startIndex) + "\n";
    out += "}\n\nbounds {\n";
    for (const Md5Bounds& b : anim.bounds) out += "\t" + vec(b.min) + " " + vec(b.max) + "\n";
    out += "}\n\nbaseframe {\n";
    for (const Md5BaseJoint& j : anim.baseframe) out += "\t" + vec(j.position) + " " + vec(j.orientation) + "\n";
    out += "}\n";

    const auto numComponents = static_cast<std::size_t>(std::max(anim.numAnimatedComponents, 0));
    std::vector<bool> lineStarts(numComponents, false);
    if (numComponents > 0) lineStarts[0] = true;
    for (const Md5HierarchyEntry& e : anim.hierarchy)
        if (animatedComponentCount(e.flags) > 0 && e.startIndex >= 0 &&
            static_cast<std::size_t>(e.startIndex) < numComponents)
            lineStarts[static_cast<std::size_t>(e.startIndex)] = true;
    for (std::size_t k = 0; k < anim.frames.size(); ++k) writeFrame(out, k, anim.frames[k], lineStarts);
    return out;
}

} // namespace afb::decl
