#include "report.hpp"

#include <algorithm>
#include <utility>

#include "libcvo/eval/percentile.hpp"

namespace cvo::tools {
namespace {

using eval::percentile;

double median(const std::vector<double>& v) { return percentile(v, 50); }

double fps(const RunReport& r) { return r.wall_s > 0 ? static_cast<double>(r.frames) / r.wall_s : 0.0; }

// One object per accepted loop, in acceptance order; null outside slam mode.
program::Json loop_list(const RunReport& r) {
  if (!r.slam) return nullptr;
  program::Json list = program::Json::array();
  for (const auto& l : r.slam->loops) {
    program::Json loop;
    loop["from"] = l.from;
    loop["to"] = l.to;
    loop["chi2"] = l.chi2;
    loop["weight"] = l.weight;
    loop["from_session"] = l.from_session;
    loop["to_session"] = l.to_session;
    list.push_back(std::move(loop));
  }
  return list;
}

// What --map wrote (the JSON's "map").
program::Json map_object(const MapReport& m) {
  program::Json o;
  o["dir"] = m.dir;
  o["up"] = m.up;
  o["width"] = m.width;
  o["height"] = m.height;
  o["resolution_m"] = m.resolution;
  o["occupied_cells"] = m.occupied;
  o["free_cells"] = m.free;
  o["keyframes"] = m.keyframes;
  o["bytes_per_keyframe"] = m.bytes_per_keyframe;
  o["cloud_points"] = m.cloud_points;
  o["place_ms"] = m.place_ms;
  o["keyframe_timestamps"] = m.keyframe_timestamps;
  return o;
}

// One object per folder, in order; null outside slam mode.
program::Json session_list(const RunReport& r) {
  if (!r.slam) return nullptr;
  program::Json list = program::Json::array();
  for (const auto& s : r.slam->sessions) {
    program::Json session;
    session["sequence"] = s.sequence;
    session["session"] = s.session;
    session["frames"] = s.frames;
    session["keyframes"] = s.keyframes;
    session["joined"] = s.joined;
    session["joined_at_keyframe"] = program::or_null(s.joined_at_keyframe);
    list.push_back(std::move(session));
  }
  return list;
}

// One object per frame skipped or predicted, in frame order.
program::Json failed_frame_list(const RunReport& r) {
  program::Json list = program::Json::array();
  for (const auto& f : r.failed) {
    program::Json frame;
    frame["index"] = f.index;
    frame["timestamp"] = f.timestamp;
    frame["stage"] = f.stage;
    frame["reason"] = f.reason;
    list.push_back(std::move(frame));
  }
  return list;
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
    const auto outliers =
        std::count_if(r.slam->loops.begin(), r.slam->loops.end(), [](const LoopEntry& l) { return l.weight < 0.1; });
    std::fprintf(out, "loops       %zu accepted of %zu tried, %td down-weighted (Cauchy weight < 0.1)\n",
                 r.slam->loops_accepted, r.slam->loops_tried, outliers);
    std::fprintf(out, "graph       %zu keyframe-graph nodes, %zu edges, %zu keyframes merged into ones covering them\n",
                 r.slam->graph_nodes, r.slam->graph_edges, r.slam->keyframes_merged);
    std::fprintf(
        out, "back end    %.0f ms in the run (local graphs, loop detection, keyframe optimisations), final %.0f ms\n",
        r.slam->backend_ms, r.slam->final_optimisation_ms);
    if (const auto& m = r.slam->map)
      std::fprintf(out,
                   "map         %s: %d x %d cells of %.0f cm (%zu occupied, %zu free), up from the %s, %zu keyframes "
                   "of %.0f kB, %zu cloud points, footprints made and placed in %.1f ms\n",
                   m->dir.c_str(), m->width, m->height, m->resolution * 100, m->occupied, m->free, m->up.c_str(),
                   m->keyframes, m->bytes_per_keyframe / 1000, m->cloud_points, m->place_ms);
    if (const auto& s = r.slam->store)
      std::fprintf(out, "store       %s: %llu records (keyframes and local graphs), written in %.0f ms\n",
                   s->file.c_str(), static_cast<unsigned long long>(s->records), s->ms);
    if (r.slam->sessions.size() > 1)
      for (const auto& s : r.slam->sessions) {
        const std::string at = s.joined_at_keyframe ? " at its keyframe " + std::to_string(*s.joined_at_keyframe) : "";
        std::fprintf(out, "session %-3lld %s: %zu frames, %zu keyframes, %s\n", static_cast<long long>(s.session),
                     s.sequence.c_str(), s.frames, s.keyframes,
                     s.joined ? ("joined the map" + at).c_str() : "NOT placed in the map (left out of the trajectory)");
      }
  }
  if (const auto& l = r.localize) {
    std::fprintf(out, "map store   %s (read only)\n", l->map_store.c_str());
    std::fprintf(out, "localized   %zu frames (%zu localizing, %zu lost), %s, %zu sessions, %zu relocalizations\n",
                 l->frames_localized, l->frames_localizing, l->frames_lost,
                 l->localized_after_s ? ("first after " + std::to_string(*l->localized_after_s) + " s").c_str()
                                      : "NEVER localized",
                 l->sessions, l->relocalizations);
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

program::Json to_json(const RunReport& r) {
  // The evaluation's values: null when there was none.
  const auto ate = [&](auto get) { return r.ate ? program::Json(get(*r.ate)) : program::Json(); };
  const auto rpe = [&](auto get) { return r.rpe ? program::Json(get(*r.rpe)) : program::Json(); };
  const auto slam = [&](auto get) { return r.slam ? program::Json(get(*r.slam)) : program::Json(); };
  program::Json o;
  o["mode"] = r.mode;
  o["sequence"] = r.sequence;
  o["trajectory"] = r.trajectory;
  o["frames"] = r.frames;
  o["poses"] = r.poses;
  o["keyframes"] = r.keyframes;
  o["failed_frames"] = r.failed.size();  // a count, like frames and keyframes
  o["failed_frame_list"] = failed_frame_list(r);
  o["wall_s"] = r.wall_s;
  o["fps"] = fps(r);
  o["ms_per_frame_median"] = median(r.track_ms);  // NaN (no frame tracked) prints as null
  o["ms_per_frame_p90"] = percentile(r.track_ms, 90);
  o["ms_per_frame_p99"] = percentile(r.track_ms, 99);
  o["ms_per_frame_max"] = percentile(r.track_ms, 100);
  o["points_median"] = median(r.points);
  o["iterations_median"] = median(r.iterations);
  o["groundtruth"] = r.groundtruth.empty() ? program::Json() : program::Json(r.groundtruth);
  o["ate_pairs"] = r.ate ? r.ate->pairs.size() : 0;
  o["ate_rmse_m"] = ate([](const auto& a) { return a.error.rmse; });
  o["ate_mean_m"] = ate([](const auto& a) { return a.error.mean; });
  o["ate_max_m"] = ate([](const auto& a) { return a.error.max; });
  o["rpe_pairs"] = r.rpe ? r.rpe->pairs.size() : 0;
  o["rpe_trans_m_s"] = rpe([](const auto& p) { return p.translation.rmse; });
  o["rpe_rot_deg_s"] = rpe([](const auto& p) { return p.rotation_deg.rmse; });
  o["loops_accepted"] = slam([](const auto& s) { return s.loops_accepted; });
  o["loops_tried"] = slam([](const auto& s) { return s.loops_tried; });
  o["keyframes_merged"] = slam([](const auto& s) { return s.keyframes_merged; });
  o["graph_nodes"] = slam([](const auto& s) { return s.graph_nodes; });
  o["graph_edges"] = slam([](const auto& s) { return s.graph_edges; });
  o["loop_list"] = loop_list(r);
  o["sessions"] = session_list(r);
  o["backend_ms_total"] = slam([](const auto& s) { return s.backend_ms; });
  o["final_optimisation_ms"] = slam([](const auto& s) { return s.final_optimisation_ms; });
  o["map"] = r.slam && r.slam->map ? map_object(*r.slam->map) : program::Json();
  o["store"] =
      r.slam && r.slam->store
          ? program::Json{{"file", r.slam->store->file}, {"records", r.slam->store->records}, {"ms", r.slam->store->ms}}
          : program::Json();
  const auto localize = [&](auto get) { return r.localize ? program::Json(get(*r.localize)) : program::Json(); };
  o["localized_frames"] = localize([](const auto& l) { return l.frames_localized; });
  o["localized_after_s"] = r.localize ? program::or_null(r.localize->localized_after_s) : program::Json();
  o["relocalizations"] = localize([](const auto& l) { return l.relocalizations; });
  o["frames_localizing"] = localize([](const auto& l) { return l.frames_localizing; });
  o["frames_localized"] = localize([](const auto& l) { return l.frames_localized; });
  o["frames_lost"] = localize([](const auto& l) { return l.frames_lost; });
  o["localization_sessions"] = localize([](const auto& l) { return l.sessions; });
  o["window_keyframes_max"] = localize([](const auto& l) { return l.window_keyframes_max; });
  o["map_store"] = localize([](const auto& l) { return l.map_store; });
  o["ate_rmse_m_odometry"] =
      r.slam && r.slam->ate_odometry ? program::Json(r.slam->ate_odometry->error.rmse) : program::Json();
  return o;
}

}  // namespace cvo::tools
