#pragma once
// Line charts for the eval's PNGs, drawn with OpenCV: a canvas holds one or more panels, each with
// a linear or log10 x axis, grid lines with tick labels, axis titles, curves and a legend. The
// proposals plot (recall against boxes per frame) and the precision-recall curves use it.
#include <opencv2/core.hpp>
#include <string>
#include <utility>
#include <vector>

namespace slamaware {

struct PlotAxis {
  double min = 0, max = 1;
  bool log10 = false;         ///< logarithmic axis (min > 0)
  std::vector<double> ticks;  ///< grid lines, labelled with %g
  std::string label;
};

/// One chart inside `area` of a canvas (the canvas is drawn on; write it with writeImage).
class PlotPanel {
 public:
  /// Draws the frame, the grid, the tick labels, the axis labels and `title` (top left).
  PlotPanel(cv::Mat& canvas, const cv::Rect& area, PlotAxis x, PlotAxis y,
            const std::string& title);

  /// Draws the legend (over the curves).
  ~PlotPanel();
  PlotPanel(const PlotPanel&) = delete;
  PlotPanel& operator=(const PlotPanel&) = delete;

  /// The pixel of a value (values outside the axes are clamped to the panel).
  cv::Point toPixel(double x, double y) const;
  /// A polyline through the points in order (one point: a dot); a legend row `label` (if not
  /// empty) in `colour`, top left inside the panel.
  void curve(const std::vector<cv::Point2d>& points, const cv::Scalar& colour,
             const std::string& label, int thickness = 2);
  /// A legend row without a curve (e.g. a note).
  void note(const std::string& text, const cv::Scalar& colour);

 private:
  cv::Mat& canvas_;
  cv::Rect plot_;  ///< the inner rectangle of the axes
  PlotAxis x_, y_;
  std::vector<std::pair<std::string, cv::Scalar>> legend_;
  double fraction(const PlotAxis& a, double v) const;
};

/// Default colours of the charts (BGR).
namespace plot_colour {
const cv::Scalar kBlue(200, 80, 0), kLightBlue(230, 170, 110), kRed(0, 0, 200),
    kOrange(0, 140, 255), kBlack(0, 0, 0), kGrey(120, 120, 120);
}

}  // namespace slamaware
