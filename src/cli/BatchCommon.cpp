// What afb plan, run and merge share: the build's identity, input hashes, and the job of each command.
#include <LinearMath/btScalar.h>

#include "Batch.h"
#include "afb/Version.h"
#include "afb/sim/Batch.h"

#ifndef AFB_BUILD_TYPE
#define AFB_BUILD_TYPE ""
#endif

namespace afb::cli {

std::string buildIdentity() {
    const int bullet = btGetVersion();
#ifdef BT_USE_DOUBLE_PRECISION
    const char* precision = "double";
#else
    const char* precision = "float";
#endif
    return "afb " AFB_VERSION_STRING " (Bullet " + std::to_string(bullet / 100) + "." + std::to_string(bullet % 100) +
           ", " + precision + ", " + (*AFB_BUILD_TYPE ? AFB_BUILD_TYPE : "no build type") + ", " __VERSION__ ")";
}

bool addEntityInputs(const decl::Library& library, const std::string& entity, const std::filesystem::path& base,
                     nlohmann::json& inputs, text::Diagnostics& diagnostics) {
    const auto r = library.resolveEntity(entity, diagnostics);
    if (!r) return false;
    const std::filesystem::path root = std::filesystem::absolute(base);
    for (const std::filesystem::path& p :
         {r->figureFile, r->meshPath, r->afPosePath, std::filesystem::path(r->entityLocation.file),
          std::filesystem::path(r->modelLocation.file)}) {
        if (p.empty()) continue;
        inputs[std::filesystem::relative(std::filesystem::absolute(p), root).generic_string()] = sim::fileHash(p);
    }
    return true;
}

nlohmann::json hashInputs(const std::filesystem::path& base, const nlohmann::json& inputs) {
    nlohmann::json now = nlohmann::json::object();
    for (const auto& [rel, hash] : inputs.items()) now[rel] = sim::fileHash(base / rel);
    return now;
}

std::unique_ptr<BatchJob> makeBatchJob(const std::string& command, const nlohmann::json& plan, bool forRunning,
                                       std::string& error) {
    if (command == "stress") return makeStressJob(plan, forRunning, error);
    if (command == "chart") return makeChartJob(plan, forRunning, error);
    if (command == "drop") return makeDropJob(plan, forRunning, error);
    if (command == "golden") return makeGoldenJob(plan, error);
    error = "unknown command '" + command + "' (stress, chart, drop, golden)";
    return nullptr;
}

} // namespace afb::cli
