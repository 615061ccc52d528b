#include "procs/recognizer/recognizer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>

#include "common/config.h"
#include "common/geometry.h"

namespace slamaware::recognizer {

Recognizer::Recognizer(std::shared_ptr<const RecognizerModel> model,
                       const RecognizerOptions& options)
    : model_(std::move(model)),
      options_(options),
      kind_(parseEncoderKind(options.encoder)),
      encoder_(model_->params, model_->pca, model_->vocabulary, options.cost) {
  classes_ = model_->classifier.classes;
  append_background_ = !model_->hasBackground();
  if (append_background_) classes_.push_back("background");
}

std::vector<std::string> Recognizer::missingClasses() const {
  std::vector<std::string> missing;
  for (const auto& c : options_.expected_classes)
    if (std::find(classes_.begin(), classes_.end(), c) == classes_.end()) missing.push_back(c);
  return missing;
}

void Recognizer::takeBoxes(int width, int height, const std::vector<BoxRequest>& requests,
                           bool carry_only, FrameDetections* out, std::vector<PyramidBox>* snapped,
                           std::vector<size_t>* classified) const {
  const double W = width, H = height;
  for (size_t i = 0; i < requests.size(); ++i) {
    const BoxRequest& r = requests[i];
    if (!std::isfinite(r.x) || !std::isfinite(r.y) || !std::isfinite(r.w) || !std::isfinite(r.h)) {
      ++out->rejected_not_finite;
      continue;
    }
    if (!(r.w > 0) || !(r.h > 0)) {
      ++out->rejected_empty;
      continue;
    }
    const double x0 = std::max(r.x, 0.0), y0 = std::max(r.y, 0.0);
    const double x1 = std::min(r.x + r.w, W), y1 = std::min(r.y + r.h, H);
    PyramidBox pb;
    if (!(x1 > x0) || !(y1 > y0) || !encoder_.snap(r.x, r.y, r.w, r.h, width, height, &pb)) {
      ++out->rejected_outside;
      continue;
    }
    if (static_cast<int>(out->boxes.size()) >= options_.max_boxes) {
      ++out->rejected_over_limit;
      continue;
    }
    const bool carry = r.carried && r.carried->log_prob.size() == classes_.size();
    if (!carry && carry_only) {
      ++out->uncarried;
      continue;
    }
    if (x0 != r.x || y0 != r.y || x1 != r.x + r.w || y1 != r.y + r.h) ++out->clipped;
    BoxDetection d;
    d.input_index = static_cast<int>(i);
    d.candidate_id = r.candidate_id;
    d.x = static_cast<float>(x0);
    d.y = static_cast<float>(y0);
    d.w = static_cast<float>(x1 - x0);
    d.h = static_cast<float>(y1 - y0);
    if (carry) {
      d.log_prob = r.carried->log_prob;
      d.carried_seq = r.carried->seq;
      ++out->carried;
    } else {
      classified->push_back(out->boxes.size());
      snapped->push_back(pb);
    }
    out->boxes.push_back(std::move(d));
  }
}

FrameDetections Recognizer::carryOnly(int width, int height,
                                      const std::vector<BoxRequest>& requests) const {
  FrameDetections out;
  out.classes = classes_;
  std::vector<PyramidBox> snapped;
  std::vector<size_t> classified;
  takeBoxes(width, height, requests, true, &out, &snapped, &classified);
  return out;
}

double Recognizer::warmUp(int width, int height) {
  const auto t0 = std::chrono::steady_clock::now();
  encoder_.warmUp(width, height, kind_);
  // Growing the encodings' buffer in the first frames with many boxes cost them tens of ms of
  // page faults; it is made (and its pages touched) here instead.
  if (width > 0 && height > 0)
    encoded_.resize(static_cast<int64_t>(kRowsPerPass), encoder_.params().encodedDims());
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

FrameDetections Recognizer::recognize(const cv::Mat& bgr, const std::vector<BoxRequest>& requests) {
  const auto t0 = std::chrono::steady_clock::now();
  FrameDetections out;
  out.classes = classes_;
  std::vector<PyramidBox> snapped;
  std::vector<size_t> classified;  // the boxes of `out` that are encoded, in the order of `snapped`
  takeBoxes(bgr.cols, bgr.rows, requests, false, &out, &snapped, &classified);
  if (snapped.empty()) return out;

  encoder_.prepare(bgr, snapped, kind_, &out.stats);
  const int C = static_cast<int>(classes_.size());
  const float log_objects =
      append_background_
          ? static_cast<float>(std::log1p(-std::exp(options_.missing_background_log_prob)))
          : 0.f;
  // kRowsPerPass boxes at a time: the encodings (430 KB a box) need a buffer of that many rows,
  // made when the model loads (warmUp), and never a larger one, whatever the number of boxes.
  for (size_t first = 0; first < snapped.size(); first += kRowsPerPass) {
    const size_t n = std::min(kRowsPerPass, snapped.size() - first);
    encoder_.encodeRows(snapped, first, n, &encoded_, &out.stats);
    model_->classifier.scores(encoded_.map(), &scores_);
    model_->classifier.logProbabilities(scores_, &log_p_);
    for (size_t b = 0; b < n; ++b) {
      auto& lp = out.boxes[classified[first + b]].log_prob;
      lp.resize(static_cast<size_t>(C));
      for (int c = 0; c < static_cast<int>(log_p_.cols()); ++c)
        lp[static_cast<size_t>(c)] = log_p_(static_cast<int64_t>(b), c) + log_objects;
      if (append_background_) lp.back() = static_cast<float>(options_.missing_background_log_prob);
    }
  }
  out.total_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

void checkOptions(const RecognizerOptions& options, const std::string& source) {
  try {
    parseEncoderKind(options.encoder);
  } catch (const std::exception& e) {
    throw ConfigError(source + ": key 'recognizer.encoder': " + e.what());
  }
  if (!(options.nms_iou > 0))
    throw ConfigError(
        source + ": key 'recognizer.nms_iou': must be above 0 (1 or more: no suppression), got " +
        std::to_string(options.nms_iou));
  const ViewSelectionOptions& v = options.view_selection;
  if (!(v.angle_deg >= 0 && v.angle_deg <= 180))
    throw ConfigError(source +
                      ": key 'recognizer.view_selection.angle_deg': degrees from 0 to 180, got " +
                      std::to_string(v.angle_deg));
  if (!(v.scale >= 0 && std::isfinite(v.scale)))
    throw ConfigError(source +
                      ": key 'recognizer.view_selection.scale': a factor of 0 or more, got " +
                      std::to_string(v.scale));
  const auto size_ok = [](int px) { return px >= 0 && px <= kMaxWarmUpPx; };
  if (!size_ok(options.warm_up_width) || !size_ok(options.warm_up_height) ||
      (options.warm_up_width == 0) != (options.warm_up_height == 0))
    throw ConfigError(
        source + ": keys 'recognizer.warm_up_width' / 'warm_up_height': a frame size of 1 to " +
        std::to_string(kMaxWarmUpPx) + " px each, or both 0 (none), got " +
        std::to_string(options.warm_up_width) + " x " + std::to_string(options.warm_up_height));
}

int suppressOverlaps(FrameDetections* d, double max_iou, bool per_class) {
  const size_t n = d->boxes.size();
  if (!(max_iou < 1) || n < 2) return 0;
  const size_t objects = !d->classes.empty() && d->classes.back() == "background"
                             ? d->classes.size() - 1
                             : d->classes.size();
  std::vector<float> confidence(n, -std::numeric_limits<float>::infinity());
  std::vector<int> best_class(n, -1);
  for (size_t i = 0; i < n; ++i) {
    const auto& lp = d->boxes[i].log_prob;
    for (size_t c = 0; c < std::min(objects, lp.size()); ++c)
      if (lp[c] > confidence[i])
        confidence[i] = lp[c], best_class[i] = static_cast<int>(c);  // NaN never wins
  }
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return confidence[a] > confidence[b]; });
  std::vector<size_t> kept;
  for (size_t i : order) {
    const BoxDetection& a = d->boxes[i];
    if (std::none_of(kept.begin(), kept.end(), [&](size_t k) {
          const BoxDetection& b = d->boxes[k];
          if (per_class && best_class[i] != best_class[k]) return false;
          return rectIou(a.x, a.y, a.w, a.h, b.x, b.y, b.w, b.h) > max_iou;
        }))
      kept.push_back(i);
  }
  std::sort(kept.begin(), kept.end());  // request order
  std::vector<BoxDetection> out;
  out.reserve(kept.size());
  for (size_t i : kept) out.push_back(std::move(d->boxes[i]));
  d->boxes = std::move(out);
  const int removed = static_cast<int>(n - kept.size());
  d->suppressed += removed;
  return removed;
}

}  // namespace slamaware::recognizer
