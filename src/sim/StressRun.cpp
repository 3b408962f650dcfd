// One run of the stress matrix (Stress.h), shared by the matrix and by `afb run`.
#include "afb/sim/Stress.h"

namespace afb::sim {

// Run k of n turns its scenario by k·360°/n.
double stressYawDeg(std::size_t k, std::size_t yaws) {
    return 360.0 * static_cast<double>(k) / static_cast<double>(yaws);
}

StressResult runStressRun(const std::optional<StressSetup>& yawed, const std::string& scenario,
                          const StressMethod& method, const StressThresholds& thresholds, double yawDeg) {
    StressResult r;
    if (yawed) r = runStress(*yawed, method, thresholds);
    else {
        r.method = method.label;
        r.cause = StressCause::Skipped;
        r.detail = "needs the bundled humanoid (--base)";
    }
    r.scenario = scenario;
    r.yawDeg = yawDeg;
    return r;
}

} // namespace afb::sim
