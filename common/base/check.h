#pragma once
// Always-on programming-invariant checks (README.md "Errors": programming errors abort).
// A failed check is a bug: it prints file, line and condition and aborts, in release
// builds too. Bad input is not checked here: it gets an exception at load time or a
// status value inside the loop.

#include <cstdio>
#include <cstdlib>

namespace microdex::internal {
[[noreturn]] inline void CheckFailed(const char* condition, const char* file, int line) {
  std::fprintf(stderr, "microdex: check failed: %s at %s:%d\n", condition, file, line);
  std::abort();
}
}  // namespace microdex::internal

#define MICRODEX_CHECK(condition)                                        \
  do {                                                                   \
    if (!(condition)) [[unlikely]]                                       \
      ::microdex::internal::CheckFailed(#condition, __FILE__, __LINE__); \
  } while (false)
