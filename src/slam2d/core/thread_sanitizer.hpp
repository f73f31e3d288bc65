// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// ThreadSanitizer builds (make check-tsan): SLAM2D_TSAN is defined (kThreadSanitizer true), and
// tsan_release(address) / tsan_acquire(address) declare a happens-before edge to TSan where the
// code synchronises in a way it cannot see (std::atomic_thread_fence, which TSan ignores). In
// every other build they compile to nothing.

#if defined(__SANITIZE_THREAD__)
#define SLAM2D_TSAN 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define SLAM2D_TSAN 1
#endif
#endif

#if defined(SLAM2D_TSAN)
#include <sanitizer/tsan_interface.h>
#endif

namespace slam2d {

#if defined(SLAM2D_TSAN)
inline constexpr bool kThreadSanitizer = true;
#else
inline constexpr bool kThreadSanitizer = false;
#endif

inline void tsan_release([[maybe_unused]] void* address) {
#if defined(SLAM2D_TSAN)
  __tsan_release(address);
#endif
}

inline void tsan_acquire([[maybe_unused]] void* address) {
#if defined(SLAM2D_TSAN)
  __tsan_acquire(address);
#endif
}

}  // namespace slam2d
