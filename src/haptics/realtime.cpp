#include "terracut/haptics/realtime.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace terracut::haptics {

RealtimeStatus enable_realtime(int priority, bool lock_memory) {
  RealtimeStatus s;
  std::string sched_text;
  // Scheduling: SCHED_FIFO for this thread.
  const int lo = sched_get_priority_min(SCHED_FIFO);
  const int hi = sched_get_priority_max(SCHED_FIFO);
  sched_param param{};
  param.sched_priority = std::clamp(priority, lo, hi);
  const int err = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
  if (err == 0) {
    s.fifo = true;
    s.priority = param.sched_priority;
    sched_text = "SCHED_FIFO priority " + std::to_string(s.priority);
  } else {
    sched_text = std::string("normal scheduling (SCHED_FIFO refused: ") + std::strerror(err) +
                 "; allow it with `setcap cap_sys_nice+ep` on the program or an rtprio limit "
                 "in /etc/security/limits.conf)";
  }

  // Memory: lock only where a later allocation cannot fail because of it.
  std::string mem_text;
  if (lock_memory) {
    rlimit limit{};
    const bool unlimited =
        getrlimit(RLIMIT_MEMLOCK, &limit) == 0 && limit.rlim_cur == RLIM_INFINITY;
    if (unlimited || geteuid() == 0) {
      if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
        s.memory_locked = true;
        mem_text = "memory locked";
      } else {
        mem_text = std::string("memory not locked (mlockall: ") + std::strerror(errno) + ")";
      }
    } else {
      mem_text = "memory not locked (RLIMIT_MEMLOCK is " +
                 std::to_string(static_cast<unsigned long long>(limit.rlim_cur / 1024)) +
                 " KiB; `ulimit -l unlimited` or CAP_IPC_LOCK allows it)";
    }
  } else {
    mem_text = "memory not locked (not asked)";
  }
  s.message = "real-time: " + sched_text + ", " + mem_text;
  return s;
}

void release_realtime(const RealtimeStatus& status) {
  if (status.memory_locked) munlockall();
}

}  // namespace terracut::haptics
