// Counts every global operator new of a test program, to prove that a hot
// path allocates nothing. Include it in exactly one source file of a test
// executable: it replaces the program's global operator new and delete.
#pragma once

#include <atomic>
#include <cstdlib>
#include <new>

// GCC pairs the replaced operator new (malloc) with free() through inlining
// and warns about a mismatch that is not one.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

/// Global operator new calls so far in this program.
inline std::atomic<long> g_allocations{0};

void* operator new(std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size ? size : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
