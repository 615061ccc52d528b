#include "tools/eval/plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>

namespace slamaware {

namespace {

constexpr int kLeft = 60, kRight = 20, kTop = 30, kBottom = 50;
constexpr double kFontScale = 0.4, kLabelScale = 0.45;
const cv::Scalar kGrid(225, 225, 225);

std::string tickText(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// Text turned 90° counter-clockwise, its top-left corner at `at` (clipped to the canvas).
void verticalText(cv::Mat& canvas, const std::string& text, cv::Point at, double scale,
                  const cv::Scalar& colour) {
  int base = 0;
  const cv::Size sz = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &base);
  cv::Mat strip(sz.height + base + 2, sz.width + 2, canvas.type(), cv::Scalar(255, 255, 255));
  cv::putText(strip, text, cv::Point(1, sz.height + 1), cv::FONT_HERSHEY_SIMPLEX, scale, colour, 1,
              cv::LINE_AA);
  cv::Mat turned;
  cv::rotate(strip, turned, cv::ROTATE_90_COUNTERCLOCKWISE);
  const cv::Rect dst = cv::Rect(at, turned.size()) & cv::Rect(0, 0, canvas.cols, canvas.rows);
  if (dst.area() > 0) turned(cv::Rect(0, 0, dst.width, dst.height)).copyTo(canvas(dst));
}

}  // namespace

PlotPanel::PlotPanel(cv::Mat& canvas, const cv::Rect& area, PlotAxis x, PlotAxis y,
                     const std::string& title)
    : canvas_(canvas),
      plot_(area.x + kLeft, area.y + kTop, std::max(1, area.width - kLeft - kRight),
            std::max(1, area.height - kTop - kBottom)),
      x_(std::move(x)),
      y_(std::move(y)) {
  const cv::Scalar black(0, 0, 0);
  for (double t : y_.ticks) {
    cv::line(canvas_, toPixel(x_.min, t), toPixel(x_.max, t), kGrid);
    cv::putText(canvas_, tickText(t), toPixel(x_.min, t) + cv::Point(-35, 5),
                cv::FONT_HERSHEY_SIMPLEX, kFontScale, black);
  }
  for (double t : x_.ticks) {
    cv::line(canvas_, toPixel(t, y_.min), toPixel(t, y_.max), kGrid);
    cv::putText(canvas_, tickText(t), toPixel(t, y_.min) + cv::Point(-5, 18),
                cv::FONT_HERSHEY_SIMPLEX, kFontScale, black);
  }
  cv::rectangle(canvas_, plot_, cv::Scalar(160, 160, 160));
  if (!x_.label.empty()) {
    int base = 0;
    const int w = cv::getTextSize(x_.label, cv::FONT_HERSHEY_SIMPLEX, kLabelScale, 1, &base).width;
    cv::putText(canvas_, x_.label,
                cv::Point(plot_.x + (plot_.width - w) / 2, area.y + area.height - 12),
                cv::FONT_HERSHEY_SIMPLEX, kLabelScale, black, 1, cv::LINE_AA);
  }
  if (!y_.label.empty()) {
    int base = 0;
    const int w = cv::getTextSize(y_.label, cv::FONT_HERSHEY_SIMPLEX, kLabelScale, 1, &base).width;
    verticalText(canvas_, y_.label,
                 cv::Point(area.x + 2, plot_.y + std::max(0, (plot_.height - w) / 2)), kLabelScale,
                 black);
  }
  if (!title.empty())
    cv::putText(canvas_, title, cv::Point(plot_.x, area.y + 18), cv::FONT_HERSHEY_SIMPLEX,
                kLabelScale, black, 1, cv::LINE_AA);
}

double PlotPanel::fraction(const PlotAxis& a, double v) const {
  double f;
  if (a.log10) {
    const double lo = std::log10(std::max(a.min, 1e-300)), hi = std::log10(std::max(a.max, 1e-300));
    f = (std::log10(std::max(v, a.min)) - lo) / std::max(hi - lo, 1e-12);
  } else {
    f = (v - a.min) / std::max(a.max - a.min, 1e-12);
  }
  return std::clamp(f, 0.0, 1.0);
}

cv::Point PlotPanel::toPixel(double x, double y) const {
  return cv::Point(
      plot_.x + static_cast<int>(std::lround(fraction(x_, x) * plot_.width)),
      plot_.y + plot_.height - static_cast<int>(std::lround(fraction(y_, y) * plot_.height)));
}

void PlotPanel::curve(const std::vector<cv::Point2d>& points, const cv::Scalar& colour,
                      const std::string& label, int thickness) {
  for (size_t i = 1; i < points.size(); ++i)
    cv::line(canvas_, toPixel(points[i - 1].x, points[i - 1].y), toPixel(points[i].x, points[i].y),
             colour, thickness, cv::LINE_AA);
  if (points.size() == 1)
    cv::circle(canvas_, toPixel(points[0].x, points[0].y), thickness + 1, colour, cv::FILLED);
  if (!label.empty()) note(label, colour);
}

void PlotPanel::note(const std::string& text, const cv::Scalar& colour) {
  legend_.emplace_back(text, colour);
}

PlotPanel::~PlotPanel() {
  for (size_t row = 0; row < legend_.size(); ++row) {
    const auto& [text, colour] = legend_[row];
    const cv::Point at(plot_.x + 10, plot_.y + 18 * static_cast<int>(row + 1));
    int base = 0;
    const cv::Size sz = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, kLabelScale, 1, &base);
    // On white, so that the curves under the legend do not hide it.
    cv::rectangle(
        canvas_,
        cv::Rect(at.x - 3, at.y - sz.height - 3, sz.width + 6, sz.height + base + 5) & plot_,
        cv::Scalar(255, 255, 255), cv::FILLED);
    cv::putText(canvas_, text, at, cv::FONT_HERSHEY_SIMPLEX, kLabelScale, colour, 1, cv::LINE_AA);
  }
}

}  // namespace slamaware
