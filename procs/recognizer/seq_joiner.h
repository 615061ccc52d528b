#pragma once
// Pairs each proposals message with the camera frame of the same seq (docs/architecture.md §2:
// downstream messages keep their frame's seq), with bounded buffers. No LCM in here: Frame and
// Proposals are whatever the caller stores (the node keeps the decoded LCM messages).
//
// Frames come in seq order from one camera. A proposals message whose frame is buffered is joined
// at once; one whose frame is older than every buffered frame, or was skipped by the camera
// stream, can never be joined and comes out as a job without a frame (the node answers it with
// empty detections and counts it); one for a frame not yet received waits, up to `max_pending`
// messages and `timeout_s` seconds.
#include <algorithm>
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <utility>

namespace slamaware::recognizer {

template <class Frame, class Proposals>
class SeqJoiner {
 public:
  enum class Outcome { kJoined, kUnknownFrame, kOverflow, kTimedOut };
  struct Job {
    int32_t seq = -1;
    Proposals proposals;
    std::optional<Frame> frame;  ///< set when joined
    Outcome outcome = Outcome::kJoined;
    bool drop = false;  ///< real time: a newer joined frame is waiting (markRealTimeDrops)
    bool late = false;  ///< real time: joined, for a frame older than one taken before
  };

  SeqJoiner(size_t max_frames, size_t max_pending, double timeout_s)
      : max_frames_(max_frames < 1 ? 1 : max_frames),
        max_pending_(max_pending),
        timeout_s_(timeout_s) {}

  /// A camera frame. A seq lower than the newest one seen means the stream restarted: the frame
  /// buffer is cleared.
  void addFrame(int32_t seq, Frame frame) {
    if (newest_frame_ && seq < *newest_frame_) {
      frames_.clear();
      taken_seq_.reset();
      ++restarts_;
    }
    newest_frame_ = seq;
    frames_[seq] = std::move(frame);
    while (frames_.size() > max_frames_) frames_.erase(frames_.begin());
    // Waiting proposals for this frame are joined; those for older frames can no longer be.
    for (auto it = pending_.begin(); it != pending_.end();) {
      if (it->job.seq == seq) {
        it->job.frame = frames_.at(seq);
        ready_.push_back(std::move(it->job));
        it = pending_.erase(it);
      } else if (it->job.seq < seq) {
        it->job.outcome = Outcome::kUnknownFrame;
        ready_.push_back(std::move(it->job));
        it = pending_.erase(it);
      } else {
        ++it;
      }
    }
  }

  /// A proposals message received at now_s (seconds, any monotonic clock).
  void addProposals(int32_t seq, Proposals proposals, double now_s) {
    Job job;
    job.seq = seq;
    job.proposals = std::move(proposals);
    auto f = frames_.find(seq);
    if (f != frames_.end()) {
      job.frame = f->second;
      ready_.push_back(std::move(job));
      return;
    }
    if (newest_frame_ && seq < *newest_frame_) {
      job.outcome = Outcome::kUnknownFrame;
      ready_.push_back(std::move(job));
      return;
    }
    pending_.push_back(Pending{std::move(job), now_s});
    while (pending_.size() > max_pending_) {
      pending_.front().job.outcome = Outcome::kOverflow;
      ready_.push_back(std::move(pending_.front().job));
      pending_.pop_front();
    }
  }

  /// Gives up on proposals that waited longer than the timeout.
  void expire(double now_s) {
    while (!pending_.empty() && now_s - pending_.front().since_s > timeout_s_) {
      pending_.front().job.outcome = Outcome::kTimedOut;
      ready_.push_back(std::move(pending_.front().job));
      pending_.pop_front();
    }
  }

  /// Real time: of the joined jobs ready, only the newest is to be handled; the others get `drop`.
  /// Late ones (`late`) never do: a seq below the newest of the jobs ready at an earlier call is
  /// proposals sent late on purpose for a frame still buffered (a map's reference keyframe,
  /// procs/proposals).
  void markRealTimeDrops() {
    const auto late = [this](const Job& j) { return taken_seq_ && j.seq < *taken_seq_; };
    size_t newest = ready_.size();
    for (size_t i = 0; i < ready_.size(); ++i)
      if (ready_[i].frame && !late(ready_[i])) newest = i;
    for (size_t i = 0; i < ready_.size(); ++i) {
      ready_[i].late = ready_[i].frame && late(ready_[i]);
      ready_[i].drop = ready_[i].frame && i != newest && !ready_[i].late;
    }
    for (const Job& j : ready_) taken_seq_ = std::max(taken_seq_.value_or(j.seq), j.seq);
  }

  /// Jobs to handle, in the order they became ready.
  std::deque<Job>& ready() { return ready_; }
  size_t pending() const { return pending_.size(); }
  size_t frames() const { return frames_.size(); }
  /// Times the camera stream restarted (a frame's seq below the newest one's).
  int64_t restarts() const { return restarts_; }

 private:
  struct Pending {
    Job job;
    double since_s;
  };
  size_t max_frames_, max_pending_;
  double timeout_s_;
  std::map<int32_t, Frame> frames_;
  std::optional<int32_t> newest_frame_;
  std::optional<int32_t> taken_seq_;
  int64_t restarts_ = 0;  ///< the newest seq of the jobs ready at markRealTimeDrops
  std::deque<Pending> pending_;
  std::deque<Job> ready_;
};

}  // namespace slamaware::recognizer
