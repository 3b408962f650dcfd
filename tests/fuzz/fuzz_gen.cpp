// libFuzzer target: afb gen's import path on arbitrary bytes. The first byte picks the format assimp is told to
// expect (glTF, GLB, FBX, X, B3D, Collada, OBJ, or md5mesh through our own reader); the rest is the file. The import
// must give a rig or an error; a rig must give a figure or an error. Crashes, sanitizer reports and hangs in our
// code are bugs. (assimp itself is Debian's build, not instrumented: a crash inside it shows as a crash here too,
// which `afb gen` turns into an error by importing in a child process.)
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "afb/decl/Md5Mesh.h"
#include "afb/gen/Generate.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 1) return 0;
    static const char* const kHints[] = {"gltf", "glb", "fbx", "x", "b3d", "dae", "obj", "md5mesh"};
    const std::string hint = kHints[data[0] % 8];
    const char* bytes = reinterpret_cast<const char*>(data + 1);
    afb::text::Diagnostics diags;
    std::optional<afb::gen::Rig> rig;
    if (hint == "md5mesh") {
        if (const auto mesh = afb::decl::parseMd5Mesh(std::string_view(bytes, size - 1), "fuzz.md5mesh", diags))
            rig = afb::gen::rigFromMd5(*mesh);
    } else {
        rig = afb::gen::importRigFromMemory(bytes, size - 1, hint, {}, diags);
    }
    if (!rig) {
        if (!diags.hasErrors()) std::abort(); // a failed import must say why
        return 0;
    }
    if (rig->joints.size() > 256) return 0; // keep each run short
    afb::gen::GenOptions options;
    options.name = "fuzz";
    const auto generated = afb::gen::generateFigure(*rig, options, diags);
    if (!generated && !diags.hasErrors()) std::abort();
    return 0;
}
