#include "common/progress.h"

#include <unistd.h>

#include <cstdio>

namespace slamaware {

ProgressBar::ProgressBar(std::string label, int64_t total)
    : label_(std::move(label)),
      total_(total > 0 ? total : 1),
      tty_(isatty(STDERR_FILENO) != 0),
      start_(std::chrono::steady_clock::now()) {}

ProgressBar::~ProgressBar() {
  if (!finished_) finish();
}

void ProgressBar::update(int64_t done) {
  done_ = done;
  const auto now = std::chrono::steady_clock::now();
  if (tty_ && now - last_draw_ < std::chrono::milliseconds(100) && done_ < total_) return;
  last_draw_ = now;
  draw(false);
}

void ProgressBar::finish() {
  finished_ = true;
  draw(true);
}

void ProgressBar::draw(bool final) {
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double frac = std::min(1.0, static_cast<double>(done_) / total_);
  const double rate = elapsed > 0 ? done_ / elapsed : 0;
  const double eta = rate > 0 ? (total_ - done_) / rate : 0;
  if (!tty_) {
    // Logs and CI: a line per 25%, and the end.
    const int pct = static_cast<int>(frac * 4) * 25;
    if (!final && pct == last_pct_logged_) return;
    last_pct_logged_ = pct;
    if (final)
      std::fprintf(stderr, "%s: %lld/%lld (%.0f%%) %.1f/s, done in %.1f s\n", label_.c_str(),
                   (long long)done_, (long long)total_, frac * 100, rate, elapsed);
    else
      std::fprintf(stderr, "%s: %lld/%lld (%.0f%%) %.1f/s %.1f s, eta %.0f s\n", label_.c_str(),
                   (long long)done_, (long long)total_, frac * 100, rate, elapsed, eta);
    return;
  }
  const int width = 30;
  const int fill = static_cast<int>(frac * width);
  std::string bar(fill, '#');
  bar += std::string(width - fill, '.');
  std::fprintf(stderr, "\r%-18s [%s] %lld/%lld %7.1f/s %s %.0f s   ", label_.c_str(), bar.c_str(),
               (long long)done_, (long long)total_, rate, final ? "done in" : "eta",
               final ? elapsed : eta);
  if (final) std::fprintf(stderr, "\n");
  std::fflush(stderr);
}

}  // namespace slamaware
