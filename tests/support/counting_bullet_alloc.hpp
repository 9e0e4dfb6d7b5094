// counting_new.hpp plus Bullet's own allocations (btAlignedAlloc), counted in
// the same g_allocations. Include it in exactly one source file of a test
// executable that links Bullet.
#pragma once

#include <LinearMath/btAlignedAllocator.h>

#include "counting_new.hpp"

namespace counting_detail {
inline void* counted_bullet_alloc(std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return std::malloc(size);
}
inline void bullet_free(void* p) { std::free(p); }
}  // namespace counting_detail

/// Installed before main, so every Bullet object of the program uses it
/// (Bullet's default also allocates with malloc and frees with free).
inline const bool g_installed = [] {
  btAlignedAllocSetCustom(counting_detail::counted_bullet_alloc, counting_detail::bullet_free);
  return true;
}();
