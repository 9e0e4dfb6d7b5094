// A wait-free "latest value" box from one writer thread to one reader thread
// (triple buffering, as terracut/haptics/snapshot.hpp): the writer never
// waits for the reader and the reader never sees a half-written value.
#pragma once

#include <atomic>

namespace terracut::viewer {

template <class T>
class Mailbox {
 public:
  /// Writer: makes value the newest.
  void write(const T& value) {
    slots_[back_] = value;
    unsigned old = middle_.exchange(back_ | kFresh, std::memory_order_acq_rel);
    back_ = old & ~kFresh;
  }
  /// Reader: copies the newest value into out when one was written since the
  /// last read and returns true; else leaves out alone and returns false.
  bool read(T& out) {
    if (!(middle_.load(std::memory_order_acquire) & kFresh)) return false;
    unsigned old = middle_.exchange(front_, std::memory_order_acq_rel);
    front_ = old & ~kFresh;
    out = slots_[front_];
    return true;
  }

 private:
  static constexpr unsigned kFresh = 4u;
  T slots_[3]{};
  unsigned back_ = 0;   // writer only
  unsigned front_ = 2;  // reader only
  std::atomic<unsigned> middle_{1};
};

}  // namespace terracut::viewer
