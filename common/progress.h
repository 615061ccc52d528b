#pragma once
// A one-line progress bar on stderr for long command-line stages (training, generation):
//   "encode crops  [##########..........]  512/1008  12.3/s  eta 40 s"
// Redraws at most 10 times a second; prints plain lines when stderr is not a terminal.
#include <chrono>
#include <cstdint>
#include <string>

namespace slamaware {

class ProgressBar {
 public:
  ProgressBar(std::string label, int64_t total);
  ~ProgressBar();
  void update(int64_t done);
  void advance(int64_t n = 1) { update(done_ + n); }
  /// Draws the final state and ends the line.
  void finish();

 private:
  void draw(bool final);
  std::string label_;
  int64_t total_, done_ = 0;
  bool tty_, finished_ = false;
  std::chrono::steady_clock::time_point start_, last_draw_;
  int last_pct_logged_ = -1;
};

}  // namespace slamaware
