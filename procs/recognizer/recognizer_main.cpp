// slamaware-recognizer: joins CAMERA frames and PROPOSALS on seq, classifies every proposal box
// (dense SIFT + RGB, PCA, VLAD with FLAIR, linear classifiers) and publishes DETECTIONS.
//
// Lockstep (bus.lockstep or --lockstep): every PROPOSALS message is answered by exactly one
// DETECTIONS message, in order, empty when it has no usable boxes or no frame. Real time: after
// draining the bus, only the newest joined frame is classified; older joined ones are dropped and
// counted (frames_dropped). Proposals for a frame older than those already taken (the late
// proposals of a map's reference keyframe, procs/proposals) are classified, never dropped. Bad
// input (a proposal for a frame never seen, boxes outside the image or of zero size, a corrupt
// JPEG, an unreadable model, classes the config names but the model lacks) is counted in
// RECOGNIZER_STATUS and never stops the process.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <memory>
#include <sstream>

#include "common/bus/box_msg.h"
#include "common/bus/bus.h"
#include "common/bus/image_msg.h"
#include "common/bus/node.h"
#include "common/bus/shutdown.h"
#include "common/bus/status.h"
#include "common/config.h"
#include "common/image_codec.h"
#include "common/thread_priority.h"
#include "procs/recognizer/recognizer.h"
#include "procs/recognizer/seq_joiner.h"
#include "slamaware/detections_t.hpp"
#include "slamaware/image_t.hpp"
#include "slamaware/proposals_t.hpp"

using namespace slamaware;
using Clock = std::chrono::steady_clock;

namespace {

double nowS() { return std::chrono::duration<double>(Clock::now().time_since_epoch()).count(); }

using Joiner = SeqJoiner<std::shared_ptr<const image_t>, proposals_t>;

class RecognizerNode {
 public:
  RecognizerNode(Bus& bus, StatusReporter& status, const SystemConfig& sys,
                 const RecognizerOptions& options)
      : bus_(bus),
        status_(status),
        ch_(sys.channels),
        lockstep_(sys.bus.lockstep),
        options_(options),
        joiner_(static_cast<size_t>(std::max(1, options.frame_buffer)),
                static_cast<size_t>(std::max(1, options.proposals_buffer)),
                options.pending_timeout_s) {
    bus_.subscribe<image_t>(
        ch_.camera,
        [this](const image_t& m) { joiner_.addFrame(m.seq, std::make_shared<const image_t>(m)); },
        static_cast<size_t>(sys.bus.max_image_bytes));
    bus_.subscribe<proposals_t>(
        ch_.proposals, [this](const proposals_t& m) { joiner_.addProposals(m.seq, m, nowS()); },
        static_cast<size_t>(sys.bus.max_message_bytes));
  }

  /// Loads the model if there is none yet (at most every model_retry_s).
  void ensureModel() {
    if (recognizer_) return;
    const auto now = Clock::now();
    if (tried_ && now - last_try_ < std::chrono::duration<double>(options_.model_retry_s)) return;
    tried_ = true;
    last_try_ = now;
    try {
      auto model = std::make_shared<const RecognizerModel>(loadModel(options_.model));
      recognizer_ = std::make_unique<Recognizer>(model, options_);
      warmUp();
      const auto missing = recognizer_->missingClasses();
      status_.setCounter("classes_missing", static_cast<int64_t>(missing.size()));
      spdlog::info("model {}: classes {}", options_.model, fmt::join(recognizer_->classes(), ", "));
      if (!missing.empty()) {
        const std::string msg = "model " + options_.model + " lacks classes named in the config: " +
                                fmt::format("{}", fmt::join(missing, ", "));
        spdlog::warn("{}", msg);
        status_.setMessage(msg);
        status_.setState(StatusReporter::State::kDegraded);
      } else {
        status_.setMessage("");
        status_.setState(StatusReporter::State::kRunning);
      }
    } catch (const std::exception& e) {
      status_.count("model_load_failures");
      status_.setMessage(e.what());
      status_.setState(StatusReporter::State::kDegraded);
      spdlog::error("{} (answering with empty detections; retrying every {:.0f} s)", e.what(),
                    options_.model_retry_s);
    }
  }

  /// Grows the buffers of a whole frame before the first one arrives; without it the first frames
  /// with boxes take several times as long (growing the memory of the features, codes and FLAIR
  /// tables), and their latency is the stream's worst.
  void warmUp() {
    try {
      const double ms = recognizer_->warmUp(options_.warm_up_width, options_.warm_up_height);
      status_.setCounter("warm_up_ms", static_cast<int64_t>(ms));
      if (ms > 0)
        spdlog::info("buffers for {}x{} frames prepared in {:.0f} ms", options_.warm_up_width,
                     options_.warm_up_height, ms);
    } catch (const std::exception& e) {
      spdlog::warn("preparing the buffers of {}x{} frames failed ({}); the first frames will grow them",
                   options_.warm_up_width, options_.warm_up_height, e.what());
    }
  }

  /// Handles the jobs that are ready.
  void process() {
    joiner_.expire(nowS());
    auto& ready = joiner_.ready();
    // Real time: of the joined frames waiting, only the newest is classified; the others are
    // dropped (and counted). Proposals without a frame are still answered (cheaply), and so are
    // late ones (for an older frame, sent late on purpose: rare).
    if (!lockstep_) joiner_.markRealTimeDrops();
    while (!ready.empty() && !shutdownRequested()) {
      Joiner::Job job = std::move(ready.front());
      ready.pop_front();
      if (job.drop) {
        status_.noteInput(job.proposals.utime, job.proposals.seq);
        status_.addDropped();
        continue;
      }
      handle(job);
    }
    status_.setQueueDepth(static_cast<int32_t>(joiner_.pending()));
  }

 private:
  void handle(Joiner::Job& job) {
    const proposals_t& p = job.proposals;
    status_.noteInput(p.utime, p.seq);
    detections_t out;
    out.utime = p.utime;
    out.seq = p.seq;
    out.map_id = p.map_id;
    out.encode_ms = 0;
    out.num_boxes = 0;
    out.class_names = recognizer_ ? recognizer_->classes() : std::vector<std::string>{"background"};
    out.num_classes = static_cast<int32_t>(out.class_names.size());
    if (!job.frame) {
      const char* why = job.outcome == Joiner::Outcome::kOverflow ? "waiting queue full"
                        : job.outcome == Joiner::Outcome::kTimedOut
                            ? "its frame did not arrive in time"
                            : "its frame was never received";
      bus_.reject(ch_.proposals, "proposals for seq " + std::to_string(p.seq) + ": " + why);
      status_.count("proposals_without_frame");
      publish(out);
      return;
    }
    if (!recognizer_) {
      status_.count("frames_without_model");
      publish(out);
      return;
    }
    cv::Mat bgr;
    try {
      bgr = decodeImageMessage(**job.frame, ch_.camera + " seq " + std::to_string(p.seq));
    } catch (const std::exception& e) {
      bus_.reject(ch_.camera, e.what());
      status_.count("frames_corrupt");
      publish(out);
      return;
    }
    std::vector<BoxRequest> requests(static_cast<size_t>(p.num_boxes));
    for (int32_t i = 0; i < p.num_boxes; ++i) {
      const box_t& b = p.boxes[static_cast<size_t>(i)];
      requests[static_cast<size_t>(i)] =
          BoxRequest{b.x, b.y, b.w, b.h, p.candidate_ids[static_cast<size_t>(i)]};
    }
    status_.addProcessed();
    FrameDetections d;
    try {
      d = recognizer_->recognize(bgr, requests);
    } catch (const std::exception& e) {
      status_.count("frames_failed");
      status_.setMessage(std::string("recognition failed: ") + e.what());
      spdlog::error("seq {}: recognition failed: {}", p.seq, e.what());
      publish(out);
      return;
    }
    suppressOverlaps(&d, options_.nms_iou, options_.nms_per_class);
    status_.count("boxes_rejected", d.rejected());
    if (d.rejected_not_finite) status_.count("boxes_rejected.not_finite", d.rejected_not_finite);
    if (d.rejected_empty) status_.count("boxes_rejected.zero_size", d.rejected_empty);
    if (d.rejected_outside) status_.count("boxes_rejected.outside_image", d.rejected_outside);
    if (d.rejected_over_limit) status_.count("boxes_rejected.over_limit", d.rejected_over_limit);
    if (d.clipped) status_.count("boxes_clipped", d.clipped);
    status_.count("boxes_classified", static_cast<int64_t>(d.boxes.size()) + d.suppressed);
    if (d.suppressed) status_.count("boxes_suppressed", d.suppressed);
    if (!d.boxes.empty()) status_.count(std::string("encoder.") + encoderName(d.stats.used));
    const double ms = d.stats.features_ms + d.stats.coding_ms + d.stats.encode_ms;
    status_.setCounter("encode_us_last", static_cast<int64_t>(ms * 1000));
    // Timing is not reproducible: lockstep outputs carry 0 so that replays are byte-identical.
    out.encode_ms = lockstep_ ? 0.f : static_cast<float>(ms);
    out.num_boxes = static_cast<int32_t>(d.boxes.size());
    for (const auto& b : d.boxes) {
      out.boxes.push_back(boxMessage(b.x, b.y, b.w, b.h));
      out.candidate_ids.push_back(b.candidate_id);
      out.log_prob.push_back(b.log_prob);
    }
    publish(out);
  }

  void publish(const detections_t& out) { bus_.publish(ch_.detections, out); }

  Bus& bus_;
  StatusReporter& status_;
  Channels ch_;
  bool lockstep_;
  RecognizerOptions options_;
  Joiner joiner_;
  std::unique_ptr<Recognizer> recognizer_;
  bool tried_ = false;
  Clock::time_point last_try_;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "slamaware-recognizer: classifies the PROPOSALS boxes of each CAMERA frame, publishes "
      "DETECTIONS"};
  NodeArgs node;
  std::string model;
  addNodeOptions(app, node);
  app.add_option("--model", model, "model file (overrides recognizer.model)");
  CLI11_PARSE(app, argc, argv);

  return runNode("recognizer", node, [&]() -> int {
    const SystemConfig sys = loadSystem(node);
    // SLAM goes first (common/thread_priority.h); threads started later inherit this.
    lowerThreadPriority(sys.scheduling.recognizer_nice, "the recognizer");
    RecognizerOptions options = loadConfig<RecognizerOptions>(node.config, "recognizer");
    if (!model.empty()) options.model = model;
    checkOptions(options, node.config.empty() ? std::string("defaults") : node.config);
    Bus bus(sys.bus.url);
    StatusReporter status(bus, node.nameOr("recognizer"), sys.channels.statusOf(node.nameOr("recognizer")));
    RecognizerNode rec(bus, status, sys, options);
    rec.ensureModel();
    status.publish();
    spdlog::info("{} -> {}, {}", sys.channels.proposals, sys.channels.detections,
                 sys.bus.lockstep ? "lockstep: one DETECTIONS per PROPOSALS"
                                  : "real time: newest frame first");
    int lcm_failures = 0;
    while (!shutdownRequested()) {
      // -1 also comes from a signal interrupting the wait (shutdown); give up only if LCM keeps
      // failing.
      if (bus.handle(20) < 0) {
        if (shutdownRequested()) break;
        if (++lcm_failures >= 50) {
          spdlog::error("LCM keeps failing; exiting");
          return 1;
        }
        continue;
      }
      lcm_failures = 0;
      // Drain what else is waiting, so that real-time mode sees the newest frame.
      for (int i = 0; i < 1000 && bus.handle(0) > 0; ++i) {
      }
      rec.ensureModel();
      rec.process();
      status.tick();
    }
    status.setState(StatusReporter::State::kStopping);
    status.publish();
    return 0;
  });
}
