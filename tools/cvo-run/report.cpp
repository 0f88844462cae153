#include "report.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "libcvo/io/json_writer.hpp"

namespace cvo::tools {

double percentile(std::vector<double> values, double p) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(values.begin(), values.end());
  const double rank = std::clamp(p, 0.0, 100.0) / 100.0 * static_cast<double>(values.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(rank));
  const std::size_t hi = std::min(lo + 1, values.size() - 1);
  return values[lo] + (rank - static_cast<double>(lo)) * (values[hi] - values[lo]);
}

namespace {

double median(const std::vector<double>& v) { return percentile(v, 50); }

double fps(const RunReport& r) { return r.wall_s > 0 ? static_cast<double>(r.frames) / r.wall_s : 0.0; }

// [{"from": j, "to": i, "chi2": s, "weight": w}, ...] one loop a line; null outside slam mode.
std::string loop_list(const RunReport& r) {
  if (!r.slam) return "null";
  if (r.slam->loops.empty()) return "[]";
  std::string out = "[";
  for (std::size_t k = 0; k < r.slam->loops.size(); ++k) {
    const auto& l = r.slam->loops[k];
    out.append(k ? ",\n    " : "\n    ")
        .append("{\"from\": " + std::to_string(l.from) + ", \"to\": " + std::to_string(l.to))
        .append(", \"chi2\": " + io::json_number(l.chi2) + ", \"weight\": " + io::json_number(l.weight))
        .append(", \"from_session\": " + std::to_string(l.from_session) + ", \"to_session\": " +
                std::to_string(l.to_session) + "}");
  }
  return out + "\n  ]";
}

// [{"sequence": ..., "session": n, "frames": .., "keyframes": .., "joined": .., "joined_at_keyframe": ..}]
std::string session_list(const RunReport& r) {
  if (!r.slam) return "null";
  std::string out = "[";
  for (std::size_t k = 0; k < r.slam->sessions.size(); ++k) {
    const auto& s = r.slam->sessions[k];
    out.append(k ? ",\n    " : "\n    ")
        .append("{\"sequence\": " + io::json_string(s.sequence) + ", \"session\": " + std::to_string(s.session))
        .append(", \"frames\": " + std::to_string(s.frames) + ", \"keyframes\": " + std::to_string(s.keyframes))
        .append(std::string(", \"joined\": ") + (s.joined ? "true" : "false") + ", \"joined_at_keyframe\": ")
        .append(s.joined_at_keyframe ? std::to_string(*s.joined_at_keyframe) : "null")
        .append("}");
  }
  return out + (r.slam->sessions.empty() ? "]" : "\n  ]");
}

}  // namespace

void print_text(std::FILE* out, const RunReport& r) {
  std::fprintf(out, "sequence    %s\nmode        %s\ntrajectory  %s (%zu poses)\n", r.sequence.c_str(), r.mode.c_str(),
               r.trajectory.c_str(), r.poses);
  std::fprintf(out, "frames      %zu in %.2f s (%.1f fps, reading images included)\n", r.frames, r.wall_s, fps(r));
  std::fprintf(out, "failed      %zu\n", r.failed.size());
  for (const auto& f : r.failed)
    std::fprintf(out, "  frame %zu (t = %.6f, %s): %s\n", f.index, f.timestamp, f.stage.c_str(), f.reason.c_str());
  std::fprintf(out, "keyframes   %zu%s\n", r.keyframes, r.mode == "cvo" ? " (frame-to-frame: no keyframes)" : "");
  if (!r.track_ms.empty())
    std::fprintf(out, "ms/frame    median %.2f  p90 %.2f  p99 %.2f  max %.2f  (%s)\n", median(r.track_ms),
                 percentile(r.track_ms, 90), percentile(r.track_ms, 99), percentile(r.track_ms, 100),
                 r.slam ? "tracking and the back end's work in that frame" : "track(): selection + registration");
  if (!r.points.empty()) std::fprintf(out, "points      median %.0f per frame\n", median(r.points));
  if (!r.iterations.empty()) std::fprintf(out, "iterations  median %.0f per registration\n", median(r.iterations));
  if (r.slam) {
    const auto outliers = std::count_if(r.slam->loops.begin(), r.slam->loops.end(),
                                        [](const LoopEntry& l) { return l.weight < 0.1; });
    std::fprintf(out, "loops       %zu accepted of %zu tried, %td down-weighted (Cauchy weight < 0.1)\n",
                 r.slam->loops_accepted, r.slam->loops_tried, outliers);
    std::fprintf(out, "back end    %.0f ms in the run (local graphs, loop detection, keyframe optimisations), final %.0f ms\n",
                 r.slam->backend_ms, r.slam->final_optimisation_ms);
    if (r.slam->sessions.size() > 1)
      for (const auto& s : r.slam->sessions) {
        const std::string at = s.joined_at_keyframe ? " at its keyframe " + std::to_string(*s.joined_at_keyframe) : "";
        std::fprintf(out, "session %-3lld %s: %zu frames, %zu keyframes, %s\n", static_cast<long long>(s.session),
                     s.sequence.c_str(), s.frames, s.keyframes,
                     s.joined ? ("joined the map" + at).c_str() : "NOT placed in the map (left out of the trajectory)");
      }
  }
  if (r.groundtruth.empty()) {
    std::fprintf(out, "evaluation  none (no ground truth)\n");
    return;
  }
  std::fprintf(out, "groundtruth %s\n", r.groundtruth.c_str());
  if (r.ate)
    std::fprintf(out, "ATE         rmse %.4f m  mean %.4f  median %.4f  max %.4f  (%zu pairs)\n", r.ate->error.rmse,
                 r.ate->error.mean, r.ate->error.median, r.ate->error.max, r.ate->pairs.size());
  else
    std::fprintf(out, "ATE         n/a (too few poses associate with the ground truth)\n");
  if (r.slam && r.slam->ate_odometry)
    std::fprintf(out, "ATE kf-cvo  rmse %.4f m  (the tracker's own poses, before the back end)\n",
                 r.slam->ate_odometry->error.rmse);
  if (r.rpe)
    std::fprintf(out, "RPE         rmse %.4f m/s  %.3f deg/s  (delta 1 s, %zu pairs)\n", r.rpe->translation.rmse,
                 r.rpe->rotation_deg.rmse, r.rpe->pairs.size());
  else
    std::fprintf(out, "RPE         n/a (the run is too short for 1 s pairs)\n");
}

std::string to_json(const RunReport& r) {
  using io::json_number;
  using io::json_string;
  const auto ate = [&](auto get) -> std::optional<double> {
    if (!r.ate) return std::nullopt;
    return get(*r.ate);
  };
  const auto rpe = [&](auto get) -> std::optional<double> {
    if (!r.rpe) return std::nullopt;
    return get(*r.rpe);
  };
  const auto slam = [&](auto get) -> std::optional<double> {
    if (!r.slam) return std::nullopt;
    return get(*r.slam);
  };
  std::ostringstream o;
  o << "{\n"
    << "  \"mode\": " << json_string(r.mode) << ",\n"
    << "  \"sequence\": " << json_string(r.sequence) << ",\n"
    << "  \"trajectory\": " << json_string(r.trajectory) << ",\n"
    << "  \"frames\": " << r.frames << ",\n"
    << "  \"poses\": " << r.poses << ",\n"
    << "  \"keyframes\": " << r.keyframes << ",\n"
    << "  \"failed_frames\": " << r.failed.size() << ",\n"  // a count, like frames and keyframes
    << "  \"failed_frame_list\": [";
  for (std::size_t k = 0; k < r.failed.size(); ++k) {
    const auto& f = r.failed[k];
    o << (k ? ",\n" : "\n") << "    {\"index\": " << f.index << ", \"timestamp\": " << json_number(f.timestamp)
      << ", \"stage\": " << json_string(f.stage) << ", \"reason\": " << json_string(f.reason) << "}";
  }
  o << (r.failed.empty() ? "],\n" : "\n  ],\n")
    << "  \"wall_s\": " << json_number(r.wall_s) << ",\n"
    << "  \"fps\": " << json_number(fps(r)) << ",\n"
    << "  \"ms_per_frame_median\": " << json_number(median(r.track_ms)) << ",\n"
    << "  \"ms_per_frame_p90\": " << json_number(percentile(r.track_ms, 90)) << ",\n"
    << "  \"ms_per_frame_p99\": " << json_number(percentile(r.track_ms, 99)) << ",\n"
    << "  \"ms_per_frame_max\": " << json_number(percentile(r.track_ms, 100)) << ",\n"
    << "  \"points_median\": " << json_number(median(r.points)) << ",\n"
    << "  \"iterations_median\": " << json_number(median(r.iterations)) << ",\n"
    << "  \"groundtruth\": " << (r.groundtruth.empty() ? "null" : json_string(r.groundtruth)) << ",\n"
    << "  \"ate_pairs\": " << (r.ate ? r.ate->pairs.size() : 0) << ",\n"
    << "  \"ate_rmse_m\": " << json_number(ate([](const auto& a) { return a.error.rmse; })) << ",\n"
    << "  \"ate_mean_m\": " << json_number(ate([](const auto& a) { return a.error.mean; })) << ",\n"
    << "  \"ate_max_m\": " << json_number(ate([](const auto& a) { return a.error.max; })) << ",\n"
    << "  \"rpe_pairs\": " << (r.rpe ? r.rpe->pairs.size() : 0) << ",\n"
    << "  \"rpe_trans_m_s\": " << json_number(rpe([](const auto& p) { return p.translation.rmse; })) << ",\n"
    << "  \"rpe_rot_deg_s\": " << json_number(rpe([](const auto& p) { return p.rotation_deg.rmse; })) << ",\n"
    << "  \"loops_accepted\": " << (r.slam ? std::to_string(r.slam->loops_accepted) : "null") << ",\n"
    << "  \"loops_tried\": " << (r.slam ? std::to_string(r.slam->loops_tried) : "null") << ",\n"
    << "  \"loop_list\": " << loop_list(r) << ",\n"
    << "  \"sessions\": " << session_list(r) << ",\n"
    << "  \"backend_ms_total\": " << json_number(slam([](const auto& s) { return s.backend_ms; })) << ",\n"
    << "  \"final_optimisation_ms\": " << json_number(slam([](const auto& s) { return s.final_optimisation_ms; }))
    << ",\n"
    << "  \"ate_rmse_m_odometry\": " << json_number(slam([](const auto& s) -> std::optional<double> {
         if (!s.ate_odometry) return std::nullopt;
         return s.ate_odometry->error.rmse;
       })) << "\n"
    << "}\n";
  return o.str();
}

}  // namespace cvo::tools
