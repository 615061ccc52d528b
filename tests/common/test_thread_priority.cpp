// The scheduling helpers change the calling thread's nice value, and only that thread's.
#include <gtest/gtest.h>
#include <pthread.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <string>
#include <thread>

#include "common/thread_priority.h"

using namespace slamaware;

namespace {

int myNice() { return getpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid))); }

}  // namespace

TEST(ThreadPriority, LowersTheCallingThreadOnlyAndItsChildrenInherit) {
  const int before = myNice();
  if (before + 4 > 19) GTEST_SKIP() << "this test already runs at nice " << before;
  int in_thread = 0, in_child = 0, zero = 0;
  std::thread([&] {
    EXPECT_TRUE(lowerThreadPriority(0, "test thread"));
    zero = myNice();
    EXPECT_TRUE(lowerThreadPriority(4, "test thread"));
    in_thread = myNice();
    std::thread([&] { in_child = myNice(); }).join();
  }).join();
  EXPECT_EQ(zero, before);
  EXPECT_EQ(in_thread, before + 4);
  EXPECT_EQ(in_child, before + 4);
  EXPECT_EQ(myNice(), before) << "the caller's own thread must keep its priority";
}

TEST(ThreadPriority, BackgroundTakesTheProcessIncrement) {
  const int before = myNice();
  if (before + 3 > 19) GTEST_SKIP() << "this test already runs at nice " << before;
  int off = 0, on = 0;
  setBackgroundNice(0);
  std::thread([&] {
    enterBackground("test job");
    off = myNice();
  }).join();
  setBackgroundNice(3);
  std::thread([&] {
    enterBackground("test job");
    on = myNice();
  }).join();
  setBackgroundNice(0);
  EXPECT_EQ(off, before);
  EXPECT_EQ(on, before + 3);
}

// top -H, ps -L and perf show a thread by the name the kernel keeps (15 characters at most).
TEST(ThreadPriority, NamesTheCallingThreadOnly) {
  const auto nameOf = [](pthread_t t) {
    char buf[32] = {};
    pthread_getname_np(t, buf, sizeof(buf));
    return std::string(buf);
  };
  const std::string mine = nameOf(pthread_self());
  std::string named;
  std::thread([&] {
    nameThisThread("slam-mapping-and-more");
    named = nameOf(pthread_self());
  }).join();
  EXPECT_EQ(named, "slam-mapping-an");
  EXPECT_EQ(nameOf(pthread_self()), mine);
}
