// The peak resident memory of a test program, to prove that refusing a bad
// input commits little memory (a lying image header, a huge scenario).
#pragma once

#include <sys/resource.h>

#include <cstdint>

namespace terracut::test {

/// Peak resident memory of this process so far, bytes (Linux reports KiB).
inline std::int64_t peak_rss_bytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return std::int64_t{usage.ru_maxrss} * 1024;
}

// AddressSanitizer keeps freed memory in quarantine and writes the shadow of
// every allocation (1/8 of its size), so under it a growth of a few MiB
// shows as hundreds; ThreadSanitizer's shadow is larger still (the threaded
// tests run under it, tests/tsan/).
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define TERRACUT_TEST_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define TERRACUT_TEST_SANITIZED 1
#endif
#endif

/// The growth of the peak allowed where about `mib` MiB are expected: that,
/// or 1 GiB under a sanitizer (still far below the gigabytes the
/// refused inputs used to take).
inline std::int64_t small_growth(std::int64_t mib) {
#if defined(TERRACUT_TEST_SANITIZED)
  (void)mib;
  return std::int64_t{1} << 30;
#else
  return mib << 20;
#endif
}

}  // namespace terracut::test
