// Real-time settings for the haptic loop's thread: SCHED_FIFO scheduling and
// locked memory where the system permits them, with a one-line message and
// a working fallback (normal scheduling, pageable memory) where it does not.
#pragma once

#include <string>

namespace terracut::haptics {

/// What enable_realtime obtained.
struct RealtimeStatus {
  bool fifo = false;           ///< the calling thread runs under SCHED_FIFO
  int priority = 0;            ///< its SCHED_FIFO priority (0 when not FIFO)
  bool memory_locked = false;  ///< mlockall(MCL_CURRENT | MCL_FUTURE) succeeded
  /// One line for the user, e.g. "real-time: SCHED_FIFO priority 80, memory
  /// locked" or what was refused and how to allow it.
  std::string message;
};

/// Asks for SCHED_FIFO at `priority` (clamped to the system's range) for the
/// calling thread, and, when lock_memory, locks the process's memory. Memory is
/// locked only when the RLIMIT_MEMLOCK limit is unlimited or the process is
/// privileged, because with a small limit MCL_FUTURE would make later
/// allocations fail. Never throws; a refusal leaves things as they were.
RealtimeStatus enable_realtime(int priority, bool lock_memory);

/// Undoes the memory lock of enable_realtime (munlockall) when it was taken.
void release_realtime(const RealtimeStatus& status);

}  // namespace terracut::haptics
