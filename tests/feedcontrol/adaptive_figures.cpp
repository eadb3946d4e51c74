// Writes the closed-loop traces of the three anti-wind-up policies as CSV (one file per policy,
// every 10th cycle) and prints the figures quoted in docs/adaptive-feed.md.
//   cncore_adaptive_figures OUT_DIR
#include <cmath>
#include <cstdio>
#include <string>

#include "scenario.hpp"

using namespace cncore::feed;

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s OUT_DIR\n", argv[0]);
    return 2;
  }
  const std::string dir = argv[1];
  const double period_s = scenario::options().period_s;
  double above_clamp = 0;
  for (AntiWindup p : {AntiWindup::kNone, AntiWindup::kClamp, AntiWindup::kBackCalculation}) {
    const auto trace = scenario::run(p);
    const std::string name(antiwindup_name(p));
    const std::string path = dir + "/adaptive-" + name + ".csv";
    std::FILE* f = std::fopen(path.c_str(), "w");
    if (!f) {
      std::fprintf(stderr, "cannot write %s\n", path.c_str());
      return 1;
    }
    std::fprintf(f,
                 "t_s,s_mm,depth_mm,feed_mm_min,override_pct,load_pct,target_pct,"
                 "integral_term_pct,limited\n");
    for (std::size_t i = 0; i < trace.size(); i += 10) {
      const TraceRow& r = trace[i];
      std::fprintf(f, "%.3f,%.3f,%.3f,%.1f,%.2f,%.2f,%.1f,%.2f,%d\n", r.t_s, r.s_mm, r.depth_mm,
                   r.feed_mm_min, r.override_pct, r.load_pct, r.target_pct, r.integral_term_pct,
                   r.limited ? 1 : 0);
    }
    std::fclose(f);
    const double above =
        scenario::time_above_s(trace, scenario::kJumpUpMm, scenario::kJumpDownMm, period_s);
    const double recover =
        scenario::time_to_recover_s(trace, scenario::kJumpUpMm, scenario::kJumpDownMm);
    const auto load_peak = scenario::range_of(
        trace, scenario::kJumpUpMm, scenario::kJumpDownMm,
        [](const TraceRow& r) { return r.load_pct; }, [](const TraceRow&) { return true; });
    const auto ovr = scenario::range_of(
        trace, scenario::kLightStartMm, scenario::kJumpUpMm,
        [](const TraceRow& r) { return r.override_pct; }, [](const TraceRow&) { return true; });
    const auto iterm_limited = scenario::range_of(
        trace, scenario::kLightStartMm + 10, scenario::kJumpUpMm,
        [](const TraceRow& r) { return r.integral_term_pct; },
        [](const TraceRow& r) { return r.limited; });
    if (p == AntiWindup::kClamp) above_clamp = above;
    std::printf("%-17s run %.3f s | light cut: override max %.1f %% | ", name.c_str(),
                trace.back().t_s, ovr.max);
    if (std::isfinite(iterm_limited.span())) {
      std::printf("Ki*I while limited %.1f..%.1f %% | ", iterm_limited.min, iterm_limited.max);
    } else {
      std::printf("never limited | ");
    }
    std::printf("after jump: load peak %.1f %%, above target+5 %.3f s, back within %.3f s",
                load_peak.max, above, recover);
    if (p == AntiWindup::kBackCalculation && above_clamp > 0) {
      std::printf(" | ratio to clamp %.3f", above / above_clamp);
    }
    std::printf("\n");
  }
  return 0;
}
