// slamaware-recognizer: joins CAMERA frames and PROPOSALS on seq, classifies the proposal boxes
// (dense SIFT + RGB, PCA, VLAD with FLAIR, linear classifiers) and publishes DETECTIONS. A box
// whose candidate is seen from about the same view as when it was last classified carries that
// result instead (view_selector.h; DETECTIONS.classified_seq says which frame's view it is), so
// every box of every handled frame is labelled and only new views cost features.
//
// Lockstep (bus.lockstep or --lockstep): every PROPOSALS message is answered by exactly one
// DETECTIONS message, in order, empty when it has no usable boxes or no frame. Real time: after
// draining the bus, only the newest joined frame is classified; older joined ones are dropped and
// counted (frames_dropped). Proposals for a frame older than those already taken (the late
// proposals of a map's reference keyframe, procs/proposals) are classified, never dropped: in
// real time on a background thread with a recognizer of their own (the same model), so that the
// newest frames never wait behind a whole frame of new views; their DETECTIONS follow. Bad
// input (a proposal for a frame never seen, boxes outside the image or of zero size, a corrupt
// JPEG, an unreadable model, classes the config names but the model lacks) is counted in
// RECOGNIZER_STATUS and never stops the process.
//
// Live reload: when the model file is replaced (checked every model_watch_s) or a RELOAD command
// names the process (`slamaware-ctl reload recognizer`), the new model is loaded and warmed up on a
// second thread while the old one goes on classifying; it is swapped in between two frames, so no
// frame waits for the load or is dropped because of it. A model that fails to load is refused
// (counted in reload_failures, the reason in the status message) and the old one keeps running.
#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <deque>
#include <future>
#include <memory>
#include <optional>
#include <sstream>
#include <vector>

#include "common/bus/box_msg.h"
#include "common/bus/bus.h"
#include "common/bus/image_msg.h"
#include "common/bus/node.h"
#include "common/bus/shutdown.h"
#include "common/bus/status.h"
#include "common/config.h"
#include "common/image_codec.h"
#include "common/serial_worker.h"
#include "common/thread_priority.h"
#include "procs/recognizer/recognizer.h"
#include "procs/recognizer/seq_joiner.h"
#include "slamaware/detections_t.hpp"
#include "slamaware/image_t.hpp"
#include "slamaware/proc_command_t.hpp"
#include "slamaware/proposals_t.hpp"

using namespace slamaware;
using namespace slamaware::recognizer;
using Clock = std::chrono::steady_clock;

namespace {

double nowS() { return std::chrono::duration<double>(Clock::now().time_since_epoch()).count(); }

using Joiner = SeqJoiner<std::shared_ptr<const image_t>, proposals_t>;

/// What tells that a file was replaced without reading it: a rename over it (as saveModel writes)
/// changes the inode, an overwrite the size or the modification time.
struct FileStamp {
  bool exists = false;
  dev_t dev = 0;
  ino_t ino = 0;
  off_t size = 0;
  int64_t mtime_ns = 0;
  bool operator==(const FileStamp& o) const {
    return exists == o.exists && dev == o.dev && ino == o.ino && size == o.size &&
           mtime_ns == o.mtime_ns;
  }
};

FileStamp stampOf(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return {};
  return {true, st.st_dev, st.st_ino, st.st_size,
          static_cast<int64_t>(st.st_mtim.tv_sec) * 1000000000 + st.st_mtim.tv_nsec};
}

/// The recognizer of the live frames and, in real time, a second one on the same model for late
/// frames: buffers of its own, so that a late frame is classified on a background thread while the
/// live frames go on (the direct encoder: no FLAIR tables kept for a rare frame).
struct Recognizers {
  std::unique_ptr<Recognizer> live;
  std::shared_ptr<Recognizer> late;
};

/// Grows `recognizer`'s buffers to a warm_up_width x warm_up_height frame (without that, its first
/// frames take several times as long); returns the ms spent. A failure is only logged: the first
/// frames grow the buffers.
double warmUp(Recognizer& recognizer, const RecognizerOptions& options) {
  try {
    return recognizer.warmUp(options.warm_up_width, options.warm_up_height);
  } catch (const std::exception& e) {
    spdlog::warn(
        "preparing the buffers of {}x{} frames failed ({}); the first frames will grow them",
        options.warm_up_width, options.warm_up_height, e.what());
    return 0;
  }
}

/// Loads the model file and prepares the recognizers with it: the live one warmed up here
/// (`warm_up_ms`), the late one on its own thread (RecognizerNode::warmUpLate). Throws on a
/// missing or bad model.
Recognizers loadRecognizers(const RecognizerOptions& options, bool with_late, double* warm_up_ms) {
  auto model = std::make_shared<const RecognizerModel>(loadModel(options.model));
  RecognizerOptions late_options = options;
  late_options.encoder = "direct";
  Recognizers out{std::make_unique<Recognizer>(model, options),
                  with_late ? std::make_shared<Recognizer>(model, late_options) : nullptr};
  *warm_up_ms = warmUp(*out.live, options);
  return out;
}

class RecognizerNode {
 public:
  RecognizerNode(Bus& bus, StatusReporter& status, const SystemConfig& sys,
                 const RecognizerOptions& options, const std::string& name)
      : bus_(bus),
        status_(status),
        ch_(sys.channels),
        lockstep_(sys.bus.lockstep),
        options_(options),
        selector_(options.view_selection),
        joiner_(static_cast<size_t>(std::max(1, options.frame_buffer)),
                static_cast<size_t>(std::max(1, options.proposals_buffer)),
                options.pending_timeout_s) {
    if (!lockstep_)
      late_worker_ =
          std::make_unique<SerialWorker>(true, "recognizer-late", sys.scheduling.background_nice);
    bus_.subscribe<image_t>(
        ch_.camera,
        [this](const image_t& m) { joiner_.addFrame(m.seq, std::make_shared<const image_t>(m)); },
        static_cast<size_t>(sys.bus.max_image_bytes));
    bus_.subscribe<proposals_t>(
        ch_.proposals, [this](const proposals_t& m) { joiner_.addProposals(m.seq, m, nowS()); },
        static_cast<size_t>(sys.bus.max_message_bytes));
    bus_.subscribe<proc_command_t>(ch_.proc_command, [this, name](const proc_command_t& c) {
      if (c.command == proc_command_t::COMMAND_RELOAD && (c.target == name || c.target == "all"))
        requestReload("asked to");
    });
  }

  ~RecognizerNode() {
    if (loading_.valid()) loading_.wait();
  }

  /// Loads the model if there is none yet (at most every model_retry_s).
  void ensureModel() {
    if (recognizer_) return;
    const auto now = Clock::now();
    if (tried_ && now - last_try_ < std::chrono::duration<double>(options_.model_retry_s)) return;
    tried_ = true;
    last_try_ = now;
    try {
      const FileStamp stamp = stampOf(options_.model);
      double warm_up_ms = 0;
      Recognizers r = loadRecognizers(options_, !lockstep_, &warm_up_ms);
      recognizer_ = std::move(r.live);
      late_recognizer_ = std::move(r.late);
      warmUpLate();
      loaded_stamp_ = stamp;
      afterLoad(warm_up_ms);
    } catch (const std::exception& e) {
      status_.count("model_load_failures");
      status_.setMessage(e.what());
      status_.setState(StatusReporter::State::kDegraded);
      spdlog::error("{} (answering with empty detections; retrying every {:.0f} s)", e.what(),
                    options_.model_retry_s);
    }
  }

  /// Live reload: starts loading the model file anew on a second thread (the current model keeps
  /// classifying); one load at a time, a request during a load is served after it if the file
  /// changed since that load began.
  void requestReload(const std::string& why) {
    if (!recognizer_) {
      tried_ = false;  // no model yet: the next ensureModel() tries at once
      return;
    }
    if (loading_.valid()) {
      // The file being loaded is the one asked for: its load answers this request too. (The
      // watch asks every model_watch_s until the load is swapped in; a load slower than that
      // was loaded twice.)
      if (!(stampOf(options_.model) == loading_stamp_)) reload_again_ = true;
      return;
    }
    spdlog::info("reloading the model {} ({})", options_.model, why);
    loading_stamp_ = stampOf(options_.model);
    loading_ = std::async(std::launch::async, [options = options_, with_late = !lockstep_] {
      Loaded l;
      l.recognizers = loadRecognizers(options, with_late, &l.warm_up_ms);
      return l;
    });
  }

  /// Watches the model file (every model_watch_s) and swaps in a model whose load has finished.
  /// Called between frames.
  void pollReload() {
    const auto now = Clock::now();
    if (recognizer_ && options_.model_watch_s > 0 &&
        now - last_watch_ >= std::chrono::duration<double>(options_.model_watch_s)) {
      last_watch_ = now;
      const FileStamp s = stampOf(options_.model);
      // A stamp whose load failed is not tried again; the next change of the file is.
      if (s.exists && !(s == loaded_stamp_) && !(s == refused_stamp_))
        requestReload("the file was replaced");
    }
    if (!loading_.valid() ||
        loading_.wait_for(std::chrono::seconds(0)) != std::future_status::ready)
      return;
    try {
      Loaded l = loading_.get();
      recognizer_ = std::move(l.recognizers.live);
      late_recognizer_ = std::move(l.recognizers.late);  // a late frame in progress keeps the old
      warmUpLate();
      selector_.clear();  // results of the old model are not carried into the new one's frames
      loaded_stamp_ = loading_stamp_;
      status_.count("reloads");
      afterLoad(l.warm_up_ms);
    } catch (const std::exception& e) {
      refused_stamp_ = loading_stamp_;
      status_.count("reload_failures");
      status_.setMessage(std::string("new model refused: ") + e.what() +
                         "; the previous model keeps running");
      spdlog::error("new model refused: {}; the previous model keeps running", e.what());
    }
    if (reload_again_) {
      reload_again_ = false;
      requestReload("asked again during the load");
    }
  }

  /// Handles the jobs that are ready.
  void process() {
    joiner_.expire(nowS());
    finishLate();
    auto& ready = joiner_.ready();
    // Real time: of the joined frames waiting, only the newest is classified. The frames it
    // overtook are answered first, at once and without their pixels: each box whose candidate has
    // a result (of the last frame handled) carries it, the others are left out (boxes_unlabelled).
    // Proposals without a frame are still answered (cheaply), and late ones (for an older frame,
    // sent late on purpose: rare) go to the background thread.
    if (!lockstep_) {
      joiner_.markRealTimeDrops();
      for (Joiner::Job& job : ready)
        if (job.drop) answerWithoutPixels(job);
    }
    while (!ready.empty() && !shutdownRequested()) {
      Joiner::Job job = std::move(ready.front());
      ready.pop_front();
      if (job.drop) continue;
      const bool late = job.late;
      std::optional<Prepared> prepared = prepare(std::move(job));
      if (!prepared) continue;
      if (late)
        startLate(std::move(*prepared));
      else
        finish(classify(*recognizer_, std::move(*prepared)));
    }
    status_.setQueueDepth(static_cast<int32_t>(joiner_.pending()));
  }

 private:
  struct Loaded {
    Recognizers recognizers;
    double warm_up_ms = 0;
  };

  /// Reports a model that was just put in place: its classes, those it lacks, its warm-up. The
  /// buffers of a whole frame are grown before the first frame (warm-up); without it the first
  /// frames with boxes take several times as long, and their latency is the stream's worst.
  void afterLoad(double warm_up_ms) {
    status_.setCounter("warm_up_ms", static_cast<int64_t>(warm_up_ms));
    if (warm_up_ms > 0)
      spdlog::info("buffers for {}x{} frames prepared in {:.0f} ms", options_.warm_up_width,
                   options_.warm_up_height, warm_up_ms);
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
  }

  /// A frame's boxes, ready to classify: the proposals, their views and the requests.
  struct Prepared {
    proposals_t proposals;
    std::shared_ptr<const image_t> frame;
    std::vector<CandidateView> views;
    std::vector<BoxRequest> requests;
  };
  /// What classify() found.
  struct Classified {
    Prepared job;
    FrameDetections detections;
    std::string corrupt;  ///< the frame's JPEG could not be decoded: why
    std::string failed;   ///< recognition threw: why
  };

  /// Counts the input and selects the views to classify; answers at once (and returns nothing)
  /// when there is nothing to classify: no frame, or no model.
  std::optional<Prepared> prepare(Joiner::Job&& job) {
    status_.noteInput(job.proposals.utime, job.proposals.seq);
    if (!job.frame) {
      const char* why = job.outcome == Joiner::Outcome::kOverflow ? "waiting queue full"
                        : job.outcome == Joiner::Outcome::kTimedOut
                            ? "its frame did not arrive in time"
                            : "its frame was never received";
      bus_.reject(ch_.proposals,
                  "proposals for seq " + std::to_string(job.proposals.seq) + ": " + why);
      status_.count("proposals_without_frame");
      publish(emptyAnswer(job.proposals));
      return std::nullopt;
    }
    if (!recognizer_) {
      status_.count("frames_without_model");
      publish(emptyAnswer(job.proposals));
      return std::nullopt;
    }
    Prepared out{std::move(job.proposals), *job.frame, {}, {}};
    const proposals_t& p = out.proposals;  // job's, moved
    const size_t n = static_cast<size_t>(p.num_boxes);
    out.views.resize(n);
    for (size_t i = 0; i < n; ++i) {
      const box_t& b = p.boxes[i];
      const auto& dir = p.view_direction[i];
      out.views[i] = CandidateView{p.candidate_ids[i], Eigen::Vector3f(dir[0], dir[1], dir[2]),
                                   p.median_depth[i], b.w, b.h};
    }
    // A restarted camera stream starts the selection afresh (its seqs start again). Proposals
    // sent late for an older frame (a map's reference keyframe) are classified in full.
    if (joiner_.restarts() != restarts_seen_) {
      restarts_seen_ = joiner_.restarts();
      selector_.clear();
    }
    const std::vector<const CarriedView*> carried = selector_.select(p.map_id, p.seq, out.views);
    out.requests.resize(n);
    for (size_t i = 0; i < n; ++i) {
      const box_t& b = p.boxes[i];
      out.requests[i] = BoxRequest{b.x, b.y, b.w, b.h, p.candidate_ids[i], carried[i]};
    }
    return out;
  }

  /// Decodes the frame and classifies its boxes with `recognizer`. Touches nothing of the node:
  /// runs on the background thread for late frames.
  static Classified classify(Recognizer& recognizer, Prepared job) {
    Classified out{std::move(job), {}, {}, {}};
    const proposals_t& p = out.job.proposals;
    cv::Mat bgr;
    try {
      bgr = decodeImageMessage(*out.job.frame, "seq " + std::to_string(p.seq));
    } catch (const std::exception& e) {
      out.corrupt = e.what();
      return out;
    }
    try {
      out.detections = recognizer.recognize(bgr, out.job.requests);
    } catch (const std::exception& e) {
      out.failed = e.what();
    }
    return out;
  }

  /// Remembers the classified views, counts and publishes.
  void finish(Classified c) {
    const proposals_t& p = c.job.proposals;
    detections_t out = emptyAnswer(p);
    if (!c.corrupt.empty()) {
      bus_.reject(ch_.camera, ch_.camera + " " + c.corrupt);
      status_.count("frames_corrupt");
      publish(out);
      return;
    }
    status_.addProcessed();
    if (!c.failed.empty()) {
      status_.count("frames_failed");
      status_.setMessage("recognition failed: " + c.failed);
      spdlog::error("seq {}: recognition failed: {}", p.seq, c.failed);
      publish(out);
      return;
    }
    FrameDetections& d = c.detections;
    for (const auto& b : d.boxes)
      if (b.carried_seq < 0)
        selector_.remember(p.map_id, p.seq, c.job.views[static_cast<size_t>(b.input_index)],
                           b.log_prob);
    const int64_t valid = countBoxes(&d);
    if (valid > d.carried) status_.count(std::string("encoder.") + encoderName(d.stats.used));
    const double ms = d.stats.features_ms + d.stats.coding_ms + d.stats.encode_ms;
    status_.setCounter("encode_us_last", static_cast<int64_t>(ms * 1000));
    // Timing is not reproducible: lockstep outputs carry 0 so that replays are byte-identical.
    out.encode_ms = lockstep_ ? 0.f : static_cast<float>(ms);
    fill(d, &out);
    publish(out);
  }

  /// Real time: queues a late frame on the background thread, after those already there, with the
  /// late recognizer (the current model); the thread runs below the recognizer's own priority.
  void startLate(Prepared job) {
    // Late frames carry nothing (ViewSelector::select), so no request points into the selector.
    for (auto& r : job.requests) r.carried = nullptr;
    status_.count("frames_late");
    auto done = std::make_shared<std::promise<Classified>>();
    late_results_.push_back(done->get_future());
    late_worker_->post([done, recognizer = late_recognizer_,
                        job = std::make_shared<const Prepared>(std::move(job))] {
      try {
        done->set_value(classify(*recognizer, *job));
      } catch (...) {  // classify() reports what it can name; this is only a guard
        done->set_value(Classified{*job, {}, {}, "unexpected error"});
      }
    });
  }

  /// Real time: grows the late recognizer's buffers on the thread that will use them (its heap
  /// arena too), queued before any late frame.
  void warmUpLate() {
    if (!late_worker_ || !late_recognizer_) return;
    late_worker_->post(
        [recognizer = late_recognizer_, options = options_] { warmUp(*recognizer, options); });
  }

  /// Publishes the late frames classified in the background that are done, in order.
  void finishLate() {
    while (!late_results_.empty() &&
           late_results_.front().wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
      finish(late_results_.front().get());
      late_results_.pop_front();
    }
  }

  /// A frame that a newer one overtook, answered with what the selection holds of its candidates
  /// (the last frame handled): nothing is classified.
  void answerWithoutPixels(const Joiner::Job& job) {
    const proposals_t& p = job.proposals;
    status_.noteInput(p.utime, p.seq);
    status_.count("frames_carried");
    detections_t out = emptyAnswer(p);
    if (recognizer_) {
      std::vector<BoxRequest> requests(static_cast<size_t>(p.num_boxes));
      for (size_t i = 0; i < requests.size(); ++i) {
        const box_t& b = p.boxes[i];
        requests[i] = BoxRequest{b.x,
                                 b.y,
                                 b.w,
                                 b.h,
                                 p.candidate_ids[i],
                                 selector_.lastResult(p.map_id, p.candidate_ids[i])};
      }
      const image_t& frame = **job.frame;
      FrameDetections d = recognizer_->carryOnly(frame.width, frame.height, requests);
      if (d.uncarried) status_.count("boxes_unlabelled", d.uncarried);
      countBoxes(&d);
      fill(d, &out);
    }
    publish(out);
  }

  /// A frame's DETECTIONS without boxes.
  detections_t emptyAnswer(const proposals_t& p) const {
    detections_t out;
    out.utime = p.utime;
    out.seq = p.seq;
    out.map_id = p.map_id;
    out.encode_ms = 0;
    out.num_boxes = 0;
    out.class_names = recognizer_ ? recognizer_->classes() : std::vector<std::string>{"background"};
    out.num_classes = static_cast<int32_t>(out.class_names.size());
    return out;
  }

  /// Suppresses overlaps among a frame's boxes and counts them; returns the valid boxes.
  int64_t countBoxes(FrameDetections* d) {
    suppressOverlaps(d, options_.nms_iou, options_.nms_per_class);
    status_.count("boxes_rejected", d->rejected());
    if (d->rejected_not_finite) status_.count("boxes_rejected.not_finite", d->rejected_not_finite);
    if (d->rejected_empty) status_.count("boxes_rejected.zero_size", d->rejected_empty);
    if (d->rejected_outside) status_.count("boxes_rejected.outside_image", d->rejected_outside);
    if (d->rejected_over_limit) status_.count("boxes_rejected.over_limit", d->rejected_over_limit);
    if (d->clipped) status_.count("boxes_clipped", d->clipped);
    const int64_t valid = static_cast<int64_t>(d->boxes.size()) + d->suppressed;
    status_.count("boxes_classified", valid - d->carried);
    if (d->carried) status_.count("boxes_carried", d->carried);
    if (d->suppressed) status_.count("boxes_suppressed", d->suppressed);
    return valid;
  }

  static void fill(const FrameDetections& d, detections_t* out) {
    out->num_boxes = static_cast<int32_t>(d.boxes.size());
    for (const auto& b : d.boxes) {
      out->boxes.push_back(boxMessage(b.x, b.y, b.w, b.h));
      out->candidate_ids.push_back(b.candidate_id);
      out->log_prob.push_back(b.log_prob);
      out->classified_seq.push_back(b.carried_seq >= 0 ? b.carried_seq : out->seq);
    }
  }

  void publish(const detections_t& out) { bus_.publish(ch_.detections, out); }

  Bus& bus_;
  StatusReporter& status_;
  Channels ch_;
  bool lockstep_;
  RecognizerOptions options_;
  ViewSelector selector_;
  int64_t restarts_seen_ = 0;  ///< camera restarts when the selection last looked
  Joiner joiner_;
  std::unique_ptr<Recognizer> recognizer_;
  std::shared_ptr<Recognizer> late_recognizer_;  ///< real time only
  // Real time: the late frames on the background thread, in order. The worker is declared last:
  // its jobs hold what they use (nothing of the node) and it finishes them before it goes.
  std::deque<std::future<Classified>> late_results_;
  std::unique_ptr<SerialWorker> late_worker_;
  bool tried_ = false;
  Clock::time_point last_try_;
  // Live reload.
  FileStamp loaded_stamp_, loading_stamp_, refused_stamp_;
  std::future<Loaded> loading_;
  bool reload_again_ = false;
  Clock::time_point last_watch_;
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
  addPrintConfigOption(app, [] { return defaultConfigFileText<RecognizerOptions>("recognizer"); });
  CLI11_PARSE(app, argc, argv);

  return runNode("recognizer", node, [&]() -> int {
    const SystemConfig sys = loadSystem(node);
    RecognizerOptions options = loadConfig<RecognizerOptions>(node.config, "recognizer");
    if (!model.empty()) options.model = model;
    checkOptions(options, node.config.empty() ? std::string("defaults") : node.config);
    Bus bus(sys.bus.url);
    StatusReporter status(bus, node.nameOr("recognizer"),
                          sys.channels.statusOf(node.nameOr("recognizer")));
    RecognizerNode rec(bus, status, sys, options, node.nameOr("recognizer"));
    rec.ensureModel();
    // SLAM goes first (common/thread_priority.h): the recognizer lowers its priority before its
    // first frame, not before loading and warming up its model, so that a restart under load is
    // short (about a second of start-up at the normal priority). Threads started later (a live
    // reload's) inherit the lowered value.
    lowerThreadPriority(sys.scheduling.recognizer_nice, "the recognizer");
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
      rec.pollReload();
      rec.process();
      status.tick();
    }
    status.setState(StatusReporter::State::kStopping);
    status.publish();
    return 0;
  });
}
