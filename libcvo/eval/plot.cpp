#include "libcvo/eval/plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "libcvo/io/input_error.hpp"

namespace cvo::eval {
namespace {

const cv::Scalar kBlack{0, 0, 0}, kBlue{200, 60, 0}, kRed{0, 0, 220}, kGrey{120, 120, 120}, kGrid{225, 225, 225},
    kWhite{255, 255, 255};
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr int kShift = 4;  // sub-pixel bits for cv::line: smooth curves at small scales
constexpr double kTickFont = 0.42, kLabelFont = 0.5, kTitleFont = 0.65;

struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void add(double v) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  [[nodiscard]] double span() const { return hi - lo; }
  [[nodiscard]] double mid() const { return 0.5 * (lo + hi); }
};

// An axes box in pixels and the data range it shows.
struct Axes {
  cv::Rect box;
  Range x, y;
  [[nodiscard]] cv::Point2d to_pixel(double u, double v) const {
    return {box.x + (u - x.lo) / x.span() * box.width, box.y + box.height - (v - y.lo) / y.span() * box.height};
  }
};

cv::Point fixed_point(cv::Point2d p) {
  return {static_cast<int>(std::lround(p.x * (1 << kShift))), static_cast<int>(std::lround(p.y * (1 << kShift)))};
}

void line(cv::Mat& img, cv::Point2d a, cv::Point2d b, const cv::Scalar& colour, int thickness = 1) {
  cv::line(img, fixed_point(a), fixed_point(b), colour, thickness, cv::LINE_AA, kShift);
}

void dashed_line(cv::Mat& img, cv::Point2d a, cv::Point2d b, const cv::Scalar& colour) {
  const double length = cv::norm(b - a);
  const int dashes = std::max(1, static_cast<int>(length / 12));
  for (int k = 0; k < dashes; ++k)
    line(img, a + (b - a) * (k / static_cast<double>(dashes)), a + (b - a) * ((k + 0.5) / dashes), colour);
}

// Text anchored at `at`: halign 0 left, 0.5 centred, 1 right; the baseline sits at at.y + height/2.
void text(cv::Mat& img, const std::string& s, cv::Point2d at, double scale, double halign = 0,
          const cv::Scalar& colour = kBlack) {
  int baseline = 0;
  const cv::Size size = cv::getTextSize(s, kFont, scale, 1, &baseline);
  const cv::Point origin(static_cast<int>(std::lround(at.x - halign * size.width)),
                         static_cast<int>(std::lround(at.y + size.height / 2.0)));
  cv::putText(img, s, origin, kFont, scale, colour, 1, cv::LINE_AA);
}

// putText cannot rotate: draw on a strip, turn it, paste it centred on `centre`.
void vertical_text(cv::Mat& img, const std::string& s, cv::Point centre, double scale) {
  int baseline = 0;
  const cv::Size size = cv::getTextSize(s, kFont, scale, 1, &baseline);
  cv::Mat strip(size.height + baseline + 4, size.width + 4, CV_8UC3, kWhite);
  cv::putText(strip, s, {2, size.height + 2}, kFont, scale, kBlack, 1, cv::LINE_AA);
  cv::Mat turned;
  cv::rotate(strip, turned, cv::ROTATE_90_COUNTERCLOCKWISE);
  const cv::Rect where = cv::Rect(centre.x - turned.cols / 2, centre.y - turned.rows / 2, turned.cols, turned.rows) &
                         cv::Rect(0, 0, img.cols, img.rows);
  if (where.area() > 0) turned(cv::Rect(0, 0, where.width, where.height)).copyTo(img(where));
}

// 1, 2 or 5 times a power of ten, giving about `target` ticks over the span.
double nice_step(double span, int target) {
  const double raw = span / target;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  const double f = raw / magnitude;
  return (f < 1.5 ? 1 : f < 3 ? 2 : f < 7 ? 5 : 10) * magnitude;
}

std::string tick_label(double v, double step) {
  const int decimals = std::max(0, static_cast<int>(-std::floor(std::log10(step) + 1e-9)));
  if (std::abs(v) < 1e-9 * step) v = 0;  // never "-0.0"
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

int text_width(const std::string& s, double scale) {
  int baseline = 0;
  return cv::getTextSize(s, kFont, scale, 1, &baseline).width;
}

// Frame, grid, ticks and labels. The y label goes left of the widest tick label, but never
// further left than `left_limit` (the panel's edge).
void draw_axes(cv::Mat& img, const Axes& ax, const std::string& xlabel, const std::string& ylabel, int left_limit) {
  text(img, xlabel, {ax.box.x + ax.box.width / 2.0, ax.box.y + ax.box.height + 38.0}, kLabelFont, 0.5);
  int widest_y_tick = 0;
  const double xstep = nice_step(ax.x.span(), std::max(3, ax.box.width / 90));
  const double ystep = nice_step(ax.y.span(), std::max(3, ax.box.height / 70));
  if (std::isfinite(xstep) && std::isfinite(ystep) && xstep > 0 && ystep > 0) {
    for (auto k = static_cast<long>(std::ceil(ax.x.lo / xstep)); static_cast<double>(k) * xstep <= ax.x.hi; ++k) {
      const double v = static_cast<double>(k) * xstep;
      const cv::Point2d p = ax.to_pixel(v, ax.y.lo);
      line(img, {p.x, static_cast<double>(ax.box.y)}, p, kGrid);
      line(img, p, {p.x, p.y + 5}, kBlack);
      text(img, tick_label(v, xstep), {p.x, p.y + 16}, kTickFont, 0.5);
    }
    for (auto k = static_cast<long>(std::ceil(ax.y.lo / ystep)); static_cast<double>(k) * ystep <= ax.y.hi; ++k) {
      const double v = static_cast<double>(k) * ystep;
      const cv::Point2d p = ax.to_pixel(ax.x.lo, v);
      line(img, p, {static_cast<double>(ax.box.x + ax.box.width), p.y}, kGrid);
      line(img, {p.x - 5, p.y}, p, kBlack);
      const std::string label = tick_label(v, ystep);
      widest_y_tick = std::max(widest_y_tick, text_width(label, kTickFont));
      text(img, label, {p.x - 8, p.y}, kTickFont, 1.0);
    }
  }
  cv::rectangle(img, ax.box, kBlack, 1);
  const int label_x = std::max(left_limit + 10, ax.box.x - widest_y_tick - 22);
  vertical_text(img, ylabel, {label_x, ax.box.y + ax.box.height / 2}, kLabelFont);
}

struct LegendEntry {
  std::string label;
  cv::Scalar colour;
  bool dashed = false;
};

void draw_legend(cv::Mat& img, const Axes& ax, const std::vector<LegendEntry>& entries) {
  int width = 0;
  for (const auto& e : entries) {
    width = std::max(width, text_width(e.label, kTickFont));
  }
  const cv::Rect frame(ax.box.x + 8, ax.box.y + 8, width + 50, static_cast<int>(entries.size()) * 20 + 8);
  cv::rectangle(img, frame, kWhite, cv::FILLED);
  cv::rectangle(img, frame, kGrey, 1);
  for (std::size_t k = 0; k < entries.size(); ++k) {
    const double y = frame.y + 14.0 + 20.0 * static_cast<double>(k);
    const cv::Point2d a(frame.x + 8.0, y), b(frame.x + 36.0, y);
    if (entries[k].dashed)
      dashed_line(img, a, b, entries[k].colour);
    else
      line(img, a, b, entries[k].colour, 2);
    text(img, entries[k].label, {frame.x + 42.0, y}, kTickFont);
  }
}

// Consecutive points are joined unless their stamps are more than 2 median intervals apart, as
// evaluate_ate.py's plot_traj does, so that gaps in a trajectory show as gaps.
void polyline(cv::Mat& img, const Axes& ax, const std::vector<double>& t, const std::vector<cv::Point2d>& xy,
              const cv::Scalar& colour, int thickness) {
  if (xy.size() < 2) return;
  std::vector<double> dt;
  for (std::size_t k = 1; k < t.size(); ++k) dt.push_back(t[k] - t[k - 1]);
  std::nth_element(dt.begin(), dt.begin() + static_cast<long>(dt.size() / 2), dt.end());
  const double max_gap = 2.0 * dt[dt.size() / 2];
  for (std::size_t k = 1; k < xy.size(); ++k)
    if (t[k] - t[k - 1] <= max_gap)
      line(img, ax.to_pixel(xy[k - 1].x, xy[k - 1].y), ax.to_pixel(xy[k].x, xy[k].y), colour, thickness);
}

Range padded(Range r, double fraction, double minimum_span) {
  if (!(r.lo <= r.hi)) r = {0, 0};  // nothing added
  const double span = std::max(r.span(), minimum_span);
  return {r.mid() - span * (0.5 + fraction), r.mid() + span * (0.5 + fraction)};
}

void draw_top_view(cv::Mat& img, cv::Rect box, int left_limit, const core::Trajectory& gt, const core::Trajectory& est,
                   const AteResult& ate) {
  std::vector<double> gt_t, est_t;
  std::vector<cv::Point2d> gt_xy, est_xy;
  Range x, y;
  for (const auto& p : gt) {
    gt_t.push_back(p.timestamp);
    gt_xy.emplace_back(p.pose.translation().x(), p.pose.translation().y());
  }
  for (const auto& p : est) {
    const Eigen::Vector3d a = ate.alignment * p.pose.translation();
    est_t.push_back(p.timestamp);
    est_xy.emplace_back(a.x(), a.y());
  }
  for (const auto* points : {&gt_xy, &est_xy}) {
    for (const auto& v : *points) {
      x.add(v.x);
      y.add(v.y);
    }
  }

  // Equal aspect: one metre is the same number of pixels on both axes, the data centred.
  const Range px = padded(x, 0.05, 1e-3), py = padded(y, 0.05, 1e-3);
  const double metres_per_pixel = std::max(px.span() / box.width, py.span() / box.height);
  const double half_w = 0.5 * box.width * metres_per_pixel, half_h = 0.5 * box.height * metres_per_pixel;
  const Axes ax{box, {px.mid() - half_w, px.mid() + half_w}, {py.mid() - half_h, py.mid() + half_h}};

  draw_axes(img, ax, "x [m]", "y [m]", left_limit);
  for (const auto& p : ate.pairs)
    line(img, ax.to_pixel(p.gt_position.x(), p.gt_position.y()),
         ax.to_pixel(p.aligned_position.x(), p.aligned_position.y()), kRed);
  polyline(img, ax, gt_t, gt_xy, kBlack, 2);
  polyline(img, ax, est_t, est_xy, kBlue, 2);
  cv::rectangle(img, ax.box, kBlack, 1);
  draw_legend(img, ax, {{"ground truth", kBlack}, {"estimate (aligned)", kBlue}, {"difference", kRed}});
}

void draw_error_over_time(cv::Mat& img, cv::Rect box, int left_limit, const AteResult& ate) {
  const double t0 = ate.pairs.empty() ? 0.0 : ate.pairs.front().gt_timestamp;
  std::vector<double> t;
  std::vector<cv::Point2d> te;
  Range x, y;
  y.add(0);
  for (const auto& p : ate.pairs) {
    t.push_back(p.gt_timestamp);
    te.emplace_back(p.gt_timestamp - t0, p.error);
    x.add(p.gt_timestamp - t0);
    y.add(p.error);
  }
  const Range px = padded(x, 0.02, 1e-3);
  const Range py{0, std::max(y.hi * 1.15, 1e-3)};
  const Axes ax{box, px, py};
  draw_axes(img, ax, "time [s]", "translational error [m]", left_limit);
  dashed_line(img, ax.to_pixel(px.lo, ate.error.rmse), ax.to_pixel(px.hi, ate.error.rmse), kGrey);
  polyline(img, ax, t, te, kBlue, 2);
  draw_legend(img, ax, {{"ATE per pose pair", kBlue}, {"RMSE", kGrey, true}});
}

std::string fit_width(std::string s, int max_width, double scale) {
  int baseline = 0;
  while (s.size() > 4 && cv::getTextSize(s, kFont, scale, 1, &baseline).width > max_width) s = "..." + s.substr(4);
  return s;
}

}  // namespace

cv::Mat render_evaluation_plot(const core::Trajectory& groundtruth, const core::Trajectory& estimate,
                               const AteResult& ate, const PlotOptions& options) {
  if (options.size.width < 400 || options.size.height < 300)
    throw std::invalid_argument("evaluation plot needs at least 400 x 300 pixels");
  cv::Mat img(options.size, CV_8UC3, kWhite);
  const int w = options.size.width, h = options.size.height;
  constexpr int kTop = 48, kLeft = 90, kRight = 18, kBottom = 56;
  const cv::Rect left(kLeft, kTop, w / 2 - kLeft - kRight, h - kTop - kBottom);
  const cv::Rect right(w / 2 + kLeft, kTop, w - w / 2 - kLeft - kRight, h - kTop - kBottom);
  draw_top_view(img, left, 0, groundtruth, estimate, ate);
  draw_error_over_time(img, right, w / 2, ate);

  char figures[128];
  std::snprintf(figures, sizeof figures, "ATE RMSE %.4f m  (%zu pose pairs, rigid alignment)", ate.error.rmse,
                ate.pairs.size());
  const std::string title = options.title.empty() ? figures : options.title + "   " + figures;
  text(img, fit_width(title, w - 20, kTitleFont), {w / 2.0, 22.0}, kTitleFont, 0.5);
  return img;
}

void write_evaluation_plot(const std::filesystem::path& png, const core::Trajectory& groundtruth,
                           const core::Trajectory& estimate, const AteResult& ate, const PlotOptions& options) {
  const cv::Mat img = render_evaluation_plot(groundtruth, estimate, ate, options);
  bool ok = false;
  try {
    ok = cv::imwrite(png.string(), img);
  } catch (const cv::Exception& e) {
    throw io::InputError(png, std::string("cannot write the plot: ") + e.what());
  }
  if (!ok) throw io::InputError(png, "cannot write the plot (is the folder there, and does the name end in .png?)");
}

}  // namespace cvo::eval
