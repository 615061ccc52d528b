#pragma once
// The LCM layer: a typed, safe subscribe over LCM 1.3.1's raw subscribe (after Drake's
// Subscribe<Message>): every message is decoded in our code, a message larger than the
// channel's cap, one that fails to decode, or one with bytes left over after decoding is
// rejected and counted; an exception from a handler is caught and counted. A malformed message
// never stops a process.
#include <climits>
#include <cstdint>
#include <exception>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace lcm {
class LCM;
class ReceiveBuffer;
}  // namespace lcm

namespace slamaware {

/// Decodes `size` bytes as Msg the way every subscription does: false (and *why) when the bytes
/// do not decode (wrong type, truncated, a length field larger than the bytes left) or leave
/// bytes over. Never allocates more than the message's own size allows (lcmtypes/ hardens
/// lcm-gen's decoders).
template <class Msg>
bool decodeMessage(const uint8_t* data, size_t size, Msg* msg, std::string* why) {
  if (size > static_cast<size_t>(INT32_MAX)) {
    *why = std::string("a ") + Msg::getTypeName() + " cannot be " + std::to_string(size) + " bytes";
    return false;
  }
  int used = -1;
  try {
    used = msg->decode(data, 0, static_cast<int>(size));
  } catch (const std::exception& e) {
    *why = std::string("cannot decode ") + Msg::getTypeName() + ": " + e.what();
    return false;
  }
  if (used < 0) {
    *why = std::string("not a valid ") + Msg::getTypeName() + " (" + std::to_string(size) +
           " bytes: wrong type, truncated or bad length field)";
    return false;
  }
  if (static_cast<size_t>(used) != size) {
    *why = std::string(Msg::getTypeName()) + " followed by " + std::to_string(size - used) +
           " trailing bytes";
    return false;
  }
  return true;
}

class Bus {
 public:
  /// A received message before decoding.
  struct RawMessage {
    const std::string& channel;
    const uint8_t* data;
    size_t size;
    int64_t recv_utime;  ///< µs, wall clock at reception
  };
  using RawHandler = std::function<void(const RawMessage& raw)>;
  static constexpr size_t kDefaultMaxBytes = 1 << 20;

  /// Opens the LCM bus at `url`; throws std::runtime_error if LCM cannot start (bad URL, no
  /// multicast route).
  explicit Bus(const std::string& url);
  ~Bus();
  Bus(const Bus&) = delete;
  Bus& operator=(const Bus&) = delete;

  const std::string& url() const { return url_; }

  /// Decodes every message of `channel` as Msg and calls handler(msg). Messages over max_bytes,
  /// that fail to decode or leave trailing bytes are rejected and counted.
  template <class Msg>
  void subscribe(const std::string& channel, std::function<void(const Msg&)> handler,
                 size_t max_bytes = kDefaultMaxBytes) {
    subscribeRaw(
        channel,
        [this, handler = std::move(handler)](const RawMessage& raw) {
          Msg msg{};
          std::string why;
          if (!decodeMessage(raw.data, raw.size, &msg, &why)) {
            reject(raw.channel, why);
            return;
          }
          handler(msg);
        },
        max_bytes);
  }
  /// Calls handler with the bytes of every message of `channel` (an LCM regular expression,
  /// anchored) up to max_bytes (larger ones are rejected and counted).
  void subscribeRaw(const std::string& channel, RawHandler handler,
                    size_t max_bytes = kDefaultMaxBytes);

  /// Encodes and publishes; returns false (and logs) on failure. Thread-safe.
  template <class Msg>
  bool publish(const std::string& channel, const Msg& msg) {
    std::vector<uint8_t> buf(static_cast<size_t>(msg.getEncodedSize()));
    if (msg.encode(buf.data(), 0, static_cast<int>(buf.size())) != static_cast<int>(buf.size()))
      return publishFailed(channel, "encode failed");
    return publishRaw(channel, buf.data(), buf.size());
  }
  bool publishRaw(const std::string& channel, const uint8_t* data, size_t size);

  /// Waits up to timeout_ms for messages and dispatches them. Returns the number handled (0 on
  /// timeout), -1 if LCM failed.
  int handle(int timeout_ms);
  /// The bus's file descriptor, readable when a message waits (for poll() with other fds).
  int fileno() const;

  /// Rejected messages per channel (over the cap, undecodable, trailing bytes).
  std::map<std::string, int64_t> rejects() const;
  /// Handler exceptions per channel.
  std::map<std::string, int64_t> handlerErrors() const;
  int64_t totalRejects() const;
  /// The last reject or handler error, as a human-readable sentence ("" if none).
  std::string lastProblem() const;

  /// Records a rejected message on `channel` (also used by handlers that find a message
  /// well-formed but unusable, e.g. a corrupt JPEG inside).
  void reject(const std::string& channel, const std::string& why);

 private:
  struct Subscription;
  static void dispatch(const lcm::ReceiveBuffer* rbuf, const std::string& channel,
                       Subscription* sub);
  bool publishFailed(const std::string& channel, const std::string& why);
  void handlerError(const std::string& channel, const std::string& why);
  void note(const std::string& channel, const std::string& what, const std::string& why);

  std::string url_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::vector<std::unique_ptr<Subscription>> subs_;
  mutable std::mutex mutex_;
  std::map<std::string, int64_t> rejects_, handler_errors_;
  std::map<std::string, int64_t> last_logged_us_;
  std::string last_problem_;
};

/// Wall clock in µs since the epoch (status messages only; algorithms use message utimes).
int64_t wallUtime();

}  // namespace slamaware
