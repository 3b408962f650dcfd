// libFuzzer target: afb gen's import path on arbitrary bytes. The first byte picks the format assimp is told to
// expect (glTF, GLB, FBX, X, B3D, Collada, OBJ, or md5mesh through our own reader); the rest is the file. The import
// must give a rig or an error; a rig must give a figure or an error. Crashes, sanitizer reports and hangs in our
// code are bugs.
//
// assimp itself (Debian's build, not instrumented) crashes on some malformed files inside its own parsers, before
// our code sees anything: a null read in its glTF 2 reader within seconds of fuzzing, failed internal asserts in
// its FBX converter. Those are not ours to fix, and `afb gen` already turns them into an error message by importing
// in a child process. So each input is first read by assimp alone in a forked child; an input that kills the child
// is skipped, and only inputs assimp survives reach importRigFromMemory in this process, where coverage and the
// sanitizers see our code. (assimp is deterministic, so the second read takes the same path as the first.)
#include <cerrno>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <assimp/Importer.hpp>
#include <sys/wait.h>
#include <unistd.h>

#include "afb/decl/Md5Mesh.h"
#include "afb/gen/Generate.h"
#include "afb/gen/Rig.h"

namespace {

// True when assimp reads (or rejects) `bytes` without dying, tried in a child process with stderr silenced.
bool assimpSurvives(const char* bytes, std::size_t size, const std::string& hint) {
    const pid_t pid = ::fork();
    if (pid < 0) return false;
    if (pid == 0) {
        std::freopen("/dev/null", "w", stderr);
        try { // as importRigFromMemory reads it: the same steps, exceptions caught
            Assimp::Importer importer;
            (void)importer.ReadFileFromMemory(bytes, size, afb::gen::assimpPostProcessSteps(), hint.c_str());
        } catch (...) {
        }
        ::_exit(0);
    }
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0)
        if (errno != EINTR) return false;
    return WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

} // namespace

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
        if (!assimpSurvives(bytes, size - 1, hint)) return 0;
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
