#pragma once
// The stress run's rest judgement (internal to sim; tests/sim use it directly): a window of restWindowS over which
// no body moved beyond the rest bounds, and the largest spin a body reported in the window's second half. Its first
// half is left out because its first steps are the settling of the motion that ended just before the window began
// (a link landing flat spins down over a few steps while turning less than the rest bound); a body that still
// reports a spin in the second half is held in place while its velocity says it turns: jitter.
#include <string>

#include "afb/sim/Stress.h"

namespace afb::sim::detail {

class RestWindow {
  public:
    enum class Verdict {
        Open,   ///< the window has not lasted restWindowS yet
        Rested, ///< still for restWindowS, no spin over the bound in its second half: at rest since start()
        Jitter, ///< still for restWindowS, but a body reported more than the bound in its second half
    };

    explicit RestWindow(const StressThresholds& th) : m_th(th) {}

    /// Whether a spin reported at `now` counts (the window's second half).
    bool counts(double now) const { return now - m_start >= m_th.restWindowS / 2 - 1e-9; }
    /// A body's spin after the step that ends at `now`; `body` names it in the failure text.
    void spin(double now, double radps, const std::string& body) {
        if (counts(now) && radps > m_worst) {
            m_worst = radps;
            m_worstBody = body;
        }
    }
    /// After the step that ends at `now`: `still` says nothing moved beyond the bounds since start(). A move starts
    /// a new window now.
    Verdict update(double now, bool still) {
        if (!still) {
            m_start = now;
            m_worst = 0;
            m_worstBody.clear();
            return Verdict::Open;
        }
        if (now - m_start < m_th.restWindowS - 1e-9) return Verdict::Open;
        return m_worst > m_th.maxResidualSpinRadps ? Verdict::Jitter : Verdict::Rested;
    }
    double start() const { return m_start; }
    double worstSpin() const { return m_worst; }
    const std::string& worstBody() const { return m_worstBody; }

  private:
    StressThresholds m_th;
    double m_start = 0;
    double m_worst = 0;
    std::string m_worstBody;
};

} // namespace afb::sim::detail
