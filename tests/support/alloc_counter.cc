#include "tests/support/alloc_counter.h"

#include <cstdlib>
#include <new>

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define MICRODEX_COUNT_MALLOC 0
#else
#define MICRODEX_COUNT_MALLOC 1
#endif

namespace {
// Initial-exec TLS of the executable: reading it never allocates (safe inside malloc).
thread_local bool t_counting = false;
thread_local std::uint64_t t_count = 0;

inline void Count() {
  if (t_counting) ++t_count;
}
}  // namespace

#if MICRODEX_COUNT_MALLOC
// glibc's own entry points: the replacements below count and forward to them.
extern "C" {
void* __libc_malloc(std::size_t n);
void* __libc_calloc(std::size_t n, std::size_t size);
void* __libc_realloc(void* p, std::size_t n);
void* __libc_memalign(std::size_t align, std::size_t n);
void __libc_free(void* p);

void* malloc(std::size_t n) {
  Count();
  return __libc_malloc(n);
}
void* calloc(std::size_t n, std::size_t size) {
  Count();
  return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t n) {
  Count();
  return __libc_realloc(p, n);
}
void* aligned_alloc(std::size_t align, std::size_t n) {
  Count();
  return __libc_memalign(align, n);
}
void* memalign(std::size_t align, std::size_t n) {
  Count();
  return __libc_memalign(align, n);
}
int posix_memalign(void** out, std::size_t align, std::size_t n) {
  Count();
  void* p = __libc_memalign(align, n);
  if (p == nullptr) return 12;  // ENOMEM
  *out = p;
  return 0;
}
void free(void* p) { __libc_free(p); }
}  // extern "C"
#endif

namespace {
void* Allocate(std::size_t n) {
  if (!MICRODEX_COUNT_MALLOC) Count();  // otherwise malloc counts it
  void* p = std::malloc(n == 0 ? 1 : n);
  if (p == nullptr) throw std::bad_alloc();
  return p;
}

void* AllocateAligned(std::size_t n, std::align_val_t a) {
  if (!MICRODEX_COUNT_MALLOC) Count();
  const std::size_t align = static_cast<std::size_t>(a);
  void* p = std::aligned_alloc(align, (n + align - 1) / align * align);
  if (p == nullptr) throw std::bad_alloc();
  return p;
}
}  // namespace

namespace microdex::testing {
void StartCountingAllocations() {
  t_count = 0;
  t_counting = true;
}
std::uint64_t StopCountingAllocations() {
  t_counting = false;
  return t_count;
}
bool CountsMalloc() { return MICRODEX_COUNT_MALLOC != 0; }
}  // namespace microdex::testing

void* operator new(std::size_t n) { return Allocate(n); }
void* operator new[](std::size_t n) { return Allocate(n); }
void* operator new(std::size_t n, std::align_val_t a) { return AllocateAligned(n, a); }
void* operator new[](std::size_t n, std::align_val_t a) { return AllocateAligned(n, a); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
