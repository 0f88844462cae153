#include "program/progress.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <string>

namespace cvo::program {

ProgressBar::ProgressBar(std::size_t total, bool enabled)
    : total_(total), active_(enabled && ::isatty(STDERR_FILENO) == 1), start_(Clock::now()), last_draw_() {}

ProgressBar::~ProgressBar() { finish(); }

void ProgressBar::update(std::size_t done) {
  if (!active_) return;
  const auto now = Clock::now();
  if (done < total_ && now - last_draw_ < std::chrono::milliseconds(100)) return;
  last_draw_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double fps = elapsed > 0 ? static_cast<double>(done) / elapsed : 0.0;
  const double eta = fps > 0 ? static_cast<double>(total_ - std::min(done, total_)) / fps : 0.0;
  constexpr std::size_t kWidth = 30;
  const std::size_t filled = total_ > 0 ? std::min(kWidth, done * kWidth / total_) : kWidth;
  const std::string bar = std::string(filled, '#') + std::string(kWidth - filled, '.');
  std::fprintf(stderr, "\r[%s] %zu/%zu frames  %5.1f fps  ETA %4.0f s ", bar.c_str(), done, total_, fps, eta);
  std::fflush(stderr);
}

void ProgressBar::finish() {
  if (!active_) return;
  std::fprintf(stderr, "\r\033[K");  // back to the line start and erase it
  std::fflush(stderr);
  active_ = false;
}

}  // namespace cvo::program
