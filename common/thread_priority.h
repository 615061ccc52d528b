#pragma once
// Who gets the CPU first. On 2 cores the pipeline asks for more than there is while a scene is
// being mapped, and Linux shares the cores out by the threads' nice values. SLAM's tracking must
// handle every frame as it comes (a frame it is late on delays every later frame and all that
// follows from them); its local mapping must keep up, or tracking thins out and is lost; its
// depth filter skips frames when behind; the recognizer classifies the newest frame and answers
// the ones it overtook from earlier views; the proposals' clustering and the object map catch up
// later. So tracking alone runs at the normal priority and everything else lowers its own, each by
// its increment in system.yaml's `scheduling` (an unprivileged process may lower its priority,
// never raise it). Only timing depends on it: lockstep runs are byte-identical at any value.
#include <string>

namespace slamaware {

/// Lowers the calling thread's priority by `increment` nice levels (0: unchanged). Threads it
/// starts afterwards inherit the value. Returns false if the system refused (the first refusal in a
/// process is logged, naming `what`).
bool lowerThreadPriority(int increment, const std::string& what);

/// The increment background threads of this process take, from system.yaml's
/// `scheduling.background_nice` (loadSystem sets it); set once at start, before the threads.
void setBackgroundNice(int increment);

/// Lowers the calling thread's priority by the process's background increment: for work deep in
/// a library (a clustering job) that does not see the configuration.
bool enterBackground(const std::string& what);

/// Names the calling thread (at most 15 characters are kept) as top -H, ps -L and perf show it.
void nameThisThread(const std::string& name);

}  // namespace slamaware
