// Internal: uninitialised double buffers on transparent huge pages where the kernel offers them.
// The engine's large scratch arrays are written before they are read, so zero-filling them
// (std::vector) only costs time; on 4 KiB pages each 2 MiB is 512 page faults and, for arrays
// read at far-apart offsets, a TLB walk every 512 values.
#pragma once
#include <sys/mman.h>

#include <cstddef>
#include <cstdlib>
#include <memory>
#include <new>

namespace rig::analysis::detail {

struct FreeDoubles {
  void operator()(double* p) const { std::free(p); }
};
using HugeBuffer = std::unique_ptr<double, FreeDoubles>;

// At least `count` doubles, rounded up to whole 2 MiB pages; `capacity` (if given) gets the
// rounded count. Throws std::bad_alloc.
inline HugeBuffer huge_buffer(std::size_t count, std::size_t* capacity = nullptr) {
  constexpr std::size_t kHuge = 2u << 20;
  const std::size_t bytes = (count * sizeof(double) + kHuge - 1) / kHuge * kHuge;
  HugeBuffer buf(static_cast<double*>(std::aligned_alloc(kHuge, bytes)));
  if (!buf) throw std::bad_alloc();
#ifdef MADV_HUGEPAGE
  ::madvise(buf.get(), bytes, MADV_HUGEPAGE);  // advisory: failure only costs speed
#endif
  if (capacity) *capacity = bytes / sizeof(double);
  return buf;
}

}  // namespace rig::analysis::detail
