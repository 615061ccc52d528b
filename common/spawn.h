#pragma once
// Starting a child program with its stdout and stderr in a file (tools and tests that run our
// processes). The supervisor has its own, with pipes and process groups.
#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <unistd.h>

#include <cstdio>
#include <string>
#include <vector>

namespace slamaware {

/// fork + exec of argv (PATH searched), stdout and stderr appended to nothing but `output`
/// (truncated). With `die_with_parent` the child gets SIGTERM when the caller dies (and saves, as
/// at any stop). Returns the child's pid (-1 if fork failed); a failed exec exits the child with
/// 127.
inline pid_t spawnWithOutput(const std::vector<std::string>& argv, const std::string& output,
                             bool die_with_parent) {
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid != 0) return pid;
  if (die_with_parent) {
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (getppid() != parent) _exit(127);
  }
  const int fd = open(output.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd >= 0) {
    dup2(fd, 1);
    dup2(fd, 2);
    close(fd);
  }
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  execvp(args[0], args.data());
  std::perror(("exec " + argv[0]).c_str());  // into the output file
  _exit(127);
}

}  // namespace slamaware
